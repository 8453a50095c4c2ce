//! The `upscale` baseline (DESIGN.md): render W/sqrt(2) x H/sqrt(2), the checkerboard's pixel
//! count, then a bilinear or bicubic (Catmull-Rom) upscale to W x H (shaders/upscale/).

use cbr_gpu::{Access, Cmd, Gpu, Image, Profiler, Result, Shaders, vk};

use super::LayerReadbacks;
use crate::frame::FrameOutput;
use crate::gpu_scene::RasterUniforms;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};

pub const REGISTRATION: Registration = Registration {
    name: "upscale",
    grammar: "upscale[:bilinear|bicubic]",
    about: "render W/sqrt(2) x H/sqrt(2) (the checkerboard's pixel count), then upscale: the \
            baseline checkerboard must beat",
    layers: &[],
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, _| Ok(Upscale::estimate(ctx.width, ctx.height)),
    passes: |ctx, p| {
        let (lw, lh) = low_resolution(ctx.width, ctx.height);
        Ok(crate::technique::PassList {
            compute: vec![decl(parse(p)?)],
            graphics: crate::scene_pass::listed(
                "upscale.raster",
                &RasterConfig::native(lw, lh),
                ctx.materials,
            )?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let filter = parse(p).map_err(|e| crate::technique::refused("upscale", p, e))?;
        Ok(Box::new(Upscale::new(ctx, filter)?))
    },
};

fn parse(params: &[&str]) -> std::result::Result<UpscaleFilter, String> {
    match params {
        [] | ["bilinear"] => Ok(UpscaleFilter::Bilinear),
        ["bicubic"] => Ok(UpscaleFilter::Bicubic),
        [_, extra, ..] => Err(unknown_param("upscale", extra, "one filter")),
        [f] => Err(unknown_param("upscale", f, "a filter: bilinear or bicubic")),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UpscaleFilter {
    Bilinear,
    Bicubic,
}

impl UpscaleFilter {
    pub fn name(self) -> &'static str {
        match self {
            UpscaleFilter::Bilinear => "bilinear",
            UpscaleFilter::Bicubic => "bicubic",
        }
    }
}

/// `cbr render --filter`: the filter of an `upscale` spec (which always names one afterwards,
/// bilinear by default); a filter contradicting the spec's, or the flag on another technique, is
/// a [`cbr_gpu::GpuError::Config`] naming the spec.
pub fn apply_shorthand(
    spec: &mut crate::spec::Spec,
    filter: Option<UpscaleFilter>,
) -> std::result::Result<(), cbr_gpu::GpuError> {
    let refuse = |message: String| cbr_gpu::GpuError::Config {
        spec: spec.to_string(),
        message,
    };
    let name = &spec.technique.name;
    if name != "upscale" {
        return match filter {
            Some(_) => Err(refuse(format!(
                "--filter applies to the upscale technique, not `{name}`"
            ))),
            None => Ok(()),
        };
    }
    if let Some(f) = filter.map(UpscaleFilter::name) {
        match spec.technique.params.first() {
            Some(p) if p != f => return Err(refuse(format!("--filter {f} contradicts `{p}`"))),
            _ => spec.technique.params = vec![f.to_string()],
        }
    }
    if spec.technique.params.is_empty() {
        spec.technique.params = vec![UpscaleFilter::Bilinear.name().into()];
    }
    Ok(())
}

/// The low resolution for a W x H output: W/sqrt(2) x H/sqrt(2), rounded, at least 1.
pub fn low_resolution(width: u32, height: u32) -> (u32, u32) {
    let f = |v: u32| ((f64::from(v) / std::f64::consts::SQRT_2).round() as u32).max(1);
    (f(width), f(height))
}

crate::push_constants! {
    struct Push {
        /// W, H, w, h: the output and the low resolution.
        sizes: [i32; 4],
    }
}

/// The upscale (shaders/upscale/upscale.comp): the low-resolution targets in, the four
/// full-resolution layers out.
pub fn decl(filter: UpscaleFilter) -> ComputeDecl {
    ComputeDecl::new("upscale", "upscale/upscale.comp")
        .define("FILTER", u32::from(filter == UpscaleFilter::Bicubic))
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("velocity"),
            Binding::sampled("ids"),
            Binding::sampled("depth"),
            Binding::image("out_color", Use::Write),
            Binding::image("out_velocity", Use::Write),
            Binding::image("out_ids", Use::Write),
            Binding::image("out_depth", Use::Write),
        ])
        .push::<Push>()
}

/// The four full-resolution outputs (post passes sample the colour and the geometry).
fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::image("out_color", COLOR_FORMAT, w, h),
        ResourceDecl::image("out_velocity", VELOCITY_FORMAT, w, h),
        ResourceDecl::image("out_ids", ID_FORMAT, w, h),
        ResourceDecl::image("out_depth", vk::Format::R32_SFLOAT, w, h),
    ]
}

pub struct UpscalePass {
    pass: ComputePass,
    res: Resources,
    push: Push,
}

impl UpscalePass {
    /// What [`UpscalePass::new`] allocates: the four full-resolution outputs.
    pub fn estimate(e: &mut MemoryEstimate, width: u32, height: u32) {
        e.append(crate::pass::estimate(&resources(width, height), "upscale"));
    }

    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        filter: UpscaleFilter,
        low: &FrameTargets,
        width: u32,
        height: u32,
    ) -> Result<UpscalePass> {
        Ok(UpscalePass {
            pass: decl(filter).build(gpu, shaders)?,
            res: Resources::new(gpu, "upscale", &resources(width, height))?,
            push: Push {
                sizes: [
                    width as i32,
                    height as i32,
                    low.color.width as i32,
                    low.color.height as i32,
                ],
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

    pub fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler, low: &FrameTargets) -> Result<()> {
        let binds = low.bind(Binds::of(&self.res));
        let size = (self.push.sizes[0] as u32, self.push.sizes[1] as u32);
        self.pass
            .dispatch_2d(cmd, profiler, &binds, &self.push, size)
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
}

impl Upscale {
    /// What [`Upscale::new`] allocates: the low-resolution targets, the upscaled layers and
    /// their readbacks.
    pub fn estimate(width: u32, height: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let (lw, lh) = low_resolution(width, height);
        FrameTargets::estimate(&mut e, "upscale.low", lw, lh, 1, 1);
        UpscalePass::estimate(&mut e, width, height);
        LayerReadbacks::estimate(&mut e, width, height);
        e
    }

    pub fn new(ctx: &BuildCtx, filter: UpscaleFilter) -> Result<Upscale> {
        let (lw, lh) = low_resolution(ctx.width, ctx.height);
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
            filter,
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
        })
    }
}

impl Technique for Upscale {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let mut view = ctx.view.clone();
        (view.width, view.height) = self.low;
        view.raster = RasterUniforms {
            viewport: (self.low.0 as f32, self.low.1 as f32),
            flags: view.raster.flags,
            ..Default::default()
        };
        ctx.upload(&view)?;
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let t = &this.targets;
            this.pass
                .record_targets(cmd, profiler, gs, t, counter, &this.config)?;
            this.up.record(cmd, profiler, t)?;
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
        let [_, depth, velocity, ids] = self.up.layers().ok()?;
        Some(Geometry {
            velocity,
            depth,
            ids,
            packed: false,
        })
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        self.readbacks
            .output(ctx.view.width, ctx.view.height, ctx.view.camera.near)
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }
}
