//! `msaa:N[:sample][:hdr]`: hardware multisampling at the standard sample positions (N = 2, 4, 8
//! where the device has them; lavapipe: 4). Per-pixel shading by default: one shade per pixel
//! and covered-sample mask, inputs at the pixel centre. `:sample` shades every sample
//! (`sampleRateShading`, `minSampleShading = 1`, inputs interpolated at the sample): the pipeline
//! state msaa2x checkerboard needs, runnable here. A compute pass resolves colour (box, or with
//! `:hdr` a tonemap-weighted mean, inverted after) and takes velocity from sample 0. Depth and
//! IDs are the pixel centre's, from a 1x depth + ID pass (the checkerboard prepass): the
//! multisampled targets hold no IDs, since lavapipe has no multisampled integer attachments.
//! docs/antialiasing.md.

use cbr_gpu::{
    Access, BindingDesc, Caps, ComputeDesc, DescriptorKind, DescriptorSet, Image, ImageDesc,
    PassKind, Pipeline, Readback, Result, Sampler, SamplerDesc, SetLayout, Write, vk,
};
use half::f16;

use super::IdPass;
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};

pub const REGISTRATION: Registration = Registration {
    name: "msaa",
    grammar: "msaa:N[:sample][:hdr]",
    about: "hardware MSAA (N = 2, 4, 8 as the device allows), per-pixel or per-sample shading, \
            box or HDR-safe compute resolve",
    layers: &[],
    check: |p| parse(p).map(|_| ()),
    needs,
    estimate: |ctx, p| Ok(Msaa::estimate(parse(p)?, ctx.width, ctx.height)),
    build: |ctx, p| {
        let c = parse(p).map_err(cbr_gpu::GpuError::Other)?;
        Ok(Box::new(Msaa::new(ctx, c)?))
    },
};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MsaaConfig {
    pub samples: u32,
    pub sample_shading: bool,
    pub hdr: bool,
}

pub fn parse(params: &[&str]) -> std::result::Result<MsaaConfig, String> {
    let n = params
        .first()
        .ok_or("msaa needs N, the samples per pixel (msaa:4)")?;
    let samples = match *n {
        "2" | "4" | "8" => n.parse().map_err(|_| "unreachable".to_string())?,
        _ => return Err(format!("msaa N `{n}` (2, 4 or 8)")),
    };
    let mut c = MsaaConfig {
        samples,
        sample_shading: false,
        hdr: false,
    };
    for p in &params[1..] {
        match *p {
            "sample" => c.sample_shading = true,
            "hdr" => c.hdr = true,
            _ => return Err(unknown_param("msaa", p, "sample, hdr")),
        }
    }
    Ok(c)
}

fn needs(params: &[&str], caps: &Caps) -> Option<String> {
    let c = parse(params).ok()?;
    if !caps.sample_counts.contains(&c.samples) {
        let counts: Vec<String> = caps.sample_counts.iter().map(u32::to_string).collect();
        return Some(format!(
            "{}x MSAA for colour and depth attachments; this device has {}",
            c.samples,
            counts.join(", ")
        ));
    }
    (c.sample_shading && !caps.sample_rate_shading)
        .then(|| "the sampleRateShading feature".to_string())
}

pub const BINDINGS: [BindingDesc; 4] = {
    use DescriptorKind::{CombinedImageSampler as S, StorageImage as I};
    [
        BindingDesc::one("color", 0, S),
        BindingDesc::one("velocity", 1, S),
        BindingDesc::one("out_color", 2, I),
        BindingDesc::one("out_velocity", 3, I),
    ]
};

pub struct Msaa {
    c: MsaaConfig,
    pass: ScenePass,
    config: RasterConfig,
    color: Image,
    velocity: Image,
    depth: Image,
    ids: IdPass,
    pipeline: Pipeline,
    _layout: SetLayout,
    set: DescriptorSet,
    _sampler: Sampler,
    out_color: Image,
    out_velocity: Image,
    color_rb: Readback,
    velocity_rb: Readback,
}

impl Msaa {
    /// What [`Msaa::new`] allocates: the multisampled colour, velocity and depth, the 1x ID
    /// pass, the resolved colour and velocity and their readbacks.
    pub fn estimate(c: MsaaConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        for (name, format) in [
            ("msaa.color", COLOR_FORMAT),
            ("msaa.velocity", VELOCITY_FORMAT),
            ("msaa.depth", DEPTH_FORMAT),
        ] {
            e.image_array(name, format, w, h, 1, c.samples);
        }
        IdPass::estimate(&mut e, w, h);
        e.image("msaa.out_color", COLOR_FORMAT, w, h);
        e.image("msaa.out_velocity", VELOCITY_FORMAT, w, h);
        e.readback("readback.msaa.color", COLOR_FORMAT, w, h, 1);
        e.readback("readback.msaa.velocity", VELOCITY_FORMAT, w, h, 1);
        e
    }

    pub fn new(ctx: &BuildCtx, c: MsaaConfig) -> Result<Msaa> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let config = RasterConfig {
            samples: c.samples,
            write_ids: false,
            sample_shading: c.sample_shading,
            ..RasterConfig::native(w, h)
        };
        let pass = ScenePass::new(
            gpu,
            ctx.shaders,
            ctx.scene,
            "msaa.raster",
            &config,
            ctx.counter,
        )?;
        let ms = |name: &str, format, usage| {
            let mut d = ImageDesc::new_2d(name, format, w, h, usage);
            d.samples = c.samples;
            Image::new(gpu, &d)
        };
        let attach = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let color = ms("msaa.color", COLOR_FORMAT, attach)?;
        let velocity = ms("msaa.velocity", VELOCITY_FORMAT, attach)?;
        let depth = ms(
            "msaa.depth",
            DEPTH_FORMAT,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        let ids = IdPass::new(gpu, ctx.shaders, ctx.scene, w, h, ctx.counter)?;
        let layout = SetLayout::new(gpu, "msaa.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("HDR_SAFE".into(), u32::from(c.hdr).to_string()));
        let cs = ctx.shaders.compile("msaa/resolve.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "msaa.resolve",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: 16,
            },
        )?;
        let sampler = Sampler::new(gpu, "msaa.sampler", SamplerDesc::NEAREST)?;
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let img =
            |name: &str, format| Image::new(gpu, &ImageDesc::new_2d(name, format, w, h, usage));
        let out_color = img("msaa.out_color", COLOR_FORMAT)?;
        let out_velocity = img("msaa.out_velocity", VELOCITY_FORMAT)?;
        let set = DescriptorSet::new(
            gpu,
            "msaa.set",
            &layout,
            &[
                Write::Sampled(0, vec![(&color, &sampler)]),
                Write::Sampled(1, vec![(&velocity, &sampler)]),
                Write::Storage(2, &out_color),
                Write::Storage(3, &out_velocity),
            ],
        )?;
        let color_rb = Readback::for_image(gpu, "readback.msaa.color", &out_color)?;
        let velocity_rb = Readback::for_image(gpu, "readback.msaa.velocity", &out_velocity)?;
        Ok(Msaa {
            c,
            pass,
            config,
            color,
            velocity,
            depth,
            ids,
            pipeline,
            _layout: layout,
            set,
            _sampler: sampler,
            out_color,
            out_velocity,
            color_rb,
            velocity_rb,
        })
    }
}

impl Technique for Msaa {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            this.ids.record(cmd, profiler, gs, counter);
            this.pass.record(
                cmd,
                profiler,
                gs,
                &[&this.color, &this.velocity],
                &this.depth,
                counter,
                &this.config,
            );
            cmd.use_image(&this.color, Access::ComputeSampled);
            cmd.use_image(&this.velocity, Access::ComputeSampled);
            cmd.use_image(&this.out_color, Access::ComputeStorageWrite);
            cmd.use_image(&this.out_velocity, Access::ComputeStorageWrite);
            let scope = profiler.begin(cmd, "msaa.resolve", PassKind::Compute);
            cmd.bind_pipeline(&this.pipeline);
            cmd.bind_set(&this.pipeline, 0, &this.set);
            let push = [
                this.out_color.width as i32,
                this.out_color.height as i32,
                this.c.samples as i32,
                0,
            ];
            cmd.push_constants(&this.pipeline, bytemuck::cast_slice(&push));
            cmd.dispatch(
                this.out_color.width.div_ceil(8),
                this.out_color.height.div_ceil(8),
                1,
            );
            profiler.end(cmd, scope);
            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            cmd.read_image(&this.out_color, &this.color_rb);
            cmd.read_image(&this.out_velocity, &this.velocity_rb);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.out_color)
    }

    /// Velocity of sample 0 (the resolve's), depth and IDs of the 1x ID pass at the pixel centres.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(Geometry {
            velocity: &self.out_velocity,
            depth: &self.ids.depth,
            ids: &self.ids.ids,
            packed: false,
        })
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let (depth, ids) = self.ids.output(ctx.view.camera.near)?;
        Ok(FrameOutput::new(
            ctx.view.width,
            ctx.view.height,
            bytemuck::cast_slice::<u8, f16>(self.color_rb.bytes()?).to_vec(),
            depth,
            bytemuck::cast_slice::<u8, [f32; 2]>(self.velocity_rb.bytes()?).to_vec(),
            ids,
        ))
    }

    fn target_bytes(&self) -> u64 {
        // Multisampled colour (8) + velocity (8) + depth (4) per sample; the 1x ID pass (8 + 4).
        let px = u64::from(self.out_color.width) * u64::from(self.out_color.height);
        px * (u64::from(self.c.samples) * 20 + 12)
    }
}

/// The CPU reference of the resolve: the N samples of one pixel (RGBA) to one value.
pub fn resolve_reference(samples: &[[f32; 4]], hdr: bool) -> [f32; 4] {
    let luma = |c: &[f32; 4]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let mut sum = [0.0f32; 4];
    for s in samples {
        let k = if hdr {
            1.0 / (1.0 + luma(s).max(0.0))
        } else {
            1.0
        };
        for c in 0..4 {
            sum[c] += s[c] * if c < 3 { k } else { 1.0 };
        }
    }
    let mut avg = sum.map(|v| v / samples.len() as f32);
    if hdr {
        let inv = 1.0 / (1.0 - luma(&avg)).max(1e-6);
        for v in &mut avg[..3] {
            *v *= inv;
        }
    }
    avg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hdr_safe_resolve_tames_bright_samples() {
        let s = [[100.0, 100.0, 100.0, 1.0], [0.1, 0.1, 0.1, 1.0]];
        let boxed = resolve_reference(&s, false);
        let safe = resolve_reference(&s, true);
        assert!((boxed[0] - 50.05).abs() < 1e-4);
        // T(100) = 100/101, T(0.1) = 0.1/1.1: mean 0.5405, inverted 1.176.
        assert!((safe[0] - 1.1762).abs() < 1e-3, "{safe:?}");
        // Equal samples resolve to themselves either way.
        let same = [[2.0, 0.5, 0.25, 1.0]; 4];
        for hdr in [false, true] {
            let r = resolve_reference(&same, hdr);
            for c in 0..4 {
                assert!((r[c] - same[0][c]).abs() < 1e-5, "{r:?}");
            }
        }
        assert!(parse(&["3"]).is_err() && parse(&[]).is_err() && parse(&["4", "x"]).is_err());
        assert_eq!(
            parse(&["4", "sample", "hdr"]),
            Ok(MsaaConfig {
                samples: 4,
                sample_shading: true,
                hdr: true
            })
        );
    }
}
