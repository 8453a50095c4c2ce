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
pub mod rsm;
pub mod vpl;

use cbr_gpu::{Access, Buffer, GpuError, Image, ImageDesc, Location, Result, vk};
use cbr_scene::PointLight;
use glam::DVec3;

use super::LayerReadbacks;
use crate::gpu_types::{LightData, Vpl};
use crate::memory::MemoryEstimate;
use crate::renderer::FrameOutput;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, GBUFFER_FORMAT, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};
use lighting::{LightSources, LightingPass, LightingPush};
use rsm::{RsmPass, VplPass};
use vpl::SunView;

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
    pub fn new(gpu: &cbr_gpu::Gpu, width: u32, height: u32) -> Result<GBuffer> {
        use vk::ImageUsageFlags as U;
        let img = |name: &str, format, usage| {
            let name = format!("deferred.{name}");
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
    lighting: LightingPass,
    /// The `points=N` lights (world), drawn at the first frame from the scene's seed.
    point_lights: Option<Vec<PointLight>>,
    points: Buffer,
    rsm: Option<RsmPass>,
    vpl_pass: Option<VplPass>,
    /// The VPLs (device-local; one unread VPL when there are none), read by the lighting pass.
    vpls: Buffer,
    vpl_readback: Option<Buffer>,
    /// The scene seed the VPL pattern was written for.
    texels_seed: Option<u64>,
    local_bounds: Option<Vec<Option<(DVec3, DVec3)>>>,
    readbacks: LayerReadbacks,
    size: (u32, u32),
}

impl Deferred {
    /// What [`Deferred::new`] allocates (crate::memory): the G-buffer and frame, the light
    /// buffers, with VPLs the sun's map, its VPL pattern and the VPL readback, and the readbacks.
    pub fn estimate(config: &DeferredConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        for name in ["position", "normal", "albedo"] {
            e.image(format!("deferred.{name}"), GBUFFER_FORMAT, w, h);
        }
        e.image("deferred.velocity", VELOCITY_FORMAT, w, h);
        e.image("deferred.ids", ID_FORMAT, w, h);
        e.image("deferred.depth", DEPTH_FORMAT, w, h);
        e.image("deferred.color", COLOR_FORMAT, w, h);
        let light = std::mem::size_of::<LightData>() as u64;
        e.storage_buffer(
            "deferred.points",
            u64::from(config.points.max(1)) * light,
            true,
        );
        let vpl_bytes = u64::from(config.vpls.max(1)) * std::mem::size_of::<Vpl>() as u64;
        e.storage_buffer("deferred.vpls", vpl_bytes, false);
        if config.vpls > 0 {
            let side = config.rsm;
            for name in ["position", "normal", "flux"] {
                e.image(format!("deferred.rsm.{name}"), GBUFFER_FORMAT, side, side);
            }
            e.image("deferred.rsm.depth", DEPTH_FORMAT, side, side);
            e.storage_buffer("deferred.vpl_texels", u64::from(config.vpls) * 8, true);
            e.buffer("readback.vpls", vpl_bytes, true);
        }
        LayerReadbacks::estimate(&mut e, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx, config: DeferredConfig) -> Result<Deferred> {
        if config.vpls > 0 && ctx.scene.light_count.0 == 0 {
            return Err(GpuError::Other(format!(
                "deferred:vpls={}: the VPLs come from a reflective shadow map rendered from the \
                 sun, the scene's first directional light, and this scene has none (use vpls=0; \
                 points=N adds point lights)",
                config.vpls
            )));
        }
        let (gpu, (w, h)) = (ctx.gpu, (ctx.width, ctx.height));
        let raster = RasterConfig {
            gbuffer: true,
            ..RasterConfig::native(w, h)
        };
        let gbuffer_pass = ScenePass::new(
            gpu,
            ctx.shaders,
            ctx.scene,
            "deferred.gbuffer",
            &raster,
            ctx.counter,
        )?;
        let g = GBuffer::new(gpu, w, h)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let points = Buffer::new(
            gpu,
            "deferred.points",
            u64::from(config.points.max(1)) * std::mem::size_of::<LightData>() as u64,
            storage,
            Location::CpuToGpu,
        )?;
        let vpls = Buffer::new(
            gpu,
            "deferred.vpls",
            u64::from(config.vpls.max(1)) * std::mem::size_of::<Vpl>() as u64,
            storage | vk::BufferUsageFlags::TRANSFER_SRC,
            Location::GpuOnly,
        )?;
        let (rsm, vpl_pass, vpl_readback) = if config.vpls > 0 {
            let rsm = RsmPass::new(gpu, ctx.shaders, ctx.scene, ctx.counter, config.rsm)?;
            let vp = VplPass::new(gpu, ctx.shaders, &rsm, &vpls, config.vpls)?;
            let rb = Buffer::new(
                gpu,
                "readback.vpls",
                vpls.size(),
                vk::BufferUsageFlags::TRANSFER_DST,
                Location::GpuToCpu,
            )?;
            (Some(rsm), Some(vp), Some(rb))
        } else {
            (None, None, None)
        };
        let sources = LightSources {
            points: &points,
            vpls: &vpls,
        };
        let lighting = LightingPass::new(gpu, ctx.shaders, ctx.scene, ctx.counter, &g, &sources)?;
        let readbacks = LayerReadbacks::new(gpu, g.layers())?;
        Ok(Deferred {
            config,
            raster,
            gbuffer_pass,
            g,
            lighting,
            point_lights: None,
            points,
            rsm,
            vpl_pass,
            vpls,
            vpl_readback,
            texels_seed: None,
            local_bounds: None,
            readbacks,
            size: (w, h),
        })
    }

    /// Writes this frame's extra point lights and, with VPLs, the pattern (once per seed); returns
    /// where the sun's map looks (`None` inside: nothing of the scene within reach, the map stays
    /// empty) and the VPL clamp c (m^2).
    fn prepare(&mut self, ctx: &FrameCtx) -> Result<Option<SunFrame>> {
        let scene = ctx.scene;
        let camera = ctx.view.camera.position;
        let reach = f64::from(self.config.reach);
        if self.config.points > 0 {
            let lights = self
                .point_lights
                .get_or_insert_with(|| vpl::random_point_lights(scene, self.config.points, reach));
            let data = vpl::light_data(lights, camera);
            self.points.write(0, bytemuck::cast_slice(&data))?;
        }
        let Some(vp) = self.vpl_pass.as_mut() else {
            return Ok(None);
        };
        let (n, side) = (self.config.vpls, self.config.rsm);
        let seed = scene.settings.seed;
        if self.texels_seed != Some(seed) {
            vp.write_texels(&vpl::vpl_texels(seed, n, side))?;
            self.texels_seed = Some(seed);
        }
        let sun = scene.directional.first().ok_or_else(|| {
            GpuError::Other("deferred: the VPLs need a directional light (the sun)".into())
        })?;
        let local = self
            .local_bounds
            .get_or_insert_with(|| vpl::local_bounds(scene));
        let bounds = vpl::bounds_at(scene, local, ctx.view.time);
        let view = match vpl::framed_region(bounds, camera, reach) {
            Some(region) => {
                Some(SunView::new(sun.direction, region, camera, side).map_err(GpuError::Other)?)
            }
            None => None,
        };
        let clamp_d2 = match (self.config.clamp, &view) {
            (Some(d), _) => d * d,
            // The VPLs' mean spacing: the map's area over N.
            (None, Some(v)) => (4.0 * v.radius * v.radius / f64::from(n)) as f32,
            (None, None) => 1.0,
        };
        Ok(Some(SunFrame { view, clamp_d2 }))
    }
}

/// The sun's map this frame.
struct SunFrame {
    view: Option<SunView>,
    clamp_d2: f32,
}

impl Technique for Deferred {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let sun = self.prepare(ctx)?;
        let bg = ctx.gpu_scene.background;
        let push = LightingPush {
            background: [bg[0], bg[1], bg[2], 0.0],
            counts: [
                self.config.points,
                self.config.vpls,
                self.size.0,
                self.size.1,
            ],
            params: [sun.as_ref().map_or(1.0, |s| s.clamp_d2), 0.0, 0.0, 0.0],
        };
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
            if let (Some(rsm), Some(vp), Some(sun)) = (&this.rsm, &this.vpl_pass, &sun) {
                rsm.record(cmd, profiler, gs, sun.view.as_ref());
                vp.record(cmd, profiler, rsm, &this.vpls);
            }
            let sources = LightSources {
                points: &this.points,
                vpls: &this.vpls,
            };
            this.lighting
                .record(cmd, profiler, g, &sources, counter, &push);
            this.readbacks.record(cmd, profiler, g.layers());
            if let Some(rb) = &this.vpl_readback {
                cmd.copy_buffer(&this.vpls, rb, rb.size());
                cmd.use_buffer(rb, Access::HostRead);
            }
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.g.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(Geometry {
            velocity: &self.g.velocity,
            depth: &self.g.depth,
            ids: &self.g.ids,
            packed: false,
        })
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let mut out =
            self.readbacks
                .output(ctx.view.width, ctx.view.height, ctx.view.camera.near)?;
        if let Some(rb) = &self.vpl_readback {
            let n = self.config.vpls as usize * std::mem::size_of::<Vpl>();
            out.vpls = Some(bytemuck::pod_collect_to_vec(&rb.bytes()?[..n]));
        }
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let (w, h) = self.size;
        u64::from(w) * u64::from(h) * GBuffer::BYTES_PER_PIXEL
            + self.rsm.as_ref().map_or(0, RsmPass::bytes)
    }
}
