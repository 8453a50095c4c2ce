//! `checkerboard`: half the pixels shaded per frame, alternating parity, in one of four raster
//! layouts (crate::layouts), then the resolve (crate::resolve) reconstructs the full frame; or,
//! with `:none`, `unpack` writes the raw frame. Optional native-resolution depth + ID prepass.
//! docs/checkerboard-layouts.md and docs/resolve.md.

pub mod config;
pub mod unpack;

use cbr_gpu::{Image, Result};
use half::f16;

pub use config::{CheckerboardConfig, LodMode};
use unpack::{UnpackPass, UnpackedPixel};

use super::{IdPass, linear_depths};
use crate::frame::{FrameOutput, ResolveOutput};
use crate::gpu_scene::{FrameView, RasterUniforms};
use crate::gpu_types::FLAG_PARITY;
use crate::layouts::LayoutPlan;
use crate::memory::MemoryEstimate;
use crate::resolve::{ResolveFrame, ResolvePass, ResolveReadbacks, ResolveSettings};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::FrameTargets;
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique};

pub const REGISTRATION: Registration = Registration {
    name: "checkerboard",
    grammar: "checkerboard[:LAYOUT][:MODE][:OPTION...]",
    about: "half the pixels per frame, alternating parity, then the resolve",
    layers: &["mask", "prepass_*", "resolve_* (debug)"],
    check: |p| CheckerboardConfig::parse(p).map(|_| ()),
    needs: |p, caps| {
        let c = CheckerboardConfig::parse(p).ok()?;
        if let Some(missing) = caps.layout_unsupported(c.layout) {
            let runs: Vec<&str> = caps.supported_layouts().iter().map(|l| l.name()).collect();
            return Some(format!(
                "the {} layout needs {missing}; layouts this device runs: {}",
                c.layout.name(),
                runs.join(", ")
            ));
        }
        if c.locations {
            return caps
                .sample_locations_unsupported()
                .map(|m| format!("msaa2x with toggled sample locations needs {m}"));
        }
        None
    },
    estimate: |ctx, p| {
        let c = CheckerboardConfig::parse(p)?;
        Ok(Checkerboard::estimate(
            c,
            ctx.width,
            ctx.height,
            ctx.instrument,
        ))
    },
    passes,
    build: |ctx, p| {
        let c = CheckerboardConfig::parse(p)
            .map_err(|e| crate::technique::refused("checkerboard", p, e))?;
        Ok(Box::new(Checkerboard::new(ctx, c)?))
    },
};

struct Resolve {
    pass: ResolvePass,
    rb: ResolveReadbacks,
}

pub struct Checkerboard {
    config: CheckerboardConfig,
    plans: [LayoutPlan; 2],
    configs: [RasterConfig; 2],
    pass: ScenePass,
    targets: FrameTargets,
    unpack: UnpackPass,
    resolve: Option<Resolve>,
    prepass: Option<IdPass>,
}

/// The compute passes [`Checkerboard::new`] builds: the unpack, and with a resolve the resolve
/// (its copy floor with `instrument`, its velocity output with `geometry`).
fn passes(
    ctx: &crate::technique::PassCtx,
    p: &[&str],
) -> std::result::Result<crate::technique::PassList, String> {
    let config = CheckerboardConfig::parse(p)?;
    let mut plan = LayoutPlan::new(config.layout, ctx.width, ctx.height, 0);
    if config.locations {
        plan = plan.with_sample_locations();
    }
    let mut compute = vec![unpack::decl(&plan)];
    if let Some(rs) = &config.resolve {
        let rs = ResolveSettings {
            bandwidth_floor: ctx.instrument,
            velocity: ctx.geometry,
            ..*rs
        };
        compute.push(crate::resolve::decl(&rs, &plan, config.prepass));
        if ctx.instrument {
            compute.push(crate::resolve::copy_floor_decl("resolve.copy_floor"));
        }
    }
    let name = format!("checkerboard.{}.raster", config.layout.name());
    let mut graphics = crate::scene_pass::listed(&name, &raster(&config, &plan), ctx.materials)?;
    if config.prepass {
        graphics.extend(super::IdPass::decls(ctx)?);
    }
    Ok(crate::technique::PassList {
        compute,
        graphics,
        packed_geometry: config.resolve.is_some(),
    })
}

/// The raster of one parity's plan (the pipelines are the same for both).
fn raster(config: &CheckerboardConfig, plan: &LayoutPlan) -> RasterConfig {
    RasterConfig {
        lod_gradients: config.lod_mode == LodMode::Gradients,
        ..RasterConfig::for_plan(plan)
    }
}

impl Checkerboard {
    /// What [`Checkerboard::new`] allocates: the layout's raster targets (layers, samples), the
    /// prepass, the unpacked frame, and the resolve with its readbacks (and its copy floor when
    /// `instrument`).
    pub fn estimate(
        config: CheckerboardConfig,
        w: u32,
        h: u32,
        instrument: bool,
    ) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let mut plan = LayoutPlan::new(config.layout, w, h, 0);
        if config.locations {
            plan = plan.with_sample_locations();
        }
        let (tw, th) = plan.target;
        let prefix = format!("checkerboard.{}", config.layout.name());
        FrameTargets::estimate(&mut e, &prefix, tw, th, plan.layers, plan.samples);
        if config.prepass {
            IdPass::estimate(&mut e, w, h);
        }
        UnpackPass::estimate(&mut e, &plan);
        if let Some(rs) = &config.resolve {
            let rs = ResolveSettings {
                bandwidth_floor: instrument,
                ..*rs
            };
            ResolvePass::estimate(&mut e, &rs, w, h);
        }
        e
    }

    pub fn new(ctx: &BuildCtx, config: CheckerboardConfig) -> Result<Checkerboard> {
        let (gpu, shaders, w, h) = (ctx.gpu, ctx.shaders, ctx.width, ctx.height);
        let layout = config.layout;
        let mut plans = [
            LayoutPlan::new(layout, w, h, 0),
            LayoutPlan::new(layout, w, h, 1),
        ];
        if config.locations {
            plans = plans.map(LayoutPlan::with_sample_locations);
        }
        let configs = plans.each_ref().map(|plan| raster(&config, plan));
        let name = format!("checkerboard.{}.raster", layout.name());
        let pass = ScenePass::new(gpu, shaders, ctx.scene, &name, &configs[0], ctx.counter)?;
        let (tw, th) = plans[0].target;
        let targets = FrameTargets::layered(
            gpu,
            &format!("checkerboard.{}", layout.name()),
            tw,
            th,
            plans[0].layers,
            plans[0].samples,
            plans[0].sample_locations.is_some(),
        )?;
        let prepass = match config.prepass {
            true => Some(IdPass::new(gpu, shaders, ctx.scene, w, h, ctx.counter)?),
            false => None,
        };
        let unpack = UnpackPass::new(gpu, shaders, &plans[0])?;
        let resolve = match &config.resolve {
            Some(rs) => {
                let mut rs = *rs;
                rs.bandwidth_floor = ctx.instrument;
                rs.velocity = ctx.geometry;
                let pass = ResolvePass::new(gpu, shaders, &rs, &plans[0], prepass.is_some())?;
                let rb = pass.readbacks(gpu)?;
                Some(Resolve { pass, rb })
            }
            None => None,
        };
        Ok(Checkerboard {
            config,
            plans,
            configs,
            pass,
            targets,
            unpack,
            resolve,
            prepass,
        })
    }

    /// The frame's view in the layout's raster target: parity, viewport, jitter, tangram.
    fn view(&self, base: &FrameView, parity: u32) -> FrameView {
        let plan = &self.plans[parity as usize];
        let flags = base.raster.flags | (plan.parity * FLAG_PARITY);
        let vp = self.configs[parity as usize].viewport;
        FrameView {
            raster: RasterUniforms {
                viewport: (vp[2], vp[3]),
                jitter: plan.jitter,
                flags,
                tangram: plan.tangram,
                pieces: plan.pieces.clone(),
            },
            ..base.clone()
        }
    }
}

/// Previous clip from current clip (NDC x, NDC y, reverse-Z depth, 1), composed in f64 with the
/// camera translation, for the `intel` resolve's camera-only reprojection.
fn reprojection(view: &FrameView) -> [f32; 16] {
    let (cam, prev) = (&view.camera, &view.prev_camera);
    let clip_from_rel = cam.projection(view.aspect) * cam.rotation();
    let prev_clip_from_rel = prev.projection(view.aspect) * prev.rotation();
    let m = prev_clip_from_rel
        * glam::DMat4::from_translation(cam.position - prev.position)
        * clip_from_rel.inverse();
    m.as_mat4().to_cols_array()
}

impl Technique for Checkerboard {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let parity = ctx.frame % 2;
        let mut view = self.view(&ctx.view, parity);
        if self.config.resolve.is_some_and(|r| r.fused) {
            let j = crate::resolve::fused_jitter(ctx.frame);
            view.screen_jitter = [view.screen_jitter[0] + j[0], view.screen_jitter[1] + j[1]];
        }
        ctx.upload(&view)?;
        let rf = ResolveFrame {
            slot: parity as usize,
            parity,
            reset: ctx.reset,
            reproj: reprojection(&view),
        };
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            if let Some(p) = &this.prepass {
                // Native resolution: the frame constants' raster fields describe the checkerboard
                // pass; the ID-only native variant ignores them (no jitter, tangram or layers).
                p.record(cmd, profiler, gs, counter)?;
            }
            let t = &this.targets;
            let config = &this.configs[parity as usize];
            this.pass
                .record_targets(cmd, profiler, gs, t, counter, config)?;
            if let Some(r) = &this.resolve {
                let pre = this.prepass.as_ref().map(|p| (&p.ids, &p.depth));
                r.pass.record(cmd, profiler, t, pre, &rf)?;
                r.pass.read(cmd, rf.slot, &r.rb, false)?;
            }
            this.unpack
                .record(cmd, profiler, t, &this.plans[parity as usize])?;
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, frame: u32) -> Option<&Image> {
        self.resolve
            .as_ref()
            .and_then(|r| r.pass.output((frame % 2) as usize))
    }

    /// The resolved frame's geometry (with a resolve): the velocity each pixel used and its
    /// history geometry.
    fn geometry(&self, frame: u32) -> Option<Geometry<'_>> {
        self.resolve
            .as_ref()
            .and_then(|r| r.pass.geometry((frame % 2) as usize))
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let (parity, reset) = (ctx.frame % 2, ctx.reset);
        let near = ctx.view.camera.near;
        let px: &[UnpackedPixel] = bytemuck::cast_slice(self.unpack.out()?.bytes()?);
        let rz: Vec<f32> = px.iter().map(|p| p.velocity_depth_mask[2]).collect();
        let mut out = FrameOutput::new(
            ctx.view.width,
            ctx.view.height,
            px.iter().flat_map(|p| p.color.map(f16::from_f32)).collect(),
            linear_depths(&rz, near),
            px.iter()
                .map(|p| [p.velocity_depth_mask[0], p.velocity_depth_mask[1]])
                .collect(),
            px.iter().map(|p| [p.ids[0], p.ids[1]]).collect(),
        );
        out.mask = Some(
            px.iter()
                .map(|p| u8::from(p.velocity_depth_mask[3] > 0.5))
                .collect(),
        );
        out.parity = Some(parity);
        if let Some(p) = &self.prepass {
            out.prepass = Some(p.output(near)?);
        }
        if let Some(r) = &self.resolve {
            // The resolved frame replaces the raw colour; depth, velocity, IDs and the mask stay
            // the raw checkerboard samples (what was rendered this frame).
            let settings = r.pass.settings();
            out.color =
                r.rb.color_rgb(settings.f32_history)?
                    .iter()
                    .flat_map(|c| [c[0], c[1], c[2], 1.0].map(f16::from_f32))
                    .collect();
            let debug = settings.debug;
            out.resolve = Some(ResolveOutput {
                reset,
                debug_bits: debug
                    .then(|| {
                        r.rb.debug_bits
                            .bytes()
                            .map(|b| bytemuck::cast_slice::<u8, u32>(b).to_vec())
                    })
                    .transpose()?,
                velocity: debug
                    .then(|| {
                        r.rb.debug_velocity
                            .bytes()
                            .map(|b| bytemuck::cast_slice::<u8, [f32; 2]>(b).to_vec())
                    })
                    .transpose()?,
            });
        }
        Ok(out)
    }

    fn jitters(&self) -> bool {
        self.config.resolve.is_some_and(|r| r.fused)
    }

    fn default_lod_bias(&self) -> f32 {
        self.config.default_lod_bias()
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }
}
