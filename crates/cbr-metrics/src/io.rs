//! Writing (and reading back) cbr's outputs. Every write is atomic: a temporary file beside the
//! target, then a rename, so an interrupted or failed run never leaves a partial file.

use std::path::{Path, PathBuf};
use std::sync::{PoisonError, RwLock};

use exr::prelude::*;
use half::f16;
use std::result::Result;

#[derive(Debug, thiserror::Error)]
pub enum IoError {
    #[error("{}: {msg}", path.display())]
    Write { path: PathBuf, msg: String },
}

/// Held (shared) by every atomic write from its first byte to its rename; [`stop_writes`] takes
/// it exclusively.
static WRITES: RwLock<()> = RwLock::new(());

/// Waits for the atomic writes in progress to finish (renamed into place, or removed) and holds
/// every later one back for the rest of the process: for an interrupt handler that exits next,
/// leaving only complete files and no temporary ones.
pub fn stop_writes() {
    let guard = WRITES.write().unwrap_or_else(PoisonError::into_inner);
    std::mem::forget(guard);
}

/// This machine's host name (`/proc/sys/kernel/hostname`, else `$HOSTNAME`, else `host`): what
/// tells writers on different machines sharing one folder apart.
pub fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "host".into())
}

/// A name no other write in flight has, on any machine writing to the same folder: host, process,
/// and a number that only grows within the process (threads included).
pub fn unique_suffix() -> String {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let host: String = hostname()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{host}-{}-{n}", std::process::id())
}

/// Runs `write` on a temporary path beside `path` (a name unique to this write: [`unique_suffix`]), then renames it into place. After
/// [`stop_writes`] it waits forever (the process is exiting).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), IoError> {
    let _writing = WRITES.read().unwrap_or_else(PoisonError::into_inner);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", unique_suffix()));
    let err = |msg: String| IoError::Write {
        path: path.to_path_buf(),
        msg,
    };
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(err(e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        err(format!("cannot move the finished file into place: {e}"))
    })
}

pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
}

pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// The layers of one rendered frame, as written to EXR.
pub struct FrameLayers<'a> {
    pub width: u32,
    pub height: u32,
    pub color: &'a [f16],
    pub depth: &'a [f32],
    pub velocity: &'a [[f32; 2]],
    pub ids: &'a [[u32; 2]],
    /// Further layers after those five, in order: (layer name, [(channel name, samples)]) (a
    /// technique's own: checkerboard's `mask`, the resolve's debug views, ...).
    pub extra: Vec<ExtraLayer>,
    /// Text attributes attached to every part (scene, technique, frame, ...).
    pub metadata: Vec<(String, String)>,
}

/// One extra layer of a frame EXR: its name and (channel, samples) pairs.
pub type ExtraLayer = (String, Vec<(String, ChannelSamples)>);

/// One channel's samples in one of OpenEXR's three sample types.
#[derive(Clone, Debug, PartialEq)]
pub enum ChannelSamples {
    F16(Vec<f16>),
    F32(Vec<f32>),
    U32(Vec<u32>),
}

impl ChannelSamples {
    pub fn len(&self) -> usize {
        match self {
            ChannelSamples::F16(v) => v.len(),
            ChannelSamples::F32(v) => v.len(),
            ChannelSamples::U32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Part (layer) names of a frame EXR.
pub const COLOR_LAYER: &str = "color";
pub const DEPTH_LAYER: &str = "depth";
pub const VELOCITY_LAYER: &str = "velocity";
pub const OBJECT_ID_LAYER: &str = "object_id";
pub const PRIMITIVE_ID_LAYER: &str = "primitive_id";

/// Scanline ZIP: read by every EXR reader (OpenImageIO, exrheader), unlike the crate's tiled preset.
fn encoding() -> Encoding {
    Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    }
}

/// Writes a multi-part EXR: `color` (R,G,B,A half), `depth` (Z float: view distance, +inf where
/// empty), `velocity` (X,Y float: pixels, current - previous), `object_id` and `primitive_id`
/// (`id` uint).
pub fn write_frame_exr(path: &Path, f: &FrameLayers) -> Result<(), IoError> {
    let size = Vec2(f.width as usize, f.height as usize);
    let n = size.area();
    let check = |what: &str, len: usize| {
        (len == n).then_some(()).ok_or_else(|| IoError::Write {
            path: path.to_path_buf(),
            msg: format!("{what}: {len} values for {n} pixels"),
        })
    };
    check("color", f.color.len() / 4)?;
    check("depth", f.depth.len())?;
    check("velocity", f.velocity.len())?;
    check("ids", f.ids.len())?;
    let attrs = |name: &str| {
        let mut a = LayerAttributes::named(name);
        for (k, v) in &f.metadata {
            a.other.insert(
                Text::from(k.as_str()),
                AttributeValue::Text(Text::from(v.as_str())),
            );
        }
        a
    };
    let channel = |name: &str, s: FlatSamples| AnyChannel::new(name, s);
    let rgba = |c: usize| FlatSamples::F16(f.color.iter().skip(c).step_by(4).copied().collect());
    let mut layers: smallvec::SmallVec<[Layer<AnyChannels<FlatSamples>>; 2]> = smallvec::smallvec![
        Layer::new(
            size,
            attrs(COLOR_LAYER),
            encoding(),
            AnyChannels::sort(smallvec::smallvec![
                channel("R", rgba(0)),
                channel("G", rgba(1)),
                channel("B", rgba(2)),
                channel("A", rgba(3)),
            ]),
        ),
        Layer::new(
            size,
            attrs(DEPTH_LAYER),
            encoding(),
            AnyChannels::sort(smallvec::smallvec![channel(
                "Z",
                FlatSamples::F32(f.depth.to_vec())
            )])
        ),
        Layer::new(
            size,
            attrs(VELOCITY_LAYER),
            encoding(),
            AnyChannels::sort(smallvec::smallvec![
                channel(
                    "X",
                    FlatSamples::F32(f.velocity.iter().map(|v| v[0]).collect())
                ),
                channel(
                    "Y",
                    FlatSamples::F32(f.velocity.iter().map(|v| v[1]).collect())
                ),
            ]),
        ),
        Layer::new(
            size,
            attrs(OBJECT_ID_LAYER),
            encoding(),
            AnyChannels::sort(smallvec::smallvec![channel(
                "id",
                FlatSamples::U32(f.ids.iter().map(|v| v[0]).collect())
            )]),
        ),
        Layer::new(
            size,
            attrs(PRIMITIVE_ID_LAYER),
            encoding(),
            AnyChannels::sort(smallvec::smallvec![channel(
                "id",
                FlatSamples::U32(f.ids.iter().map(|v| v[1]).collect())
            )]),
        ),
    ];
    for (name, channels) in &f.extra {
        let mut list = smallvec::SmallVec::new();
        for (ch, values) in channels {
            check(name, values.len())?;
            let samples = match values {
                ChannelSamples::F16(v) => FlatSamples::F16(v.clone()),
                ChannelSamples::F32(v) => FlatSamples::F32(v.clone()),
                ChannelSamples::U32(v) => FlatSamples::U32(v.clone()),
            };
            list.push(channel(ch, samples));
        }
        layers.push(Layer::new(
            size,
            attrs(name),
            encoding(),
            AnyChannels::sort(list),
        ));
    }
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(size)),
        layers,
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| IoError::Write {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
    let mut bytes = bytes.into_inner();
    sort_header_attributes(&mut bytes).map_err(|msg| IoError::Write {
        path: path.to_path_buf(),
        msg,
    })?;
    write_bytes(path, &bytes)
}

/// Sorts the attributes of every header of an OpenEXR file by name, in place, so that the same
/// image always gives the same bytes: the exr crate writes custom attributes (`cbr.frame`, ...)
/// in the order of a `HashMap` seeded afresh in every process. OpenEXR gives attribute order no
/// meaning, and sorting keeps each header's length, so the offset tables after the headers (the
/// byte positions of the pixel chunks) stay valid.
fn sort_header_attributes(bytes: &mut [u8]) -> Result<(), String> {
    const MULTIPART: u32 = 0x1000;
    let bad = || "the EXR writer's headers could not be read back".to_string();
    let flags = bytes
        .get(4..8)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .ok_or_else(bad)?;
    let nul_after = |bytes: &[u8], at: usize| -> Result<usize, String> {
        bytes
            .get(at..)
            .and_then(|rest| rest.iter().position(|&b| b == 0))
            .map(|i| at + i)
            .ok_or_else(bad)
    };
    let mut pos = 8;
    loop {
        let start = pos;
        // (name, byte range) of each attribute: name\0 type\0 size (i32 LE) value.
        let mut attrs: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
        while *bytes.get(pos).ok_or_else(bad)? != 0 {
            let name_end = nul_after(bytes, pos)?;
            let type_end = nul_after(bytes, name_end + 1)?;
            let size = bytes
                .get(type_end + 1..type_end + 5)
                .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or_else(bad)?;
            let end = type_end + 5 + usize::try_from(size).map_err(|_| bad())?;
            if end > bytes.len() {
                return Err(bad());
            }
            attrs.push((bytes[pos..name_end].to_vec(), pos..end));
            pos = end;
        }
        attrs.sort_by(|a, b| a.0.cmp(&b.0));
        let sorted: Vec<u8> = attrs
            .iter()
            .flat_map(|(_, r)| bytes[r.clone()].iter().copied())
            .collect();
        bytes[start..pos].copy_from_slice(&sorted);
        pos += 1; // the header's terminating null byte
        // A multi-part file ends its header list with an empty header (one null byte).
        if flags & MULTIPART == 0 || *bytes.get(pos).ok_or_else(bad)? == 0 {
            return Ok(());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_exr_round_trips_every_layer() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("f.exr");
        let (w, h) = (3u32, 2u32);
        let color: Vec<f16> = (0..w * h * 4)
            .map(|i| f16::from_f32(i as f32 * 0.25))
            .collect();
        let depth: Vec<f32> = (0..w * h)
            .map(|i| if i == 0 { f32::INFINITY } else { i as f32 })
            .collect();
        let velocity: Vec<[f32; 2]> = (0..w * h).map(|i| [i as f32, -(i as f32)]).collect();
        let ids: Vec<[u32; 2]> = (0..w * h).map(|i| [i, 1000 + i]).collect();
        let layers = FrameLayers {
            width: w,
            height: h,
            color: &color,
            depth: &depth,
            velocity: &velocity,
            ids: &ids,
            extra: Vec::new(),
            metadata: vec![("cbr.frame".into(), "7".into())],
        };
        write_frame_exr(&path, &layers).expect("write");
        let channel = |layer: &str, c: &str| {
            let img = crate::input::load(&path, Some(layer), Some(&[c.to_string()])).expect(c);
            (img.rgb.width, img.rgb.height, img.rgb.c[0].data.clone())
        };
        let (rw, rh, g) = channel(COLOR_LAYER, "G");
        assert_eq!((rw, rh), (3, 2));
        assert_eq!(g[1], 5.0 * 0.25);
        assert_eq!(channel(DEPTH_LAYER, "Z").2[0], f32::INFINITY);
        assert_eq!(channel(VELOCITY_LAYER, "Y").2[3], -3.0);
        assert_eq!(channel(PRIMITIVE_ID_LAYER, "id").2[5], 1005.0);
        let err = crate::input::load(&path, Some("nope"), None)
            .err()
            .expect("no such layer")
            .to_string();
        assert!(
            err.contains("no layer `nope`") && err.contains("color"),
            "{err}"
        );
        // Nothing but the finished file is left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("e").file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn frame_exrs_are_byte_identical_across_writes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (w, h) = (4u32, 3u32);
        let n = (w * h) as usize;
        let color: Vec<f16> = (0..n * 4).map(|i| f16::from_f32(i as f32)).collect();
        let depth = vec![1.0f32; n];
        let velocity = vec![[0.5f32, -0.5]; n];
        let ids = vec![[1u32, 2]; n];
        let mask = vec![f16::ONE; n];
        let metadata: Vec<(String, String)> = ["scene", "technique", "frame", "time", "device"]
            .iter()
            .map(|k| (format!("cbr.{k}"), format!("value of {k}")))
            .collect();
        let write = |i: usize| {
            let path = dir.path().join(format!("f{i}.exr"));
            let layers = FrameLayers {
                width: w,
                height: h,
                color: &color,
                depth: &depth,
                velocity: &velocity,
                ids: &ids,
                extra: vec![
                    (
                        "mask".into(),
                        vec![("Y".into(), ChannelSamples::F16(mask.clone()))],
                    ),
                    (
                        "extra".into(),
                        vec![("Y".into(), ChannelSamples::F32(vec![0.25; n]))],
                    ),
                    (
                        "ids".into(),
                        vec![("id".into(), ChannelSamples::U32(vec![7; n]))],
                    ),
                ],
                metadata: metadata.clone(),
            };
            write_frame_exr(&path, &layers).expect("write");
            std::fs::read(&path).expect("read")
        };
        // Every write builds new attribute maps (new hash seeds): 5! orders per part.
        let first = write(0);
        for i in 1..8 {
            assert!(write(i) == first, "write {i} differs from write 0");
        }
        // The sorted file still reads, attributes and pixels.
        let path = dir.path().join("f0.exr");
        let img = exr::prelude::read_all_flat_layers_from_file(&path).expect("read back");
        assert_eq!(img.layer_data.len(), 8);
        for layer in &img.layer_data {
            let frame = layer.attributes.other.get(&Text::from("cbr.frame"));
            assert_eq!(
                frame,
                Some(&AttributeValue::Text(Text::from("value of frame")))
            );
        }
        let g =
            crate::input::load(&path, Some(COLOR_LAYER), Some(&["G".to_string()])).expect("color");
        assert_eq!(g.rgb.c[0].data[2], 9.0);
    }

    #[test]
    fn stop_writes_waits_for_the_write_in_progress_and_holds_back_the_next() {
        use std::sync::mpsc::channel;
        use std::time::Duration;
        // Its own process: stop_writes blocks every later write of the process it runs in.
        if std::env::var_os("CBR_STOP_WRITES_CHILD").is_none() {
            let me = std::env::current_exe().expect("test binary");
            let o = std::process::Command::new(me)
                .args([
                    "--exact",
                    "io::tests::stop_writes_waits_for_the_write_in_progress_and_holds_back_the_next",
                    "--nocapture",
                ])
                .env("CBR_STOP_WRITES_CHILD", "1")
                .output()
                .expect("run the child");
            let text = String::from_utf8_lossy(&o.stdout).into_owned()
                + &String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{text}");
            assert!(text.contains("1 passed"), "{text}");
            return;
        }
        let dir = tempfile::tempdir().expect("tempdir");
        let (first, second) = (dir.path().join("a.bin"), dir.path().join("b.bin"));
        let (started_tx, started) = channel();
        let (finish, finish_rx) = channel::<()>();
        let path = first.clone();
        let writer = std::thread::spawn(move || {
            write_atomic(&path, |tmp| {
                std::fs::write(tmp, b"half").map_err(|e| e.to_string())?;
                started_tx.send(()).map_err(|e| e.to_string())?;
                finish_rx.recv().map_err(|e| e.to_string())?;
                std::fs::write(tmp, b"whole").map_err(|e| e.to_string())
            })
        });
        started.recv().expect("the write started");
        let (stopped_tx, stopped) = channel();
        std::thread::spawn(move || {
            stop_writes();
            let _ = stopped_tx.send(());
        });
        std::thread::sleep(Duration::from_millis(200));
        assert!(
            stopped.try_recv().is_err(),
            "stop_writes returned while a write was in progress"
        );
        finish.send(()).expect("finish");
        writer.join().expect("writer").expect("the write completes");
        stopped
            .recv_timeout(Duration::from_secs(10))
            .expect("stop_writes returns once the write is done");
        assert_eq!(std::fs::read(&first).expect("whole file"), b"whole");
        // A later write never starts.
        std::thread::spawn(move || write_bytes(&second, b"late"));
        std::thread::sleep(Duration::from_millis(200));
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.bin")]);
    }

    #[test]
    fn failed_writes_leave_nothing() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("x.png");
        let r = write_atomic(&path, |tmp| {
            std::fs::write(tmp, b"partial").map_err(|e| e.to_string())?;
            Err("simulated failure".into())
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
    }
}
