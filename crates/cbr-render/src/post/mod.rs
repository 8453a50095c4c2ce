//! Post passes: a full-resolution HDR frame in, one out, chained after any technique that gives
//! a full frame (`SPEC+sharpen+...`). One module and shader folder each, and its name in the one
//! list below. Each pass is declared once (crate::pass); its input (the technique's colour or the
//! previous link's output) is bound when it records.

/// Declares each post pass's module and lists its registration.
macro_rules! post_passes {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*
        /// Every post pass, in the order `cbr render --help` lists them.
        pub const POST_PASSES: &[PostRegistration] = &[$($m::REGISTRATION),*];
    };
}

post_passes!(fxaa, taa, sharpen);

use cbr_gpu::{Cmd, Gpu, GpuError, Image, Profiler, Result, Shaders};

use crate::memory::MemoryEstimate;
use crate::technique::{EstimateCtx, Geometry};

/// What a post pass's constructor gets.
pub struct PostBuildCtx<'a> {
    pub gpu: &'a Gpu,
    pub shaders: &'a Shaders,
    pub width: u32,
    pub height: u32,
    /// The scene's display exposure in stops (passes that judge display-space luma use it).
    pub exposure_stops: f32,
    /// The technique's geometry, one per frame parity; empty unless a pass of the chain
    /// registered `geometry` (and then the technique gives it).
    pub geometry: &'a [Geometry<'a>],
}

/// A post pass's refusal of its parameters: `+name:params` and why.
pub fn refused(name: &str, params: &[&str], message: String) -> GpuError {
    let mut spec = format!("+{name}");
    for p in params {
        spec.push(':');
        spec.push_str(p);
    }
    GpuError::Config { spec, message }
}

/// The frame a post pass records for.
pub struct PostFrame<'a> {
    pub frame: u32,
    /// No usable history (post passes with histories start over): the first frame, a frame that
    /// does not follow the last one rendered, a camera cut.
    pub reset: bool,
    /// The sub-pixel jitter the frame was rendered with (pixels; crate::renderer::RenderSettings).
    pub jitter: [f32; 2],
    /// The technique's geometry this frame (when a pass of the chain reads it).
    pub geometry: Option<Geometry<'a>>,
    /// Each object's turn this frame by object ID ([`crate::gpu_scene::object_turns`]).
    pub turns: &'a [f32],
}

pub trait PostPass {
    /// Records the pass over `input` (the technique's colour or the previous link's output
    /// this frame).
    fn record(
        &mut self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        frame: &PostFrame,
        input: &Image,
    ) -> Result<()>;
    /// Its full-resolution RGBA16F output for frame `frame` (sampled by the next link, read back
    /// after the last): passes with a ping-pong history give the history slot they just wrote.
    fn output(&self, frame: u32) -> Result<&Image>;
    /// The sub-pixel jitter (pixels) the pass wants frame `frame` rendered with (TAA's Halton
    /// sequence); at most one pass of a chain jitters.
    fn jitter(&self, _frame: u32) -> Option<[f32; 2]> {
        None
    }
    /// Added to the technique's texture LOD bias (TAA: its jittered samples average over the
    /// pixel, so each may look up a sharper level; the setting `--lod-bias` overrides).
    fn lod_bias(&self) -> f32 {
        0.0
    }
    /// The speed (pixels per frame) at which a moving fragment sheds [`PostPass::lod_shed`] of
    /// the LOD bias and is shaded at the unjittered pixel centre, linearly from neither at rest
    /// (TAA: a fast pixel's history averages too few jittered samples for a shifted, sharper
    /// one); 0: every fragment is the jittered raster's, at the full bias.
    fn lod_speed(&self) -> f32 {
        0.0
    }
    /// The part of [`PostPass::lod_bias`] a turning object's fragments withdraw by their turn
    /// (TAA's reactive rule: all of it; [`crate::gpu_scene::FrameView::lod_turn`]).
    fn lod_turn(&self) -> f32 {
        0.0
    }
    /// It applies a reactive rule to turning objects (TAA's): the scene pass gets each object's
    /// turn ([`crate::gpu_scene::FrameView::turns`]).
    fn reactive(&self) -> bool {
        false
    }
    /// The part of the LOD bias a fragment moving at [`PostPass::lod_speed`] or faster sheds
    /// (TAA's `motionlod`: all of [`PostPass::lod_bias`]; `unjitter`: none).
    fn lod_shed(&self) -> f32 {
        self.lod_bias()
    }
    /// A jittering pass's frames without history (the first, a camera cut: [`PostFrame::reset`])
    /// are rendered unjittered and without [`PostPass::lod_bias`] (TAA: nothing to average a
    /// jittered, sharper sample over, so the pixel-centred frame is the better one to show).
    fn centred_at_reset(&self) -> bool {
        false
    }
}

/// A post pass's constructor: context and parameters.
pub type PostBuild = fn(&PostBuildCtx, &[&str]) -> Result<Box<dyn PostPass>>;

pub struct PostRegistration {
    pub name: &'static str,
    pub grammar: &'static str,
    pub about: &'static str,
    pub check: fn(&[&str]) -> std::result::Result<(), String>,
    /// It reads the technique's geometry (velocity, depth, IDs): temporal passes.
    pub geometry: bool,
    /// The GPU memory `build` allocates (crate::memory), written beside the constructor.
    pub estimate: fn(&EstimateCtx, &[&str]) -> MemoryEstimate,
    /// Its compute passes for the parameters, given whether the technique's geometry is packed.
    pub passes: fn(&[&str], bool) -> std::result::Result<Vec<crate::pass::ComputeDecl>, String>,
    pub build: PostBuild,
}
