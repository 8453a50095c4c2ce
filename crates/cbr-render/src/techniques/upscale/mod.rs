//! The `upscale` baseline (DESIGN.md, docs/upscale.md): render at SCALE per axis (default
//! 1/sqrt(2), the checkerboard's pixel count), then upscale to W x H: bilinear, bicubic
//! (Catmull-Rom) or AMD's FSR 1 (EASU, then RCAS) (shaders/upscale/). [`config`]: its
//! parameters; [`reference`]: FSR 1's CPU reference.

pub mod config;
pub mod reference;

use cbr_gpu::{Access, Cmd, Gpu, Image, Profiler, Result, Shaders, vk};

pub use config::{UpscaleConfig, UpscaleFilter, apply_shorthand, parse};

use super::LayerReadbacks;
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique};

pub const REGISTRATION: Registration = Registration {
    name: "upscale",
    grammar: "upscale[:bilinear|bicubic|fsr1][:SCALE][:sharpness=S][:lod=B]",
    about: "render at SCALE per axis (default 1/sqrt(2): the checkerboard's pixel count; \
            e.g. 0.5, 0.77), then upscale; fsr1: AMD FSR 1's EASU then RCAS, sharpness in \
            stops (0 sharpest, default 0.2): the baseline checkerboard must beat",
    outputs: crate::technique::Outputs::NONE,
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Upscale::estimate(ctx.width, ctx.height, &parse(p)?)),
    passes: |ctx, p| {
        let c = parse(p)?;
        let (lw, lh) = c.low_resolution(ctx.width, ctx.height);
        Ok(crate::technique::PassList {
            compute: decls(c.filter),
            graphics: crate::scene_pass::listed(
                "upscale.raster",
                &RasterConfig::native(lw, lh),
                ctx.materials,
            )?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("upscale", p, e))?;
        Ok(Box::new(Upscale::new(ctx, &c)?))
    },
};

/// RCAS's push constants (those of every upscale pass).
pub type RcasPush = Push;

crate::push_constants! {
    pub struct Push {
        /// W, H, w, h: the output and the low resolution.
        sizes: [i32; 4],
        /// FSR 1: exposure scale (2^stops, before the encoding), RCAS's 2^-sharpness, 0, 0.
        params: [f32; 4],
    }
}

/// What every filter's first pass reads and writes beside the colour: the low-resolution
/// targets and the full-resolution geometry (shaders/upscale/geometry.glsl).
fn geometry_bindings() -> [Binding; 7] {
    [
        Binding::sampled("color"),
        Binding::sampled("velocity"),
        Binding::sampled("ids"),
        Binding::sampled("depth"),
        Binding::image("out_velocity", Use::Write),
        Binding::image("out_ids", Use::Write),
        Binding::image("out_depth", Use::Write),
    ]
}

/// The first pass of `filter`: bilinear or bicubic (shaders/upscale/upscale.comp) into the
/// output colour, or FSR 1's EASU (easu.comp) into `easu`; both write the geometry.
pub fn decl(filter: UpscaleFilter) -> ComputeDecl {
    let (d, colour) = match filter {
        UpscaleFilter::Fsr1 => (ComputeDecl::new("upscale.easu", "upscale/easu.comp"), "easu"),
        f => (
            ComputeDecl::new("upscale", "upscale/upscale.comp")
                .define("FILTER", u32::from(f == UpscaleFilter::Bicubic)),
            "out_color",
        ),
    };
    d.bindings(&geometry_bindings())
        .bind(Binding::image(colour, Use::Write))
        .push::<Push>()
}

/// FSR 1's RCAS (shaders/upscale/rcas.comp): EASU's output sharpened into the output colour.
pub fn rcas_decl() -> ComputeDecl {
    rcas_decl_named("upscale.rcas")
}

/// RCAS as pass `name`: `rcas_in` sharpened into `out_color` (taau's last pass too), with
/// [`RcasPush`]'s constants.
pub fn rcas_decl_named(name: &str) -> ComputeDecl {
    ComputeDecl::new(name, "upscale/rcas.comp")
        .bind(Binding::sampled("rcas_in"))
        .bind(Binding::image("out_color", Use::Write))
        .push::<Push>()
}

/// Every pass of `filter`, in dispatch order.
pub fn decls(filter: UpscaleFilter) -> Vec<ComputeDecl> {
    match filter {
        UpscaleFilter::Fsr1 => vec![decl(filter), rcas_decl()],
        f => vec![decl(f)],
    }
}

/// The four full-resolution outputs (post passes sample the colour and the geometry), and
/// FSR 1's EASU output (linear HDR, RCAS's input).
fn resources(w: u32, h: u32, filter: UpscaleFilter) -> Vec<ResourceDecl> {
    let mut r = vec![
        ResourceDecl::image("out_color", COLOR_FORMAT, w, h),
        ResourceDecl::image("out_velocity", VELOCITY_FORMAT, w, h),
        ResourceDecl::image("out_ids", ID_FORMAT, w, h),
        ResourceDecl::image("out_depth", vk::Format::R32_SFLOAT, w, h),
    ];
    if filter == UpscaleFilter::Fsr1 {
        r.push(ResourceDecl::image("easu", COLOR_FORMAT, w, h));
    }
    r
}

pub struct UpscalePass {
    pass: ComputePass,
    rcas: Option<ComputePass>,
    res: Resources,
    push: Push,
}

impl UpscalePass {
    /// What [`UpscalePass::new`] allocates: the full-resolution outputs.
    pub fn estimate(e: &mut MemoryEstimate, width: u32, height: u32, filter: UpscaleFilter) {
        e.append(crate::pass::estimate(
            &resources(width, height, filter),
            "upscale",
        ));
    }

    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        config: &UpscaleConfig,
        low: &FrameTargets,
        width: u32,
        height: u32,
    ) -> Result<UpscalePass> {
        let fsr1 = config.filter == UpscaleFilter::Fsr1;
        Ok(UpscalePass {
            pass: decl(config.filter).build(gpu, shaders)?,
            rcas: fsr1.then(|| rcas_decl().build(gpu, shaders)).transpose()?,
            res: Resources::new(gpu, "upscale", &resources(width, height, config.filter))?,
            push: Push {
                sizes: [
                    width as i32,
                    height as i32,
                    low.color.width as i32,
                    low.color.height as i32,
                ],
                params: [1.0, config.sharpness_linear(), 0.0, 0.0],
            },
        })
    }

    /// Colour, depth, velocity and IDs at full resolution (the common layers' order).
    pub fn layers(&self) -> Result<[&Image; 4]> {
        let r = |n| self.res.image(n);
        Ok([
            r("out_color")?,
            r("out_depth")?,
            r("out_velocity")?,
            r("out_ids")?,
        ])
    }

    /// FSR 1's EASU output (before RCAS); `None` for the other filters.
    pub fn easu(&self) -> Option<&Image> {
        self.rcas.as_ref().and(self.res.image("easu").ok())
    }

    /// The upscale of `low`; FSR 1 encodes colour exposed by `exposure_stops` (the scene's
    /// display exposure: its perceptual encoding is the displayed image's).
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        low: &FrameTargets,
        exposure_stops: f32,
    ) -> Result<()> {
        let binds = low.bind(Binds::of(&self.res));
        let size = (self.push.sizes[0] as u32, self.push.sizes[1] as u32);
        let push = Push {
            params: [
                exposure_stops.exp2(),
                self.push.params[1],
                0.0,
                0.0,
            ],
            ..self.push
        };
        self.pass
            .dispatch_2d(cmd, profiler, &binds.only(&self.pass), &push, size)?;
        if let Some(rcas) = &self.rcas {
            let binds = binds.clone().image("rcas_in", self.res.image("easu")?);
            rcas.dispatch_2d(cmd, profiler, &binds.only(rcas), &push, size)?;
        }
        Ok(())
    }
}

/// The technique: the scene pass at the low resolution, the upscale, the readbacks.
pub struct Upscale {
    config: RasterConfig,
    pass: ScenePass,
    targets: FrameTargets,
    up: UpscalePass,
    readbacks: LayerReadbacks,
    low: (u32, u32),
    lod_bias: f32,
}

impl Upscale {
    /// What [`Upscale::new`] allocates: the low-resolution targets, the upscaled layers (and
    /// FSR 1's EASU output) and their readbacks.
    pub fn estimate(width: u32, height: u32, c: &UpscaleConfig) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let (lw, lh) = c.low_resolution(width, height);
        FrameTargets::estimate(&mut e, "upscale.low", lw, lh, 1, 1);
        UpscalePass::estimate(&mut e, width, height, c.filter);
        LayerReadbacks::estimate(&mut e, width, height);
        e
    }

    pub fn new(ctx: &BuildCtx, c: &UpscaleConfig) -> Result<Upscale> {
        let (lw, lh) = c.low_resolution(ctx.width, ctx.height);
        let config = RasterConfig::native(lw, lh);
        let pass = ScenePass::new(
            ctx.gpu,
            ctx.shaders,
            ctx.scene,
            "upscale.raster",
            &config,
            ctx.counter,
        )?;
        let targets = FrameTargets::new(ctx.gpu, "upscale.low", lw, lh)?;
        let up = UpscalePass::new(
            ctx.gpu,
            ctx.shaders,
            c,
            &targets,
            ctx.width,
            ctx.height,
        )?;
        let readbacks = LayerReadbacks::new(ctx.gpu, up.layers()?)?;
        Ok(Upscale {
            config,
            pass,
            targets,
            up,
            readbacks,
            low: (lw, lh),
            lod_bias: c.lod_bias(),
        })
    }
}

impl Technique for Upscale {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.at_size(self.low.0, self.low.1);
        ctx.upload(&view)?;
        let counter = ctx.counter;
        let exposure = ctx.scene.settings.exposure;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let t = &this.targets;
            this.pass
                .record_targets(cmd, profiler, gs, t, counter, &this.config)?;
            this.up.record(cmd, profiler, t, exposure)?;
            this.readbacks.record(cmd, profiler, this.up.layers()?);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        self.up.layers().ok().map(|l| l[0])
    }

    /// The upscale's full-resolution layers: nearest low-resolution sample, velocity rescaled.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        self.up.layers().ok().map(Geometry::of_layers)
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        self.readbacks
            .output(ctx.view.width, ctx.view.height, ctx.view.camera.near)
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }

    fn default_lod_bias(&self) -> f32 {
        self.lod_bias
    }
}
