//! `msaa:N[:sample][:hdr]`: hardware multisampling at the standard sample positions (N = 2, 4, 8
//! where the device has them; lavapipe: 4). Per-pixel shading by default: one shade per pixel
//! and covered-sample mask, inputs at the pixel centre. `:sample` shades every sample
//! (`sampleRateShading`, `minSampleShading = 1`, inputs interpolated at the sample): the pipeline
//! state msaa2x checkerboard needs, runnable here. A compute pass resolves colour (box, or with
//! `:hdr` a tonemap-weighted mean, inverted after) and takes velocity from sample 0. Depth and
//! IDs are the pixel centre's, from a 1x depth + ID pass (the checkerboard prepass): the
//! multisampled targets hold no IDs, since lavapipe has no multisampled integer attachments.
//! docs/antialiasing.md.

use cbr_gpu::{Access, Caps, Image, PassKind, Readback, Result};
use half::f16;

use super::IdPass;
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
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
    passes: |ctx, p| {
        let c = parse(p)?;
        let mut graphics = crate::scene_pass::listed(
            "msaa.raster",
            &raster(c, ctx.width, ctx.height),
            ctx.materials,
        )?;
        graphics.extend(IdPass::decls(ctx)?);
        Ok(crate::technique::PassList {
            compute: vec![decl(c)],
            graphics,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("msaa", p, e))?;
        Ok(Box::new(Msaa::new(ctx, c)?))
    },
};

/// The readbacks of the resolved colour and velocity.
fn readbacks(w: u32, h: u32) -> [ResourceDecl; 2] {
    [
        ResourceDecl::readback("msaa.color", COLOR_FORMAT, w, h),
        ResourceDecl::readback("msaa.velocity", VELOCITY_FORMAT, w, h),
    ]
}

/// The multisampled raster: colour and velocity (no IDs: devices without multisampled integer
/// attachments), per sample with `sample`.
fn raster(c: MsaaConfig, w: u32, h: u32) -> RasterConfig {
    RasterConfig {
        samples: c.samples,
        write_ids: false,
        sample_shading: c.sample_shading,
        ..RasterConfig::native(w, h)
    }
}

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

/// `cbr render --sample-shading`: `msaa:N` becomes `msaa:N:sample`; the flag on another
/// technique is a [`cbr_gpu::GpuError::Config`] naming the spec.
pub fn apply_shorthand(
    spec: &mut crate::spec::Spec,
    sample_shading: bool,
) -> std::result::Result<(), cbr_gpu::GpuError> {
    if !sample_shading {
        return Ok(());
    }
    let name = &spec.technique.name;
    if name != "msaa" {
        return Err(cbr_gpu::GpuError::Config {
            spec: spec.to_string(),
            message: format!("--sample-shading applies to the msaa technique, not `{name}`"),
        });
    }
    if !spec.has("sample") {
        spec.technique.params.push("sample".into());
    }
    Ok(())
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

crate::push_constants! {
    struct Push {
        /// W, H, N, 0.
        size_samples: [i32; 4],
    }
}

/// The resolve of the multisampled colour and velocity (shaders/msaa/resolve.comp).
pub fn decl(c: MsaaConfig) -> ComputeDecl {
    ComputeDecl::new("msaa.resolve", "msaa/resolve.comp")
        .define("HDR_SAFE", u32::from(c.hdr))
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("velocity"),
            Binding::image("out_color", Use::Write),
            Binding::image("out_velocity", Use::Write),
        ])
        .push::<Push>()
}

/// The multisampled colour, velocity and depth, and the resolved colour and velocity.
fn resources(c: MsaaConfig, w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::attachment("color", COLOR_FORMAT, w, h, c.samples),
        ResourceDecl::attachment("velocity", VELOCITY_FORMAT, w, h, c.samples),
        ResourceDecl::attachment("depth", DEPTH_FORMAT, w, h, c.samples),
        ResourceDecl::image("out_color", COLOR_FORMAT, w, h),
        ResourceDecl::image("out_velocity", VELOCITY_FORMAT, w, h),
    ]
}

pub struct Msaa {
    c: MsaaConfig,
    pass: ScenePass,
    config: RasterConfig,
    ids: IdPass,
    resolve: ComputePass,
    res: Resources,
    size: (u32, u32),
    color_rb: Readback,
    velocity_rb: Readback,
}

impl Msaa {
    /// What [`Msaa::new`] allocates: the declared resources, the 1x ID pass, and the readbacks
    /// of the resolved colour and velocity.
    pub fn estimate(c: MsaaConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = crate::pass::estimate(&resources(c, w, h), "msaa");
        IdPass::estimate(&mut e, w, h);
        e.append(crate::pass::estimate(&readbacks(w, h), "readback"));
        e
    }

    pub fn new(ctx: &BuildCtx, c: MsaaConfig) -> Result<Msaa> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let config = raster(c, w, h);
        let pass = ScenePass::new(
            gpu,
            ctx.shaders,
            ctx.scene,
            "msaa.raster",
            &config,
            ctx.counter,
        )?;
        let res = Resources::new(gpu, "msaa", &resources(c, w, h))?;
        let ids = IdPass::new(gpu, ctx.shaders, ctx.scene, w, h, ctx.counter)?;
        let resolve = decl(c).build(gpu, ctx.shaders)?;
        let [color_rb, velocity_rb] = readbacks(w, h).map(|r| r.make_readback(gpu, "readback"));
        let (color_rb, velocity_rb) = (color_rb?, velocity_rb?);
        Ok(Msaa {
            c,
            pass,
            config,
            ids,
            resolve,
            res,
            size: (w, h),
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
            let r = &this.res;
            this.ids.record(cmd, profiler, gs, counter)?;
            let targets = Binds::new()
                .image("color", r.image("color")?)
                .image("velocity", r.image("velocity")?)
                .image("depth", r.image("depth")?);
            this.pass
                .record(cmd, profiler, gs, &targets, counter, &this.config)?;
            let push = Push {
                size_samples: [
                    this.size.0 as i32,
                    this.size.1 as i32,
                    this.c.samples as i32,
                    0,
                ],
            };
            this.resolve
                .dispatch_2d(cmd, profiler, &Binds::of(r), &push, this.size)?;
            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            cmd.read_image(r.image("out_color")?, &this.color_rb);
            cmd.read_image(r.image("out_velocity")?, &this.velocity_rb);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        self.res.image("out_color").ok()
    }

    /// Velocity of sample 0 (the resolve's), depth and IDs of the 1x ID pass at the pixel centres.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(Geometry {
            velocity: self.res.image("out_velocity").ok()?,
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
        let px = u64::from(self.size.0) * u64::from(self.size.1);
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
