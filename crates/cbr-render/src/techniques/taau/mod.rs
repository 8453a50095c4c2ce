//! `taau`: temporal upsampling at checkerboard's shading budget (docs/upsampling.md), after AMD's
//! FSR 2 and Karis' "High Quality Temporal Supersampling". The scene renders at SCALE per axis
//! with a Halton(2, 3) jitter of 8 (W / w)^2 phases, then four compute passes (shaders/taau/):
//!
//! 1. `taau.dilate` (render resolution): closest-depth velocity and depth, the reconstructed
//!    previous depth (the dilated depth scattered to where each pixel was last frame) and the
//!    prepared colour (perceptual YCoCg, once per render pixel);
//! 2. `taau.depth_clip` (render resolution): the disocclusion that depth shows;
//! 3. `taau.lock` (render resolution): thin features, locked at the output pixel they fall in;
//! 4. `taau.accumulate` (output resolution): the current samples reconstructed at the output
//!    pixel with a kernel sized to the upscale ratio (Lanczos-2 by default; at its widest,
//!    the render grid's own, without history and from the moving cap's speed on), the history
//!    reprojected (dropped where the depth clip or the object test finds a disocclusion),
//!    rectified (unless still or locked), weighted by its stability and accumulated; then FSR 1's
//!    RCAS (`taau.rcas`).
//!
//! FSR 2's reactive mask is made from the scene's own motion: a turning object keeps (1 - turn)
//! of the history's cap and withdraws the LOD bias by its turn (`gpu_scene::turn`, the `turns`
//! buffer, [`TaauPasses::set_turns`]). [`config`]: its parameters; [`reference`]: the CPU
//! reference of every pass. Left out, as our scenes need none of it: the transparency and
//! composition mask (no particles), auto-exposure (the scene's exposure is known).

pub mod config;
pub mod reference;

use cbr_gpu::{Access, Cmd, Gpu, Image, Profiler, Result, Shaders, vk};

pub use config::{Kernel, TaauConfig, parse};

use super::LayerReadbacks;
use crate::frame::{ExrType, FrameOutput, LayerDecl, SampleType};
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::{COLOR_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{BuildCtx, FrameCtx, Geometry, Outputs, Registration, Technique};

/// `taau` (with `debug`): per output pixel the disocclusion, the lock, the current sample's
/// weight and the history's weight after this frame.
pub const DEBUG_LAYER: LayerDecl = LayerDecl {
    name: "taau",
    channels: &["disocclusion", "lock", "sample_weight", "history_weight"],
    samples: SampleType::F32,
    exr: Some(ExrType::Float),
    about: "disocclusion: the depth clip's, or 1 where the object test drops the history (1 \
            drops it); lock: a thin feature's lock \
            strength (1: the history is not rectified); sample_weight: the current sample's \
            weight (1 on the pixel centre); history_weight: the accumulated weight",
};

const LAYERS: [LayerDecl; 1] = [DEBUG_LAYER];

pub const REGISTRATION: Registration = Registration {
    name: "taau",
    grammar: "taau[:SCALE][:bilinear|catmull|lanczos][:without-locks][:without-depth-clip]\
              [:without-ids][:without-reactive][:without-rcas][:without-stability][:without-surface-velocity][:sharpness=S][:lobes=2|3][:accum=A][:moving=A][:gamma=G][:tol=T]\
              [:lod=B][:debug]",
    about: "temporal upsampling after FSR 2: render at SCALE per axis (default 1/sqrt(2): the \
            checkerboard's pixel count) with a Halton jitter, dilate, depth clip, lock thin \
            features, reproject and accumulate with a Lanczos-2 kernel sized to the ratio, \
            luminance stability, RCAS",
    outputs: Outputs {
        layers: &LAYERS,
        stats: &[],
        pngs: Some(debug_pngs),
        settings: None,
    },
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Taau::estimate(ctx.width, ctx.height, &parse(p)?)),
    passes: |ctx, p| {
        let c = parse(p)?;
        let (w, h) = c.render_resolution(ctx.width, ctx.height);
        Ok(crate::technique::PassList {
            compute: decls(&c),
            graphics: crate::scene_pass::listed("taau.raster", &RasterConfig::native(w, h), ctx.materials)?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("taau", p, e))?;
        Ok(Box::new(Taau::new(ctx, &c)?))
    },
};

crate::push_constants! {
    struct Push {
        /// W, H (output), w, h (render).
        sizes: [i32; 4],
        /// The frame's jitter (render pixels), W / w, H / h.
        jitter_ratio: [f32; 4],
        /// Exposure scale, depth tolerance, gamma, the kernel's largest bias.
        params: [f32; 4],
        /// History weight cap still, moving, the speed of the moving cap, a lock's decay.
        accum: [f32; 4],
        /// x: F_RESET | F_BACKGROUND.
        flags: [u32; 4],
    }
}

/// No history this frame (first frame, a gap, a camera cut).
pub const F_RESET: u32 = 1;
/// The background moved this frame (the camera turned): a pixel whose 3x3 is all background
/// (no velocity written there) is not still.
pub const F_BACKGROUND: u32 = 2;

/// The kernel's largest bias: FSR 2 caps the Lanczos kernel's scale below 2.
pub const MAX_BIAS: f32 = 1.99;

pub fn dilate_decl(c: &TaauConfig) -> ComputeDecl {
    let mut d = ComputeDecl::new("taau.dilate", "taau/dilate.comp")
        .define("SURFACE_VELOCITY", u32::from(c.surface_velocity))
        .bind(Binding::sampled("depth"))
        .bind(Binding::sampled("velocity"))
        .bind(Binding::sampled("color"))
        .bind(Binding::image("dilated", Use::Write))
        .bind(Binding::image("prepared", Use::Write));
    if c.depth_clip {
        d = d.bind(Binding::buffer("recon", Use::ReadWrite));
    }
    d.push::<Push>()
}

pub fn depth_clip_decl() -> ComputeDecl {
    ComputeDecl::new("taau.depth_clip", "taau/depth_clip.comp")
        .bind(Binding::sampled("dilated"))
        .bind(Binding::buffer("recon", Use::Read))
        .bind(Binding::image("disocclusion", Use::Write))
        .push::<Push>()
}

pub fn lock_decl() -> ComputeDecl {
    ComputeDecl::new("taau.lock", "taau/lock.comp")
        .bind(Binding::sampled("prepared"))
        .bind(Binding::buffer("new_locks", Use::Write))
        .push::<Push>()
}

pub fn accumulate_decl(c: &TaauConfig) -> ComputeDecl {
    let mut d = ComputeDecl::new("taau.accumulate", "taau/accumulate.comp")
        .define("KERNEL", c.kernel as u32)
        .define("STABILITY", u32::from(c.stability))
        .define("OBJECT_TEST", u32::from(c.ids))
        .define("HISTORY_LOBES", c.history_lobes)
        .define("REACTIVE", u32::from(c.reactive))
        .constants(&[("F_RESET", F_RESET), ("F_BACKGROUND", F_BACKGROUND)])
        .bind(Binding::sampled("prepared"))
        .bind(Binding::sampled("dilated"));
    if c.depth_clip {
        d = d.bind(Binding::sampled("disocclusion"));
    }
    if c.locks {
        d = d.bind(Binding::buffer("new_locks", Use::Read));
    }
    if c.reactive {
        d = d.bind(Binding::buffer("turns", Use::Read));
    }
    d = d.bindings(&[
        Binding::sampled("hist"),
        Binding::sampled("hist_aux"),
        Binding::image("out_hist", Use::Write),
        Binding::image("out_aux", Use::Write),
        Binding::image("accumulated", Use::Write),
    ]);
    if c.debug {
        d = d.bind(Binding::image("debug", Use::Write));
    }
    d.bindings(&[
        Binding::sampled("velocity"),
        Binding::sampled("ids"),
        Binding::sampled("depth"),
        Binding::image("out_velocity", Use::Write),
        Binding::image("out_ids", Use::Write),
        Binding::image("out_depth", Use::Write),
    ])
    .push::<Push>()
}

/// FSR 1's RCAS on the accumulated colour (shaders/upscale/rcas.comp).
pub fn rcas_decl() -> ComputeDecl {
    crate::techniques::upscale::rcas_decl_named("taau.rcas")
}

/// Every pass of `c`, in dispatch order.
pub fn decls(c: &TaauConfig) -> Vec<ComputeDecl> {
    let mut v = vec![dilate_decl(c)];
    if c.depth_clip {
        v.push(depth_clip_decl());
    }
    if c.locks {
        v.push(lock_decl());
    }
    v.push(accumulate_decl(c));
    if c.rcas {
        v.push(rcas_decl());
    }
    v
}

/// The history's format: perceptual colour and weight; lock, luma, luma change. f32: FSR 2's
/// half floats raised FLIP by 2% on the moving demo (0.1004 against 0.0985) for half the
/// accumulation's history traffic (docs/upsampling.md); the CPU reference compares exactly.
const HISTORY_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The prepared colour (perceptual, finite flag): f32 (RGBA16F cost 1% FLIP on the moving demo,
/// and the CPU reference compares exactly).
const PREPARED_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Everything the passes own for a W x H output rendered at w x h.
fn resources(out: (u32, u32), size: (u32, u32), c: &TaauConfig) -> Vec<ResourceDecl> {
    let ((ow, oh), (w, h)) = (out, size);
    let mut r = vec![
        ResourceDecl::image("dilated", vk::Format::R32G32B32A32_SFLOAT, w, h),
        ResourceDecl::image("prepared", PREPARED_FORMAT, w, h),
        ResourceDecl::image("history", HISTORY_FORMAT, ow, oh).history(),
        ResourceDecl::image("history_aux", HISTORY_FORMAT, ow, oh).history(),
        ResourceDecl::image("accumulated", COLOR_FORMAT, ow, oh),
        ResourceDecl::image("out_velocity", VELOCITY_FORMAT, ow, oh),
        ResourceDecl::image("out_ids", ID_FORMAT, ow, oh),
        ResourceDecl::image("out_depth", vk::Format::R32_SFLOAT, ow, oh),
    ];
    if c.depth_clip {
        r.push(ResourceDecl::buffer("recon", u64::from(w) * u64::from(h) * 4));
        r.push(ResourceDecl::image("disocclusion", vk::Format::R32_SFLOAT, w, h));
    }
    if c.locks {
        r.push(ResourceDecl::buffer("new_locks", u64::from(ow) * u64::from(oh) * 4));
    }
    if c.rcas {
        r.push(ResourceDecl::image("out_color", COLOR_FORMAT, ow, oh));
    }
    if c.reactive {
        let n = crate::gpu_scene::MAX_TURN_IDS;
        r.push(ResourceDecl::upload_buffer("turns", u64::from(n) * 4));
    }
    if c.debug {
        r.push(ResourceDecl::image("debug", vk::Format::R32G32B32A32_SFLOAT, ow, oh));
        r.push(ResourceDecl::readback("taau_debug", vk::Format::R32G32B32A32_SFLOAT, ow, oh));
    }
    r
}

/// `debug`: the debug layer's channels as grey PNGs (`taau_disocclusion`, `taau_lock`,
/// `taau_sample_weight`; `taau_history_weight` over the largest weight in the frame), over the
/// displayed frame darkened to a quarter where the channel is 0.
fn debug_pngs(out: &FrameOutput, display: &[u8]) -> Vec<crate::frame::DebugPng> {
    let mut pngs = Vec::new();
    for c in DEBUG_LAYER.channels {
        let Some(v) = out.channel::<f32>(DEBUG_LAYER.name, c) else {
            continue;
        };
        let top = match *c {
            "history_weight" => v.iter().fold(1e-6f32, |a, &b| a.max(b)),
            _ => 1.0,
        };
        let rgba = v
            .iter()
            .zip(display.chunks(4))
            .flat_map(|(&x, d)| {
                let t = (x / top).clamp(0.0, 1.0);
                let g = |k: usize| (f32::from(d[k]) * 0.25 * (1.0 - t) + 255.0 * t).round() as u8;
                [g(0), g(1), g(2), 255]
            })
            .collect();
        pngs.push(crate::frame::DebugPng {
            name: format!("taau_{c}"),
            width: out.width,
            height: out.height,
            rgba,
        });
    }
    pngs
}

/// One frame's view of the passes: which history slot, reset, jitter.
#[derive(Clone, Copy, Debug)]
pub struct TaauFrame {
    pub frame: u32,
    pub reset: bool,
    /// Render pixels.
    pub jitter: [f32; 2],
    pub exposure_stops: f32,
    /// The background moved since the previous frame (by more than the still threshold, 1/64
    /// output pixel: [`crate::gpu_scene::FrameView::background_motion`]).
    pub background_moves: bool,
}

/// The four passes and RCAS, their resources, on a render frame's targets.
pub struct TaauPasses {
    pub config: TaauConfig,
    passes: Vec<ComputePass>,
    pub res: Resources,
    push: Push,
}

impl TaauPasses {
    pub fn estimate(e: &mut MemoryEstimate, out: (u32, u32), c: &TaauConfig) {
        let size = c.render_resolution(out.0, out.1);
        e.append(crate::pass::estimate(&resources(out, size, c), "taau"));
    }

    pub fn new(gpu: &Gpu, shaders: &Shaders, c: &TaauConfig, out: (u32, u32)) -> Result<TaauPasses> {
        let size = c.render_resolution(out.0, out.1);
        let passes = decls(c)
            .iter()
            .map(|d| d.build(gpu, shaders))
            .collect::<Result<Vec<_>>>()?;
        let ratio = [
            out.0 as f32 / size.0 as f32,
            out.1 as f32 / size.1 as f32,
        ];
        Ok(TaauPasses {
            config: *c,
            passes,
            res: Resources::new(gpu, "taau", &resources(out, size, c))?,
            push: Push {
                sizes: [out.0 as i32, out.1 as i32, size.0 as i32, size.1 as i32],
                jitter_ratio: [0.0, 0.0, ratio[0], ratio[1]],
                params: [
                    1.0,
                    c.depth_tolerance,
                    c.gamma,
                    ratio[0].min(ratio[1]).clamp(1.0, MAX_BIAS),
                ],
                accum: [
                    c.accumulation,
                    c.moving_accumulation,
                    config::SPEED,
                    1.0 / c.phases(out.0, out.1) as f32,
                ],
                flags: [0; 4],
            },
        })
    }

    /// Each object's turn this frame, indexed by object ID (0 the background; IDs from
    /// [`crate::gpu_scene::MAX_TURN_IDS`] on count as not turning), for the reactive rule.
    pub fn set_turns(&mut self, turns: &[f32]) -> Result<()> {
        match self.config.reactive {
            true => crate::gpu_scene::write_turns(self.res.buffer_mut("turns")?, turns),
            false => Ok(()),
        }
    }

    /// The push constants of frame `f` (also the CPU reference's parameters: [`Self::params`]).
    fn push_for(&self, f: &TaauFrame) -> Push {
        let mut p = self.push;
        p.jitter_ratio[0] = f.jitter[0];
        p.jitter_ratio[1] = f.jitter[1];
        p.params[0] = f.exposure_stops.exp2();
        p.flags[0] = if f.reset { F_RESET } else { 0 }
            | if f.background_moves { F_BACKGROUND } else { 0 };
        p
    }

    /// The CPU reference's view of frame `f`.
    pub fn params(&self, f: &TaauFrame) -> reference::Params {
        let p = self.push_for(f);
        reference::Params {
            out: (p.sizes[0] as usize, p.sizes[1] as usize),
            size: (p.sizes[2] as usize, p.sizes[3] as usize),
            jitter: f.jitter,
            ratio: [p.jitter_ratio[2], p.jitter_ratio[3]],
            exposure: p.params[0],
            depth_tolerance: p.params[1],
            gamma: p.params[2],
            bias_max: p.params[3],
            accum: p.accum,
            reset: f.reset,
            background_moves: f.background_moves,
            kernel: self.config.kernel,
            stability: self.config.stability,
            ids: self.config.ids,
            history_lobes: self.config.history_lobes,
            surface_velocity: self.config.surface_velocity,
        }
    }

    /// The output size.
    pub fn out_size(&self) -> (u32, u32) {
        (self.push.sizes[0] as u32, self.push.sizes[1] as u32)
    }

    /// The render size.
    pub fn render_size(&self) -> (u32, u32) {
        (self.push.sizes[2] as u32, self.push.sizes[3] as u32)
    }

    /// The final colour of frame `frame` (RCAS's, or the accumulation's without it).
    pub fn color(&self) -> Result<&Image> {
        self.res.image(if self.config.rcas { "out_color" } else { "accumulated" })
    }

    /// Colour, depth, velocity and IDs at the output resolution (the common layers' order).
    pub fn layers(&self) -> Result<[&Image; 4]> {
        let r = |n| self.res.image(n);
        Ok([self.color()?, r("out_depth")?, r("out_velocity")?, r("out_ids")?])
    }

    /// The history written by frame `frame` (perceptual colour, weight) and its auxiliary image.
    pub fn history(&self, frame: u32) -> Result<(&Image, &Image)> {
        Ok((
            self.res.history("history")?.write(frame),
            self.res.history("history_aux")?.write(frame),
        ))
    }

    /// Records the passes of frame `f` on the render frame `low`.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        low: &FrameTargets,
        f: &TaauFrame,
    ) -> Result<()> {
        let push = self.push_for(f);
        if let Ok(b) = self.res.buffer("recon") {
            cmd.fill_buffer(b, 0);
        }
        if let Ok(b) = self.res.buffer("new_locks") {
            cmd.fill_buffer(b, 0);
        }
        let binds = low
            .bind(Binds::of(&self.res))
            .history(self.res.history("history")?, f.frame, "hist", "out_hist")
            .history(self.res.history("history_aux")?, f.frame, "hist_aux", "out_aux");
        let rcas_in = Binds::of(&self.res).image("rcas_in", self.res.image("accumulated")?);
        let (size, out) = (self.render_size(), self.out_size());
        let rcas_push = crate::techniques::upscale::RcasPush {
            sizes: push.sizes,
            params: [push.params[0], self.config.sharpness_linear(), 0.0, 0.0],
        };
        for pass in &self.passes {
            match pass.name() {
                "taau.rcas" => pass.dispatch_2d(cmd, profiler, &rcas_in.only(pass), &rcas_push, out)?,
                "taau.accumulate" => pass.dispatch_2d(cmd, profiler, &binds.only(pass), &push, out)?,
                _ => pass.dispatch_2d(cmd, profiler, &binds.only(pass), &push, size)?,
            }
        }
        if let (Ok(d), Ok(rb)) = (self.res.image("debug"), self.res.readback("taau_debug")) {
            cmd.read_image(d, rb);
        }
        Ok(())
    }

    /// `debug`: this frame's debug layer from its readback.
    fn debug_layer(&self) -> Result<Option<crate::frame::Layer>> {
        let Ok(rb) = self.res.readback("taau_debug") else {
            return Ok(None);
        };
        let (w, h) = self.out_size();
        let texels: &[[f32; 4]] = bytemuck::cast_slice(rb.bytes()?);
        let planes = (0..4).map(|c| texels.iter().map(|t| t[c]).collect()).collect();
        DEBUG_LAYER.layer(w, h, planes).map(Some)
    }
}

/// The technique: the scene pass at the render resolution, jittered, then [`TaauPasses`].
pub struct Taau {
    config: TaauConfig,
    raster: RasterConfig,
    pass: ScenePass,
    targets: FrameTargets,
    passes: TaauPasses,
    readbacks: LayerReadbacks,
    phases: u32,
}

impl Taau {
    /// What [`Taau::new`] allocates: the render targets, the passes' resources, the readbacks.
    pub fn estimate(width: u32, height: u32, c: &TaauConfig) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let (w, h) = c.render_resolution(width, height);
        FrameTargets::estimate(&mut e, "taau.render", w, h, 1, 1);
        TaauPasses::estimate(&mut e, (width, height), c);
        LayerReadbacks::estimate(&mut e, width, height);
        e
    }

    pub fn new(ctx: &BuildCtx, c: &TaauConfig) -> Result<Taau> {
        let (w, h) = c.render_resolution(ctx.width, ctx.height);
        let raster = RasterConfig::native(w, h);
        let pass = ScenePass::new(ctx.gpu, ctx.shaders, ctx.scene, "taau.raster", &raster, ctx.counter)?;
        let targets = FrameTargets::new(ctx.gpu, "taau.render", w, h)?;
        let passes = TaauPasses::new(ctx.gpu, ctx.shaders, c, (ctx.width, ctx.height))?;
        let readbacks = LayerReadbacks::new(ctx.gpu, passes.layers()?)?;
        Ok(Taau {
            config: *c,
            raster,
            pass,
            targets,
            passes,
            readbacks,
            phases: c.phases(ctx.width, ctx.height),
        })
    }
}

/// The jitter of frame `frame` (render pixels): Halton(2, 3) over `phases` phases.
pub fn jitter(phases: u32, frame: u32) -> [f32; 2] {
    crate::post::taa::jitter(phases, frame)
}

impl Technique for Taau {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let (w, h) = self.passes.render_size();
        let j = jitter(self.phases, ctx.frame);
        let mut view = ctx.view.at_size(w, h);
        view.screen_jitter = [view.screen_jitter[0] + j[0], view.screen_jitter[1] + j[1]];
        ctx.upload(&view)?;
        let turns = crate::gpu_scene::object_turns(ctx.scene, view.time, view.prev_time);
        self.passes.set_turns(&turns)?;
        let f = TaauFrame {
            frame: ctx.frame,
            reset: ctx.reset,
            jitter: view.screen_jitter,
            exposure_stops: ctx.scene.settings.exposure,
            background_moves: ctx.view.background_motion() > f64::from(reference::STILL),
        };
        let counter = ctx.counter;
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let t = &this.targets;
            this.pass.record_targets(cmd, profiler, gs, t, counter, &this.raster)?;
            this.passes.record(cmd, profiler, t, &f)?;
            this.readbacks.record(cmd, profiler, this.passes.layers()?);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        self.passes.color().ok()
    }

    /// The output-resolution geometry: the render sample under each pixel, velocity rescaled.
    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        self.passes.layers().ok().map(Geometry::of_layers)
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let mut out = self
            .readbacks
            .output(ctx.view.width, ctx.view.height, ctx.view.camera.near)?;
        if let Some(l) = self.passes.debug_layer()? {
            out.layers.push(l);
        }
        Ok(out)
    }

    fn default_lod_bias(&self) -> f32 {
        self.config.lod_bias()
    }

    /// All of it: FSR 2's log2(SCALE) - 1 is for the accumulated output's resolution; a
    /// turning object, whose history holds a frame or none, is sampled for the render grid.
    fn temporal_lod_bias(&self) -> f32 {
        if self.config.reactive {
            self.config.lod_bias()
        } else {
            0.0
        }
    }

    fn reactive(&self) -> bool {
        self.config.reactive
    }

    fn jitters(&self) -> bool {
        true
    }

    fn target_bytes(&self) -> u64 {
        self.targets.bytes()
    }
}
