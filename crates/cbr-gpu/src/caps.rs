//! Feature negotiation as data: what the chosen device can do, and which checkerboard layouts
//! (DESIGN.md) it can therefore run.

use ash::vk;
use serde::Serialize;

/// Capabilities that matter to cbr, read once from the device. `Default` is a device that can do
/// nothing (tests start from it and set what they need).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Caps {
    pub sample_rate_shading: bool,
    /// Sample counts usable for a colour + depth + integer-ID target together.
    pub sample_counts: Vec<u32>,
    pub integer_color_sample_counts: Vec<u32>,
    pub sample_locations: bool,
    /// VK_EXT_sample_locations usable for the msaa2x alternative: 2-sample locations settable,
    /// at least 2 sub-pixel bits (0.25 steps), covering [0, 1).
    pub sample_locations_2x: bool,
    pub maintenance4: bool,
    pub dynamic_rendering: bool,
    pub pipeline_statistics: bool,
    /// Whether a COMPUTE_SHADER_INVOCATIONS statistics query is safe: lavapipe 22.3 crashes on it.
    pub compute_invocation_query: bool,
    pub timestamps: bool,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    pub geometry_shader: bool,
    pub shader_output_layer: bool,
    pub clip_distance: bool,
    pub multiview: bool,
    pub max_image_dimension_2d: u32,
    pub max_viewport: [u32; 2],
    pub max_framebuffer: [u32; 2],
    pub viewport_sub_pixel_bits: u32,
    pub sub_pixel_precision_bits: u32,
    /// Bits of the linear filter's weights a device guarantees (lavapipe reports 8 and filters
    /// float formats exactly; tests/filtering.rs measures it).
    pub sub_texel_precision_bits: u32,
    /// float16 arithmetic in shaders (the resolve's `--resolve-fp16`).
    pub shader_float16: bool,
    /// Largest storage buffer range one descriptor can bind (lavapipe: 128 MiB).
    pub max_storage_buffer_range: u32,
    /// Size of the largest memory heap with VK_MEMORY_HEAP_DEVICE_LOCAL_BIT (lavapipe: 2 GiB).
    pub device_local_heap_bytes: u64,
    /// Every memory heap is device-local (lavapipe, most integrated GPUs): host-visible memory,
    /// the readbacks, comes out of the same heap as the images.
    pub unified_memory: bool,
    /// The largest single memory allocation, maxMemoryAllocationSize
    /// (VkPhysicalDeviceMaintenance3Properties, core in Vulkan 1.1; lavapipe: 2 GiB).
    pub max_memory_allocation_size: u64,
    pub fragment_stores_and_atomics: bool,
    /// 64-bit integer atomics on storage buffers (shaderInt64 + shaderBufferInt64Atomics).
    pub int64_atomics: bool,
}

/// The checkerboard raster layouts of DESIGN.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    Msaa2x,
    Rotated,
    Split,
    Masked,
}

impl Layout {
    pub const ALL: [Layout; 4] = [
        Layout::Msaa2x,
        Layout::Rotated,
        Layout::Split,
        Layout::Masked,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Layout::Msaa2x => "msaa2x",
            Layout::Rotated => "rotated",
            Layout::Split => "split",
            Layout::Masked => "masked",
        }
    }
}

pub(crate) fn sample_count_list(flags: vk::SampleCountFlags) -> Vec<u32> {
    (0..7)
        .map(|b| 1u32 << b)
        .filter(|&n| flags.contains(vk::SampleCountFlags::from_raw(n)))
        .collect()
}

/// The largest device-local heap's size, and whether every heap is device-local (unified memory).
/// A device that marks no heap device-local (none should) gets its largest heap.
pub(crate) fn heap_limits(heaps: &[vk::MemoryHeap]) -> (u64, bool) {
    let local = |h: &&vk::MemoryHeap| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL);
    let largest = heaps
        .iter()
        .filter(local)
        .map(|h| h.size)
        .max()
        .or_else(|| heaps.iter().map(|h| h.size).max())
        .unwrap_or(0);
    (
        largest,
        !heaps.is_empty() && heaps.iter().all(|h| local(&h)),
    )
}

impl Caps {
    /// Why the msaa2x layout cannot toggle sample locations instead of shifting the viewport.
    pub fn sample_locations_unsupported(&self) -> Option<String> {
        if let Some(m) = self.layout_unsupported(Layout::Msaa2x) {
            return Some(m);
        }
        if !self.sample_locations {
            return Some("VK_EXT_sample_locations".into());
        }
        if !self.sample_locations_2x {
            return Some(
                "VK_EXT_sample_locations for 2 samples with 2 sub-pixel bits over [0, 1)".into(),
            );
        }
        None
    }

    /// Why `layout` cannot run on this device, or `None` when it can.
    pub fn layout_unsupported(&self, layout: Layout) -> Option<String> {
        let mut missing = Vec::new();
        match layout {
            Layout::Msaa2x => {
                if !self.sample_counts.contains(&2) {
                    missing.push("2x MSAA for colour and depth attachments");
                }
                if !self.integer_color_sample_counts.contains(&2) {
                    missing.push("2x MSAA for integer (ID) attachments");
                }
                if !self.sample_rate_shading {
                    missing.push("sampleRateShading");
                }
                if !self.clip_distance {
                    missing.push("shaderClipDistance");
                }
            }
            Layout::Rotated => {
                if !self.clip_distance {
                    missing.push("shaderClipDistance");
                }
            }
            Layout::Split => {
                if !self.shader_output_layer {
                    missing.push("shaderOutputLayer (gl_Layer from the vertex shader)");
                }
                if !self.clip_distance {
                    missing.push("shaderClipDistance");
                }
            }
            Layout::Masked => {}
        }
        (!missing.is_empty()).then(|| missing.join(", "))
    }

    pub fn supported_layouts(&self) -> Vec<Layout> {
        Layout::ALL
            .into_iter()
            .filter(|&l| self.layout_unsupported(l).is_none())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lavapipe_like() -> Caps {
        Caps {
            shader_float16: true,
            max_storage_buffer_range: 1 << 27,
            device_local_heap_bytes: 1 << 31,
            unified_memory: true,
            max_memory_allocation_size: 1 << 31,
            fragment_stores_and_atomics: true,
            int64_atomics: true,
            sample_rate_shading: true,
            sample_counts: vec![1, 4],
            integer_color_sample_counts: vec![1],
            sample_locations: false,
            sample_locations_2x: false,
            maintenance4: true,
            dynamic_rendering: true,
            pipeline_statistics: true,
            compute_invocation_query: false,
            timestamps: true,
            timestamp_period_ns: 1.0,
            timestamp_valid_bits: 64,
            geometry_shader: true,
            shader_output_layer: true,
            clip_distance: true,
            multiview: true,
            max_image_dimension_2d: 16384,
            max_viewport: [16384, 16384],
            max_framebuffer: [16384, 16384],
            viewport_sub_pixel_bits: 0,
            sub_pixel_precision_bits: 8,
            sub_texel_precision_bits: 8,
        }
    }

    #[test]
    fn lavapipe_runs_the_portable_layouts_only() {
        let caps = lavapipe_like();
        assert_eq!(
            caps.supported_layouts(),
            vec![Layout::Rotated, Layout::Split, Layout::Masked]
        );
        let why = caps.layout_unsupported(Layout::Msaa2x).unwrap_or_default();
        assert!(why.contains("2x MSAA"), "{why}");
    }

    #[test]
    fn a_gpu_with_2x_runs_all() {
        let mut caps = lavapipe_like();
        caps.sample_counts = vec![1, 2, 4, 8];
        caps.integer_color_sample_counts = vec![1, 2, 4, 8];
        assert_eq!(caps.supported_layouts(), Layout::ALL.to_vec());
    }

    #[test]
    fn heaps_give_the_largest_device_local_one_and_whether_memory_is_unified() {
        let heap = |size: u64, local: bool| vk::MemoryHeap {
            size,
            flags: if local {
                vk::MemoryHeapFlags::DEVICE_LOCAL
            } else {
                vk::MemoryHeapFlags::empty()
            },
        };
        // lavapipe: one heap, device-local.
        assert_eq!(heap_limits(&[heap(1 << 31, true)]), (1 << 31, true));
        // A discrete GPU: VRAM, the host's memory, and a small device-local BAR window.
        let discrete = [
            heap(80 << 30, true),
            heap(128 << 30, false),
            heap(1 << 28, true),
        ];
        assert_eq!(heap_limits(&discrete), (80 << 30, false));
        assert_eq!(heap_limits(&[heap(4 << 30, false)]), (4 << 30, false));
        assert_eq!(heap_limits(&[]), (0, false));
    }

    #[test]
    fn sample_count_flags_decode() {
        let f = vk::SampleCountFlags::TYPE_1 | vk::SampleCountFlags::TYPE_4;
        assert_eq!(sample_count_list(f), vec![1, 4]);
    }
}
