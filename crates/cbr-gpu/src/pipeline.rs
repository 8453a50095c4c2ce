//! Descriptor set layouts (one shared definition per pass), descriptor sets, and pipelines.

use std::sync::Arc;

use ash::vk;

use crate::context::{Garbage, Gpu, Inner};
use crate::error::{GpuError, Result, VkContext};
use crate::executables::{self, PipelineExecutables};
use crate::resource::{Buffer, Image, Sampler};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DescriptorKind {
    UniformBuffer,
    StorageBuffer,
    CombinedImageSampler,
    StorageImage,
}

impl DescriptorKind {
    fn vk(self) -> vk::DescriptorType {
        match self {
            DescriptorKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            DescriptorKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            DescriptorKind::CombinedImageSampler => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            DescriptorKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        }
    }
}

/// One binding of a set: the single definition both the Rust side and (through generated
/// `#define`s) the shaders use.
#[derive(Clone, Copy, Debug)]
pub struct BindingDesc {
    pub name: &'static str,
    pub binding: u32,
    pub kind: DescriptorKind,
    pub count: u32,
}

impl BindingDesc {
    /// A single-descriptor binding.
    pub const fn one(name: &'static str, binding: u32, kind: DescriptorKind) -> BindingDesc {
        BindingDesc {
            name,
            binding,
            kind,
            count: 1,
        }
    }

    /// `("BINDING_<NAME>", "<n>")`, for shader defines.
    pub fn define(&self) -> (String, String) {
        (
            format!("BINDING_{}", self.name.to_uppercase()),
            self.binding.to_string(),
        )
    }
}

pub struct SetLayout {
    gpu: Arc<Inner>,
    pub(crate) raw: vk::DescriptorSetLayout,
    pub bindings: Vec<BindingDesc>,
}

impl SetLayout {
    pub fn new(gpu: &Gpu, name: &str, bindings: &[BindingDesc]) -> Result<SetLayout> {
        let vk_bindings: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.kind.vk())
                    .descriptor_count(b.count)
                    .stage_flags(vk::ShaderStageFlags::ALL)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&vk_bindings);
        // SAFETY: valid create info.
        let raw = unsafe { gpu.device().create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        gpu.name_object(raw, name);
        Ok(SetLayout {
            gpu: gpu.inner.clone(),
            raw,
            bindings: bindings.to_vec(),
        })
    }
}

impl Drop for SetLayout {
    fn drop(&mut self) {
        self.gpu.defer(Garbage::DescriptorSetLayout(self.raw));
    }
}

/// What to bind at one binding.
#[derive(Clone)]
pub enum Write<'a> {
    Buffer(u32, &'a Buffer),
    /// `bytes` of a buffer from `offset` (a multiple of the device's offset alignment).
    BufferRange(u32, &'a Buffer, u64, u64),
    /// Images in `SHADER_READ_ONLY_OPTIMAL` (depth: `DEPTH_READ_ONLY_OPTIMAL`) with their samplers.
    Sampled(u32, Vec<(&'a Image, &'a Sampler)>),
    /// An image used as storage, in `GENERAL`.
    Storage(u32, &'a Image),
}

/// A descriptor set with its own small pool.
pub struct DescriptorSet {
    gpu: Arc<Inner>,
    pool: vk::DescriptorPool,
    pub(crate) raw: vk::DescriptorSet,
}

impl DescriptorSet {
    pub fn new(
        gpu: &Gpu,
        name: &str,
        layout: &SetLayout,
        writes: &[Write],
    ) -> Result<DescriptorSet> {
        let sizes: Vec<vk::DescriptorPoolSize> = layout
            .bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize {
                ty: b.kind.vk(),
                descriptor_count: b.count,
            })
            .collect();
        let pinfo = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        let dev = gpu.device();
        // SAFETY: valid create info.
        let pool =
            unsafe { dev.create_descriptor_pool(&pinfo, None) }.vk("vkCreateDescriptorPool")?;
        gpu.name_object(pool, &format!("{name}.pool"));
        let layouts = [layout.raw];
        let ainfo = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for this layout.
        let raw = match unsafe { dev.allocate_descriptor_sets(&ainfo) } {
            Ok(s) => s[0],
            Err(r) => {
                // SAFETY: nothing allocated from the pool.
                unsafe { dev.destroy_descriptor_pool(pool, None) };
                return Err(GpuError::Vk {
                    call: "vkAllocateDescriptorSets",
                    result: r,
                });
            }
        };
        gpu.name_object(raw, name);
        let set = DescriptorSet {
            gpu: gpu.inner.clone(),
            pool,
            raw,
        };
        set.update(gpu, layout, writes)?;
        Ok(set)
    }

    /// Points the given bindings at new resources (the others keep theirs). The set must not be
    /// in use by a command buffer that has not completed.
    pub fn update(&self, gpu: &Gpu, layout: &SetLayout, writes: &[Write]) -> Result<()> {
        // Each write's binding must exist and hold what the write gives: a buffer for a buffer
        // binding, sampled images (no more than the binding's count) for a combined image
        // sampler, one storage image for a storage image.
        let check = |binding: u32, given: &str, n: u32| {
            let b = layout
                .bindings
                .iter()
                .find(|b| b.binding == binding)
                .ok_or_else(|| {
                    GpuError::Other(format!("binding {binding} is not in the layout"))
                })?;
            let fits = match b.kind {
                DescriptorKind::UniformBuffer | DescriptorKind::StorageBuffer => given == "buffer",
                DescriptorKind::CombinedImageSampler => given == "sampled image",
                DescriptorKind::StorageImage => given == "storage image",
            };
            if !fits {
                return Err(GpuError::Other(format!(
                    "binding {binding} (`{}`) is a {:?}, given a {given}",
                    b.name, b.kind
                )));
            }
            if n == 0 || n > b.count {
                return Err(GpuError::Other(format!(
                    "binding {binding} (`{}`) holds {} descriptors, given {n}",
                    b.name, b.count
                )));
            }
            Ok(b.kind)
        };
        let mut buffer_infos = Vec::new();
        let mut image_infos = Vec::new();
        for w in writes {
            match w {
                Write::Buffer(b, buf) => {
                    buffer_infos.push((
                        *b,
                        check(*b, "buffer", 1)?,
                        [vk::DescriptorBufferInfo::default()
                            .buffer(buf.raw())
                            .range(vk::WHOLE_SIZE)],
                    ));
                }
                Write::BufferRange(b, buf, offset, bytes) => {
                    if offset
                        .checked_add(*bytes)
                        .is_none_or(|end| end > buf.size())
                        || *bytes == 0
                    {
                        return Err(GpuError::Other(format!(
                            "binding {b}: {bytes} bytes from {offset} of a {}-byte buffer",
                            buf.size()
                        )));
                    }
                    buffer_infos.push((
                        *b,
                        check(*b, "buffer", 1)?,
                        [vk::DescriptorBufferInfo::default()
                            .buffer(buf.raw())
                            .offset(*offset)
                            .range(*bytes)],
                    ));
                }
                Write::Sampled(b, imgs) => {
                    let infos: Vec<vk::DescriptorImageInfo> = imgs
                        .iter()
                        .map(|(img, s)| {
                            let layout = if crate::resource::is_depth_format(img.format) {
                                vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL
                            } else {
                                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
                            };
                            vk::DescriptorImageInfo::default()
                                .image_view(img.view())
                                .sampler(s.raw())
                                .image_layout(layout)
                        })
                        .collect();
                    let kind = check(*b, "sampled image", infos.len() as u32)?;
                    image_infos.push((*b, kind, infos));
                }
                Write::Storage(b, img) => {
                    let infos = vec![
                        vk::DescriptorImageInfo::default()
                            .image_view(img.view())
                            .image_layout(vk::ImageLayout::GENERAL),
                    ];
                    image_infos.push((*b, check(*b, "storage image", 1)?, infos));
                }
            }
        }
        let mut vk_writes = Vec::new();
        for (b, kind, info) in &buffer_infos {
            vk_writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.raw)
                    .dst_binding(*b)
                    .descriptor_type(kind.vk())
                    .buffer_info(info),
            );
        }
        for (b, kind, info) in &image_infos {
            vk_writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.raw)
                    .dst_binding(*b)
                    .descriptor_type(kind.vk())
                    .image_info(info),
            );
        }
        // SAFETY: every write targets a binding of this set's layout with the matching type and
        // no more descriptors than the binding holds (checked above).
        unsafe { gpu.device().update_descriptor_sets(&vk_writes, &[]) };
        Ok(())
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        self.gpu.defer(Garbage::DescriptorPool(self.pool));
    }
}

/// A graphics pipeline for dynamic rendering. Viewport and scissor are dynamic; vertices are
/// pulled from storage buffers (no vertex input state).
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    pub vertex: &'a [u32],
    pub geometry: Option<&'a [u32]>,
    pub fragment: &'a [u32],
    pub set_layouts: &'a [&'a SetLayout],
    pub push_constant_bytes: u32,
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    pub depth_compare: vk::CompareOp,
    pub depth_write: bool,
    pub samples: u32,
    /// `Some(1.0)` enables per-sample shading.
    pub min_sample_shading: Option<f32>,
    pub cull_back_faces: bool,
    /// Custom sample locations, set per frame (VK_EXT_sample_locations dynamic state).
    pub sample_locations: bool,
}

pub struct ComputeDesc<'a> {
    pub name: &'a str,
    pub shader: &'a [u32],
    pub set_layouts: &'a [&'a SetLayout],
    pub push_constant_bytes: u32,
}

pub struct Pipeline {
    gpu: Arc<Inner>,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) bind_point: vk::PipelineBindPoint,
    pub push_constant_bytes: u32,
    /// What the driver reported, when the device's `CompileSettings` captured statistics.
    executables: Option<PipelineExecutables>,
}

fn make_layout(
    gpu: &Gpu,
    name: &str,
    sets: &[&SetLayout],
    push: u32,
) -> Result<vk::PipelineLayout> {
    let raw_sets: Vec<vk::DescriptorSetLayout> = sets.iter().map(|s| s.raw).collect();
    let ranges = [vk::PushConstantRange {
        stage_flags: vk::ShaderStageFlags::ALL,
        offset: 0,
        size: push,
    }];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&raw_sets);
    if push > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    // SAFETY: valid create info.
    let layout =
        unsafe { gpu.device().create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
    gpu.name_object(layout, &format!("{name}.layout"));
    Ok(layout)
}

struct Modules<'a> {
    dev: &'a ash::Device,
    list: Vec<vk::ShaderModule>,
}

impl Modules<'_> {
    fn add(&mut self, code: &[u32]) -> Result<vk::ShaderModule> {
        let info = vk::ShaderModuleCreateInfo::default().code(code);
        // SAFETY: `code` is SPIR-V from shaderc.
        let m = unsafe { self.dev.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
        self.list.push(m);
        Ok(m)
    }
}

impl Drop for Modules<'_> {
    fn drop(&mut self) {
        for m in self.list.drain(..) {
            // SAFETY: modules are only needed during pipeline creation.
            unsafe { self.dev.destroy_shader_module(m, None) };
        }
    }
}

impl Pipeline {
    pub fn graphics(gpu: &Gpu, d: &GraphicsDesc) -> Result<Pipeline> {
        let dev = gpu.device();
        let layout = make_layout(gpu, d.name, d.set_layouts, d.push_constant_bytes)?;
        let mut modules = Modules {
            dev,
            list: Vec::new(),
        };
        let mut stages = vec![
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(modules.add(d.vertex)?)
                .name(c"main"),
        ];
        if let Some(g) = d.geometry {
            stages.push(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::GEOMETRY)
                    .module(modules.add(g)?)
                    .name(c"main"),
            );
        }
        stages.push(
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(modules.add(d.fragment)?)
                .name(c"main"),
        );
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let ia = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let vp = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let rs = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(if d.cull_back_faces {
                vk::CullModeFlags::BACK
            } else {
                vk::CullModeFlags::NONE
            })
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let mut ms = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::from_raw(d.samples));
        if let Some(m) = d.min_sample_shading {
            ms = ms.sample_shading_enable(true).min_sample_shading(m);
        }
        // The locations themselves are dynamic state (`Cmd::set_sample_locations`).
        let mut sl =
            vk::PipelineSampleLocationsStateCreateInfoEXT::default().sample_locations_enable(true);
        if d.sample_locations {
            ms = ms.push_next(&mut sl);
        }
        let ds = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(d.depth_format.is_some())
            .depth_write_enable(d.depth_write)
            .depth_compare_op(d.depth_compare);
        let blend: Vec<vk::PipelineColorBlendAttachmentState> = d
            .color_formats
            .iter()
            .map(|_| {
                vk::PipelineColorBlendAttachmentState::default()
                    .color_write_mask(vk::ColorComponentFlags::RGBA)
            })
            .collect();
        let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let mut dyn_states = vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        if d.sample_locations {
            dyn_states.push(vk::DynamicState::SAMPLE_LOCATIONS_EXT);
        }
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dyn_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(d.color_formats)
            .depth_attachment_format(d.depth_format.unwrap_or(vk::Format::UNDEFINED));
        let settings = gpu.compile_settings();
        let info = vk::GraphicsPipelineCreateInfo::default()
            .flags(settings.flags())
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&ia)
            .viewport_state(&vp)
            .rasterization_state(&rs)
            .multisample_state(&ms)
            .depth_stencil_state(&ds)
            .color_blend_state(&cb)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering);
        // SAFETY: all referenced state lives until the call returns.
        let raw =
            unsafe { dev.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
                .map_err(|(_, r)| GpuError::Vk {
                    call: "vkCreateGraphicsPipelines",
                    result: r,
                });
        let raw = match raw {
            Ok(p) => p[0],
            Err(e) => {
                // SAFETY: unused layout.
                unsafe { dev.destroy_pipeline_layout(layout, None) };
                return Err(e);
            }
        };
        gpu.name_object(raw, d.name);
        Pipeline {
            gpu: gpu.inner.clone(),
            raw,
            layout,
            bind_point: vk::PipelineBindPoint::GRAPHICS,
            push_constant_bytes: d.push_constant_bytes,
            executables: None,
        }
        .captured(d.name, "graphics", &settings)
    }

    pub fn compute(gpu: &Gpu, d: &ComputeDesc) -> Result<Pipeline> {
        let dev = gpu.device();
        let layout = make_layout(gpu, d.name, d.set_layouts, d.push_constant_bytes)?;
        let mut modules = Modules {
            dev,
            list: Vec::new(),
        };
        let settings = gpu.compile_settings();
        let mut wave = vk::PipelineShaderStageRequiredSubgroupSizeCreateInfo::default()
            .required_subgroup_size(settings.compute_subgroup_size.unwrap_or(0));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(modules.add(d.shader)?)
            .name(c"main");
        if settings.compute_subgroup_size.is_some() {
            stage = stage.push_next(&mut wave);
        }
        let info = vk::ComputePipelineCreateInfo::default()
            .flags(settings.flags())
            .stage(stage)
            .layout(layout);
        // SAFETY: valid create info.
        let raw = unsafe { dev.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, r)| GpuError::Vk {
                call: "vkCreateComputePipelines",
                result: r,
            });
        let raw = match raw {
            Ok(p) => p[0],
            Err(e) => {
                // SAFETY: unused layout.
                unsafe { dev.destroy_pipeline_layout(layout, None) };
                return Err(e);
            }
        };
        gpu.name_object(raw, d.name);
        Pipeline {
            gpu: gpu.inner.clone(),
            raw,
            layout,
            bind_point: vk::PipelineBindPoint::COMPUTE,
            push_constant_bytes: d.push_constant_bytes,
            executables: None,
        }
        .captured(d.name, "compute", &settings)
    }

    /// Reads what the driver reported when `settings` captured it, keeps it, and appends a copy
    /// to the device's log (`Gpu::take_captured`).
    fn captured(
        mut self,
        name: &str,
        kind: &'static str,
        settings: &executables::CompileSettings,
    ) -> Result<Pipeline> {
        if settings.captures() {
            let e = executables::read(&self.gpu, self.raw, name, kind, settings)?;
            if let Ok(mut log) = self.gpu.captured.lock() {
                log.push(e.clone());
            }
            self.executables = Some(e);
        }
        Ok(self)
    }

    /// The driver's statistics (and disassembly, when asked) for this pipeline's executables,
    /// when it was created with capture on (`Gpu::set_compile_settings`); `None` otherwise.
    pub fn executables(&self) -> Option<&PipelineExecutables> {
        self.executables.as_ref()
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        self.gpu.defer(Garbage::Pipeline(self.raw));
        self.gpu.defer(Garbage::PipelineLayout(self.layout));
    }
}
