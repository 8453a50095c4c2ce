//! The Vulkan instance and device, validation-message capture, one-shot submission and the
//! deferred deletion of resources.

use std::ffi::{CStr, CString, c_void};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, Allocator, AllocatorCreateDesc};

use crate::caps::{
    Caps, INTEGER_ATTACHMENTS, compute_subgroup_sizes, heap_limits, integer_sample_counts,
    sample_count_list,
};
use crate::error::{GpuError, Result, VkContext};
use crate::executables::{CompileSettings, PipelineExecutables};
use crate::null_device;
use crate::select::{self, Candidate, DeviceKind};

/// How to open the device.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Device index or name substring (`--device`).
    pub device: Option<String>,
    /// Validation layer + synchronization validation, every message captured.
    pub validation: bool,
}

/// Facts about the opened device, recorded with every result.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: DeviceKind,
    pub api_version: String,
    pub driver_name: String,
    pub driver_info: String,
    pub vendor_id: u32,
    pub device_id: u32,
}

/// Messages from the validation layer. Counted and reported; tests fail on any.
#[derive(Default, Debug)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn count(&self) -> usize {
        self.messages.lock().map(|m| m.len()).unwrap_or(0)
    }
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
    fn push(&self, msg: String) {
        if let Ok(mut m) = self.messages.lock() {
            m.push(msg);
        }
    }
}

/// A Vulkan object whose destruction waits until the GPU can no longer use it.
pub(crate) enum Garbage {
    Buffer(vk::Buffer, Allocation),
    Image(vk::Image, Vec<vk::ImageView>, Allocation),
    Sampler(vk::Sampler),
    Pipeline(vk::Pipeline),
    PipelineLayout(vk::PipelineLayout),
    DescriptorSetLayout(vk::DescriptorSetLayout),
    DescriptorPool(vk::DescriptorPool),
    QueryPool(vk::QueryPool),
}

pub(crate) struct Inner {
    _entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    debug_instance: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) debug_device: Option<ash::ext::debug_utils::Device>,
    pub(crate) device: ash::Device,
    pub(crate) queue: Mutex<vk::Queue>,
    #[allow(dead_code)] // kept for queue-family ownership transfers
    pub(crate) queue_family: u32,
    pub(crate) allocator: Mutex<Option<Allocator>>,
    /// Memory allocations made so far (a count that only grows).
    pub(crate) allocations_made: AtomicU64,
    command_pool: Mutex<vk::CommandPool>,
    pub(crate) validation: Arc<ValidationLog>,
    garbage: Mutex<Vec<(u64, Garbage)>>,
    submitted: AtomicU64,
    completed: AtomicU64,
    pub(crate) info: DeviceInfo,
    pub(crate) caps: Caps,
    /// VK_EXT_sample_locations entry points, when the device has the extension.
    pub(crate) sample_locations: Option<ash::ext::sample_locations::Device>,
    /// VK_KHR_pipeline_executable_properties entry points, when enabled.
    pub(crate) executable_properties: Option<ash::khr::pipeline_executable_properties::Device>,
    /// What every pipeline creation also asks for (capture, wave size).
    pub(crate) compile: Mutex<CompileSettings>,
    /// What the pipelines created with capture on reported, in creation order.
    pub(crate) captured: Mutex<Vec<PipelineExecutables>>,
}

/// The opened device. Cheap to clone; resources keep it alive.
#[derive(Clone)]
pub struct Gpu {
    pub(crate) inner: Arc<Inner>,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let important = severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
            | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
    );
    if !important || data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes a valid callback-data struct for the duration of the call.
    let data = unsafe { &*data };
    // SAFETY: the strings are valid NUL-terminated strings or null (handled by the helpers).
    let id = unsafe { data.message_id_name_as_c_str() }
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    // SAFETY: as above.
    let text = unsafe { data.message_as_c_str() }
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let msg = format!("[{severity:?} {kind:?}] {id}: {text}");
    eprintln!("vulkan: {msg}");
    // SAFETY: `user` is the `ValidationLog` pointer installed in `Gpu::new`, alive while the
    // messenger exists.
    unsafe { &*(user as *const ValidationLog) }.push(msg);
    vk::FALSE
}

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

fn api_pair(v: u32) -> (u32, u32) {
    (vk::api_version_major(v), vk::api_version_minor(v))
}

fn device_kind(t: vk::PhysicalDeviceType) -> DeviceKind {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => DeviceKind::Discrete,
        vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceKind::Integrated,
        vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceKind::Virtual,
        vk::PhysicalDeviceType::CPU => DeviceKind::Cpu,
        _ => DeviceKind::Other,
    }
}

/// The features cbr cannot work without, as (name, present) pairs.
fn required_features(
    f10: &vk::PhysicalDeviceFeatures,
    f12: &vk::PhysicalDeviceVulkan12Features,
    f13: &vk::PhysicalDeviceVulkan13Features,
) -> [(&'static str, bool); 5] {
    [
        ("dynamicRendering", f13.dynamic_rendering != 0),
        ("synchronization2", f13.synchronization2 != 0),
        ("hostQueryReset", f12.host_query_reset != 0),
        (
            "shaderDemoteToHelperInvocation",
            f13.shader_demote_to_helper_invocation != 0,
        ),
        (
            "fragmentStoresAndAtomics",
            f10.fragment_stores_and_atomics != 0,
        ),
    ]
}

struct Probe {
    props: vk::PhysicalDeviceProperties,
    f10: vk::PhysicalDeviceFeatures,
    /// VK_KHR_pipeline_executable_properties' pipelineExecutableInfo (false without the extension).
    pipeline_executable_info: bool,
    /// subgroupSize (Vulkan 1.1 properties).
    subgroup_size: u32,
    /// minSubgroupSize, maxSubgroupSize, and whether compute is in requiredSubgroupSizeStages
    /// (Vulkan 1.3 properties).
    subgroup_range: (u32, u32, bool),
    f11_multiview: bool,
    f12: vk::PhysicalDeviceVulkan12Features<'static>,
    f13: vk::PhysicalDeviceVulkan13Features<'static>,
    queue_family: Option<u32>,
    extensions: Vec<CString>,
    driver_name: String,
    driver_info: String,
    /// maxMemoryAllocationSize (VkPhysicalDeviceMaintenance3Properties).
    max_memory_allocation_size: u64,
}

fn probe(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Probe {
    // SAFETY: `pd` was enumerated from `instance`.
    let extensions: Vec<CString> = unsafe { instance.enumerate_device_extension_properties(pd) }
        .unwrap_or_default()
        .iter()
        .filter_map(|e| e.extension_name_as_c_str().ok().map(CStr::to_owned))
        .collect();
    let has_exec_props = extensions
        .iter()
        .any(|e| e.as_c_str() == ash::khr::pipeline_executable_properties::NAME);
    let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut fexec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f11)
        .push_next(&mut f12)
        .push_next(&mut f13);
    if has_exec_props {
        f2 = f2.push_next(&mut fexec);
    }
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut m3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut p11 = vk::PhysicalDeviceVulkan11Properties::default();
    let mut p13 = vk::PhysicalDeviceVulkan13Properties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut driver)
        .push_next(&mut m3)
        .push_next(&mut p11)
        .push_next(&mut p13);
    // SAFETY: `pd` was enumerated from `instance`; the chained structs outlive the calls, and the
    // extension's struct is chained only when the device has the extension.
    unsafe {
        instance.get_physical_device_features2(pd, &mut f2);
        instance.get_physical_device_properties2(pd, &mut p2);
    }
    let f10 = f2.features;
    let props = p2.properties;
    let pipeline_executable_info = has_exec_props && fexec.pipeline_executable_info != 0;
    let subgroup_size = p11.subgroup_size;
    let subgroup_range = (
        p13.min_subgroup_size,
        p13.max_subgroup_size,
        p13.required_subgroup_size_stages
            .contains(vk::ShaderStageFlags::COMPUTE),
    );
    let max_memory_allocation_size = m3.max_memory_allocation_size;
    let f11_multiview = f11.multiview != 0;
    // Drop the pNext chains so the structs can be stored.
    f12.p_next = std::ptr::null_mut();
    f13.p_next = std::ptr::null_mut();
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    let queue_family = families
        .iter()
        .position(|q| q.queue_flags.contains(want) && q.timestamp_valid_bits > 0)
        .or_else(|| families.iter().position(|q| q.queue_flags.contains(want)))
        .map(|i| i as u32);
    let driver_name = driver
        .driver_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_info = driver
        .driver_info_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Probe {
        props,
        f10,
        pipeline_executable_info,
        subgroup_size,
        subgroup_range,
        f11_multiview,
        f12: vk::PhysicalDeviceVulkan12Features {
            p_next: std::ptr::null_mut(),
            ..f12
        },
        f13: vk::PhysicalDeviceVulkan13Features {
            p_next: std::ptr::null_mut(),
            ..f13
        },
        queue_family,
        extensions,
        driver_name,
        driver_info,
        max_memory_allocation_size,
    }
}

fn candidate(index: usize, p: &Probe) -> Candidate {
    Candidate {
        index,
        name: p
            .props
            .device_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        kind: device_kind(p.props.device_type),
        api: api_pair(p.props.api_version),
        has_graphics_compute_queue: p.queue_family.is_some(),
        missing: required_features(&p.f10, &p.f12, &p.f13)
            .into_iter()
            .filter(|(_, ok)| !ok)
            .map(|(n, _)| n)
            .collect(),
    }
}

fn caps_of(instance: &ash::Instance, pd: vk::PhysicalDevice, p: &Probe) -> Caps {
    let l = &p.props.limits;
    let both = l.framebuffer_color_sample_counts & l.framebuffer_depth_sample_counts;
    let has_ext = |name: &CStr| p.extensions.iter().any(|e| e.as_c_str() == name);
    // SAFETY: `pd` belongs to `instance`.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    // SAFETY: `pd` belongs to `instance`.
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let heaps = memory
        .memory_heaps
        .get(..memory.memory_heap_count as usize)
        .unwrap_or(&[]);
    let (device_local_heap_bytes, unified_memory) = heap_limits(heaps);
    let name = p
        .props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (min_subgroup, max_subgroup, compute_subgroups) = p.subgroup_range;
    let ts_bits = p
        .queue_family
        .and_then(|q| families.get(q as usize))
        .map(|q| q.timestamp_valid_bits)
        .unwrap_or(0);
    Caps {
        can_execute: null_device::can_execute(
            &name,
            memory.memory_heap_count,
            memory.memory_type_count,
        ),
        pipeline_executable_info: p.pipeline_executable_info,
        subgroup_size: p.subgroup_size,
        compute_subgroup_sizes: compute_subgroup_sizes(
            p.f13.subgroup_size_control != 0,
            compute_subgroups,
            min_subgroup,
            max_subgroup,
        ),
        sample_rate_shading: p.f10.sample_rate_shading != 0,
        sample_counts: sample_count_list(both),
        integer_color_sample_counts: integer_sample_counts(
            &INTEGER_ATTACHMENTS
                .iter()
                .map(|&(format, usage)| image_sample_counts(instance, pd, format, usage))
                .collect::<Vec<_>>(),
            both,
        ),
        sample_locations: has_ext(ash::ext::sample_locations::NAME),
        sample_locations_2x: false, // properties read in `Gpu::new`
        maintenance4: p.f13.maintenance4 != 0,
        dynamic_rendering: p.f13.dynamic_rendering != 0,
        pipeline_statistics: p.f10.pipeline_statistics_query != 0,
        // lavapipe (driver "llvmpipe") crashes in its queue thread on compute-invocation queries.
        compute_invocation_query: p.f10.pipeline_statistics_query != 0
            && p.driver_name != "llvmpipe",
        timestamps: l.timestamp_compute_and_graphics != 0 && ts_bits > 0,
        timestamp_period_ns: l.timestamp_period,
        timestamp_valid_bits: ts_bits,
        geometry_shader: p.f10.geometry_shader != 0,
        shader_output_layer: p.f12.shader_output_layer != 0,
        clip_distance: p.f10.shader_clip_distance != 0,
        multiview: p.f11_multiview,
        max_image_dimension_2d: l.max_image_dimension2_d,
        max_viewport: l.max_viewport_dimensions,
        max_framebuffer: [l.max_framebuffer_width, l.max_framebuffer_height],
        viewport_sub_pixel_bits: l.viewport_sub_pixel_bits,
        sub_pixel_precision_bits: l.sub_pixel_precision_bits,
        sub_texel_precision_bits: l.sub_texel_precision_bits,
        shader_float16: p.f12.shader_float16 != 0,
        max_storage_buffer_range: l.max_storage_buffer_range,
        max_uniform_buffer_range: l.max_uniform_buffer_range,
        min_storage_buffer_offset_alignment: l.min_storage_buffer_offset_alignment,
        device_local_heap_bytes,
        unified_memory,
        max_memory_allocation_size: p.max_memory_allocation_size,
        fragment_stores_and_atomics: p.f10.fragment_stores_and_atomics != 0,
        int64_atomics: p.f10.shader_int64 != 0 && p.f12.shader_buffer_int64_atomics != 0,
    }
}

/// The sample counts a 2D optimal-tiling image of `format` with `usage` may have, or `None` when
/// the device cannot create one at all (vkGetPhysicalDeviceImageFormatProperties).
fn image_sample_counts(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> Option<vk::SampleCountFlags> {
    // SAFETY: `pd` belongs to `instance`; a plain query.
    unsafe {
        instance.get_physical_device_image_format_properties(
            pd,
            format,
            vk::ImageType::TYPE_2D,
            vk::ImageTiling::OPTIMAL,
            usage,
            vk::ImageCreateFlags::empty(),
        )
    }
    .ok()
    .map(|p| p.sample_counts)
}

/// Describes every device the loader sees, for `cbr info` and the selection error.
pub struct DeviceReport {
    pub candidates: Vec<Candidate>,
}

fn load_entry() -> Result<ash::Entry> {
    null_device::check_forced_family()?;
    // SAFETY: loading libvulkan runs its initialisers; the loader is a well-behaved library.
    unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader(e.to_string()))
}

impl Gpu {
    /// Opens the device `opts.device` (or the best one) with the features cbr needs.
    pub fn new(opts: &GpuOptions) -> Result<Gpu> {
        let entry = load_entry()?;
        if opts.validation {
            // SAFETY: plain enumeration.
            let layers = unsafe { entry.enumerate_instance_layer_properties() }
                .vk("vkEnumerateInstanceLayerProperties")?;
            if !layers
                .iter()
                .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER))
            {
                return Err(GpuError::NoValidationLayer);
            }
        }
        // SAFETY: plain enumeration.
        let inst_exts =
            unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
        let has_debug_utils = inst_exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(ash::ext::debug_utils::NAME));

        let app = vk::ApplicationInfo::default()
            .application_name(c"cbr")
            .engine_name(c"cbr")
            .api_version(vk::API_VERSION_1_3);
        let layers = if opts.validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let extensions = if has_debug_utils {
            vec![ash::ext::debug_utils::NAME.as_ptr()]
        } else {
            vec![]
        };
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut vfeatures =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if opts.validation {
            info = info.push_next(&mut vfeatures);
        }
        // SAFETY: every pointer in `info` refers to locals alive for the call.
        let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDevices(driver_env()),
            r => GpuError::Vk {
                call: "vkCreateInstance",
                result: r,
            },
        })?;

        let validation = Arc::new(ValidationLog::default());
        let validation_raw = Arc::as_ptr(&validation);
        let debug_instance = if has_debug_utils {
            let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let mi = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(validation_raw as *mut c_void);
            // SAFETY: the callback's user data outlives the messenger (destroyed in Drop first).
            let m = unsafe { du.create_debug_utils_messenger(&mi, None) }
                .vk("vkCreateDebugUtilsMessengerEXT")?;
            Some((du, m))
        } else {
            None
        };

        let destroy_instance =
            |di: &Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| {
                // SAFETY: nothing else was created from the instance yet.
                unsafe {
                    if let Some((du, m)) = di {
                        du.destroy_debug_utils_messenger(*m, None);
                    }
                    instance.destroy_instance(None);
                }
            };

        // SAFETY: plain enumeration.
        let pds = match unsafe { instance.enumerate_physical_devices() } {
            Ok(p) if !p.is_empty() => p,
            _ => {
                destroy_instance(&debug_instance);
                return Err(GpuError::NoDevices(driver_env()));
            }
        };
        let probes: Vec<Probe> = pds.iter().map(|&pd| probe(&instance, pd)).collect();
        let cands: Vec<Candidate> = probes
            .iter()
            .enumerate()
            .map(|(i, p)| candidate(i, p))
            .collect();
        let index = match select::choose(&cands, opts.device.as_deref()) {
            Ok(i) => i,
            Err(report) => {
                destroy_instance(&debug_instance);
                return Err(GpuError::NoSuitableDevice(report));
            }
        };
        let pd = pds[index];
        let p = &probes[index];
        let queue_family = p.queue_family.unwrap_or(0);
        let mut caps = caps_of(&instance, pd, p);
        {
            let mut psl = vk::PhysicalDeviceSampleLocationsPropertiesEXT::default();
            let mut p2 = vk::PhysicalDeviceProperties2::default();
            if caps.sample_locations {
                p2 = p2.push_next(&mut psl);
            }
            // SAFETY: `pd` belongs to `instance`; the extension struct is chained only when the
            // device exposes the extension.
            unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
            caps.sample_locations_2x = caps.sample_locations
                && psl
                    .sample_location_sample_counts
                    .contains(vk::SampleCountFlags::TYPE_2)
                && psl.sample_location_sub_pixel_bits >= 2
                && psl.sample_location_coordinate_range[0] <= 0.0
                && psl.sample_location_coordinate_range[1] >= 0.75;
        }

        // Enable what is required plus what is available and useful.
        let f10 = vk::PhysicalDeviceFeatures::default()
            .sample_rate_shading(caps.sample_rate_shading)
            .shader_clip_distance(caps.clip_distance)
            .geometry_shader(caps.geometry_shader)
            .shader_int64(caps.int64_atomics)
            .pipeline_statistics_query(caps.pipeline_statistics)
            .fragment_stores_and_atomics(true)
            .shader_storage_image_write_without_format(
                p.f10.shader_storage_image_write_without_format != 0,
            )
            .independent_blend(p.f10.independent_blend != 0);
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
            .host_query_reset(true)
            .shader_output_layer(caps.shader_output_layer)
            .scalar_block_layout(p.f12.scalar_block_layout != 0)
            .shader_float16(p.f12.shader_float16 != 0)
            .shader_buffer_int64_atomics(caps.int64_atomics);
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true)
            .shader_demote_to_helper_invocation(true)
            .maintenance4(caps.maintenance4)
            .subgroup_size_control(p.f13.subgroup_size_control != 0)
            .compute_full_subgroups(p.f13.compute_full_subgroups != 0);
        let mut fexec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
            .pipeline_executable_info(true);
        let prio = [1.0f32];
        let qinfo = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&prio)];
        let mut dev_exts = Vec::new();
        if caps.sample_locations {
            dev_exts.push(ash::ext::sample_locations::NAME.as_ptr());
        }
        if caps.pipeline_executable_info {
            dev_exts.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
        }
        let mut dinfo = vk::DeviceCreateInfo::default()
            .queue_create_infos(&qinfo)
            .enabled_features(&f10)
            .enabled_extension_names(&dev_exts)
            .push_next(&mut f12)
            .push_next(&mut f13);
        if caps.pipeline_executable_info {
            dinfo = dinfo.push_next(&mut fexec);
        }
        // SAFETY: features were checked against the device; pointers are to locals.
        let device = match unsafe { instance.create_device(pd, &dinfo, None) } {
            Ok(d) => d,
            Err(r) => {
                destroy_instance(&debug_instance);
                return Err(GpuError::Vk {
                    call: "vkCreateDevice",
                    result: r,
                });
            }
        };
        // SAFETY: queue 0 of the family we created.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let debug_device =
            has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        // A device that cannot execute (RADV's null device) gets neither allocator nor command
        // pool: `Image::new`, `Buffer::new` and `Gpu::submit` refuse before reaching them.
        let (allocator, command_pool) = if caps.can_execute {
            let allocator = Allocator::new(&AllocatorCreateDesc {
                instance: instance.clone(),
                device: device.clone(),
                physical_device: pd,
                debug_settings: Default::default(),
                buffer_device_address: false,
                allocation_sizes: Default::default(),
            })
            .map_err(|e| GpuError::Alloc {
                name: "allocator".into(),
                source: e,
            })?;
            let pool_info = vk::CommandPoolCreateInfo::default()
                .queue_family_index(queue_family)
                .flags(vk::CommandPoolCreateFlags::TRANSIENT);
            // SAFETY: valid device and family.
            let command_pool = unsafe { device.create_command_pool(&pool_info, None) }
                .vk("vkCreateCommandPool")?;
            (Some(allocator), command_pool)
        } else {
            (None, vk::CommandPool::null())
        };

        let cand = &cands[index];
        let info = DeviceInfo {
            index,
            name: cand.name.clone(),
            kind: cand.kind,
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(p.props.api_version),
                vk::api_version_minor(p.props.api_version),
                vk::api_version_patch(p.props.api_version)
            ),
            driver_name: p.driver_name.clone(),
            driver_info: p.driver_info.clone(),
            vendor_id: p.props.vendor_id,
            device_id: p.props.device_id,
        };
        tracing::info!(
            "device [{index}] {} ({}, {})",
            info.name,
            info.driver_name,
            info.driver_info
        );
        let sample_locations = caps
            .sample_locations
            .then(|| ash::ext::sample_locations::Device::new(&instance, &device));
        let executable_properties = caps
            .pipeline_executable_info
            .then(|| ash::khr::pipeline_executable_properties::Device::new(&instance, &device));
        let gpu = Gpu {
            inner: Arc::new(Inner {
                sample_locations,
                executable_properties,
                compile: Mutex::new(CompileSettings::default()),
                captured: Mutex::new(Vec::new()),
                _entry: entry,
                instance,
                debug_instance,
                debug_device,
                device,
                queue: Mutex::new(queue),
                queue_family,
                allocator: Mutex::new(allocator),
                allocations_made: AtomicU64::new(0),
                command_pool: Mutex::new(command_pool),
                validation,
                garbage: Mutex::new(Vec::new()),
                submitted: AtomicU64::new(0),
                completed: AtomicU64::new(0),
                info,
                caps,
            }),
        };
        if gpu.inner.caps.can_execute {
            gpu.name_object(command_pool, "cbr.command_pool");
        }
        Ok(gpu)
    }

    /// Every device the loader sees, with the reason any of them would be rejected.
    pub fn enumerate() -> Result<DeviceReport> {
        let entry = load_entry()?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let info = vk::InstanceCreateInfo::default().application_info(&app);
        // SAFETY: minimal instance, destroyed below.
        let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDevices(driver_env()),
            r => GpuError::Vk {
                call: "vkCreateInstance",
                result: r,
            },
        })?;
        // SAFETY: plain enumeration.
        let pds = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
        let candidates = pds
            .iter()
            .enumerate()
            .map(|(i, &pd)| candidate(i, &probe(&instance, pd)))
            .collect();
        // SAFETY: nothing was created from this instance.
        unsafe { instance.destroy_instance(None) };
        Ok(DeviceReport { candidates })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.inner.info
    }
    pub fn caps(&self) -> &Caps {
        &self.inner.caps
    }
    pub fn validation(&self) -> &ValidationLog {
        &self.inner.validation
    }

    /// How many memory allocations were made since the device was opened, freed ones included
    /// (tests check that a refusal allocated nothing, not even briefly).
    pub fn allocations_made(&self) -> u64 {
        self.inner.allocations_made.load(Ordering::SeqCst)
    }

    /// Every live memory allocation, (name, bytes), those waiting in the deletion queue included
    /// (tests hold the renderer's memory estimates to what was really allocated).
    pub fn allocations(&self) -> Vec<(String, u64)> {
        match self.inner.allocator.lock() {
            Ok(guard) => guard
                .as_ref()
                .map(|a| {
                    a.generate_report()
                        .allocations
                        .into_iter()
                        .map(|r| (r.name, r.size))
                        .collect()
                })
                .unwrap_or_default(),
            Err(_) => Vec::new(),
        }
    }
    pub fn device(&self) -> &ash::Device {
        &self.inner.device
    }

    /// `Err(GpuError::CannotExecute)` naming the device and `what`, on a device that can only
    /// compile pipelines (`Caps::can_execute`).
    pub fn require_execution(&self, what: &str) -> Result<()> {
        if self.inner.caps.can_execute {
            Ok(())
        } else {
            Err(GpuError::CannotExecute {
                device: self.inner.info.name.clone(),
                what: what.to_string(),
            })
        }
    }

    /// Gives a Vulkan object a debug name (visible in validation messages and capture tools).
    pub fn name_object<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(du) = &self.inner.debug_device else {
            return;
        };
        let Ok(cname) = CString::new(name) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&cname);
        // SAFETY: the handle is a live object of this device.
        let _ = unsafe { du.set_debug_utils_object_name(&info) };
    }

    /// Records commands with `record`, submits them and waits for completion, then frees the
    /// resources whose last use was in this or an earlier submission.
    pub fn submit<R>(
        &self,
        label: &str,
        record: impl FnOnce(&mut crate::cmd::Cmd) -> Result<R>,
    ) -> Result<R> {
        self.require_execution(&format!("submitting `{label}`"))?;
        let dev = &self.inner.device;
        let pool = self
            .inner
            .command_pool
            .lock()
            .map_err(|_| GpuError::Other("command pool lock poisoned".into()))?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: pool is valid and externally synchronised by the mutex held for this function.
        let cb = unsafe { dev.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        self.name_object(cb, label);
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: freshly allocated command buffer.
        unsafe { dev.begin_command_buffer(cb, &begin) }.vk("vkBeginCommandBuffer")?;
        let mut cmd = crate::cmd::Cmd::new(self.clone(), cb);
        let out = record(&mut cmd);
        // SAFETY: the buffer is in the recording state.
        let end = unsafe { dev.end_command_buffer(cb) }.vk("vkEndCommandBuffer");
        let result = out.and_then(|out| {
            end?;
            let serial = self.inner.submitted.fetch_add(1, Ordering::SeqCst) + 1;
            let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cbs)];
            // SAFETY: default fence info.
            let fence = unsafe { dev.create_fence(&vk::FenceCreateInfo::default(), None) }
                .vk("vkCreateFence")?;
            let queue = self
                .inner
                .queue
                .lock()
                .map_err(|_| GpuError::Other("queue lock poisoned".into()))?;
            // SAFETY: the command buffer is executable; queue access is serialised by the mutex.
            let r = unsafe { dev.queue_submit2(*queue, &submit, fence) }
                .vk("vkQueueSubmit2")
                // SAFETY: fence belongs to this device.
                .and_then(|_| {
                    unsafe { dev.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
                });
            drop(queue);
            // SAFETY: the fence is signalled (or the submit failed); no longer in use.
            unsafe { dev.destroy_fence(fence, None) };
            r?;
            self.inner.completed.fetch_max(serial, Ordering::SeqCst);
            Ok(out)
        });
        // SAFETY: execution finished (waited above) or never started.
        unsafe { dev.free_command_buffers(*pool, &[cb]) };
        drop(pool);
        // The descriptor sets the recording made go to the deletion queue now that their
        // submission has completed (or never started).
        drop(cmd);
        self.inner.collect_garbage();
        result
    }
}

fn driver_env() -> String {
    std::env::var("VK_DRIVER_FILES")
        .or_else(|_| std::env::var("VK_ICD_FILENAMES"))
        .unwrap_or_else(|_| "<unset>".into())
}

impl Inner {
    /// Queues `g` for destruction once every submission recorded so far has completed.
    pub(crate) fn defer(&self, g: Garbage) {
        let serial = self.submitted.load(Ordering::SeqCst);
        if let Ok(mut q) = self.garbage.lock() {
            q.push((serial, g));
        }
        if self.completed.load(Ordering::SeqCst) >= serial {
            self.collect_garbage();
        }
    }

    fn collect_garbage(&self) {
        let done = self.completed.load(Ordering::SeqCst);
        let ready: Vec<Garbage> = match self.garbage.lock() {
            Ok(mut q) => {
                let (ready, keep): (Vec<_>, Vec<_>) = q.drain(..).partition(|(s, _)| *s <= done);
                *q = keep;
                ready.into_iter().map(|(_, g)| g).collect()
            }
            Err(_) => return,
        };
        for g in ready {
            self.destroy(g);
        }
    }

    fn destroy(&self, g: Garbage) {
        let d = &self.device;
        let free = |a: Allocation| {
            if let Ok(mut al) = self.allocator.lock()
                && let Some(al) = al.as_mut()
            {
                let _ = al.free(a);
            }
        };
        // SAFETY: each object's last use completed (serial check in `collect_garbage`, or
        // `device_wait_idle` in Drop) and nothing references it any more.
        unsafe {
            match g {
                Garbage::Buffer(b, a) => {
                    d.destroy_buffer(b, None);
                    free(a);
                }
                Garbage::Image(i, views, a) => {
                    for v in views {
                        d.destroy_image_view(v, None);
                    }
                    d.destroy_image(i, None);
                    free(a);
                }
                Garbage::Sampler(s) => d.destroy_sampler(s, None),
                Garbage::Pipeline(p) => d.destroy_pipeline(p, None),
                Garbage::PipelineLayout(p) => d.destroy_pipeline_layout(p, None),
                Garbage::DescriptorSetLayout(l) => d.destroy_descriptor_set_layout(l, None),
                Garbage::DescriptorPool(p) => d.destroy_descriptor_pool(p, None),
                Garbage::QueryPool(q) => d.destroy_query_pool(q, None),
            }
        }
    }
}

impl Drop for Inner {
    fn drop(&mut self) {
        // A device that cannot execute has nothing to wait for (and RADV's null device crashes in
        // vkDeviceWaitIdle).
        if self.caps.can_execute {
            // SAFETY: last owner; wait for the GPU, then destroy in dependency order.
            unsafe {
                let _ = self.device.device_wait_idle();
            }
        }
        self.completed.store(u64::MAX, Ordering::SeqCst);
        self.collect_garbage();
        if let Ok(mut a) = self.allocator.lock()
            && let Some(a) = a.take()
        {
            a.report_memory_leaks(log::Level::Warn);
            drop(a);
        }
        // SAFETY: all children of the device are gone; the messenger goes before the instance and
        // before the log it points at (kept alive by `self.validation`).
        unsafe {
            if let Ok(pool) = self.command_pool.lock()
                && *pool != vk::CommandPool::null()
            {
                self.device.destroy_command_pool(*pool, None);
            }
            self.device.destroy_device(None);
            if let Some((du, m)) = &self.debug_instance {
                du.destroy_debug_utils_messenger(*m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
