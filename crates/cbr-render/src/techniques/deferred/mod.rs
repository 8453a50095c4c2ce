//! `deferred[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D]`: deferred shading
//! (docs/interleaved.md).
//!
//! Passes per frame, one submission: (1) `deferred.gbuffer`, the scene pass with the GBUFFER
//! define (shaders/scene/forward.frag stops before lighting and writes the surface it would shade:
//! position, shading normal, albedo in f32, with native's velocity, IDs and depth); with `vpls=N`
//! (2) `deferred.rsm`, the reflective shadow map from the sun and (3) `deferred.vpls`, N virtual
//! point lights at a seeded low-discrepancy pattern of its texels; (4) `deferred.lighting`, a
//! compute pass calling the forward pass's `shade` on the G-buffer, then the `points=N` random
//! point lights through the same light term, then the VPLs' one-bounce indirect light. Without
//! extra lights it equals `native` within fp16 rounding (tests/deferred.rs). With them it is the
//! reference the interleaved technique approximates: every light at every pixel.

pub mod config;
pub mod gbuffer;
pub mod lighting;
pub mod lights;
pub mod rsm;
pub mod vpl;

use cbr_gpu::{Access, Image, Result};

use super::LayerReadbacks;
use crate::frame::{FrameOutput, LayerDecl, SampleType};
use crate::gpu_types::Vpl;
use crate::memory::MemoryEstimate;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Outputs, Registration, Technique};
pub use config::*;
pub use gbuffer::GBuffer;
use lighting::{LightingPass, LightingPush};
use lights::ManyLights;

pub const REGISTRATION: Registration = Registration {
    name: "deferred",
    grammar: "deferred[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D]",
    about: "G-buffer then a lighting pass (native's shading); `vpls=N`: one-bounce indirect light \
            from N virtual point lights of the sun's reflective shadow map; `points=N`: N random \
            point lights",
    outputs: Outputs {
        layers: &[VPL_LAYER],
        ..Outputs::NONE
    },
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Deferred::estimate(&parse(p)?, ctx.width, ctx.height)),
    passes: |ctx, p| {
        let c = parse(p)?;
        let mut compute = vec![lighting::decl_culled(None, c.cull)];
        if c.vpls > 0 {
            compute.push(rsm::vpl_decl());
        }
        Ok(crate::technique::PassList {
            compute,
            graphics: raster_decls(ctx, "deferred", c.vpls)?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("deferred", p, e))?;
        Ok(Box::new(Deferred::new(ctx, c)?))
    },
};

/// The most VPLs: every pixel sums every VPL (16384 VPLs at 1280x720 are 15 G light terms a
/// frame, minutes on lavapipe).
/// The technique: G-buffer, optional RSM + VPLs, lighting, readbacks.
pub struct Deferred {
    config: DeferredConfig,
    raster: RasterConfig,
    gbuffer_pass: ScenePass,
    g: GBuffer,
    lights: ManyLights,
    lighting: LightingPass,
    readbacks: LayerReadbacks,
    size: (u32, u32),
}

impl Deferred {
    /// What [`Deferred::new`] allocates (crate::memory): [`estimate_gbuffer_and_lights`] and the
    /// readbacks.
    pub fn estimate(config: &DeferredConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        estimate_gbuffer_and_lights(&mut e, "deferred", config, w, h);
        LayerReadbacks::estimate(&mut e, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx, config: DeferredConfig) -> Result<Deferred> {
        let lights = ManyLights::new(ctx, &config, "deferred")?;
        let (raster, gbuffer_pass, g) = gbuffer(ctx, "deferred")?;
        let lighting = LightingPass::new(ctx, None, config.cull)?;
        let readbacks = LayerReadbacks::new(ctx.gpu, g.layers())?;
        Ok(Deferred {
            config,
            raster,
            gbuffer_pass,
            g,
            lights,
            lighting,
            readbacks,
            size: (ctx.width, ctx.height),
        })
    }
}

/// The G-buffer pass (native's raster with `RasterConfig::gbuffer`) and its targets.
/// What [`gbuffer`] and [`ManyLights::new`] allocate under `prefix` (crate::memory): the
/// G-buffer and frame, the light buffers and, with VPLs, the sun's map, its VPL pattern and the
/// VPL readback.
pub fn estimate_gbuffer_and_lights(
    e: &mut MemoryEstimate,
    prefix: &str,
    config: &DeferredConfig,
    w: u32,
    h: u32,
) {
    use crate::pass::estimate;
    e.append(estimate(&GBuffer::decls(w, h), prefix));
    e.append(estimate(&lights::resources(config), prefix));
    if config.vpls > 0 {
        e.append(estimate(&rsm::resources(config.rsm), "deferred.rsm"));
        e.append(estimate(&[rsm::texels(config.vpls)], "deferred"));
        e.append(estimate(&[lights::vpl_readback(config)], "readback"));
    }
}

/// The frame's layers read back, with the frame's VPLs (deferred and interleaved).
pub fn output(
    readbacks: &LayerReadbacks,
    lights: &ManyLights,
    ctx: &FrameCtx,
) -> Result<FrameOutput> {
    let mut out = readbacks.output(ctx.view.width, ctx.view.height, ctx.view.camera.near)?;
    if let Some(vpls) = lights.read_vpls()? {
        out.layers.push(vpl_layer(&vpls)?);
    }
    Ok(out)
}

/// `vpls` (`vpls=N`): the frame's N virtual point lights, camera-relative, as an N x 1 layer of
/// [`Vpl`]'s twelve floats; on the host only (no image: not in the EXR).
pub const VPL_LAYER: LayerDecl = LayerDecl {
    name: "vpls",
    channels: &[
        "position.x",
        "position.y",
        "position.z",
        "position.w",
        "normal.x",
        "normal.y",
        "normal.z",
        "normal.w",
        "flux.x",
        "flux.y",
        "flux.z",
        "flux.w",
    ],
    samples: SampleType::F32,
    exr: None,
    about: "the frame's virtual point lights (position, w: alive; normal; flux), camera-relative",
};

fn vpl_layer(vpls: &[Vpl]) -> Result<crate::frame::Layer> {
    let floats = |v: &Vpl| -> [f32; 12] { bytemuck::cast(*v) };
    let planes = (0..12)
        .map(|c| vpls.iter().map(|v| floats(v)[c]).collect())
        .collect();
    VPL_LAYER.layer(vpls.len() as u32, 1, planes)
}

/// A frame's VPLs (`deferred:vpls=N`, `interleaved`), when it has them.
pub fn vpls(out: &FrameOutput) -> Option<Vec<Vpl>> {
    let l = out.layer(VPL_LAYER.name)?;
    let planes: Vec<&[f32]> = VPL_LAYER
        .channels
        .iter()
        .map(|c| l.channel::<f32>(c))
        .collect::<Option<_>>()?;
    Some(
        (0..l.width as usize)
            .map(|i| {
                let mut f = [0f32; 12];
                for (c, p) in planes.iter().enumerate() {
                    f[c] = p[i];
                }
                bytemuck::cast(f)
            })
            .collect(),
    )
}

/// The G-buffer raster: native's with the surface written instead of its shading, after a depth
/// pre-pass.
fn gbuffer_raster(w: u32, h: u32) -> RasterConfig {
    RasterConfig {
        gbuffer: true,
        depth_prepass: true,
        ..RasterConfig::native(w, h)
    }
}

/// The raster pipelines of `deferred` and `interleaved` (named `name`) with `vpls` VPLs: the
/// G-buffer pass's and, with VPLs, the sun's map's (the compile-only list).
pub fn raster_decls(
    ctx: &crate::technique::PassCtx,
    name: &str,
    vpls: u32,
) -> std::result::Result<Vec<crate::pass::GraphicsDecl>, String> {
    let mut d = crate::scene_pass::listed(
        &format!("{name}.gbuffer"),
        &gbuffer_raster(ctx.width, ctx.height),
        ctx.materials,
    )?;
    if vpls > 0 {
        d.push(rsm::decl());
    }
    Ok(d)
}

pub fn gbuffer(ctx: &BuildCtx, name: &str) -> Result<(RasterConfig, ScenePass, GBuffer)> {
    let (w, h) = (ctx.width, ctx.height);
    let raster = gbuffer_raster(w, h);
    let pass = ScenePass::new(
        ctx.gpu,
        ctx.shaders,
        ctx.scene,
        &format!("{name}.gbuffer"),
        &raster,
        ctx.counter,
    )?;
    Ok((raster, pass, GBuffer::new(ctx.gpu, name, w, h)?))
}

impl Technique for Deferred {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let sun = self.lights.prepare(ctx)?;
        let push = LightingPush::new(ctx, &self.config, self.size, sun.as_ref());
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let g = &this.g;
            this.gbuffer_pass
                .record(cmd, profiler, gs, &g.bind(), counter, &this.raster)?;
            this.lights.record(cmd, profiler, gs, sun.as_ref())?;
            this.lighting.record(
                cmd,
                profiler,
                gs,
                g,
                &this.lights.sources(),
                counter,
                &push,
                None,
            )?;
            this.readbacks.record(cmd, profiler, g.layers());
            this.lights.record_readback(cmd);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.g.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(self.g.geometry())
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        output(&self.readbacks, &self.lights, ctx)
    }

    fn target_bytes(&self) -> u64 {
        let (w, h) = self.size;
        GBuffer::bytes(w, h) + self.lights.bytes()
    }
}
