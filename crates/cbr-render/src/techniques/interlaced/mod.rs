//! `interlaced`: even rows on even frames, odd rows on odd frames. The scene pass rasterises
//! native's grid and demotes the rows of the other parity (LAYOUT_INTERLACED); the resolve
//! (`resolve`, shaders/interlaced/) passes rendered rows through and rebuilds the others from the
//! previous resolved frame or from the rows around them. docs/interlaced.md.

pub mod reference;
pub mod resolve;

use cbr_gpu::{Image, Result};
use half::f16;

pub use resolve::{InterlacedFrame, InterlacedResolve, InterlacedSettings, ResolvedReadbacks};

use super::{MASK_LAYER, linear_depths};
use crate::frame::{FrameOutput, LayerDecl, Stat, join};
use crate::gpu_types::FLAG_PARITY;
use crate::memory::MemoryEstimate;
use crate::resolve::{DEBUG_LAYERS, ResolveOutput};
use crate::scene_pass::{LAYOUT_INTERLACED, RasterConfig, ScenePass};
use crate::targets::FrameTargets;
use crate::technique::{
    BuildCtx, FrameCtx, Geometry, Outputs, Registration, Technique, unknown_param,
};

/// `mask` (the rows shaded this frame) and, with `debug`, the resolve's debug views (the same
/// bits as the checkerboard resolve's; `resolve_velocity` is never written).
const LAYERS: [LayerDecl; 10] = join([MASK_LAYER], DEBUG_LAYERS);

pub const REGISTRATION: Registration = Registration {
    name: "interlaced",
    grammar: "interlaced[:debug][:margin=M][:without-history|ids|depth|clamp|diagonals]",
    about: "even rows on even frames, odd rows on odd frames; missing rows from the previous \
            frame (velocity, ID and depth tests), else edge-directed line averaging",
    outputs: Outputs {
        layers: &LAYERS,
        stats: &crate::resolve::layers::STATS,
        pngs: Some(crate::resolve::layers::debug_pngs),
        settings: None,
    },
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Interlaced::estimate(&parse(p)?, ctx.width, ctx.height)),
    passes: |ctx, p| {
        Ok(crate::technique::PassList {
            compute: vec![resolve::decl(&parse(p)?)],
            graphics: crate::scene_pass::listed(
                "interlaced.raster",
                &raster(ctx.width, ctx.height),
                ctx.materials,
            )?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let s = parse(p).map_err(|e| crate::technique::refused("interlaced", p, e))?;
        Ok(Box::new(Interlaced::new(ctx, s)?))
    },
};

/// Native's targets, viewport and samples; the layout only demotes rows.
fn raster(w: u32, h: u32) -> RasterConfig {
    RasterConfig {
        layout: LAYOUT_INTERLACED,
        ..RasterConfig::native(w, h)
    }
}

const EXPECTED: &str = "debug, margin=M, without-history, without-ids, without-depth, \
    without-clamp, without-diagonals";

/// The parameters: `debug`, the clamp margin and the ablations, in any order.
pub fn parse(params: &[&str]) -> std::result::Result<InterlacedSettings, String> {
    let mut s = InterlacedSettings::default();
    for p in params {
        match *p {
            "debug" => s.debug = true,
            "without-history" => s.history = false,
            "without-ids" => s.ids = false,
            "without-depth" => s.depth = false,
            "without-clamp" => s.clamp = false,
            "without-diagonals" => s.diagonals = false,
            _ => match p.strip_prefix("margin=").map(str::parse::<f32>) {
                Some(Ok(m)) if m >= 0.0 && m.is_finite() => s.clamp_margin = m,
                Some(_) => return Err(format!("`{p}`: the clamp margin is a number >= 0")),
                None => return Err(unknown_param("interlaced", p, EXPECTED)),
            },
        }
    }
    Ok(s)
}

/// The canonical parameters of `s` (defaults left out), the inverse of `parse`.
pub fn params(s: &InterlacedSettings) -> Vec<String> {
    let mut p = Vec::new();
    if s.debug {
        p.push("debug".to_string());
    }
    if s.clamp_margin != InterlacedSettings::default().clamp_margin {
        p.push(format!("margin={}", s.clamp_margin));
    }
    for (on, name) in [
        (!s.history, "without-history"),
        (!s.ids, "without-ids"),
        (!s.depth, "without-depth"),
        (!s.clamp, "without-clamp"),
        (!s.diagonals, "without-diagonals"),
    ] {
        if on {
            p.push(name.to_string());
        }
    }
    p
}

pub struct Interlaced {
    config: RasterConfig,
    pass: ScenePass,
    targets: FrameTargets,
    resolve: InterlacedResolve,
    readbacks: ResolvedReadbacks,
}

impl Interlaced {
    /// What [`Interlaced::new`] allocates: native's targets, the resolve's two slots and debug
    /// bits, and the readbacks.
    pub fn estimate(settings: &InterlacedSettings, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        FrameTargets::estimate(&mut e, "interlaced", w, h, 1, 1);
        InterlacedResolve::estimate(&mut e, settings, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx, settings: InterlacedSettings) -> Result<Interlaced> {
        let (w, h) = (ctx.width, ctx.height);
        let config = raster(w, h);
        let pass = ScenePass::new(
            ctx.gpu,
            ctx.shaders,
            ctx.scene,
            "interlaced.raster",
            &config,
            ctx.counter,
        )?;
        let targets = FrameTargets::new(ctx.gpu, "interlaced", w, h)?;
        let resolve = InterlacedResolve::new(ctx.gpu, ctx.shaders, &settings, &targets)?;
        let readbacks = resolve.readbacks(ctx.gpu)?;
        Ok(Interlaced {
            config,
            pass,
            targets,
            resolve,
            readbacks,
        })
    }
}

/// 1 where row y of a frame of `parity` is rendered.
pub fn row_mask(width: u32, height: u32, parity: u32) -> Vec<u8> {
    (0..height)
        .flat_map(|y| std::iter::repeat_n(u8::from(y % 2 == parity), width as usize))
        .collect()
}

impl Technique for Interlaced {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let parity = ctx.frame % 2;
        // The frame's view as native renders it (jitter included), plus the row parity.
        let mut view = ctx.view.clone();
        view.raster.flags |= parity * FLAG_PARITY;
        ctx.upload(&view)?;
        let frame = InterlacedFrame {
            slot: parity as usize,
            parity,
            reset: ctx.reset,
        };
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let t = &this.targets;
            this.pass
                .record_targets(cmd, profiler, gs, t, counter, &this.config)?;
            this.resolve.record(cmd, profiler, t, &frame)?;
            this.resolve
                .read(cmd, profiler, frame.slot, &this.readbacks)?;
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, frame: u32) -> Option<&Image> {
        self.resolve.layers((frame % 2) as usize).ok().map(|l| l[0])
    }

    fn geometry(&self, frame: u32) -> Option<Geometry<'_>> {
        self.resolve
            .layers((frame % 2) as usize)
            .ok()
            .map(Geometry::of_layers)
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let (w, h, parity) = (ctx.view.width, ctx.view.height, ctx.frame % 2);
        let raw = self.readbacks.frame()?;
        let mut out = FrameOutput::new(
            w,
            h,
            raw.color.iter().flatten().copied().collect::<Vec<f16>>(),
            linear_depths(&raw.depth, ctx.view.camera.near),
            raw.velocity,
            raw.ids,
        );
        out.layers
            .push(MASK_LAYER.layer(w, h, vec![row_mask(w, h, parity)])?);
        out.set_stat("parity", Stat::Count(u64::from(parity)));
        ResolveOutput {
            reset: ctx.reset || !self.resolve.settings().history,
            debug_bits: raw.debug,
            velocity: None,
        }
        .write(&mut out)?;
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_round_trip_and_refuse_unknown_ones() {
        let all = [
            "debug",
            "margin=0.25",
            "without-history",
            "without-ids",
            "without-depth",
            "without-clamp",
            "without-diagonals",
        ];
        assert_eq!(params(&parse(&all).expect("all")), all);
        assert_eq!(parse(&[]).expect("none"), InterlacedSettings::default());
        let s = parse(&["without-clamp", "debug"]).expect("two");
        assert_eq!(params(&s), ["debug", "without-clamp"]);
        let err = parse(&["fields"]).expect_err("unknown");
        assert!(
            err.contains("`fields`") && err.contains("without-ids"),
            "{err}"
        );
    }

    #[test]
    fn the_mask_alternates_rows() {
        assert_eq!(row_mask(2, 3, 0), [1, 1, 0, 0, 1, 1]);
        assert_eq!(row_mask(2, 3, 1), [0, 0, 1, 1, 0, 0]);
    }
}
