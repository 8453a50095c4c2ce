//! The GPU memory a spec needs at a resolution, estimated before anything is allocated from what
//! the constructors allocate (each technique, post pass and the scene write theirs beside their
//! constructor), and the refusal of what the device cannot hold: the total over its largest
//! device-local heap, one allocation over maxMemoryAllocationSize, a storage buffer over
//! maxStorageBufferRange, an image side over maxImageDimension2D.

use cbr_gpu::{Caps, vk};

/// What one estimated allocation is, for the limit that applies to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An image of this size (level 0).
    Image { width: u32, height: u32 },
    /// A buffer bound as a storage buffer (its whole size in one descriptor).
    StorageBuffer,
    /// Any other buffer (index, uniform, staging, readback).
    Buffer,
}

/// One allocation a constructor makes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// The name it is allocated under (resource names, debug utils).
    pub name: String,
    pub bytes: u64,
    pub kind: Kind,
    /// Host-visible memory (readbacks, per-frame uploads, staging): device-local only on devices
    /// with unified memory.
    pub host: bool,
}

/// The allocations of a technique, a post pass, the scene or a whole renderer.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub items: Vec<Item>,
}

/// Bytes of one texel (sample) of `format`; formats cbr does not read back count as the widest
/// it uses (16 bytes), so that an unknown format is never under-counted.
pub fn texel_bytes(format: vk::Format) -> u64 {
    cbr_gpu::resource::texel_size(format).map_or(16, |t| t as u64)
}

impl MemoryEstimate {
    pub fn new() -> MemoryEstimate {
        MemoryEstimate::default()
    }

    fn push(&mut self, name: impl Into<String>, bytes: u64, kind: Kind, host: bool) {
        self.items.push(Item {
            name: name.into(),
            // cbr_gpu::Buffer allocates at least 4 bytes.
            bytes: match kind {
                Kind::Image { .. } => bytes,
                _ => bytes.max(4),
            },
            kind,
            host,
        });
    }

    /// A single-level, single-layer, single-sample image (`ImageDesc::new_2d`).
    pub fn image(&mut self, name: impl Into<String>, format: vk::Format, width: u32, height: u32) {
        self.image_array(name, format, width, height, 1, 1);
    }

    /// An image with `layers` array layers of `samples` samples.
    pub fn image_array(
        &mut self,
        name: impl Into<String>,
        format: vk::Format,
        width: u32,
        height: u32,
        layers: u32,
        samples: u32,
    ) {
        let bytes = u64::from(width)
            * u64::from(height)
            * u64::from(layers)
            * u64::from(samples)
            * texel_bytes(format);
        self.push(name, bytes, Kind::Image { width, height }, false);
    }

    /// An image whose levels (a mip chain) take `bytes` in all.
    pub fn image_bytes(&mut self, name: impl Into<String>, bytes: u64, width: u32, height: u32) {
        self.push(name, bytes, Kind::Image { width, height }, false);
    }

    /// A storage buffer in device-local (`host` false) or host-visible memory.
    pub fn storage_buffer(&mut self, name: impl Into<String>, bytes: u64, host: bool) {
        self.push(name, bytes, Kind::StorageBuffer, host);
    }

    /// Any other buffer.
    pub fn buffer(&mut self, name: impl Into<String>, bytes: u64, host: bool) {
        self.push(name, bytes, Kind::Buffer, host);
    }

    /// `Readback::for_image` of a `width` x `height` image of `format` with `layers` layers.
    pub fn readback(
        &mut self,
        name: impl Into<String>,
        format: vk::Format,
        width: u32,
        height: u32,
        layers: u32,
    ) {
        let bytes = u64::from(width) * u64::from(height) * u64::from(layers) * texel_bytes(format);
        self.push(name, bytes, Kind::Buffer, true);
    }

    pub fn append(&mut self, other: MemoryEstimate) {
        self.items.extend(other.items);
    }

    /// Bytes in device-local memory.
    pub fn device_bytes(&self) -> u64 {
        self.items.iter().filter(|i| !i.host).map(|i| i.bytes).sum()
    }

    /// Bytes in host-visible memory (readbacks, uploads, staging).
    pub fn host_bytes(&self) -> u64 {
        self.items.iter().filter(|i| i.host).map(|i| i.bytes).sum()
    }

    pub fn total(&self) -> u64 {
        self.device_bytes() + self.host_bytes()
    }

    /// The largest single allocation (the first of equals).
    pub fn largest(&self) -> Option<&Item> {
        self.items
            .iter()
            .reduce(|a, b| if b.bytes > a.bytes { b } else { a })
    }
}

/// `bytes` in binary units with one decimal: `512 bytes`, `3.0 KiB`, `16.0 GiB`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut v = bytes as f64 / 1024.0;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    format!("{v:.1} {}", UNITS[unit])
}

/// The refusal of `estimate` (the spec `spec` at `width` x `height`) on a device with `caps`
/// named `device`, or `Ok` when it fits: the total over the largest device-local heap (host-visible
/// memory counted too where the device's memory is unified), the largest allocation over
/// maxMemoryAllocationSize, a storage buffer over maxStorageBufferRange, an image side over
/// maxImageDimension2D. One message: what is needed, the largest allocation, every limit crossed.
pub fn check(
    spec: &str,
    width: u32,
    height: u32,
    estimate: &MemoryEstimate,
    caps: &Caps,
    device: &str,
) -> Result<(), String> {
    let mut over = Vec::new();
    let (device_bytes, host_bytes) = (estimate.device_bytes(), estimate.host_bytes());
    let in_heap = if caps.unified_memory {
        device_bytes + host_bytes
    } else {
        device_bytes
    };
    if in_heap > caps.device_local_heap_bytes {
        over.push(format!(
            "its largest device-local heap is {}{}",
            human_bytes(caps.device_local_heap_bytes),
            if caps.unified_memory {
                " (unified: readbacks come out of it too)"
            } else {
                ""
            }
        ));
    }
    let largest = estimate.largest();
    if let Some(l) = largest.filter(|l| l.bytes > caps.max_memory_allocation_size) {
        let more = estimate
            .items
            .iter()
            .filter(|i| i.bytes > caps.max_memory_allocation_size)
            .count();
        over.push(format!(
            "one allocation may be at most {} (maxMemoryAllocationSize) and `{}`{} is larger",
            human_bytes(caps.max_memory_allocation_size),
            l.name,
            match more {
                1 => String::new(),
                n => format!(" (with {} more)", n - 1),
            }
        ));
    }
    let range = u64::from(caps.max_storage_buffer_range);
    if let Some(b) = estimate
        .items
        .iter()
        .filter(|i| i.kind == Kind::StorageBuffer && i.bytes > range)
        .max_by_key(|i| i.bytes)
    {
        over.push(format!(
            "a storage buffer binds at most {} (maxStorageBufferRange) and `{}` takes {}",
            human_bytes(range),
            b.name,
            human_bytes(b.bytes)
        ));
    }
    let max_side = caps.max_image_dimension_2d;
    if let Some((i, width, height)) = estimate.items.iter().find_map(|i| match i.kind {
        Kind::Image { width, height } if width > max_side || height > max_side => {
            Some((i, width, height))
        }
        _ => None,
    }) {
        over.push(format!(
            "an image side may be at most {max_side} (maxImageDimension2D) and `{}` is \
             {width}x{height}",
            i.name
        ));
    }
    if over.is_empty() {
        return Ok(());
    }
    let split = match host_bytes {
        0 => String::new(),
        h => format!(
            " ({} device-local, {} host-visible)",
            human_bytes(device_bytes),
            human_bytes(h)
        ),
    };
    let largest = largest
        .map(|l| format!(", the largest one `{}` {}", l.name, human_bytes(l.bytes)))
        .unwrap_or_default();
    Err(format!(
        "`{spec}` at {width}x{height} needs about {} of GPU memory{split}{largest}, more than \
         `{device}` can hold: {}. Nothing was allocated: lower the resolution or the samples",
        human_bytes(device_bytes + host_bytes),
        over.join("; ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps() -> Caps {
        Caps {
            device_local_heap_bytes: 2 << 30,
            unified_memory: true,
            max_memory_allocation_size: 2 << 30,
            max_storage_buffer_range: 128 << 20,
            max_image_dimension_2d: 16384,
            ..Caps::default()
        }
    }

    #[test]
    fn human_units() {
        assert_eq!(human_bytes(0), "0 bytes");
        assert_eq!(human_bytes(1023), "1023 bytes");
        assert_eq!(human_bytes(3 * 1024), "3.0 KiB");
        assert_eq!(human_bytes(128 << 20), "128.0 MiB");
        assert_eq!(human_bytes(16 << 30), "16.0 GiB");
        assert_eq!(human_bytes((3 << 30) / 2), "1.5 GiB");
    }

    #[test]
    fn sums_and_the_largest() {
        let mut e = MemoryEstimate::new();
        e.image("a", vk::Format::R16G16B16A16_SFLOAT, 10, 10);
        e.image_array("b", vk::Format::D32_SFLOAT, 10, 10, 2, 4);
        e.readback("rb", vk::Format::R32G32_UINT, 10, 10, 1);
        e.buffer("tiny", 1, true);
        e.image_array("b2", vk::Format::D32_SFLOAT, 10, 10, 2, 4);
        assert_eq!(e.device_bytes(), 800 + 3200 + 3200);
        assert_eq!(e.host_bytes(), 800 + 4);
        assert_eq!(e.total(), 8004);
        assert_eq!(e.largest().map(|l| l.name.as_str()), Some("b"));
    }

    #[test]
    fn what_fits_passes_and_each_limit_is_named() {
        let fits = {
            let mut e = MemoryEstimate::new();
            e.image("ok", vk::Format::R16G16B16A16_SFLOAT, 1920, 1080);
            e
        };
        assert_eq!(check("native", 1920, 1080, &fits, &caps(), "dev"), Ok(()));

        // ssaa at 16384 x 16384: 4 GiB of fp32 accumulation alone.
        let mut e = MemoryEstimate::new();
        e.image("ssaa.accum", vk::Format::R32G32B32A32_SFLOAT, 16384, 16384);
        e.readback(
            "readback.ssaa.out",
            vk::Format::R16G16B16A16_SFLOAT,
            16384,
            16384,
            1,
        );
        let err = check("ssaa:16", 16384, 16384, &e, &caps(), "llvmpipe").unwrap_err();
        for want in [
            "`ssaa:16` at 16384x16384 needs about 6.0 GiB of GPU memory (4.0 GiB device-local, \
             2.0 GiB host-visible), the largest one `ssaa.accum` 4.0 GiB, more than `llvmpipe` \
             can hold: its largest device-local heap is 2.0 GiB (unified",
            "at most 2.0 GiB (maxMemoryAllocationSize) and `ssaa.accum` is larger",
            "Nothing was allocated",
        ] {
            assert!(err.contains(want), "no `{want}` in: {err}");
        }
        assert!(!err.contains("maxStorageBufferRange"), "{err}");

        // The same total in a discrete GPU's VRAM: readbacks live in the host's heap.
        let discrete = Caps {
            device_local_heap_bytes: 5 << 30,
            unified_memory: false,
            max_memory_allocation_size: 8 << 30,
            ..caps()
        };
        assert_eq!(check("ssaa:16", 16384, 16384, &e, &discrete, "gpu"), Ok(()));
        let unified = Caps {
            unified_memory: true,
            ..discrete.clone()
        };
        let err = check("ssaa:16", 16384, 16384, &e, &unified, "igpu").unwrap_err();
        assert!(err.contains("heap is 5.0 GiB"), "{err}");

        // A storage buffer over the range, an image over the side limit.
        let mut e = MemoryEstimate::new();
        e.storage_buffer("unpack.out", 200 << 20, true);
        e.image("wide", vk::Format::R32_SFLOAT, 20000, 4);
        let err = check("checkerboard", 20000, 4, &e, &caps(), "dev").unwrap_err();
        assert!(
            err.contains(
                "at most 128.0 MiB (maxStorageBufferRange) and `unpack.out` takes 200.0 MiB"
            ),
            "{err}"
        );
        assert!(
            err.contains("at most 16384 (maxImageDimension2D) and `wide` is 20000x4"),
            "{err}"
        );
        assert!(!err.contains("heap"), "{err}");
    }
}
