//! `deferred`'s lighting pass (shaders/deferred/lighting.comp): the G-buffer's surfaces through
//! the forward pass's `shade`, the extra point lights and the VPLs, into the RGBA16F frame.

use bytemuck::{Pod, Zeroable};
use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, PassKind,
    Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Shaders, Write,
};

use super::GBuffer;
use crate::gpu_scene::GpuScene;

/// The lighting pass's set: the one definition of its bindings.
pub const BINDINGS: [BindingDesc; 12] = {
    use DescriptorKind::{
        CombinedImageSampler as S, StorageBuffer as B, StorageImage as I, UniformBuffer as U,
    };
    [
        BindingDesc::one("frame", 0, U),
        BindingDesc::one("objects", 1, B),
        BindingDesc::one("materials", 2, B),
        BindingDesc::one("lights", 3, B),
        BindingDesc::one("points", 4, B),
        BindingDesc::one("vpls", 5, B),
        BindingDesc::one("counter", 6, B),
        BindingDesc::one("position", 7, S),
        BindingDesc::one("normal", 8, S),
        BindingDesc::one("albedo", 9, S),
        BindingDesc::one("ids", 10, S),
        BindingDesc::one("out_color", 11, I),
    ]
};

pub fn shader_defines() -> Vec<(String, String)> {
    BINDINGS.iter().map(BindingDesc::define).collect()
}

/// Push constants (lighting.comp's `Push`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightingPush {
    /// rgb: the background radiance.
    pub background: [f32; 4],
    /// Extra point lights, VPLs, width, height.
    pub counts: [u32; 4],
    /// x: the VPL clamp c of 1/max(d^2, c), in m^2.
    pub params: [f32; 4],
}

/// What the lighting pass reads besides the G-buffer and the scene.
pub struct LightSources<'a> {
    /// Extra point lights (`points=N`), camera-relative, host-written each frame.
    pub points: &'a Buffer,
    /// The VPLs (`vpls=N`), written by the VPL pass this frame.
    pub vpls: &'a Buffer,
}

pub struct LightingPass {
    pipeline: Pipeline,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
}

impl LightingPass {
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &GpuScene,
        counter: &Buffer,
        g: &GBuffer,
        sources: &LightSources,
    ) -> Result<LightingPass> {
        let layout = SetLayout::new(gpu, "deferred.lighting.set_layout", &BINDINGS)?;
        let cs = shaders.compile("deferred/lighting.comp", &shader_defines())?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "deferred.lighting",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: std::mem::size_of::<LightingPush>() as u32,
            },
        )?;
        let sampler = Sampler::new(gpu, "deferred.lighting.sampler", SamplerDesc::NEAREST)?;
        let set = DescriptorSet::new(
            gpu,
            "deferred.lighting.set",
            &layout,
            &[
                Write::Buffer(0, &scene.frame),
                Write::Buffer(1, &scene.objects),
                Write::Buffer(2, &scene.materials),
                Write::Buffer(3, &scene.lights),
                Write::Buffer(4, sources.points),
                Write::Buffer(5, sources.vpls),
                Write::Buffer(6, counter),
                Write::Sampled(7, vec![(&g.position, &sampler)]),
                Write::Sampled(8, vec![(&g.normal, &sampler)]),
                Write::Sampled(9, vec![(&g.albedo, &sampler)]),
                Write::Sampled(10, vec![(&g.ids, &sampler)]),
                Write::Storage(11, &g.color),
            ],
        )?;
        Ok(LightingPass {
            pipeline,
            _layout: layout,
            set,
            _sampler: sampler,
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        g: &GBuffer,
        sources: &LightSources,
        counter: &Buffer,
        push: &LightingPush,
    ) {
        for img in [&g.position, &g.normal, &g.albedo, &g.ids] {
            cmd.use_image(img, Access::ComputeSampled);
        }
        cmd.use_image(&g.color, Access::ComputeStorageWrite);
        cmd.use_buffer(sources.points, Access::ComputeSampled);
        cmd.use_buffer(sources.vpls, Access::ComputeSampled);
        cmd.use_buffer(counter, Access::ComputeStorageReadWrite);
        let scope = profiler.begin(cmd, "deferred.lighting", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(push));
        let [_, _, w, h] = push.counts;
        cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
        profiler.end(cmd, scope);
    }
}
