//! `interleaved:MxN[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D][:raw|box]`: interleaved
//! many-light shading (Segovia et al. 2006; docs/interleaved.md) on `deferred`'s G-buffer and
//! VPLs.
//!
//! Passes per frame, one submission: `interleaved.gbuffer` (deferred's G-buffer pass), the sun's
//! map and the VPLs (deferred::lights), then (split.rs) `interleaved.split` (the G-buffer into
//! M x N sub-images of every M-th column and N-th row), `interleaved.shade` (sub-image k with VPL
//! subset k, every (M N)-th VPL, times M N), `interleaved.gather` (the estimates back to their
//! pixels), and `interleaved.lighting`: deferred's lighting pass, whose VPL term becomes the
//! filter over the M x N window (shaders/interleaved/filter.glsl) times albedo. Each pixel
//! evaluates N / (M N) VPLs instead of N; `deferred:vpls=N` is the reference.

pub mod split;

use cbr_gpu::{Access, GpuError, Image, Result};

use super::LayerReadbacks;
use super::deferred::lighting::{Interleaving, LightingPass, LightingPush};
use super::deferred::lights::ManyLights;
use super::deferred::{self, DeferredConfig, GBuffer};
use crate::memory::MemoryEstimate;
use crate::renderer::FrameOutput;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::GBUFFER_FORMAT;
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique, unknown_param};
use split::SplitPasses;

pub const REGISTRATION: Registration = Registration {
    name: "interleaved",
    grammar: "interleaved:MxN[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D][:raw|box]",
    about: "deferred's VPLs, interleaved: the G-buffer split into M x N sub-images, sub-image k \
            shaded with every (M N)-th VPL from the k-th, gathered back, filtered over the M x N \
            window (geometry-aware; `box`: plain mean, `raw`: none), times albedo",
    layers: &[],
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Interleaved::estimate(&parse(p)?, ctx.width, ctx.height)),
    build: |ctx, p| {
        let c = parse(p).map_err(GpuError::Other)?;
        Ok(Box::new(Interleaved::new(ctx, c)?))
    },
};

/// The largest M and N.
pub const MAX_TILE: u32 = 8;
/// VPLs unless `vpls=N` says otherwise.
pub const DEFAULT_VPLS: u32 = 1024;

/// How the lighting pass combines the window's estimates (the FILTER define).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Each pixel keeps its own subset's estimate: the interleaved pattern, unfiltered.
    Raw = 0,
    /// The mean over the M x N window (one pixel of each subset), whatever the geometry.
    Box = 1,
    /// The mean where the neighbour lies on the pixel's surface, else its subset shaded at the
    /// pixel.
    Geometry = 2,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterleavedConfig {
    pub m: u32,
    pub n: u32,
    pub filter: Filter,
    pub lights: DeferredConfig,
}

fn tile(p: &str) -> std::result::Result<(u32, u32), String> {
    let bad = || {
        format!(
            "interleaved `{p}`: give the sub-images as MxN, M and N from 1 to {MAX_TILE} (`4x4`)"
        )
    };
    let (m, n) = p.split_once('x').ok_or_else(bad)?;
    let side = |v: &str| v.parse::<u32>().ok().filter(|v| (1..=MAX_TILE).contains(v));
    Ok((side(m).ok_or_else(bad)?, side(n).ok_or_else(bad)?))
}

pub fn parse(params: &[&str]) -> std::result::Result<InterleavedConfig, String> {
    let Some((first, rest)) = params.split_first() else {
        return Err("interleaved needs its sub-images, MxN (`interleaved:4x4`)".into());
    };
    let (m, n) = tile(first)?;
    let mut filter = Filter::Geometry;
    let mut light_params = Vec::new();
    for p in rest {
        let key = p.split_once('=').map_or(*p, |(k, _)| k);
        match key {
            "raw" => filter = Filter::Raw,
            "box" => filter = Filter::Box,
            "vpls" | "points" | "rsm" | "reach" | "clamp" => light_params.push(*p),
            _ => {
                return Err(unknown_param(
                    "interleaved",
                    p,
                    "vpls=N, points=N, rsm=R, reach=D, clamp=D, raw, box",
                ));
            }
        }
    }
    // deferred's parameters, read by deferred's reader; its messages name it.
    let mut lights =
        deferred::parse(&light_params).map_err(|e| e.replacen("deferred", "interleaved", 1))?;
    if !light_params.iter().any(|p| p.starts_with("vpls=")) {
        lights.vpls = DEFAULT_VPLS;
    }
    let subsets = m * n;
    if lights.vpls == 0 || lights.vpls % subsets != 0 {
        return Err(format!(
            "interleaved:{m}x{n} vpls={}: a positive multiple of {subsets}, so that each of the \
             {subsets} sub-images shades as many VPLs",
            lights.vpls
        ));
    }
    Ok(InterleavedConfig {
        m,
        n,
        filter,
        lights,
    })
}

pub struct Interleaved {
    config: InterleavedConfig,
    raster: RasterConfig,
    gbuffer_pass: ScenePass,
    g: GBuffer,
    lights: ManyLights,
    split: SplitPasses,
    lighting: LightingPass,
    readbacks: LayerReadbacks,
    size: (u32, u32),
}

impl Interleaved {
    /// What [`Interleaved::new`] allocates (crate::memory): deferred's G-buffer and lights, the
    /// M x N split images and the gathered irradiance, and the readbacks.
    pub fn estimate(config: &InterleavedConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        deferred::estimate_gbuffer_and_lights(&mut e, "interleaved", &config.lights, w, h);
        let (ws, hs) = split::sub_image(w, h, config.m, config.n);
        let (sw, sh) = (config.m * ws, config.n * hs);
        for name in ["split_position", "split_normal", "split_irradiance"] {
            e.image(format!("interleaved.{name}"), GBUFFER_FORMAT, sw, sh);
        }
        e.image("interleaved.irradiance", GBUFFER_FORMAT, w, h);
        LayerReadbacks::estimate(&mut e, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx, config: InterleavedConfig) -> Result<Interleaved> {
        let lights = ManyLights::new(ctx, &config.lights, "interleaved")?;
        let (raster, gbuffer_pass, g) = deferred::gbuffer(ctx, "interleaved")?;
        let sources = lights.sources();
        let split = SplitPasses::new(ctx, &g, sources.vpls, (config.m, config.n))?;
        let interleaving = Interleaving {
            m: config.m,
            n: config.n,
            filter: config.filter as u32,
            irradiance: &split.irradiance,
        };
        let lighting = LightingPass::new(ctx, &g, &sources, Some(&interleaving))?;
        let readbacks = LayerReadbacks::new(ctx.gpu, g.layers())?;
        Ok(Interleaved {
            config,
            raster,
            gbuffer_pass,
            g,
            lights,
            split,
            lighting,
            readbacks,
            size: (ctx.width, ctx.height),
        })
    }
}

impl Technique for Interleaved {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let sun = self.lights.prepare(ctx)?;
        let push = LightingPush::new(ctx, &self.config.lights, self.size, sun.as_ref());
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
            let sources = this.lights.sources();
            this.split.record(
                cmd,
                profiler,
                g,
                sources.vpls,
                this.config.lights.vpls,
                push.params[0],
            );
            let interleaving = Interleaving {
                m: this.config.m,
                n: this.config.n,
                filter: this.config.filter as u32,
                irradiance: &this.split.irradiance,
            };
            this.lighting.record(
                cmd,
                profiler,
                g,
                &sources,
                counter,
                &push,
                Some(&interleaving),
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
        deferred::output(&self.readbacks, &self.lights, ctx)
    }

    fn target_bytes(&self) -> u64 {
        let (w, h) = self.size;
        u64::from(w) * u64::from(h) * GBuffer::BYTES_PER_PIXEL
            + self.lights.bytes()
            + self.split.bytes()
    }
}
