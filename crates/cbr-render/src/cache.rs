//! The on-disk cache of expensive frames (techniques that say `cacheable`: `ssaa`). A frame is
//! keyed on everything that changes it: the technique spec, resolution, LOD bias and debug flags,
//! the scene's content (geometry, materials, texture texels, lights, camera path, animation,
//! ambient and background), the frame index and its time, the shader modules the technique and its post chain were built
//! from (path, defines and SPIR-V without debug instructions: comments, line shifts and code in
//! branches the defines exclude keep the key), the device and
//! its driver, and the cache format. An entry is one file `<blake3 key>.cbrf`: a header, the
//! layers, and a blake3 checksum of both; an entry that fails the checksum or does not parse is
//! reported and recomputed.
//!
//! Many processes on many machines may share one cache folder (a sharded bench on a cluster,
//! docs/cluster.md). An entry is written under a temporary name unique to the writer (host,
//! process, sequence) and renamed into place, so a reader sees a whole entry or none, and two
//! writers of one key leave one whole entry (the last rename). A process that misses an entry
//! claims it first (`<key>.cbrf.claim`, created exclusively, holding host, process and time)
//! and renders it; a process that misses an entry another live process has claimed waits for
//! it, polling, at most [`wait_bound`] (`CBR_CACHE_WAIT_S`, default 1800 s), then renders it
//! itself. A claim whose process is gone (same host, no such process) is stale: the frame is
//! rendered at once. Storing an entry removes its claim.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use cbr_gpu::{Gpu, GpuError, Result, Shaders};
use cbr_scene::Scene;
use half::f16;

use crate::frame::{ExrType, FrameOutput, Layer, Samples, Stat};
use crate::gpu_scene::FrameView;
use crate::renderer::RenderSettings;

/// The format: 0002 holds every layer and statistic of the frame (0001 only ssaa's coverage).
const MAGIC: &[u8; 8] = b"CBRF0002";

/// The default cache folder: `$CBR_CACHE_DIR`, else `$XDG_CACHE_HOME/cbr`, else
/// `$HOME/.cache/cbr`, else `.cbr-cache` in the working directory.
pub fn default_dir() -> PathBuf {
    let env = |k| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    env("CBR_CACHE_DIR")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("cbr")))
        .or_else(|| env("HOME").map(|d| d.join(".cache/cbr")))
        .unwrap_or_else(|| PathBuf::from(".cbr-cache"))
}

pub struct FrameCache {
    dir: PathBuf,
    /// The hash state after everything but the frame.
    base: blake3::Hasher,
}

/// One frame's key.
pub struct FrameKey(String);

impl FrameCache {
    pub fn new(
        dir: &Path,
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &Scene,
        s: &RenderSettings,
        modules: &[cbr_gpu::Request],
    ) -> Result<FrameCache> {
        std::fs::create_dir_all(dir).map_err(|e| {
            GpuError::Other(format!(
                "cannot create the cache folder {}: {e}",
                dir.display()
            ))
        })?;
        let mut h = blake3::Hasher::new();
        let mut put = |label: &str, bytes: &[u8]| {
            h.update(label.as_bytes());
            h.update(&(bytes.len() as u64).to_le_bytes());
            h.update(bytes);
        };
        put("format", MAGIC);
        put("spec", s.spec.to_string().as_bytes());
        let flags = format!(
            "{}x{} lod {:?} count {} debug_lod {} jitter {:?}",
            s.width, s.height, s.lod_bias, s.count_shaded, s.debug_lod, s.jitter
        );
        put("settings", flags.as_bytes());
        let info = gpu.info();
        let device = format!(
            "{} {} {} {} {:x}:{:x}",
            info.name,
            info.driver_name,
            info.driver_info,
            info.api_version,
            info.vendor_id,
            info.device_id
        );
        put("device", device.as_bytes());
        for (path, defines) in modules {
            let words = cbr_gpu::semantic_words(&shaders.compile(path, defines)?);
            put(&format!("{path} {defines:?}"), bytemuck::cast_slice(&words));
        }
        for o in &scene.objects {
            put(&o.name, bytemuck::cast_slice(&o.vertices));
            // Keyed only when set, so the keys of scenes at the origin stay what they were.
            if o.origin != [0.0; 3] {
                put("origin", bytemuck::cast_slice(&o.origin));
            }
            put("indices", bytemuck::cast_slice(&o.indices));
            put("material", &o.material.to_le_bytes());
        }
        for t in &scene.textures {
            put(&format!("{} {} {}", t.name, t.srgb, t.has_alpha), &[]);
            for l in &t.levels {
                put(&format!("{}x{}", l.width, l.height), &l.rgba);
            }
        }
        let mut settings = scene.settings.clone();
        (settings.width, settings.height, settings.frames) = (0, 0, 0);
        let described = format!(
            "{:?} {:?} {:?} {:?} {:?} {:?}",
            scene.materials, scene.camera, scene.directional, scene.points, scene.motions, settings
        );
        put("scene", described.as_bytes());
        Ok(FrameCache {
            dir: dir.to_path_buf(),
            base: h,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The key of frame `frame` (its time and cameras are part of it).
    pub fn key(&self, view: &FrameView, frame: u32) -> FrameKey {
        let mut h = self.base.clone();
        h.update(&frame.to_le_bytes());
        let cams = format!(
            "{:?} {:?} {} {}",
            view.camera, view.prev_camera, view.time, view.prev_time
        );
        h.update(cams.as_bytes());
        FrameKey(h.finalize().to_hex().to_string())
    }

    fn path(&self, key: &FrameKey) -> PathBuf {
        self.dir.join(format!("{}.cbrf", key.0))
    }

    /// The cached frame; `None` when it is absent or corrupt (reported), and then this process
    /// has claimed it (or another's claim went stale or past [`wait_bound`]): render it and
    /// [`FrameCache::store`] it. Waits while another live process holds its claim.
    pub fn load(&self, key: &FrameKey, frame: u32, time: f64) -> Option<FrameOutput> {
        let path = self.path(key);
        let mut out = fetch(&path, wait_bound())?;
        out.index = frame;
        out.time = time;
        out.cached = Some(path);
        Some(out)
    }

    /// Stores a frame; returns its path (a failed write is reported, not fatal), and releases
    /// the frame's claim.
    pub fn store(&self, key: &FrameKey, out: &FrameOutput) -> Option<PathBuf> {
        put(&self.path(key), out)
    }
}

/// How long a reader waits for a frame another live process has claimed before rendering it
/// itself: `CBR_CACHE_WAIT_S` seconds, default 1800 (an `ssaa:16` frame of Sibenik at 1280x720
/// takes about 300 s on lavapipe).
pub fn wait_bound() -> Duration {
    let s = std::env::var("CBR_CACHE_WAIT_S")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(1800);
    Duration::from_secs(s)
}

fn claim_path(entry: &Path) -> PathBuf {
    let mut p = entry.as_os_str().to_owned();
    p.push(".claim");
    PathBuf::from(p)
}

/// Whether a claim is no reason to wait: it names this host and either this process (a claim it
/// left itself) or a process that does not exist here (its holder died). Another host's claim is
/// always waited for (until [`wait_bound`]).
fn claim_is_stale(text: &str) -> bool {
    let mut parts = text.split_whitespace();
    let (Some(host), Some(pid)) = (parts.next(), parts.next()) else {
        // Being written right now (created, not yet filled): live.
        return false;
    };
    host == cbr_metrics::io::hostname()
        && pid.parse::<u32>().is_ok_and(|pid| {
            pid == std::process::id() || !Path::new(&format!("/proc/{pid}")).exists()
        })
}

/// The entry at `path`, or `None` when the caller is to render it (absent or corrupt and now
/// claimed by the caller; or its claim stale, or held longer than `wait`).
pub fn fetch(path: &Path, wait: Duration) -> Option<FrameOutput> {
    let started = Instant::now();
    let claim = claim_path(path);
    let mut poll = Duration::from_millis(20);
    loop {
        if let Ok(bytes) = std::fs::read(path) {
            match decode(&bytes) {
                Ok(out) => return Some(out),
                Err(why) => {
                    tracing::warn!("cache entry {} is corrupt ({why})", path.display());
                    eprintln!(
                        "warning: cache entry {} is corrupt ({why}): recomputing",
                        path.display()
                    );
                    return None;
                }
            }
        }
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&claim)
        {
            Ok(mut f) => {
                use std::io::Write;
                let now = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| d.as_secs())
                    .unwrap_or(0);
                let host = cbr_metrics::io::hostname();
                let _ = writeln!(f, "{host} {} {now}", std::process::id());
                // The entry may have landed between the read and the claim.
                if let Some(out) = std::fs::read(path).ok().and_then(|b| decode(&b).ok()) {
                    let _ = std::fs::remove_file(&claim);
                    return Some(out);
                }
                return None;
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let holder = std::fs::read_to_string(&claim).unwrap_or_default();
                if claim_is_stale(&holder) {
                    eprintln!(
                        "cache: the claim on {} is stale ({}): rendering it here",
                        path.display(),
                        holder.trim()
                    );
                    return None;
                }
                if started.elapsed() >= wait {
                    eprintln!(
                        "cache: waited {:.0} s for {} (claimed by {}): rendering it here",
                        wait.as_secs_f64(),
                        path.display(),
                        holder.trim()
                    );
                    return None;
                }
                std::thread::sleep(poll);
                poll = (poll * 2).min(Duration::from_millis(500));
            }
            // A folder this process cannot create files in: render without claiming.
            Err(_) => return None,
        }
    }
}

/// Writes an entry under a unique temporary name, renames it into place, and removes its claim.
/// The write is cbr's atomic one, which an interrupt lets finish.
pub fn put(path: &Path, out: &FrameOutput) -> Option<PathBuf> {
    let written = cbr_metrics::io::write_bytes(path, &encode(out));
    let _ = std::fs::remove_file(claim_path(path));
    match written {
        Ok(()) => Some(path.to_path_buf()),
        Err(e) => {
            tracing::warn!("cannot write cache entry: {e}");
            None
        }
    }
}

fn put_str(b: &mut Vec<u8>, s: &str) {
    b.extend_from_slice(&(s.len() as u32).to_le_bytes());
    b.extend_from_slice(s.as_bytes());
}

/// The four common layers, then every layer (name, channels, size, sample and EXR types,
/// samples) and every statistic (name, kind, value), then a blake3 checksum of it all.
fn encode(o: &FrameOutput) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.extend_from_slice(&o.width.to_le_bytes());
    b.extend_from_slice(&o.height.to_le_bytes());
    b.extend_from_slice(bytemuck::cast_slice(&o.color));
    b.extend_from_slice(bytemuck::cast_slice(&o.depth));
    b.extend_from_slice(bytemuck::cast_slice(&o.velocity));
    b.extend_from_slice(bytemuck::cast_slice(&o.ids));
    b.extend_from_slice(&(o.layers.len() as u32).to_le_bytes());
    for l in &o.layers {
        put_str(&mut b, &l.name);
        b.extend_from_slice(&(l.channels.len() as u32).to_le_bytes());
        for c in &l.channels {
            put_str(&mut b, c);
        }
        b.extend_from_slice(&l.width.to_le_bytes());
        b.extend_from_slice(&l.height.to_le_bytes());
        b.push(match l.exr {
            None => 0,
            Some(ExrType::Half) => 1,
            Some(ExrType::Float) => 2,
            Some(ExrType::Uint) => 3,
        });
        b.extend_from_slice(&(l.samples.len() as u64).to_le_bytes());
        match &l.samples {
            Samples::U8(v) => {
                b.push(0);
                b.extend_from_slice(v);
            }
            Samples::U32(v) => {
                b.push(1);
                v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
            }
            Samples::F16(v) => {
                b.push(2);
                v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
            }
            Samples::F32(v) => {
                b.push(3);
                v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
            }
        }
    }
    b.extend_from_slice(&(o.stats.len() as u32).to_le_bytes());
    for (name, s) in &o.stats {
        put_str(&mut b, name);
        match s {
            Stat::Count(n) => {
                b.push(0);
                b.extend_from_slice(&n.to_le_bytes());
            }
            Stat::Real(x) => {
                b.push(1);
                b.extend_from_slice(&x.to_le_bytes());
            }
            Stat::Flag(f) => {
                b.push(2);
                b.push(u8::from(*f));
            }
            Stat::Counts(v) => {
                b.push(3);
                b.extend_from_slice(&(v.len() as u32).to_le_bytes());
                v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
            }
        }
    }
    let sum = blake3::hash(&b);
    b.extend_from_slice(sum.as_bytes());
    b
}

/// Reads what [`encode`] wrote; every length is checked against the bytes left before anything
/// is allocated, so a corrupt entry is an error, never a panic or a huge allocation.
fn decode(b: &[u8]) -> std::result::Result<FrameOutput, String> {
    if b.len() < MAGIC.len() + 8 + 32 || &b[..MAGIC.len()] != MAGIC {
        return Err("not a cbr frame file of this version".into());
    }
    let (body, sum) = b.split_at(b.len() - 32);
    if blake3::hash(body).as_bytes() != sum {
        return Err("checksum mismatch".into());
    }
    let mut r = Reader {
        body,
        at: MAGIC.len(),
    };
    let w = r.u32()?;
    let h = r.u32()?;
    let n = (w as usize) * (h as usize);
    // Copy into typed vectors (the file bytes carry no alignment).
    let color: Vec<f16> = r.array::<2>(4 * n)?.map(f16::from_le_bytes).collect();
    let depth: Vec<f32> = r.array::<4>(n)?.map(f32::from_le_bytes).collect();
    let vel: Vec<f32> = r.array::<4>(2 * n)?.map(f32::from_le_bytes).collect();
    let ids: Vec<u32> = r.array::<4>(2 * n)?.map(u32::from_le_bytes).collect();
    let mut out = FrameOutput::new(
        w,
        h,
        color,
        depth,
        vel.chunks_exact(2).map(|v| [v[0], v[1]]).collect(),
        ids.chunks_exact(2).map(|v| [v[0], v[1]]).collect(),
    );
    for _ in 0..r.u32()? {
        let name = r.str()?;
        let channels = (0..r.u32()?)
            .map(|_| r.str())
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let (width, height) = (r.u32()?, r.u32()?);
        let exr = match r.u8()? {
            0 => None,
            1 => Some(ExrType::Half),
            2 => Some(ExrType::Float),
            3 => Some(ExrType::Uint),
            t => return Err(format!("layer `{name}`: EXR type {t}")),
        };
        let len = usize::try_from(r.u64()?).map_err(|_| "a layer too long")?;
        let expected = (width as usize)
            .checked_mul(height as usize)
            .and_then(|p| p.checked_mul(channels.len()));
        if expected != Some(len) {
            return Err(format!("layer `{name}`: {len} samples"));
        }
        let samples = match r.u8()? {
            0 => Samples::U8(r.take(len)?.to_vec()),
            1 => Samples::U32(r.array::<4>(len)?.map(u32::from_le_bytes).collect()),
            2 => Samples::F16(r.array::<2>(len)?.map(f16::from_le_bytes).collect()),
            3 => Samples::F32(r.array::<4>(len)?.map(f32::from_le_bytes).collect()),
            t => return Err(format!("layer `{name}`: sample type {t}")),
        };
        out.layers.push(Layer {
            name,
            channels,
            width,
            height,
            samples,
            exr,
        });
    }
    for _ in 0..r.u32()? {
        let name = r.str()?;
        let stat = match r.u8()? {
            0 => Stat::Count(r.u64()?),
            1 => Stat::Real(f64::from_bits(r.u64()?)),
            2 => Stat::Flag(r.u8()? != 0),
            3 => {
                let k = r.u32()? as usize;
                Stat::Counts(r.array::<8>(k)?.map(u64::from_le_bytes).collect())
            }
            t => return Err(format!("statistic `{name}`: kind {t}")),
        };
        out.stats.insert(name, stat);
    }
    if r.at != body.len() {
        return Err("trailing bytes".into());
    }
    Ok(out)
}

/// Reads an entry's body front to back.
struct Reader<'a> {
    body: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self.at.checked_add(n).ok_or("truncated")?;
        let s = self.body.get(self.at..end).ok_or("truncated")?;
        self.at = end;
        Ok(s)
    }

    /// `count` values of `N` bytes each.
    fn array<const N: usize>(
        &mut self,
        count: usize,
    ) -> std::result::Result<impl Iterator<Item = [u8; N]> + 'a, String> {
        let bytes = self.take(count.checked_mul(N).ok_or("truncated")?)?;
        Ok(bytes.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])))
    }

    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }

    fn u64(&mut self) -> std::result::Result<u64, String> {
        let s = self.take(8)?;
        Ok(u64::from_le_bytes(std::array::from_fn(|i| s[i])))
    }

    fn str(&mut self) -> std::result::Result<String, String> {
        let n = self.u32()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| "a name not UTF-8".to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame that depends on nothing but `k` (what a lone run of key `k` would store).
    fn frame_of(k: u32) -> FrameOutput {
        let (w, h) = (64u32, 36u32);
        let n = (w * h) as usize;
        let v = |i: usize, c: u32| ((i as u32).wrapping_mul(2654435761) ^ (k * 97 + c)) % 4093;
        FrameOutput::new(
            w,
            h,
            (0..4 * n)
                .map(|i| f16::from_f32(v(i, 1) as f32 / 64.0))
                .collect(),
            (0..n).map(|i| v(i, 2) as f32).collect(),
            (0..n)
                .map(|i| [v(i, 3) as f32, -(v(i, 4) as f32)])
                .collect(),
            (0..n).map(|i| [k, v(i, 5)]).collect(),
        )
    }

    fn same(a: &FrameOutput, b: &FrameOutput) -> bool {
        (
            a.width,
            a.height,
            &a.color,
            &a.depth,
            &a.velocity,
            &a.ids,
            &a.layers,
            &a.stats,
        ) == (
            b.width,
            b.height,
            &b.color,
            &b.depth,
            &b.velocity,
            &b.ids,
            &b.layers,
            &b.stats,
        )
    }

    const CHILD: &str = "CBR_CACHE_TEST_CHILD";
    const KEYS: u32 = 40;
    const WRITES: u32 = 125;

    /// One of the 8 processes of `many_processes_share_one_cache`: in `raw/`, 125 writes of
    /// overlapping keys, each followed by a read of another key; in `claimed/`, the same keys
    /// through the claims (fetch, render on a miss, store). Prints what it saw.
    fn child(dir: &Path, me: u32) {
        let (mut corrupt, mut wrong, mut renders, mut hits) = (0, 0, 0, 0);
        let key = |i: u32| (me * 7 + i * 3) % KEYS;
        let entry = |sub: &str, k: u32| dir.join(sub).join(format!("{k:04}.cbrf"));
        for i in 0..WRITES {
            put(&entry("raw", key(i)), &frame_of(key(i)));
            let k = key(i + 11);
            if let Ok(b) = std::fs::read(entry("raw", k)) {
                match decode(&b) {
                    Ok(f) if same(&f, &frame_of(k)) => {}
                    Ok(_) => wrong += 1,
                    Err(_) => corrupt += 1,
                }
            }
        }
        for i in 0..WRITES {
            let k = key(i);
            match fetch(&entry("claimed", k), Duration::from_secs(60)) {
                Some(f) if same(&f, &frame_of(k)) => hits += 1,
                Some(_) => wrong += 1,
                None => {
                    // "Rendering" takes a while, so that others find the claim.
                    std::thread::sleep(Duration::from_millis(5));
                    put(&entry("claimed", k), &frame_of(k));
                    renders += 1;
                }
            }
        }
        println!("RESULT {corrupt} {wrong} {renders} {hits}");
    }

    /// Issue 56: 8 processes writing and reading overlapping keys of one folder at once: no
    /// read finds a partial or corrupt entry, every entry left is the lone run's frame, no
    /// temporary file or claim is left, and with the claims every key is rendered exactly once.
    #[test]
    fn many_processes_share_one_cache() {
        if let Some(dir) = std::env::var_os(CHILD) {
            let me = std::env::var("CBR_CACHE_TEST_INDEX")
                .unwrap()
                .parse()
                .unwrap();
            child(Path::new(&dir), me);
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("raw")).unwrap();
        std::fs::create_dir_all(dir.path().join("claimed")).unwrap();
        let exe = std::env::current_exe().unwrap();
        let children: Vec<_> = (0..8)
            .map(|i| {
                std::process::Command::new(&exe)
                    .args(["--exact", "cache::tests::many_processes_share_one_cache"])
                    .args(["--nocapture", "--test-threads", "1"])
                    .env(CHILD, dir.path())
                    .env("CBR_CACHE_TEST_INDEX", i.to_string())
                    .stdout(std::process::Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        let mut total = [0u32; 4];
        for c in children {
            let out = c.wait_with_output().unwrap();
            assert!(out.status.success());
            let text = String::from_utf8_lossy(&out.stdout);
            // libtest prints the test's name on the same line.
            let line = text.split("RESULT ").nth(1).and_then(|t| t.lines().next());
            let line = line.expect("the child's counts");
            for (t, v) in total.iter_mut().zip(line.split_whitespace()) {
                *t += v.parse::<u32>().unwrap();
            }
        }
        let [corrupt, wrong, renders, hits] = total;
        eprintln!(
            "8 processes, {} raw writes: {corrupt} corrupt and {wrong} wrong reads; claimed: {renders} renders, {hits} hits",
            8 * WRITES
        );
        assert_eq!((corrupt, wrong), (0, 0));
        // Every key of the claimed folder was rendered once, then read.
        assert_eq!(renders, KEYS);
        assert_eq!(hits, 8 * WRITES - KEYS);
        for sub in ["raw", "claimed"] {
            let mut n = 0;
            for e in std::fs::read_dir(dir.path().join(sub)).unwrap() {
                let p = e.unwrap().path();
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                let k: u32 = name
                    .strip_suffix(".cbrf")
                    .unwrap_or_else(|| panic!("{sub}/{name} left behind"))
                    .parse()
                    .unwrap();
                let f = decode(&std::fs::read(&p).unwrap()).expect("a whole entry");
                assert!(same(&f, &frame_of(k)), "{sub}/{name}");
                n += 1;
            }
            assert_eq!(n, KEYS, "{sub}");
        }
    }

    /// A claim left by a process that is gone (this host, no such pid) is not waited for; one
    /// from another host is waited for up to the bound; storing the entry ends a live wait.
    #[test]
    fn stale_claims_end_at_once_and_live_ones_at_the_bound() {
        let dir = tempfile::tempdir().unwrap();
        let entry = dir.path().join("k.cbrf");
        let claim = claim_path(&entry);
        let host = cbr_metrics::io::hostname();
        std::fs::write(&claim, format!("{host} 4000000 0\n")).unwrap();
        let t = Instant::now();
        assert!(fetch(&entry, Duration::from_secs(30)).is_none());
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "no wait for a dead process"
        );
        std::fs::write(&claim, "elsewhere 1 0\n").unwrap();
        let t = Instant::now();
        assert!(fetch(&entry, Duration::from_millis(600)).is_none());
        assert!(
            t.elapsed() >= Duration::from_millis(600),
            "waited for the bound"
        );
        // Another process stores the entry while this one waits.
        let (e, f) = (entry.clone(), frame_of(3));
        let writer = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            put(&e, &f);
        });
        let got = fetch(&entry, Duration::from_secs(30)).expect("the stored frame");
        writer.join().unwrap();
        assert!(same(&got, &frame_of(3)));
        assert!(!claim.exists(), "storing removed the claim");
    }

    #[test]
    fn frames_round_trip_and_corruption_is_detected() {
        let mut o = FrameOutput::new(
            2,
            1,
            [0.5, 1.0, 2.0, 1.0, 3.0, 0.25, 0.0, 1.0]
                .map(f16::from_f32)
                .to_vec(),
            vec![1.5, f32::INFINITY],
            vec![[0.1, -0.2], [0.0, 3.0]],
            vec![[1, 7], [0, 0]],
        );
        let coverage = crate::techniques::Coverage {
            edge: vec![1, 0],
            fraction: vec![0.75, 0.0],
        };
        o.layers.push(coverage.layer(2, 1).expect("coverage"));
        // A layer of each sample type, one of another size, and a statistic of each kind.
        let decl = |name, samples, exr| crate::frame::LayerDecl {
            name,
            channels: &["a", "b"],
            samples,
            exr,
            about: "",
        };
        use crate::frame::SampleType;
        let u8s = decl("u8s", SampleType::U8, None);
        o.layers
            .push(u8s.layer(2, 1, vec![vec![3u8, 4], vec![5, 6]]).expect("u8"));
        let u32s = decl("u32s", SampleType::U32, Some(ExrType::Uint));
        o.layers.push(
            u32s.layer(1, 2, vec![vec![7u32, u32::MAX], vec![0, 9]])
                .expect("u32"),
        );
        let f16s = decl("f16s", SampleType::F16, Some(ExrType::Half));
        let h = f16::from_f32;
        o.layers.push(
            f16s.layer(1, 1, vec![vec![h(0.5)], vec![h(-2.0)]])
                .expect("f16"),
        );
        o.set_stat("n", Stat::Count(u64::MAX));
        o.set_stat("x.real", Stat::Real(0.1));
        o.set_stat("flag", Stat::Flag(true));
        o.set_stat("tile", Stat::Counts(vec![4, 2]));
        let b = encode(&o);
        let d = decode(&b).expect("decodes");
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.color, o.color);
        assert_eq!(d.depth, o.depth);
        assert_eq!(d.velocity, o.velocity);
        assert_eq!(d.ids, o.ids);
        assert_eq!(d.layers, o.layers);
        assert_eq!(d.stats, o.stats);
        assert_eq!(
            crate::techniques::Coverage::from_frame(&d),
            Some(coverage),
            "typed access after the round trip"
        );
        for i in [0, 9, 20, b.len() - 1] {
            let mut bad = b.clone();
            bad[i] ^= 0x10;
            assert!(decode(&bad).is_err(), "flipped byte {i}");
        }
        assert!(decode(&b[..b.len() - 5]).is_err());
    }
}
