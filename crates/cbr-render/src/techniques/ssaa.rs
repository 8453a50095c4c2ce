//! `ssaa:N[:jittered]`: the ground-truth reference. N x N sub-pixel samples per pixel, each a full
//! native raster (same shaders, same shading) with the projection jittered so that the pixel
//! centre lands on the sample, added into an fp32 accumulation image (memory independent of N),
//! then divided by N^2: a box filter over the pixel square. Positions: an ordered grid at the
//! stratum centres ((i + 1/2) / N, (j + 1/2) / N), or with `:jittered` one seeded uniform point
//! per stratum (SplitMix64 of the scene seed, frame and sample: deterministic). Depth, velocity
//! and IDs are those of the pixel-centre sample (a raster with no jitter; for odd N it is also
//! the middle grid sample). Layer `coverage`: an edge mask (the samples saw more than one object
//! ID, background included) and the fraction of samples on geometry. Texture LOD: each sample's
//! footprint is 1/N pixel, so the default LOD bias is -log2 N. docs/antialiasing.md.

use cbr_gpu::{Image, PassKind, Readback, Result, vk};
use cbr_scene::rng::SplitMix;
use half::f16;

use super::LayerReadbacks;
use crate::frame::{Coverage, FrameOutput};
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, FrameTargets};
use crate::technique::{BuildCtx, FrameCtx, Registration, Technique, unknown_param};

pub const REGISTRATION: Registration = Registration {
    name: "ssaa",
    grammar: "ssaa:N[:jittered]",
    about: "N x N sub-pixel samples per pixel (N = 1..32), box filter: the ground-truth reference",
    layers: &["coverage"],
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, _| Ok(Ssaa::estimate(ctx.width, ctx.height)),
    passes: |ctx, p| {
        parse(p)?;
        Ok(crate::technique::PassList {
            compute: vec![decl()],
            graphics: crate::scene_pass::listed(
                "ssaa.raster",
                &RasterConfig::native(ctx.width, ctx.height),
                ctx.materials,
            )?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("ssaa", p, e))?;
        Ok(Box::new(Ssaa::new(ctx, c)?))
    },
};

pub const MAX_N: u32 = 32;

/// The readbacks of the frame (`out`) and its coverage (`aux`).
fn readbacks(w: u32, h: u32) -> [ResourceDecl; 2] {
    [
        ResourceDecl::readback("ssaa.out", COLOR_FORMAT, w, h),
        ResourceDecl::readback("ssaa.aux", vk::Format::R32G32_UINT, w, h),
    ]
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsaaConfig {
    pub n: u32,
    pub jittered: bool,
}

pub fn parse(params: &[&str]) -> std::result::Result<SsaaConfig, String> {
    let Some(n) = params.first() else {
        return Err("ssaa needs N, the samples per pixel side (ssaa:16 = 256 spp)".into());
    };
    let n: u32 = match n.parse() {
        Ok(v) if (1..=MAX_N).contains(&v) => v,
        _ => return Err(format!("ssaa N `{n}` (a whole number from 1 to {MAX_N})")),
    };
    let mut c = SsaaConfig { n, jittered: false };
    for p in &params[1..] {
        match *p {
            "jittered" => c.jittered = true,
            _ => return Err(unknown_param("ssaa", p, "jittered")),
        }
    }
    Ok(c)
}

/// Sample `s` of frame `frame`: its position in the pixel square, [0, 1)^2 from the top-left
/// corner. Samples run row by row over the N x N strata.
pub fn sample_position(c: SsaaConfig, seed: u64, frame: u32, s: u32) -> [f64; 2] {
    let (i, j) = (s % c.n, s / c.n);
    let (u, v) = if c.jittered {
        let mut r = SplitMix(seed ^ (u64::from(frame) << 32) ^ u64::from(s).wrapping_mul(0x9E37));
        (r.next_f64(), r.next_f64())
    } else {
        (0.5, 0.5)
    };
    let n = f64::from(c.n);
    [(f64::from(i) + u) / n, (f64::from(j) + v) / n]
}

/// Coverage: set in `aux.y` once a sample shows another object ID than the first.
pub const EDGE: u32 = 0x8000_0000;

crate::push_constants! {
    struct Push {
        /// W, H; the sample's index (0 starts the sum); 0 accumulate, 1 resolve.
        size_sample_mode: [i32; 4],
        /// x: the number of samples (the divisor of the resolve).
        samples: [f32; 4],
    }
}

/// The accumulation and resolve pass (shaders/ssaa/accumulate.comp).
pub fn decl() -> ComputeDecl {
    ComputeDecl::new("ssaa.accumulate", "ssaa/accumulate.comp")
        .constants(&[("EDGE", EDGE)])
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("ids"),
            Binding::image("accum", Use::ReadWrite),
            Binding::image("aux", Use::ReadWrite),
            Binding::image("out", Use::Write),
        ])
        .push::<Push>()
}

/// The fp32 accumulation, the coverage and the resolved frame (post passes read it).
fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::image("accum", vk::Format::R32G32B32A32_SFLOAT, w, h),
        ResourceDecl::image("aux", vk::Format::R32G32_UINT, w, h),
        ResourceDecl::image("out", COLOR_FORMAT, w, h),
    ]
}

pub struct Ssaa {
    c: SsaaConfig,
    pass: ScenePass,
    config: RasterConfig,
    targets: FrameTargets,
    accumulate: ComputePass,
    res: Resources,
    size: (u32, u32),
    centre: LayerReadbacks,
    out_rb: Readback,
    aux_rb: Readback,
}

impl Ssaa {
    /// What [`Ssaa::new`] allocates, whatever N: native's targets and readbacks, the declared
    /// resources, and the readbacks of the frame and its coverage.
    pub fn estimate(w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        FrameTargets::estimate(&mut e, "ssaa", w, h, 1, 1);
        e.append(crate::pass::estimate(&resources(w, h), "ssaa"));
        LayerReadbacks::estimate(&mut e, w, h);
        e.append(crate::pass::estimate(&readbacks(w, h), "readback"));
        e
    }

    pub fn new(ctx: &BuildCtx, c: SsaaConfig) -> Result<Ssaa> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let config = RasterConfig::native(w, h);
        let pass = ScenePass::new(
            gpu,
            ctx.shaders,
            ctx.scene,
            "ssaa.raster",
            &config,
            ctx.counter,
        )?;
        let targets = FrameTargets::new(gpu, "ssaa", w, h)?;
        let accumulate = decl().build(gpu, ctx.shaders)?;
        let res = Resources::new(gpu, "ssaa", &resources(w, h))?;
        let centre = LayerReadbacks::new(gpu, targets.layers())?;
        let [out_rb, aux_rb] = readbacks(w, h).map(|r| r.make_readback(gpu, "readback"));
        let (out_rb, aux_rb) = (out_rb?, aux_rb?);
        Ok(Ssaa {
            c,
            pass,
            config,
            targets,
            accumulate,
            res,
            size: (w, h),
            centre,
            out_rb,
            aux_rb,
        })
    }

    fn binds(&self) -> Binds<'_> {
        Binds::of(&self.res)
            .image("color", &self.targets.color)
            .image("ids", &self.targets.ids)
    }

    fn push(&self, sample: u32, resolve: bool) -> Push {
        let samples = self.c.n * self.c.n;
        Push {
            size_sample_mode: [
                self.size.0 as i32,
                self.size.1 as i32,
                sample as i32,
                i32::from(resolve),
            ],
            samples: [samples as f32, 0.0, 0.0, 0.0],
        }
    }

    /// Rasters one sample at `pos` in the pixel square; accumulates it as sample `index` unless
    /// `None`; reads the geometry layers back when `centre`.
    fn sample(
        &self,
        ctx: &mut FrameCtx,
        pos: [f64; 2],
        index: Option<u32>,
        centre: bool,
    ) -> Result<()> {
        let mut view = ctx.view.clone();
        // A jitter of j pixels moves the geometry by +j: the pixel centre then sees the point
        // that was at centre - j, so j = 1/2 - pos.
        view.raster.jitter[0] = [(0.5 - pos[0]) as f32, (0.5 - pos[1]) as f32];
        ctx.upload(&view)?;
        let counter = ctx.counter;
        let push = index.map(|s| self.push(s, false));
        ctx.submit("ssaa.sample", |cmd, profiler, gs| {
            let t = &self.targets;
            self.pass
                .record_targets(cmd, profiler, gs, t, counter, &self.config)?;
            if centre {
                self.centre.record(cmd, profiler, t.layers());
            }
            if let Some(push) = push {
                let binds = self.binds();
                self.accumulate
                    .dispatch_2d(cmd, profiler, &binds, &push, self.size)?;
            }
            Ok(())
        })
    }
}

impl Technique for Ssaa {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let n = self.c.n;
        let total = n * n;
        let seed = ctx.scene.settings.seed;
        // The centre sample first: it gives depth, velocity and IDs. For odd N on the ordered
        // grid it is the middle stratum's sample, accumulated first.
        let middle = (!self.c.jittered && n % 2 == 1).then_some((n / 2) * n + n / 2);
        self.sample(ctx, [0.5, 0.5], middle.map(|_| 0), true)?;
        let mut index = u32::from(middle.is_some());
        for s in (0..total).filter(|s| Some(*s) != middle) {
            let pos = sample_position(self.c, seed, ctx.frame, s);
            self.sample(ctx, pos, Some(index), false)?;
            index += 1;
            ctx.report_progress(index, total);
        }
        let push = self.push(0, true);
        let counter = ctx.counter;
        ctx.submit("ssaa.resolve", |cmd, profiler, _| {
            let binds = self.binds();
            self.accumulate.prepare(cmd, &binds)?;
            let scope = profiler.begin(cmd, "ssaa.resolve", PassKind::Compute);
            let groups = self.accumulate.groups_2d(self.size);
            let r = self.accumulate.dispatch_untimed(cmd, &binds, &push, groups);
            profiler.end(cmd, scope);
            r?;
            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            cmd.read_image(self.res.image("out")?, &self.out_rb);
            cmd.read_image(self.res.image("aux")?, &self.aux_rb);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        self.res.image("out").ok()
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let v = &ctx.view;
        let mut out = self.centre.output(v.width, v.height, v.camera.near)?;
        out.color = bytemuck::cast_slice::<u8, f16>(self.out_rb.bytes()?).to_vec();
        let aux: &[[u32; 2]] = bytemuck::cast_slice(self.aux_rb.bytes()?);
        let samples = (self.c.n * self.c.n) as f32;
        out.coverage = Some(Coverage {
            edge: aux.iter().map(|a| u8::from(a[1] & EDGE != 0)).collect(),
            fraction: aux
                .iter()
                .map(|a| (a[1] & !EDGE) as f32 / samples)
                .collect(),
        });
        Ok(out)
    }

    fn default_lod_bias(&self) -> f32 {
        -(self.c.n as f32).log2()
    }

    fn target_bytes(&self) -> u64 {
        // The native targets plus the fp32 accumulation, coverage and output images.
        let px = u64::from(self.size.0) * u64::from(self.size.1);
        self.targets.bytes() + px * (16 + 8 + 8)
    }

    fn cacheable(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_are_stratified_and_seeded() {
        let c = SsaaConfig {
            n: 4,
            jittered: false,
        };
        assert_eq!(sample_position(c, 0, 0, 0), [0.125, 0.125]);
        assert_eq!(sample_position(c, 0, 0, 6), [0.625, 0.375]);
        let j = SsaaConfig {
            n: 4,
            jittered: true,
        };
        for s in 0..16 {
            let p = sample_position(j, 7, 3, s);
            let (i, k) = (f64::from(s % 4), f64::from(s / 4));
            assert!(p[0] >= i / 4.0 && p[0] < (i + 1.0) / 4.0, "{p:?}");
            assert!(p[1] >= k / 4.0 && p[1] < (k + 1.0) / 4.0, "{p:?}");
            assert_eq!(p, sample_position(j, 7, 3, s), "deterministic");
        }
        assert_ne!(sample_position(j, 7, 3, 0), sample_position(j, 8, 3, 0));
        assert!(parse(&["0"]).is_err() && parse(&["33"]).is_err() && parse(&[]).is_err());
        assert!(parse(&["4", "halton"]).is_err());
        assert_eq!(
            parse(&["16", "jittered"]),
            Ok(SsaaConfig {
                n: 16,
                jittered: true
            })
        );
    }
}
