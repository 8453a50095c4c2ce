//! The `upscale` baseline (DESIGN.md): render W/sqrt(2) x H/sqrt(2), the checkerboard's pixel
//! count, then a bilinear or bicubic (Catmull-Rom) upscale to W x H (shaders/upscale/).

use cbr_gpu::{
    Access, BindingDesc, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, Image, ImageDesc,
    PassKind, Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Shaders, Write, vk,
};

use super::LayerReadbacks;
use crate::frame::FrameOutput;
use crate::gpu_scene::RasterUniforms;
use crate::memory::MemoryEstimate;
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
    build: |ctx, p| {
        let filter = parse(p).map_err(cbr_gpu::GpuError::Other)?;
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

/// The low resolution for a W x H output: W/sqrt(2) x H/sqrt(2), rounded, at least 1.
pub fn low_resolution(width: u32, height: u32) -> (u32, u32) {
    let f = |v: u32| ((f64::from(v) / std::f64::consts::SQRT_2).round() as u32).max(1);
    (f(width), f(height))
}

pub const BINDINGS: [BindingDesc; 8] = {
    use DescriptorKind::{CombinedImageSampler as S, StorageImage as I};
    [
        BindingDesc::one("color", 0, S),
        BindingDesc::one("velocity", 1, S),
        BindingDesc::one("ids", 2, S),
        BindingDesc::one("depth", 3, S),
        BindingDesc::one("out_color", 4, I),
        BindingDesc::one("out_velocity", 5, I),
        BindingDesc::one("out_ids", 6, I),
        BindingDesc::one("out_depth", 7, I),
    ]
};

/// Full-resolution outputs of the upscale.
pub struct Upscaled {
    pub color: Image,
    pub velocity: Image,
    pub ids: Image,
    pub depth: Image,
}

pub struct UpscalePass {
    pipeline: Pipeline,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
    pub out: Upscaled,
    sizes: [i32; 4],
}

impl UpscalePass {
    /// What [`UpscalePass::new`] allocates: the four full-resolution outputs.
    pub fn estimate(e: &mut MemoryEstimate, width: u32, height: u32) {
        for (name, format) in [
            ("upscale.color", COLOR_FORMAT),
            ("upscale.velocity", VELOCITY_FORMAT),
            ("upscale.ids", ID_FORMAT),
            ("upscale.depth", vk::Format::R32_SFLOAT),
        ] {
            e.image(name, format, width, height);
        }
    }

    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        filter: UpscaleFilter,
        low: &FrameTargets,
        width: u32,
        height: u32,
    ) -> Result<UpscalePass> {
        let layout = SetLayout::new(gpu, "upscale.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push((
            "FILTER".into(),
            u32::from(filter == UpscaleFilter::Bicubic).to_string(),
        ));
        let cs = shaders.compile("upscale/upscale.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "upscale",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: 16,
            },
        )?;
        let sampler = Sampler::new(gpu, "upscale.sampler", SamplerDesc::NEAREST)?;
        // SAMPLED: post passes read the upscaled colour.
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED;
        let img = |name: &str, format| {
            Image::new(gpu, &ImageDesc::new_2d(name, format, width, height, usage))
        };
        let out = Upscaled {
            color: img("upscale.color", COLOR_FORMAT)?,
            velocity: img("upscale.velocity", VELOCITY_FORMAT)?,
            ids: img("upscale.ids", ID_FORMAT)?,
            depth: img("upscale.depth", vk::Format::R32_SFLOAT)?,
        };
        let set = DescriptorSet::new(
            gpu,
            "upscale.set",
            &layout,
            &[
                Write::Sampled(0, vec![(&low.color, &sampler)]),
                Write::Sampled(1, vec![(&low.velocity, &sampler)]),
                Write::Sampled(2, vec![(&low.ids, &sampler)]),
                Write::Sampled(3, vec![(&low.depth, &sampler)]),
                Write::Storage(4, &out.color),
                Write::Storage(5, &out.velocity),
                Write::Storage(6, &out.ids),
                Write::Storage(7, &out.depth),
            ],
        )?;
        Ok(UpscalePass {
            pipeline,
            _layout: layout,
            set,
            _sampler: sampler,
            out,
            sizes: [
                width as i32,
                height as i32,
                low.color.width as i32,
                low.color.height as i32,
            ],
        })
    }

    pub fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler, low: &FrameTargets) {
        for img in [&low.color, &low.velocity, &low.ids, &low.depth] {
            cmd.use_image(img, Access::ComputeSampled);
        }
        let o = &self.out;
        for img in [&o.color, &o.velocity, &o.ids, &o.depth] {
            cmd.use_image(img, Access::ComputeStorageWrite);
        }
        let scope = profiler.begin(cmd, "upscale", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.set);
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&self.sizes));
        cmd.dispatch(
            (self.sizes[0] as u32).div_ceil(8),
            (self.sizes[1] as u32).div_ceil(8),
            1,
        );
        profiler.end(cmd, scope);
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
        let o = &up.out;
        let readbacks = LayerReadbacks::new(ctx.gpu, [&o.color, &o.depth, &o.velocity, &o.ids])?;
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
                .record_targets(cmd, profiler, gs, t, counter, &this.config);
            this.up.record(cmd, profiler, t);
            let o = &this.up.out;
            this.readbacks
                .record(cmd, profiler, [&o.color, &o.depth, &o.velocity, &o.ids]);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.up.out.color)
    }

    /// The upscale's full-resolution layers: nearest low-resolution sample, velocity rescaled.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        let o = &self.up.out;
        Some(Geometry {
            velocity: &o.velocity,
            depth: &o.depth,
            ids: &o.ids,
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
