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

pub mod lighting;
pub mod lights;
pub mod rsm;
pub mod vpl;

use cbr_gpu::{Access, GpuError, Image, ImageDesc, Result, vk};

use super::LayerReadbacks;
use crate::gpu_types::{LightData, Vpl};
use crate::memory::MemoryEstimate;
use crate::renderer::FrameOutput;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, GBUFFER_FORMAT, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};
use lighting::{LightingPass, LightingPush};
use lights::ManyLights;

pub const REGISTRATION: Registration = Registration {
    name: "deferred",
    grammar: "deferred[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D]",
    about: "G-buffer then a lighting pass (native's shading); `vpls=N`: one-bounce indirect light \
            from N virtual point lights of the sun's reflective shadow map; `points=N`: N random \
            point lights",
    layers: &[],
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Deferred::estimate(&parse(p)?, ctx.width, ctx.height)),
    build: |ctx, p| {
        let c = parse(p).map_err(GpuError::Other)?;
        Ok(Box::new(Deferred::new(ctx, c)?))
    },
};

/// The most VPLs: every pixel sums every VPL (16384 VPLs at 1280x720 are 15 G light terms a
/// frame, minutes on lavapipe).
pub const MAX_VPLS: u32 = 16384;
/// The most extra point lights (each pixel sums them all too).
pub const MAX_POINTS: u32 = 16384;
/// The reflective shadow map's side unless `rsm=R` says otherwise, and its bounds.
pub const DEFAULT_RSM: u32 = 512;
pub const MIN_RSM: u32 = 16;
pub const MAX_RSM: u32 = 4096;
/// How far from the camera (metres, a cube's half-side) the map frames the scene unless
/// `reach=D` says otherwise.
pub const DEFAULT_REACH: f32 = 32.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeferredConfig {
    /// VPLs from the sun's reflective shadow map (0: no indirect light).
    pub vpls: u32,
    /// Random point lights added to the scene's (deterministic per scene seed).
    pub points: u32,
    /// The reflective shadow map's side in texels.
    pub rsm: u32,
    /// The map frames the scene within this many metres of the camera (a cube's half-side); the
    /// random point lights fill the scene within this many metres of the camera path.
    pub reach: f32,
    /// The VPL clamp distance in metres (1/max(d^2, clamp^2)); `None`: the VPLs' mean spacing,
    /// sqrt(map area / N).
    pub clamp: Option<f32>,
}

fn count(key: &str, value: &str, max: u32, what: &str) -> std::result::Result<u32, String> {
    let n: u64 = value
        .parse()
        .map_err(|_| format!("deferred {key}=`{value}`: give a whole number from 0 to {max}"))?;
    if n > u64::from(max) {
        return Err(format!(
            "deferred {key}={n}: at most {max} {what} (every pixel sums every one)"
        ));
    }
    Ok(n as u32)
}

fn metres(key: &str, value: &str) -> std::result::Result<f32, String> {
    value
        .parse()
        .ok()
        .filter(|d: &f32| d.is_finite() && *d > 0.0 && *d <= 1e9)
        .ok_or_else(|| {
            format!("deferred {key}=`{value}`: a distance in metres, above 0, at most 1e9")
        })
}

pub fn parse(params: &[&str]) -> std::result::Result<DeferredConfig, String> {
    let mut c = DeferredConfig {
        vpls: 0,
        points: 0,
        rsm: DEFAULT_RSM,
        reach: DEFAULT_REACH,
        clamp: None,
    };
    for p in params {
        let (key, value) = p.split_once('=').unwrap_or((p, ""));
        match key {
            "vpls" => c.vpls = count(key, value, MAX_VPLS, "VPLs")?,
            "points" => c.points = count(key, value, MAX_POINTS, "point lights")?,
            "rsm" => {
                c.rsm = value
                    .parse()
                    .ok()
                    .filter(|r| (MIN_RSM..=MAX_RSM).contains(r))
                    .ok_or_else(|| {
                        format!("deferred rsm=`{value}`: a side from {MIN_RSM} to {MAX_RSM} texels")
                    })?
            }
            "clamp" => c.clamp = Some(metres(key, value)?),
            "reach" => c.reach = metres(key, value)?,
            _ => {
                return Err(unknown_param(
                    "deferred",
                    p,
                    "vpls=N, points=N, rsm=R, reach=D, clamp=D",
                ));
            }
        }
    }
    if u64::from(c.vpls) > u64::from(c.rsm) * u64::from(c.rsm) {
        return Err(format!(
            "deferred vpls={}: more VPLs than the {}x{} reflective shadow map has texels",
            c.vpls, c.rsm, c.rsm
        ));
    }
    Ok(c)
}

/// The G-buffer (the scene pass's targets with GBUFFER) and the lit frame.
pub struct GBuffer {
    pub position: Image,
    pub normal: Image,
    pub albedo: Image,
    pub velocity: Image,
    pub ids: Image,
    pub depth: Image,
    /// RGBA16F, written by the lighting pass.
    pub color: Image,
}

impl GBuffer {
    pub fn new(gpu: &cbr_gpu::Gpu, prefix: &str, width: u32, height: u32) -> Result<GBuffer> {
        use vk::ImageUsageFlags as U;
        let img = |name: &str, format, usage| {
            let name = format!("{prefix}.{name}");
            Image::new(gpu, &ImageDesc::new_2d(&name, format, width, height, usage))
        };
        let attachment = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;
        Ok(GBuffer {
            position: img("position", GBUFFER_FORMAT, attachment)?,
            normal: img("normal", GBUFFER_FORMAT, attachment)?,
            albedo: img("albedo", GBUFFER_FORMAT, attachment)?,
            velocity: img("velocity", VELOCITY_FORMAT, attachment)?,
            ids: img("ids", ID_FORMAT, attachment)?,
            depth: img(
                "depth",
                DEPTH_FORMAT,
                U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC,
            )?,
            color: img(
                "color",
                COLOR_FORMAT,
                U::STORAGE | U::SAMPLED | U::TRANSFER_SRC,
            )?,
        })
    }

    /// The G-buffer pass's colour attachments, in the pipeline's order.
    pub fn attachments(&self) -> [&Image; 5] {
        [
            &self.position,
            &self.normal,
            &self.albedo,
            &self.velocity,
            &self.ids,
        ]
    }

    /// Velocity, depth and IDs for temporal post passes.
    pub fn geometry(&self) -> Geometry<'_> {
        Geometry {
            velocity: &self.velocity,
            depth: &self.depth,
            ids: &self.ids,
            packed: false,
        }
    }

    /// Colour, depth, velocity, IDs: the common layers.
    pub fn layers(&self) -> [&Image; 4] {
        [&self.color, &self.depth, &self.velocity, &self.ids]
    }

    /// Bytes per pixel: three f32 RGBA surface layers, velocity, IDs, depth and the frame.
    pub const BYTES_PER_PIXEL: u64 = 3 * 16 + 8 + 8 + 4 + 8;
}

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
        let lighting = LightingPass::new(ctx, &g, &lights.sources(), None)?;
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
    for name in ["position", "normal", "albedo"] {
        e.image(format!("{prefix}.{name}"), GBUFFER_FORMAT, w, h);
    }
    e.image(format!("{prefix}.velocity"), VELOCITY_FORMAT, w, h);
    e.image(format!("{prefix}.ids"), ID_FORMAT, w, h);
    e.image(format!("{prefix}.depth"), DEPTH_FORMAT, w, h);
    e.image(format!("{prefix}.color"), COLOR_FORMAT, w, h);
    let light = std::mem::size_of::<LightData>() as u64;
    e.storage_buffer(
        format!("{prefix}.points"),
        u64::from(config.points.max(1)) * light,
        true,
    );
    let vpl_bytes = u64::from(config.vpls.max(1)) * std::mem::size_of::<Vpl>() as u64;
    e.storage_buffer(format!("{prefix}.vpls"), vpl_bytes, false);
    if config.vpls > 0 {
        let side = config.rsm;
        for name in ["position", "normal", "flux"] {
            e.image(format!("deferred.rsm.{name}"), GBUFFER_FORMAT, side, side);
        }
        e.image("deferred.rsm.depth", DEPTH_FORMAT, side, side);
        e.storage_buffer("deferred.vpl_texels", u64::from(config.vpls) * 8, true);
        e.buffer("readback.vpls", vpl_bytes, true);
    }
}

/// The frame's layers read back, with the frame's VPLs (deferred and interleaved).
pub fn output(
    readbacks: &LayerReadbacks,
    lights: &ManyLights,
    ctx: &FrameCtx,
) -> Result<FrameOutput> {
    let mut out = readbacks.output(ctx.view.width, ctx.view.height, ctx.view.camera.near)?;
    out.vpls = lights.read_vpls()?;
    Ok(out)
}

pub fn gbuffer(ctx: &BuildCtx, name: &str) -> Result<(RasterConfig, ScenePass, GBuffer)> {
    let (w, h) = (ctx.width, ctx.height);
    let raster = RasterConfig {
        gbuffer: true,
        depth_prepass: true,
        ..RasterConfig::native(w, h)
    };
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
            this.gbuffer_pass.record(
                cmd,
                profiler,
                gs,
                &g.attachments(),
                &g.depth,
                counter,
                &this.raster,
            );
            this.lights.record(cmd, profiler, gs, sun.as_ref());
            this.lighting.record(
                cmd,
                profiler,
                g,
                &this.lights.sources(),
                counter,
                &push,
                None,
            );
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
        u64::from(w) * u64::from(h) * GBuffer::BYTES_PER_PIXEL + self.lights.bytes()
    }
}
