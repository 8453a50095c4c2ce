//! Feature negotiation as data: what the chosen device can do, and which checkerboard layouts
//! (DESIGN.md) it can therefore run.

use ash::vk;
use serde::Serialize;

/// Capabilities that matter to cbr, read once from the device. `Default` is a device that can do
/// nothing (tests start from it and set what they need).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Caps {
    /// Whether the device can allocate memory and execute commands. False on RADV's null device
    /// (`RADV_FORCE_FAMILY`, crate::null_device), which only compiles pipelines: images,
    /// buffers and submissions are refused there with `GpuError::CannotExecute`.
    pub can_execute: bool,
    /// VK_KHR_pipeline_executable_properties with pipelineExecutableInfo, enabled: pipelines can be
    /// compiled with their statistics (and disassembly) captured (`CompileSettings`).
    pub pipeline_executable_info: bool,
    /// The subgroup (wave) size compute runs with when none is required.
    pub subgroup_size: u32,
    /// Subgroup sizes a compute pipeline can require (subgroupSizeControl, compute in
    /// requiredSubgroupSizeStages: the powers of two from minSubgroupSize to maxSubgroupSize);
    /// empty where it cannot. RDNA: [32, 64]; GCN: none (wave64 only); lavapipe: [8].
    pub compute_subgroup_sizes: Vec<u32>,
    pub sample_rate_shading: bool,
    /// Sample counts usable for a colour + depth + integer-ID target together.
    pub sample_counts: Vec<u32>,
    /// Sample counts usable for the integer colour attachments cbr renders
    /// ([`INTEGER_ATTACHMENTS`]), asked per format and usage
    /// (vkGetPhysicalDeviceImageFormatProperties), within `sample_counts`. Not Vulkan 1.2's
    /// framebufferIntegerColorSampleCounts: RADV reports 1 there and 2/4/8 per format.
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
    /// Largest uniform buffer range one descriptor can bind (lavapipe and NVIDIA: 64 KiB; the
    /// scene's lights need 64 KiB: cbr-render's gpu_types, UNIFORM_LIGHTS).
    pub max_uniform_buffer_range: u32,
    /// Alignment of a storage buffer descriptor's offset (lavapipe: 16; at most 256).
    pub min_storage_buffer_offset_alignment: u64,
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

/// Every usage a frame target gets (crate cbr-render's `FrameTargets::decls`): colour attachment,
/// sampled, copied from and to.
pub const TARGET_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::COLOR_ATTACHMENT.as_raw()
        | vk::ImageUsageFlags::SAMPLED.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw()
        | vk::ImageUsageFlags::TRANSFER_DST.as_raw(),
);

/// The integer colour attachments cbr renders multisampled, with their usages: the ID target
/// (R32G32_UINT). `integer_color_sample_counts` is decided from these; a test in cbr-render holds
/// `FrameTargets::decls` to this list.
pub const INTEGER_ATTACHMENTS: &[(vk::Format, vk::ImageUsageFlags)] =
    &[(vk::Format::R32G32_UINT, TARGET_USAGE)];

/// The sample counts every integer attachment supports: the per-format answers (`None`: the
/// format cannot be created with that usage at all) intersected, within `limits` (the colour and
/// depth framebuffer counts). No answer at all gives no sample count.
pub fn integer_sample_counts(
    answers: &[Option<vk::SampleCountFlags>],
    limits: vk::SampleCountFlags,
) -> Vec<u32> {
    if answers.is_empty() {
        return Vec::new();
    }
    let common = answers.iter().fold(limits, |acc, a| match a {
        Some(flags) => acc & *flags,
        None => vk::SampleCountFlags::empty(),
    });
    sample_count_list(common)
}

/// The sizes a compute pipeline may require: powers of two from `min` to `max`, when subgroup
/// size control is enabled and compute is among the stages that accept a required size.
pub fn compute_subgroup_sizes(control: bool, compute_stage: bool, min: u32, max: u32) -> Vec<u32> {
    if !control || !compute_stage || min == 0 || min > max {
        return Vec::new();
    }
    (0..16)
        .map(|b| 1u32 << b)
        .filter(|s| (min..=max).contains(s))
        .collect()
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
            can_execute: true,
            pipeline_executable_info: false,
            subgroup_size: 8,
            compute_subgroup_sizes: vec![8],
            shader_float16: true,
            max_storage_buffer_range: 1 << 27,
            max_uniform_buffer_range: 1 << 16,
            min_storage_buffer_offset_alignment: 16,
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
    fn integer_attachments_are_decided_per_format() {
        use vk::SampleCountFlags as S;
        let all = S::TYPE_1 | S::TYPE_2 | S::TYPE_4 | S::TYPE_8;
        // RADV: framebufferIntegerColorSampleCounts says 1, the per-format query 1/2/4/8.
        let radv = integer_sample_counts(&[Some(all)], all);
        assert_eq!(radv, vec![1, 2, 4, 8]);
        let mut caps = lavapipe_like();
        caps.sample_counts = vec![1, 2, 4, 8];
        caps.integer_color_sample_counts = radv;
        assert_eq!(caps.layout_unsupported(Layout::Msaa2x), None);
        // lavapipe: 1 and 4 everywhere, so no 2x for anything.
        let lvp = integer_sample_counts(&[Some(S::TYPE_1 | S::TYPE_4)], S::TYPE_1 | S::TYPE_4);
        assert_eq!(lvp, vec![1, 4]);
        caps.integer_color_sample_counts = lvp;
        let why = caps.layout_unsupported(Layout::Msaa2x).unwrap_or_default();
        assert!(
            why.contains("2x MSAA for integer (ID) attachments"),
            "{why}"
        );
        // The framebuffer limits bound what a format allows; one format without 2x, or one
        // format/usage the device refuses, removes 2x; no format answers nothing.
        assert_eq!(
            integer_sample_counts(&[Some(all)], S::TYPE_1 | S::TYPE_4),
            vec![1, 4]
        );
        assert_eq!(
            integer_sample_counts(&[Some(all), Some(S::TYPE_1 | S::TYPE_4)], all),
            vec![1, 4]
        );
        assert_eq!(
            integer_sample_counts(&[Some(all), None], all),
            Vec::<u32>::new()
        );
        assert_eq!(integer_sample_counts(&[], all), Vec::<u32>::new());
    }

    #[test]
    fn compute_subgroup_sizes_span_the_range() {
        assert_eq!(compute_subgroup_sizes(true, true, 32, 64), vec![32, 64]);
        assert_eq!(compute_subgroup_sizes(true, true, 64, 64), vec![64]);
        assert_eq!(compute_subgroup_sizes(true, true, 8, 8), vec![8]);
        assert_eq!(
            compute_subgroup_sizes(true, true, 4, 128),
            vec![4, 8, 16, 32, 64, 128]
        );
        assert!(compute_subgroup_sizes(false, true, 32, 64).is_empty());
        assert!(compute_subgroup_sizes(true, false, 32, 64).is_empty());
        assert!(compute_subgroup_sizes(true, true, 0, 64).is_empty());
        assert!(compute_subgroup_sizes(true, true, 64, 32).is_empty());
    }

    #[test]
    fn sample_count_flags_decode() {
        let f = vk::SampleCountFlags::TYPE_1 | vk::SampleCountFlags::TYPE_4;
        assert_eq!(sample_count_list(f), vec![1, 4]);
    }
}
