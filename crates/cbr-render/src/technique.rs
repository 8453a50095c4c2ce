//! What a technique is to the frame sequencer: a registration (name, parameters, device needs,
//! the layers it writes, a constructor) and a [`Technique`] that renders one full-resolution
//! frame per call through its own chain of passes. The sequencer (crate::renderer) knows no
//! technique by name; adding one is a module under `techniques/`, a shader folder and its name in
//! the `techniques!` list of crate::techniques (docs/OVERVIEW.md walks through an example).

use cbr_gpu::{Buffer, Caps, Cmd, Gpu, Image, PassTiming, Profiler, Result, Shaders};
use cbr_scene::Scene;

use crate::frame::{DebugPng, FrameOutput, LayerDecl, StatDecl};
use crate::gpu_scene::{FrameView, GpuScene};
use crate::memory::MemoryEstimate;

/// What a technique's constructor gets: the device, the shader library, the uploaded scene, the
/// shaded-fragment counter the scene shaders write, and the output resolution.
pub struct BuildCtx<'a> {
    pub gpu: &'a Gpu,
    pub shaders: &'a Shaders,
    pub scene: &'a GpuScene,
    pub counter: &'a Buffer,
    pub width: u32,
    pub height: u32,
    /// Also build instrumentation passes (the resolve's copy-kernel floor) for benchmarks.
    pub instrument: bool,
    /// A post pass of the chain reads the frame's geometry ([`Technique::geometry`]): write
    /// full-resolution velocity, depth and IDs where the technique would not otherwise.
    pub geometry: bool,
}

pub use crate::frame::Geometry;

/// What a technique gets for one frame. `view` is the frame's camera at the output resolution
/// with no jitter and the generic flags (count shaded, debug LOD); a technique adjusts a copy
/// (resolution, raster uniforms, jitter) and uploads it before each raster.
pub struct FrameCtx<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a Scene,
    pub gpu_scene: &'a mut GpuScene,
    pub profiler: &'a mut Profiler,
    pub counter: &'a Buffer,
    pub frame: u32,
    /// No usable history: the first frame, or one that does not follow the last frame rendered.
    pub reset: bool,
    pub view: FrameView,
    /// GPU time of every pass so far this frame; passes of the same name add up (a technique that
    /// submits several times, like `ssaa`, reports one total per pass).
    pub timings: Vec<PassTiming>,
    /// Called with (done, total) by techniques whose frame takes many submissions.
    pub progress: Option<&'a mut dyn FnMut(u32, u32)>,
}

impl FrameCtx<'_> {
    /// Uploads the frame constants and object transforms for `view`.
    pub fn upload(&mut self, view: &FrameView) -> Result<()> {
        self.gpu_scene.update(self.scene, view)
    }

    /// Records and submits one command buffer (waiting for it), adding its pass timings.
    pub fn submit(
        &mut self,
        name: &str,
        record: impl FnOnce(&mut Cmd, &mut Profiler, &GpuScene) -> Result<()>,
    ) -> Result<()> {
        self.profiler.begin_frame();
        let (profiler, scene) = (&mut *self.profiler, &*self.gpu_scene);
        self.gpu.submit(name, |cmd| record(cmd, profiler, scene))?;
        add_timings(&mut self.timings, self.profiler.results()?);
        Ok(())
    }

    pub fn report_progress(&mut self, done: u32, total: u32) {
        if let Some(p) = self.progress.as_mut() {
            p(done, total);
        }
    }
}

/// Adds `new` to `all`: same-named passes sum their GPU time and statistics.
pub fn add_timings(all: &mut Vec<PassTiming>, new: Vec<PassTiming>) {
    for t in new {
        match all.iter_mut().find(|a| a.name == t.name) {
            Some(a) => {
                a.gpu_ms += t.gpu_ms;
                if let (Some(s), Some(n)) = (a.stats.as_mut(), t.stats) {
                    s.vertex_invocations += n.vertex_invocations;
                    s.clipping_primitives += n.clipping_primitives;
                    s.fragment_invocations += n.fragment_invocations;
                    s.compute_invocations += n.compute_invocations;
                }
                a.traffic.add(&t.traffic);
            }
            None => all.push(t),
        }
    }
}

/// A technique built for one scene and resolution.
pub trait Technique {
    /// Renders frame `ctx.frame` and records the readbacks of its layers (may submit several
    /// times).
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()>;
    /// The frame's full-resolution HDR colour on the GPU (sampled), input of the post chain;
    /// `None` where the technique has no full frame (the raw checkerboard, `:none`).
    fn color(&self, frame: u32) -> Option<&Image>;
    /// The frame's full-resolution geometry on the GPU, input of temporal post passes (`+taa`):
    /// `None` where the technique has none (`ssaa`, the raw checkerboard). Only asked for, and
    /// only needed, when the [`BuildCtx::geometry`] flag was set.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        None
    }
    /// The frame's layers read back to the host. The sequencer fills index, time, timings and
    /// the shaded-fragment count.
    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput>;
    /// The texture LOD bias that matches the technique's sample spacing.
    fn default_lod_bias(&self) -> f32 {
        0.0
    }
    /// The part of [`Technique::default_lod_bias`] that only an accumulated history makes up
    /// for (`taau`'s): a turning object's fragments withdraw it (`FrameView::lod_turn`).
    fn temporal_lod_bias(&self) -> f32 {
        0.0
    }
    /// It applies a reactive rule to turning objects (`taau`'s): the scene pass gets each
    /// object's turn ([`crate::gpu_scene::FrameView::turns`]).
    fn reactive(&self) -> bool {
        false
    }
    /// Bytes of the technique's raster targets (what it costs in memory).
    fn target_bytes(&self) -> u64;
    /// It jitters its own frames (checkerboard `fused`): a jittering post pass after it would
    /// add a second jitter, so the sequencer refuses the pair.
    fn jitters(&self) -> bool {
        false
    }
    /// Frames of this technique are worth caching on disk (expensive references).
    fn cacheable(&self) -> bool {
        false
    }
}

/// A technique's constructor: context and parameters.
pub type Build = fn(&BuildCtx, &[&str]) -> Result<Box<dyn Technique>>;

/// What a memory estimate gets: the device's capabilities (`analytic` fits its lists to them),
/// the output resolution, and whether instrumentation passes are built (BuildCtx::instrument).
pub struct EstimateCtx<'a> {
    pub caps: &'a Caps,
    pub width: u32,
    pub height: u32,
    pub instrument: bool,
}

/// A technique's memory estimate: what `build` allocates for these parameters (crate::memory),
/// or the technique's own refusal of the size.
pub type Estimate = fn(&EstimateCtx, &[&str]) -> std::result::Result<MemoryEstimate, String>;

/// What a compile-only build gets (crate::pass): the output size, the device's capabilities,
/// and the flags `BuildCtx` carries that change which passes are built.
#[derive(Clone, Copy)]
pub struct PassCtx<'a> {
    pub caps: &'a Caps,
    pub width: u32,
    pub height: u32,
    pub instrument: bool,
    pub geometry: bool,
    /// The material feature combinations (`MAT_FEATURES`) the scene's materials use: one raster
    /// pipeline variant each (crate::scene_pass::MaterialVariants); empty: the one variant with
    /// every texture path.
    pub materials: &'a [u32],
}

/// The passes a technique (or post pass) builds for its parameters, each declared once
/// (the same `decl` functions its constructor builds from), and whether its frame geometry is
/// packed (the checkerboard resolve's: `+taa` compiles its PACKED variant).
#[derive(Default)]
pub struct PassList {
    pub compute: Vec<crate::pass::ComputeDecl>,
    pub graphics: Vec<crate::pass::GraphicsDecl>,
    pub packed_geometry: bool,
}

impl PassList {
    /// Every shader the list compiles, with its defines (each stage of a raster pipeline).
    pub fn shaders(&self) -> Vec<(&'static str, Vec<(String, String)>)> {
        let mut s: Vec<_> = self
            .compute
            .iter()
            .map(|d| (d.shader, d.all_defines()))
            .collect();
        s.extend(self.graphics.iter().flat_map(|d| d.stages()));
        s
    }
}

/// A technique's compile-only list; `Err`: the parameters are refused (named in the message).
pub type Passes = fn(&PassCtx, &[&str]) -> std::result::Result<PassList, String>;

/// One registered technique.
pub struct Registration {
    pub name: &'static str,
    /// The grammar of its spec, e.g. `ssaa:N[:jittered]`.
    pub grammar: &'static str,
    pub about: &'static str,
    /// What its frames carry beyond colour, depth, velocity and IDs (layers, statistics) and
    /// how `cbr render` shows it (debug PNGs, run.json's settings entry).
    pub outputs: Outputs,
    /// Reads the parameters (after the name); the error names the one it could not read.
    pub check: fn(&[&str]) -> std::result::Result<(), String>,
    /// The device feature the parameters need and `caps` lacks, if any.
    pub needs: fn(&[&str], &Caps) -> Option<String>,
    /// The GPU memory `build` allocates (targets, per-pixel buffers, readbacks), written beside
    /// the constructor; the renderer refuses what cannot fit before anything is allocated.
    pub estimate: Estimate,
    /// Its passes, for compiling without building (`cbr_render::registry::passes`).
    pub passes: Passes,
    pub build: Build,
}

/// What a technique's frames carry beyond the four common layers, declared once: the writers
/// (EXR, run.json, PNGs) and the cache handle them without knowing the technique.
#[derive(Clone, Copy)]
pub struct Outputs {
    /// Its layers, in the order its frames hold them (the EXR's order); a frame holds those its
    /// parameters produce.
    pub layers: &'static [LayerDecl],
    /// Its per-frame statistics (run.json writes `null` for one a frame lacks).
    pub stats: &'static [StatDecl],
    /// Its debug images of a frame, given the frame as displayed (RGBA8).
    pub pngs: Option<DebugPngs>,
    /// run.json's `settings.<technique name>` entry for these parameters (`null` when `None`).
    pub settings: Option<SettingsJson>,
}

/// A technique's debug images of a frame, given the frame as displayed (RGBA8).
pub type DebugPngs = fn(&FrameOutput, &[u8]) -> Vec<DebugPng>;

/// run.json's `settings.<technique name>` entry for a technique's parameters (`None`: `null`).
pub type SettingsJson = fn(&[&str]) -> Option<serde_json::Value>;

impl Outputs {
    /// The four common layers only.
    pub const NONE: Outputs = Outputs {
        layers: &[],
        stats: &[],
        pngs: None,
        settings: None,
    };
}

/// A technique's refusal of its parameters: the spec (`name:params`) and why.
pub fn refused(name: &str, params: &[&str], message: String) -> cbr_gpu::GpuError {
    let mut spec = name.to_string();
    for p in params {
        spec.push(':');
        spec.push_str(p);
    }
    cbr_gpu::GpuError::Config { spec, message }
}

/// The error for a parameter no registration reads.
pub fn unknown_param(technique: &str, p: &str, expected: &str) -> String {
    format!("`{p}` is not a parameter of {technique} (expected {expected})")
}
