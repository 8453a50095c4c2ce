//! The on-disk cache of expensive frames (techniques that say `cacheable`: `ssaa`). A frame is
//! keyed on everything that changes it: the technique spec, resolution, LOD bias and debug flags,
//! the scene's content (geometry, materials, texture texels, lights, camera path, animation,
//! ambient and background), the frame index and its time, the shader modules the technique and its post chain were built
//! from (path, defines and SPIR-V without debug instructions: comments, line shifts and code in
//! branches the defines exclude keep the key), the device and
//! its driver, and the cache format. An entry is one file `<blake3 key>.cbrf`: a header, the
//! layers, and a blake3 checksum of both; an entry that fails the checksum or does not parse is
//! reported and recomputed. Writes go to a temporary name and are renamed.

use std::path::{Path, PathBuf};

use cbr_gpu::{Gpu, GpuError, Result, Shaders};
use cbr_scene::Scene;
use half::f16;

use crate::frame::{Coverage, FrameOutput};
use crate::gpu_scene::FrameView;
use crate::renderer::RenderSettings;

const MAGIC: &[u8; 8] = b"CBRF0001";

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

    /// The cached frame, or `None` when absent or corrupt (then reported and recomputed).
    pub fn load(&self, key: &FrameKey, frame: u32, time: f64) -> Option<FrameOutput> {
        let path = self.path(key);
        let bytes = std::fs::read(&path).ok()?;
        match decode(&bytes) {
            Ok(mut out) => {
                out.index = frame;
                out.time = time;
                out.cached = Some(path);
                Some(out)
            }
            Err(why) => {
                tracing::warn!(
                    "cache entry {} is corrupt ({why}): recomputing",
                    path.display()
                );
                eprintln!(
                    "warning: cache entry {} is corrupt ({why}): recomputing",
                    path.display()
                );
                None
            }
        }
    }

    /// Stores a frame; returns its path (a failed write is reported, not fatal). The write is
    /// cbr's atomic one (temporary name, rename), which an interrupt lets finish.
    pub fn store(&self, key: &FrameKey, out: &FrameOutput) -> Option<PathBuf> {
        let path = self.path(key);
        match cbr_metrics::io::write_bytes(&path, &encode(out)) {
            Ok(()) => Some(path),
            Err(e) => {
                tracing::warn!("cannot write cache entry: {e}");
                None
            }
        }
    }
}

fn encode(o: &FrameOutput) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    b.extend_from_slice(&o.width.to_le_bytes());
    b.extend_from_slice(&o.height.to_le_bytes());
    b.extend_from_slice(bytemuck::cast_slice(&o.color));
    b.extend_from_slice(bytemuck::cast_slice(&o.depth));
    b.extend_from_slice(bytemuck::cast_slice(&o.velocity));
    b.extend_from_slice(bytemuck::cast_slice(&o.ids));
    match &o.coverage {
        Some(c) => {
            b.push(1);
            b.extend_from_slice(&c.edge);
            b.extend_from_slice(bytemuck::cast_slice(&c.fraction));
        }
        None => b.push(0),
    }
    let sum = blake3::hash(&b);
    b.extend_from_slice(sum.as_bytes());
    b
}

fn decode(b: &[u8]) -> std::result::Result<FrameOutput, String> {
    if b.len() < MAGIC.len() + 8 + 32 || &b[..MAGIC.len()] != MAGIC {
        return Err("not a cbr frame file of this version".into());
    }
    let (body, sum) = b.split_at(b.len() - 32);
    if blake3::hash(body).as_bytes() != sum {
        return Err("checksum mismatch".into());
    }
    let mut at = MAGIC.len();
    let mut take = |n: usize| -> std::result::Result<&[u8], String> {
        let s = body.get(at..at + n).ok_or("truncated")?;
        at += n;
        Ok(s)
    };
    let u32_at = |s: &[u8]| u32::from_le_bytes([s[0], s[1], s[2], s[3]]);
    let w = u32_at(take(4)?);
    let h = u32_at(take(4)?);
    let n = (w as usize) * (h as usize);
    // Copy into typed vectors (the file bytes carry no alignment).
    let color: Vec<f16> = take(8 * n)?
        .chunks_exact(2)
        .map(|c| f16::from_le_bytes([c[0], c[1]]))
        .collect();
    let f32s = |s: &[u8]| -> Vec<f32> {
        s.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let depth = f32s(take(4 * n)?);
    let vel = f32s(take(8 * n)?);
    let ids: Vec<u32> = take(8 * n)?.chunks_exact(4).map(u32_at).collect();
    let mut out = FrameOutput::new(
        w,
        h,
        color,
        depth,
        vel.chunks_exact(2).map(|v| [v[0], v[1]]).collect(),
        ids.chunks_exact(2).map(|v| [v[0], v[1]]).collect(),
    );
    if take(1)?[0] == 1 {
        let edge = take(n)?.to_vec();
        let fraction = f32s(take(4 * n)?);
        out.coverage = Some(Coverage { edge, fraction });
    }
    if at != body.len() {
        return Err("trailing bytes".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        o.coverage = Some(Coverage {
            edge: vec![1, 0],
            fraction: vec![0.75, 0.0],
        });
        let b = encode(&o);
        let d = decode(&b).expect("decodes");
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.color, o.color);
        assert_eq!(d.depth, o.depth);
        assert_eq!(d.velocity, o.velocity);
        assert_eq!(d.ids, o.ids);
        assert_eq!(d.coverage, o.coverage);
        for i in [0, 9, 20, b.len() - 1] {
            let mut bad = b.clone();
            bad[i] ^= 0x10;
            assert!(decode(&bad).is_err(), "flipped byte {i}");
        }
        assert!(decode(&b[..b.len() - 5]).is_err());
    }
}
