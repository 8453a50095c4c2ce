//! `native`: full resolution, one sample at each pixel centre (the reconstruction reference).
//! The scene pass (crate::scene_pass, shaders/scene/) straight into four full-resolution targets.

use cbr_gpu::{Image, Result};

use super::{LayerReadbacks, no_params};
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::FrameTargets;
use crate::technique::{BuildCtx, FrameCtx, Geometry, Registration, Technique};

pub const REGISTRATION: Registration = Registration {
    name: "native",
    grammar: "native",
    about: "full resolution, one sample at each pixel centre: the reconstruction reference",
    layers: &[],
    check: |p| no_params("native", p),
    needs: |_, _| None,
    estimate: |ctx, _| Ok(Native::estimate(ctx.width, ctx.height)),
    passes: |ctx, _| {
        Ok(crate::technique::PassList {
            graphics: crate::scene_pass::listed(
                "native.raster",
                &RasterConfig::native(ctx.width, ctx.height),
                ctx.materials,
            )?,
            ..Default::default()
        })
    },
    build: |ctx, _| Ok(Box::new(Native::new(ctx)?)),
};

pub struct Native {
    pass: ScenePass,
    config: RasterConfig,
    targets: FrameTargets,
    readbacks: LayerReadbacks,
}

impl Native {
    /// What [`Native::new`] allocates: the four targets and their readbacks.
    pub fn estimate(w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        FrameTargets::estimate(&mut e, "native", w, h, 1, 1);
        LayerReadbacks::estimate(&mut e, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx) -> Result<Native> {
        let (w, h) = (ctx.width, ctx.height);
        let config = RasterConfig::native(w, h);
        let pass = ScenePass::new(
            ctx.gpu,
            ctx.shaders,
            ctx.scene,
            "native.raster",
            &config,
            ctx.counter,
        )?;
        let targets = FrameTargets::new(ctx.gpu, "native", w, h)?;
        let readbacks = LayerReadbacks::new(ctx.gpu, targets.layers())?;
        Ok(Native {
            pass,
            config,
            targets,
            readbacks,
        })
    }
}

impl Technique for Native {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let (pass, config, targets, rb, counter) = (
            &self.pass,
            &self.config,
            &self.targets,
            &self.readbacks,
            ctx.counter,
        );
        ctx.submit("frame", |cmd, profiler, scene| {
            pass.record_targets(cmd, profiler, scene, targets, counter, config)?;
            rb.record(cmd, profiler, targets.layers());
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.targets.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(self.targets.geometry())
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        self.readbacks
            .output(ctx.view.width, ctx.view.height, ctx.view.camera.near)
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }
}
