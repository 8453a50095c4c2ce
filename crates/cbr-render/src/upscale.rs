//! The `upscale` baseline (DESIGN.md): render W/sqrt(2) x H/sqrt(2), the checkerboard's pixel
//! count, then a bilinear or bicubic (Catmull-Rom) upscale to W x H (shaders/upscale/).

use cbr_gpu::{
    Access, BindingDesc, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, Image, ImageDesc,
    PassKind, Pipeline, Profiler, Readback, Result, Sampler, SamplerDesc, SetLayout, Shaders,
    Write, vk,
};

use crate::targets::{COLOR_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};

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
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
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

    /// Readbacks for colour, depth, velocity and IDs (the native readback order).
    pub fn readbacks(&self, gpu: &Gpu) -> Result<[Readback; 4]> {
        let o = &self.out;
        Ok([
            Readback::for_image(gpu, "readback.upscale.color", &o.color)?,
            Readback::for_image(gpu, "readback.upscale.depth", &o.depth)?,
            Readback::for_image(gpu, "readback.upscale.velocity", &o.velocity)?,
            Readback::for_image(gpu, "readback.upscale.ids", &o.ids)?,
        ])
    }
}
