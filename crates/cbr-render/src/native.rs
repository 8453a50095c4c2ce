//! The scene raster pass at full resolution, one sample at each pixel centre: the `native`
//! technique and the reference every other technique is measured against.

use cbr_gpu::{
    Attachment, BindingDesc, Cmd, DescriptorKind, DescriptorSet, Gpu, GraphicsDesc, PassKind,
    Pipeline, Profiler, Result, SetLayout, Shaders, Write, vk,
};

use crate::gpu_scene::GpuScene;
use crate::gpu_types::ScenePush;
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};

/// The scene pass's descriptor set: the one definition the pipeline layout, the descriptor writes
/// and (through `shader_defines`) the GLSL binding numbers all come from.
pub const BINDINGS: [BindingDesc; 5] = [
    BindingDesc {
        name: "frame",
        binding: 0,
        kind: DescriptorKind::UniformBuffer,
        count: 1,
    },
    BindingDesc {
        name: "objects",
        binding: 1,
        kind: DescriptorKind::StorageBuffer,
        count: 1,
    },
    BindingDesc {
        name: "vertices",
        binding: 2,
        kind: DescriptorKind::StorageBuffer,
        count: 1,
    },
    BindingDesc {
        name: "materials",
        binding: 3,
        kind: DescriptorKind::StorageBuffer,
        count: 1,
    },
    BindingDesc {
        name: "lights",
        binding: 4,
        kind: DescriptorKind::StorageBuffer,
        count: 1,
    },
];

/// Set 1, one per material. Separate samplers rather than an indexed array: lavapipe has no
/// `shaderSampledImageArrayDynamicIndexing`.
pub const MATERIAL_BINDINGS: [BindingDesc; 3] = [
    BindingDesc {
        name: "albedo",
        binding: 0,
        kind: DescriptorKind::CombinedImageSampler,
        count: 1,
    },
    BindingDesc {
        name: "mask",
        binding: 1,
        kind: DescriptorKind::CombinedImageSampler,
        count: 1,
    },
    BindingDesc {
        name: "bump",
        binding: 2,
        kind: DescriptorKind::CombinedImageSampler,
        count: 1,
    },
];

fn binding(name: &str) -> u32 {
    BINDINGS
        .iter()
        .chain(&MATERIAL_BINDINGS)
        .find(|b| b.name == name)
        .map(|b| b.binding)
        .unwrap_or(u32::MAX)
}

/// Defines for the scene shaders: the binding numbers.
pub fn shader_defines() -> Vec<(String, String)> {
    BINDINGS
        .iter()
        .chain(&MATERIAL_BINDINGS)
        .map(BindingDesc::define)
        .collect()
}

pub struct ScenePass {
    pipeline: Pipeline,
    _layouts: [SetLayout; 2],
    set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    name: String,
}

impl ScenePass {
    pub fn new(gpu: &Gpu, shaders: &Shaders, scene: &GpuScene, name: &str) -> Result<ScenePass> {
        let layout = SetLayout::new(gpu, &format!("{name}.set_layout"), &BINDINGS)?;
        let material_layout =
            SetLayout::new(gpu, &format!("{name}.material_layout"), &MATERIAL_BINDINGS)?;
        let defines = shader_defines();
        let vs = shaders.compile("scene/forward.vert", &defines)?;
        let fs = shaders.compile("scene/forward.frag", &defines)?;
        let pipeline = Pipeline::graphics(
            gpu,
            &GraphicsDesc {
                name,
                vertex: &vs,
                geometry: None,
                fragment: &fs,
                set_layouts: &[&layout, &material_layout],
                push_constant_bytes: std::mem::size_of::<ScenePush>() as u32,
                color_formats: &[COLOR_FORMAT, VELOCITY_FORMAT, ID_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                // Reverse-Z: nearer is larger.
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                samples: 1,
                min_sample_shading: None,
                cull_back_faces: false,
            },
        )?;
        let set = DescriptorSet::new(
            gpu,
            &format!("{name}.set"),
            &layout,
            &[
                Write::Buffer(binding("frame"), &scene.frame),
                Write::Buffer(binding("objects"), &scene.objects),
                Write::Buffer(binding("vertices"), &scene.vertices),
                Write::Buffer(binding("materials"), &scene.materials),
                Write::Buffer(binding("lights"), &scene.lights),
            ],
        )?;
        let material_sets = scene
            .material_textures
            .iter()
            .enumerate()
            .map(|(i, slots)| {
                let tex = |slot: Option<u32>| {
                    (
                        slot.map(|t| &scene.textures[t as usize])
                            .unwrap_or(&scene.white),
                        &scene.sampler,
                    )
                };
                DescriptorSet::new(
                    gpu,
                    &format!("{name}.material[{i}]"),
                    &material_layout,
                    &[
                        Write::Sampled(binding("albedo"), vec![tex(slots[0])]),
                        Write::Sampled(binding("mask"), vec![tex(slots[1])]),
                        Write::Sampled(binding("bump"), vec![tex(slots[2])]),
                    ],
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ScenePass {
            pipeline,
            _layouts: [layout, material_layout],
            set,
            material_sets,
            name: name.to_string(),
        })
    }

    /// Clears the targets and draws every object.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        targets: &FrameTargets,
    ) {
        let scope = profiler.begin(cmd, &self.name, PassKind::Graphics);
        for buf in [
            &scene.frame,
            &scene.objects,
            &scene.vertices,
            &scene.materials,
            &scene.lights,
            &scene.indices,
        ] {
            cmd.use_buffer(buf, cbr_gpu::Access::GraphicsRead);
        }
        let clear_f = |c: [f32; 4]| {
            Some(vk::ClearValue {
                color: vk::ClearColorValue { float32: c },
            })
        };
        cmd.begin_rendering(
            &[
                // Background: the scene's constant sky radiance, alpha 1 (the native pass renders
                // every pixel).
                Attachment {
                    image: &targets.color,
                    clear: clear_f([
                        scene.background[0],
                        scene.background[1],
                        scene.background[2],
                        1.0,
                    ]),
                },
                Attachment {
                    image: &targets.velocity,
                    clear: clear_f([0.0; 4]),
                },
                Attachment {
                    image: &targets.ids,
                    clear: Some(vk::ClearValue {
                        color: vk::ClearColorValue { uint32: [0; 4] },
                    }),
                },
            ],
            Some(Attachment {
                image: &targets.depth,
                clear: Some(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: 0.0,
                        stencil: 0,
                    },
                }),
            }),
            1,
        );
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        cmd.bind_index_buffer(&scene.indices);
        for d in &scene.draws {
            cmd.bind_set(&self.pipeline, 1, &self.material_sets[d.material as usize]);
            let push = ScenePush {
                object_index: d.object,
            };
            cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
            cmd.draw_indexed(d.index_count, 1, d.first_index, 0);
        }
        cmd.end_rendering();
        profiler.end(cmd, scope);
    }
}
