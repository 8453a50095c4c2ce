//! `deferred`'s lighting pass (shaders/deferred/lighting.comp): the G-buffer's surfaces through
//! the forward pass's `shade`, the extra point lights and the VPLs, into the RGBA16F frame. For
//! `interleaved` the same pass takes the VPLs' light from the gathered sub-image estimates through
//! its filter (the INTERLEAVED define, shaders/interleaved/filter.glsl).

use bytemuck::{Pod, Zeroable};
use cbr_gpu::{
    Access, BindingDesc, Buffer, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Image, PassKind,
    Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Write,
};

use super::config::DeferredConfig;
use super::gbuffer::GBuffer;
use super::vpl::SunView;
use crate::technique::{BuildCtx, FrameCtx};

/// The lighting pass's set: the one definition of its bindings.
pub const BINDINGS: [BindingDesc; 15] = {
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
        // `interleaved` only: the gathered sub-image estimates of the VPLs' irradiance.
        BindingDesc::one("irradiance", 12, S),
        // `interleaved:...:debug` only: the debug bits (shaders/interleaved/filter.glsl).
        BindingDesc::one("debug_bits", 13, I),
        // `interleaved:...:direct` only: the point lights' specular estimates.
        BindingDesc::one("specular", 14, S),
    ]
};

/// The sun's map this frame.
pub struct SunFrame {
    /// `None`: nothing of the scene within reach; the map stays empty.
    pub view: Option<SunView>,
    /// The VPL clamp c of 1/max(d^2, c), in m^2.
    pub clamp_d2: f32,
}

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

impl LightingPush {
    /// This frame's constants for `config`'s lights at `size`.
    pub fn new(
        ctx: &FrameCtx,
        config: &DeferredConfig,
        size: (u32, u32),
        sun: Option<&SunFrame>,
    ) -> LightingPush {
        let bg = ctx.gpu_scene.background;
        LightingPush {
            background: [bg[0], bg[1], bg[2], 0.0],
            counts: [config.points, config.vpls, size.0, size.1],
            params: [sun.map_or(1.0, |s| s.clamp_d2), 0.0, 0.0, 0.0],
        }
    }
}

/// `interleaved`'s VPL light: the M x N sub-images' estimates gathered back to full resolution,
/// and the filter that combines them (shaders/interleaved/filter.glsl).
pub struct Interleaving<'a> {
    pub m: u32,
    pub n: u32,
    /// The SEARCH define (`ours` only): 1 looks one period beyond the window.
    pub search: u32,
    /// The EXACT_EDGES define (`ours` only): R > 0 makes a pixel with a pixel off its surface
    /// within R (a square) shade every subset itself; 0 off.
    pub exact_edges: u32,
    /// The ENOUGH define (`ours` only): found subsets that spare the fallback.
    pub enough: u32,
    /// The SAME_NORMAL_COS and PLANE_TOLERANCE defines (`ours` only): its same-surface test.
    pub same_normal_cos: f32,
    pub plane_tolerance: f32,
    /// The FILTER define: 0 none (each pixel its own subset), 1 box over the M x N window,
    /// 2 ours (geometry-aware), 3 seed (the image is already the seed's blur).
    pub filter: u32,
    /// The BOX_ROWS define (`box` with the split passes): `irradiance` (and `specular`) hold
    /// each pixel's window row summed by the gather, not its own estimate.
    pub box_rows: bool,
    pub irradiance: &'a Image,
    /// `direct`: the point lights' specular estimates (the DIRECT define).
    pub specular: Option<&'a Image>,
    /// `debug`: the R32UI image the pass writes its debug bits to.
    pub debug: Option<&'a Image>,
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
    name: &'static str,
}

impl LightingPass {
    /// The pass over `g` lighting with `sources`; with `interleaving`, the VPLs' light comes from
    /// the sub-image estimates instead of every VPL at every pixel.
    pub fn new(
        ctx: &BuildCtx,
        g: &GBuffer,
        sources: &LightSources,
        interleaving: Option<&Interleaving>,
    ) -> Result<LightingPass> {
        let gpu = ctx.gpu;
        let name = match interleaving {
            None => "deferred.lighting",
            Some(_) => "interleaved.lighting",
        };
        let layout = SetLayout::new(gpu, &format!("{name}.set_layout"), &BINDINGS)?;
        let mut defines = shader_defines();
        if let Some(i) = interleaving {
            for (k, v) in [
                ("INTERLEAVED", 1),
                ("TILE_M", i.m),
                ("TILE_N", i.n),
                ("FILTER", i.filter),
                ("SEARCH", i.search),
                ("EXACT_EDGES", i.exact_edges),
                ("ENOUGH", i.enough),
            ] {
                defines.push((k.into(), v.to_string()));
            }
            // `{:?}` keeps the decimal point (0.9, 1.0, 1e-5): a GLSL float literal.
            defines.push(("SAME_NORMAL_COS".into(), format!("{:?}", i.same_normal_cos)));
            defines.push(("PLANE_TOLERANCE".into(), format!("{:?}", i.plane_tolerance)));
            if i.debug.is_some() {
                defines.push(("DEBUG".into(), "1".into()));
            }
            if i.box_rows {
                defines.push(("BOX_ROWS".into(), "1".into()));
            }
            if i.specular.is_some() {
                defines.push(("DIRECT".into(), "1".into()));
            }
        }
        let cs = ctx.shaders.compile("deferred/lighting.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name,
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: std::mem::size_of::<LightingPush>() as u32,
            },
        )?;
        let sampler = Sampler::new(gpu, &format!("{name}.sampler"), SamplerDesc::NEAREST)?;
        let scene = ctx.scene;
        let mut writes = vec![
            Write::Buffer(0, &scene.frame),
            Write::Buffer(1, &scene.objects),
            Write::Buffer(2, &scene.materials),
            Write::Buffer(3, &scene.lights),
            Write::Buffer(4, sources.points),
            Write::Buffer(5, sources.vpls),
            Write::Buffer(6, ctx.counter),
            Write::Sampled(7, vec![(&g.position, &sampler)]),
            Write::Sampled(8, vec![(&g.normal, &sampler)]),
            Write::Sampled(9, vec![(&g.albedo, &sampler)]),
            Write::Sampled(10, vec![(&g.ids, &sampler)]),
            Write::Storage(11, &g.color),
        ];
        // Without interleaving the binding is never read, but it holds an image: lavapipe crashes
        // binding a set with an unwritten sampler.
        let irradiance = interleaving.map_or(&g.albedo, |i| i.irradiance);
        writes.push(Write::Sampled(12, vec![(irradiance, &sampler)]));
        // Likewise the debug bits: the frame (a storage image) where there are none.
        let debug = interleaving.and_then(|i| i.debug).unwrap_or(&g.color);
        writes.push(Write::Storage(13, debug));
        let specular = interleaving.and_then(|i| i.specular).unwrap_or(irradiance);
        writes.push(Write::Sampled(14, vec![(specular, &sampler)]));
        let set = DescriptorSet::new(gpu, &format!("{name}.set"), &layout, &writes)?;
        Ok(LightingPass {
            pipeline,
            _layout: layout,
            set,
            _sampler: sampler,
            name,
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
        interleaving: Option<&Interleaving>,
    ) {
        for img in [&g.position, &g.normal, &g.albedo, &g.ids] {
            cmd.use_image(img, Access::ComputeSampled);
        }
        if let Some(i) = interleaving {
            cmd.use_image(i.irradiance, Access::ComputeSampled);
            if let Some(s) = i.specular {
                cmd.use_image(s, Access::ComputeSampled);
            }
            if let Some(d) = i.debug {
                cmd.use_image(d, Access::ComputeStorageWrite);
            }
        }
        cmd.use_image(&g.color, Access::ComputeStorageWrite);
        cmd.use_buffer(sources.points, Access::ComputeSampled);
        cmd.use_buffer(sources.vpls, Access::ComputeSampled);
        cmd.use_buffer(counter, Access::ComputeStorageReadWrite);
        let scope = profiler.begin(cmd, self.name, PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(push));
        let [_, _, w, h] = push.counts;
        cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
        profiler.end(cmd, scope);
    }
}
