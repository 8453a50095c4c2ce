//! `deferred`'s lighting pass (shaders/deferred/lighting.comp): the G-buffer's surfaces through
//! the forward pass's `shade`, the extra point lights and the VPLs, into the RGBA16F frame. For
//! `interleaved` the same pass takes the VPLs' light from the gathered sub-image estimates through
//! its filter (the INTERLEAVED define, shaders/interleaved/filter.glsl).

use cbr_gpu::{Buffer, Cmd, Image, Profiler, Result};

use super::config::DeferredConfig;
use super::gbuffer::GBuffer;
use super::vpl::SunView;
use crate::gpu_scene::GpuScene;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, Use};
use crate::technique::{BuildCtx, FrameCtx};

crate::push_constants! {
    /// Push constants (lighting.comp's).
    pub struct LightingPush {
        /// rgb: the background radiance.
        background: [f32; 4],
        /// Extra point lights, VPLs, width, height.
        counts: [u32; 4],
        /// x: the VPL clamp c of 1/max(d^2, c), in m^2.
        params: [f32; 4],
    }
}

/// The sun's map this frame.
pub struct SunFrame {
    /// `None`: nothing of the scene within reach; the map stays empty.
    pub view: Option<SunView>,
    /// The VPL clamp c of 1/max(d^2, c), in m^2.
    pub clamp_d2: f32,
}

/// The defines of `deferred`'s lighting pass (gpu_types' layout test compiles with them).
pub fn shader_defines() -> Vec<(String, String)> {
    decl(None).all_defines()
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

/// `interleaved`'s variant of the pass: the filter that combines the M x N sub-images'
/// estimates (shaders/interleaved/filter.glsl) and what it reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterleavedLighting {
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
    /// `direct`: the point lights' specular estimates are filtered too (the DIRECT define).
    pub direct: bool,
    /// `debug`: the pass writes its debug bits (the DEBUG define).
    pub debug: bool,
}

/// `interleaved`'s VPL light: the M x N sub-images' estimates gathered back to full resolution.
pub struct Interleaving<'a> {
    pub variant: InterleavedLighting,
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

/// The lighting pass (shaders/deferred/lighting.comp): `deferred`'s, or with `interleaving`
/// `interleaved`'s variant (the VPLs' light from the sub-image estimates).
pub fn decl(interleaving: Option<&InterleavedLighting>) -> ComputeDecl {
    let name = match interleaving {
        None => "deferred.lighting",
        Some(_) => "interleaved.lighting",
    };
    let mut d = ComputeDecl::new(name, "deferred/lighting.comp")
        .bindings(&[
            Binding::uniform("frame"),
            Binding::buffer("objects", Use::Read),
            Binding::buffer("materials", Use::Read),
            Binding::buffer("lights", Use::Read),
            Binding::buffer("points", Use::Read),
            Binding::buffer("vpls", Use::Read),
            Binding::buffer("counter", Use::ReadWrite),
            Binding::sampled("position"),
            Binding::sampled("normal"),
            Binding::sampled("albedo"),
            Binding::sampled("ids"),
            Binding::image("out_color", Use::Write),
        ])
        .push::<LightingPush>();
    if let Some(i) = interleaving {
        d = d
            .define("INTERLEAVED", 1)
            .define("TILE_M", i.m)
            .define("TILE_N", i.n)
            .define("FILTER", i.filter)
            .define("SEARCH", i.search)
            .define("EXACT_EDGES", i.exact_edges)
            .define("ENOUGH", i.enough)
            // `{:?}` keeps the decimal point (0.9, 1.0, 1e-5): a GLSL float literal.
            .define("SAME_NORMAL_COS", format!("{:?}", i.same_normal_cos))
            .define("PLANE_TOLERANCE", format!("{:?}", i.plane_tolerance))
            // The gathered sub-image estimates of the VPLs' irradiance, and (`direct`) of the
            // point lights' specular: without `direct` the binding holds the irradiance, never
            // read.
            .bind(Binding::sampled("irradiance"))
            .bind(Binding::sampled("specular"));
        if i.debug {
            d = d
                .define("DEBUG", 1)
                .bind(Binding::image("debug_bits", Use::Write));
        }
        if i.box_rows {
            d = d.define("BOX_ROWS", 1);
        }
        if i.direct {
            d = d.define("DIRECT", 1);
        }
    }
    d
}

pub struct LightingPass {
    pass: ComputePass,
}

impl LightingPass {
    /// The pass; with `interleaving`, the VPLs' light comes from the sub-image estimates
    /// instead of every VPL at every pixel.
    pub fn new(ctx: &BuildCtx, interleaving: Option<&InterleavedLighting>) -> Result<LightingPass> {
        Ok(LightingPass {
            pass: decl(interleaving).build(ctx.gpu, ctx.shaders)?,
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        g: &GBuffer,
        sources: &LightSources,
        counter: &Buffer,
        push: &LightingPush,
        interleaving: Option<&Interleaving>,
    ) -> Result<()> {
        let mut binds = Binds::new()
            .buffer("frame", &scene.frame)
            .buffer("objects", &scene.objects)
            .buffer("materials", &scene.materials)
            .buffer("lights", &scene.lights)
            .buffer("points", sources.points)
            .buffer("vpls", sources.vpls)
            .buffer("counter", counter)
            .image("position", &g.position)
            .image("normal", &g.normal)
            .image("albedo", &g.albedo)
            .image("ids", &g.ids)
            .image("out_color", &g.color);
        if let Some(i) = interleaving {
            binds = binds
                .image("irradiance", i.irradiance)
                .image("specular", i.specular.unwrap_or(i.irradiance));
            if let Some(d) = i.debug {
                binds = binds.image("debug_bits", d);
            }
        }
        let [_, _, w, h] = push.counts;
        self.pass.dispatch_2d(cmd, profiler, &binds, push, (w, h))
    }
}
