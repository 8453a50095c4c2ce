//! The checkerboard technique's own passes: the layouts' raster targets, and `unpack`, which
//! rebuilds the full-resolution checkerboard frame through shaders/inc/layout_fetch.glsl
//! (`--resolve none`; the resolve of the next issue reads the same include).

use cbr_gpu::{Access, Buffer, Cmd, Gpu, Profiler, Result, Shaders};

use crate::layouts::LayoutPlan;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::scene_pass::layout_id;
use crate::targets::FrameTargets;

/// One unpacked pixel, as `Pixel` in shaders/checkerboard/unpack.comp (std430: 48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct UnpackedPixel {
    pub color: [f32; 4],
    /// Velocity x, y; reverse-Z depth; 1 when shaded this frame.
    pub velocity_depth_mask: [f32; 4],
    pub ids: [u32; 4],
}

crate::push_constants! {
    struct Push {
        /// W, H, parity, tangram side.
        size_parity_side: [i32; 4],
    }
}

/// The unpack (shaders/checkerboard/unpack.comp) of a layout plan's layout.
pub fn decl(plan: &LayoutPlan) -> ComputeDecl {
    ComputeDecl::new("checkerboard.unpack", "checkerboard/unpack.comp")
        .define("LAYOUT", layout_id(plan.layout))
        .define("MSAA_LOCATIONS", u32::from(plan.sample_locations.is_some()))
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("velocity"),
            Binding::sampled("ids"),
            Binding::sampled("depth"),
            Binding::buffer("out", Use::Write),
        ])
        .push::<Push>()
}

/// One host-visible `UnpackedPixel` per full-resolution pixel, bound as a storage buffer.
fn resources(plan: &LayoutPlan) -> Vec<ResourceDecl> {
    let bytes = u64::from(plan.width)
        * u64::from(plan.height)
        * std::mem::size_of::<UnpackedPixel>() as u64;
    vec![ResourceDecl::host_buffer("out", bytes)]
}

pub struct UnpackPass {
    pass: ComputePass,
    res: Resources,
    width: u32,
    height: u32,
}

impl UnpackPass {
    /// What [`UnpackPass::new`] allocates.
    pub fn estimate(e: &mut MemoryEstimate, plan: &LayoutPlan) {
        e.append(crate::pass::estimate(&resources(plan), "unpack"));
    }

    pub fn new(gpu: &Gpu, shaders: &Shaders, plan: &LayoutPlan) -> Result<UnpackPass> {
        Ok(UnpackPass {
            pass: decl(plan).build(gpu, shaders)?,
            res: Resources::new(gpu, "unpack", &resources(plan))?,
            width: plan.width,
            height: plan.height,
        })
    }

    /// The host-visible result, one `UnpackedPixel` per full-resolution pixel.
    pub fn out(&self) -> Result<&Buffer> {
        self.res.buffer("out")
    }

    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        targets: &FrameTargets,
        plan: &LayoutPlan,
    ) -> Result<()> {
        let binds = targets.bind(Binds::of(&self.res));
        let push = Push {
            size_parity_side: [
                self.width as i32,
                self.height as i32,
                plan.parity as i32,
                plan.tangram as i32,
            ],
        };
        self.pass
            .dispatch_2d(cmd, profiler, &binds, &push, (self.width, self.height))?;
        cmd.use_buffer(self.out()?, Access::HostRead);
        Ok(())
    }
}
