//! `+taa`: temporal anti-aliasing as a post pass (docs/post-aa.md, shaders/post/taa.comp).
//!
//! The frame is jittered by a Halton(2, 3) sequence of length 8 or 16 ([`jitter`]; the sequencer
//! applies [`PostPass::jitter`] to the projection). Each pixel blends the current sample with the
//! history reprojected through the technique's velocity:
//!
//! - `+taa` (after Karis 2014): velocity of the nearest of the 3x3 neighbours (dilation; a pixel
//!   whose 3x3 is one plane keeps its own), history
//!   by Karis' 5-tap Catmull-Rom mixed half and half with a 6x6 Lanczos-3 (`sharp`), clipped towards the neighbourhood mean into the YCoCg variance box
//!   mean +- gamma sigma (Salvi 2016), blended with current-frame weight alpha, both weighted by
//!   1 / (1 + luma) (Karis); alpha rises with the pixel's speed (0.1 still, 0.5 from 2 px per
//!   frame: every reprojection resamples and softens the history). Beyond the published: the
//!   history is rejected where the object ID it shows is none of the current 3x3's, or its depth
//!   is outside their span (the checkerboard resolve's tests). The current frame's weight is at
//!   least 1 / (m + 1), m the frames the pixel's history holds (a count kept per pixel in the
//!   history geometry, 1 after a reset or a rejection): a running mean until the exponential
//!   window is full, so a disoccluded or reset pixel converges as fast as possible instead of
//!   keeping its first jittered sample at weight (1 - alpha)^k (issue 55). Thin features (a
//!   luma ridge with no similar 2x2) are locked for a jitter cycle: on a surface (the 3x3 one
//!   plane) a locked history skips the ID test and the clip in the lock's proportion (FSR 2's
//!   locks). Moving fragments are shaded at the pixel centre by the scene pass (`unjitter`, the
//!   default); with `motionlod` (or `interior`) moving interiors take the current frame. A
//!   turning object (its own rotation per frame, `gpu_scene::turn`) takes the current frame by
//!   its turn, as does a pixel whose history shows one, and under `unjitter` the scene pass
//!   rasterises it unjittered and withdraws the LOD bias, both by its turn (the reactive rule). The blend is h + (c - h) t,
//!   exactly h where c = h. `without-X` switches one part off ([`ABLATIONS`]); `adaptive`
//!   reconstructs the current sample at the pixel centre in proportion 1 / m.
//! - `+taa:inside` (Pedersen 2016, Playdead's INSIDE): Halton x16, 3x3 closest-depth dilation,
//!   bilinear history, the rounded min-max box (3x3 averaged with the cross) with chroma shrunk to
//!   1/8 of the luma extent around the centre's, clipped towards the clamped mean, feedback
//!   lerp(0.88, 0.97, (1 - |dL| / max(L0, L1, 0.2))^2). No ID or depth tests.
//! - `mean`: blend weight 1 / (n + 1), n frames since the reset: the running mean of the jittered
//!   frames (with `without-clip`, a static scene's frame n is the mean of n + 1 jittered frames).
//!
//! Colours are compared in a perceptual space (exposure-scaled, Reinhard on luminance, YCoCg);
//! history and output stay linear HDR (RGBA16F). A non-finite current sample is replaced by the
//! mean of its finite neighbours, so NaN and Inf never enter the history. [`reference`] is the
//! CPU reference, operation for operation.

use cbr_gpu::{Cmd, GpuError, Image, Profiler, Result, vk};

use super::{PostBuildCtx, PostFrame, PostPass, PostRegistration};
use crate::frame::Geometry;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, Filter, ResourceDecl, Resources, Use};
use crate::targets::COLOR_FORMAT;

pub const REGISTRATION: PostRegistration = PostRegistration {
    name: "taa",
    grammar: "taa[:inside][:8|16][:alpha=A][:amax=A][:speed=V][:uspeed=V][:ispeed=V][:gamma=G][:tol=T][:ctol=T][:lod=B][:sharp=S][:mean][:filter][:adaptive][:motionlod][:interior][:without-X...]",
    about: "temporal AA: Halton jitter, dilated velocity, Catmull-Rom and Lanczos-3 history, YCoCg variance \
            clipping, ID and depth rejection, speed-dependent weight, per-pixel frame count, \
            thin-feature locks, moving fragments shaded at the pixel centre, turning objects' \
            current frame (X: dilation, clip, ids, depth, lanczos: Catmull-Rom alone, catmull: \
            bilinear, reactive, speed, count, luma, \
            cycle: still pixels show the mean of their last jitter cycle, centred-reset, \
            interior, locks, unjitter); `motionlod`: the sharper LOD shed with motion too, and \
            moving interiors taking the current frame (`interior`: that alone); \
            `inside`: Playdead's INSIDE TAA",
    check: |p| TaaConfig::parse(p).map(|_| ()),
    geometry: true,
    estimate: |ctx, _| crate::pass::estimate(&resources(ctx.width, ctx.height), "taa"),
    passes: |p, packed| Ok(vec![decl(&TaaConfig::parse(p)?, packed)]),
    build: |ctx, p| {
        let c = TaaConfig::parse(p).map_err(|e| super::refused("taa", p, e))?;
        Ok(Box::new(Taa::new(ctx, c)?))
    },
};

/// The parts `without-X` switches off.
pub const ABLATIONS: [&str; 16] = [
    "dilation",
    "surface-velocity",
    "reactive",
    "clip",
    "ids",
    "depth",
    "lanczos",
    "catmull",
    "speed",
    "count",
    "luma",
    "cycle",
    "centred-reset",
    "interior",
    "locks",
    "unjitter",
];

/// `cbr render --taa-without X,...`: adds `without-X` (X one of [`ABLATIONS`]) to the spec's
/// `+taa`; a spec without `+taa`, or a result `+taa` refuses, is a
/// [`cbr_gpu::GpuError::Config`] naming the spec.
pub fn apply_shorthand(
    spec: &mut crate::spec::Spec,
    without: &[&str],
) -> std::result::Result<(), cbr_gpu::GpuError> {
    if without.is_empty() {
        return Ok(());
    }
    let text = spec.to_string();
    let refuse = |message: String| cbr_gpu::GpuError::Config {
        spec: text.clone(),
        message,
    };
    let taa = spec
        .post
        .iter_mut()
        .find(|p| p.name == "taa")
        .ok_or_else(|| refuse(format!("--taa-without needs `+taa` in the spec `{text}`")))?;
    for a in without {
        let p = format!("without-{a}");
        if !taa.params.contains(&p) {
            taa.params.push(p);
        }
    }
    TaaConfig::parse(&taa.params()).map_err(|e| refuse(format!("--taa-without: {e}")))?;
    Ok(())
}

/// The switches only ours has (INSIDE's TAA refuses them): the parameter, what INSIDE lacks (for
/// the error), and what it sets.
type Switch = (&'static str, &'static str, fn(&mut TaaConfig));
const OURS_SWITCHES: &[Switch] = &[
    ("without-ids", "ID test", |c| c.ids = false),
    ("without-depth", "depth test", |c| c.depth = false),
    ("without-speed", "speed-dependent weight", |c| c.speed = 0.0),
    ("without-count", "per-pixel frame count", |c| c.count = false),
    ("without-luma", "luminance-weighted blend", |c| c.luma = false),
    ("without-cycle", "still pixels' jitter cycle", |c| c.cycle = false),
    ("without-centred-reset", "centred frame at a reset", |c| {
        c.centred_reset = false
    }),
    ("without-locks", "thin-feature locks", |c| c.locks = false),
    ("without-surface-velocity", "a surface's own velocity", |c| {
        c.surface_velocity = false
    }),
    ("without-reactive", "turning objects' reactive weight", |c| {
        c.reactive = false
    }),
    ("without-interior", "moving interiors' current frame", |c| {
        c.interior = Some(false)
    }),
    ("interior", "moving interiors' current frame", |c| {
        c.interior = Some(true)
    }),
    ("without-lanczos", "Lanczos-3 history (it is Catmull-Rom)", |c| {
        c.sharp = 0.0
    }),
    ("without-catmull", "Catmull-Rom history (it is bilinear)", |c| {
        c.catmull = false
    }),
    ("unjitter", "moving fragments shaded at the pixel centre", |c| {
        c.unjitter = true
    }),
    ("without-unjitter", "moving fragments shaded at the pixel centre", |c| {
        c.unjitter = false;
        c.motion_lod = false
    }),
    ("motionlod", "LOD bias withdrawn with motion", |c| {
        c.motion_lod = true;
        c.unjitter = true
    }),
];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaaConfig {
    /// Playdead's INSIDE TAA instead of ours.
    pub inside: bool,
    /// Halton(2, 3) sequence length (8 or 16).
    pub length: u32,
    /// Current-frame blend weight of a still pixel (ours).
    pub alpha: f32,
    /// The current-frame weight at and above `speed` pixels per frame: alpha rises linearly with
    /// the pixel's speed to it (each reprojection resamples and softens the history). `speed`
    /// 0: off (`without-speed`, which also drops `unjitter`'s centring and `motionlod`). `speed`
    /// is 1 since 2026-12-07, night (2 before; docs/post-aa.md: every gallery case at most
    /// `native`'s, at a cost of 2% on moving Šibenik).
    pub alpha_max: f32,
    pub speed: f32,
    /// Variance clipping box half-width in standard deviations (ours).
    pub gamma: f32,
    /// Relative linear-depth tolerance of the history depth test (ours).
    pub depth_tolerance: f32,
    /// Blend weight 1 / (n + 1): the running mean.
    pub mean: bool,
    /// Added to the technique's texture LOD bias: the jittered samples average over the pixel
    /// footprint, so each looks up a level finer (texture prefiltering would blur twice).
    pub lod_bias: f32,
    pub dilation: bool,
    /// With `dilation`: a pixel whose 3x3 is one plane (the test of `interior`) keeps its own
    /// velocity; dilation is for silhouettes, and on a receding surface the nearest texel's
    /// velocity is off by the perspective's gradient, a reprojection error the history
    /// accumulates (`without-surface-velocity`: dilation everywhere, as published; off in
    /// INSIDE's mode).
    pub surface_velocity: bool,
    /// FSR 2's reactive mask from the scene's own motion, as `taau`'s: a turning object's
    /// pixel takes the current frame with weight mix(a, 1, turn), whatever its speed
    /// (`gpu_scene::turn`), and so does a pixel whose history shows a turning object (no
    /// trails of it where it uncovered the background); its fragments withdraw the LOD bias as
    /// much and, under `unjitter`, are rasterised without the jitter as much (`native`'s
    /// centred sample; `without-reactive`; off in INSIDE's mode).
    pub reactive: bool,
    pub clip: bool,
    pub ids: bool,
    pub depth: bool,
    pub catmull: bool,
    /// With `catmull`: the history resampled by (1 - sharp) x the 5-tap Catmull-Rom + sharp x a
    /// 6x6 Lanczos-3 (`sharp=S`, 0 to 1; `without-lanczos`: 0, Karis' kernel alone). The
    /// resampling's blur compounds over the frames the history holds: Lanczos-3 alone took the
    /// moving demo from 0.708x to 0.692x `native`'s FLIP, but kept more of a view-dependent
    /// highlight's lag (`specular` 1.10x `native`); 0.5 gave 0.697x and 0.97x
    /// (docs/post-aa.md). 0 in INSIDE's mode.
    pub sharp: f32,
    /// `filter`: reconstruct the current sample at the pixel centre from the 3x3 (Karis'
    /// Blackman-Harris fit). Off by default: on the moving demo it blurs texture more than it
    /// removes jitter (docs/post-aa.md).
    pub filter: bool,
    /// The current frame's weight is at least 1 / (m + 1), m the frames the pixel's history
    /// holds (kept per pixel in the history geometry): the running mean until the exponential
    /// window is full, after a reset and after every rejection (`without-count`).
    pub count: bool,
    /// Karis' luminance weights 1 / (1 + luma) in the blend (`without-luma`).
    pub luma: bool,
    /// The current sample reconstructed at the pixel centre (the `filter` Gaussian) in the
    /// proportion 1 / m of a history of m frames (all of it where there is no history), the
    /// jittered point sample otherwise (`adaptive`; off by default: measured mixed on the
    /// hard-case gallery, docs/post-aa.md; and with `mean` or `filter`).
    pub adaptive: bool,
    /// A still pixel shows the mean of its last complete jitter cycle (`length` samples, each
    /// phase once), held until the next cycle is complete, and restarts its cycle when a
    /// sample leaves the last cycle's luma range by more than `cycle_tolerance` (`without-cycle`;
    /// off with `mean` and in INSIDE's mode).
    pub cycle: bool,
    /// The cycle's change test: how far (perceptual luma, 0..1) a sample may lie outside the
    /// last complete cycle's range (`ctol=T`).
    pub cycle_tolerance: f32,
    /// Moving fragments are shaded at the pixel centre: their shading inputs are moved back by
    /// their share of the jitter, linearly up to `uspeed` pixels per frame (the scene pass's
    /// `unjittered()`, [`PostPass::lod_speed`]), and with `interior` their pixels away from
    /// edges take the current frame (`motionlod` needs it). A pixel that moves keeps few
    /// jittered samples to average a shifted sample over. On by default since 2026-12-07
    /// (docs/post-aa.md: at most `+taa`'s error on every scene measured); `without-unjitter`
    /// is the jittered path.
    pub unjitter: bool,
    /// `unjitter`, and the LOD bias withdrawn from moving fragments by the same share
    /// ([`PostPass::lod_shed`]; `motionlod`): with an isotropic texture filter the sharper level
    /// stands in for anisotropic filtering on grazing surfaces and the foliage's leaves, so
    /// `unjitter` alone is better there; with `anisotropy` the shed is right (docs/post-aa.md).
    pub motion_lod: bool,
    /// With `unjitter`: the speed (pixels per frame) at and above which a moving fragment is
    /// shaded at the pixel centre, its share of the jitter rising linearly to it (and with
    /// `motionlod` the LOD bias shed by the same share); `None`: [`CENTRING_SPEED`]
    /// (`uspeed=V`).
    pub unjitter_speed: Option<f32>,
    /// With `interior`: the speed at which a moving interior's current-frame weight reaches 1;
    /// `None`: [`CENTRING_SPEED`] (`ispeed=V`).
    pub interior_speed: Option<f32>,
    /// With `unjitter`: a moving pixel away from edges (its 3x3 one object, its reverse-Z depth
    /// one plane within `depth_tolerance`: a receding floor is no edge) takes the current frame
    /// at a weight rising to 1 at `ispeed`, not to `alpha_max`: the scene pass shades it at the
    /// pixel centre, so its current sample is the technique's own and the history only softens
    /// it; edges keep `alpha_max`, where the history is what anti-aliases them. `None`: on with
    /// `motionlod` only ([`TaaConfig::interior`]); `interior` / `without-interior` set it.
    pub interior: Option<bool>,
    /// A frame with no history (the first, a camera cut) is rendered unjittered at the
    /// technique's own LOD bias, and shown as it is: with nothing to average a jittered sample
    /// and a sharper texture over, the pixel-centred frame is the better estimate of the pixel
    /// (`native`'s own frame); it starts no jitter cycle (`without-centred-reset`; off in
    /// INSIDE's mode, which jitters every frame as published).
    pub centred_reset: bool,
    /// Thin features' locks (FSR 2's, as `taau`'s): a pixel whose sample is a luma ridge with no
    /// similar 2x2 around it is locked for `length` frames (renewed while it stays one, carried
    /// with the history); a locked history is kept from the clip in proportion to the lock's
    /// life and from the ID test, and a locked pixel is no interior. A sub-pixel feature that
    /// this frame's jitter missed (`zfight`'s far stripes) keeps its share of the history
    /// instead of being clipped to the surface around it (`without-locks`; off in INSIDE's
    /// mode).
    pub locks: bool,
}

/// Below this motion (pixels) a pixel is still: when its history texel was still too, the ID
/// and depth tests are skipped (the checkerboard resolve's static threshold).
pub const STILL_THRESHOLD: f32 = 1.0 / 64.0;
/// `uspeed`'s and `ispeed`'s default (pixels per frame): a moving fragment is wholly centred,
/// and with `interior` a moving interior's weight reaches 1, from 2 px a frame. (They followed
/// `speed`, 2, until `speed` became 1: a centring ramp of 1 px lost foliage, 0.562x -> 0.579x of
/// `native`'s FLIP, docs/post-aa.md.)
pub const CENTRING_SPEED: f32 = 2.0;
/// History geometry's moved bit.
pub const MOVED: u32 = 0x8000_0000;
/// History geometry: the frames the history holds (1 after a reset or a rejection, at most
/// [`COUNT_MAX`]) in bits 24-30, the object ID below.
pub const COUNT_SHIFT: u32 = 24;
pub const COUNT_MAX: u32 = 0x7f;
pub const HIST_ID_MASK: u32 = (1 << COUNT_SHIFT) - 1;

/// The history geometry's x: object ID, frames held, moved bit.
pub fn hist_geom_x(id: u32, count: u32, moved: bool) -> u32 {
    (id & HIST_ID_MASK) | (count.min(COUNT_MAX) << COUNT_SHIFT) | if moved { MOVED } else { 0 }
}

/// INSIDE's feedback range (the history's weight).
pub const INSIDE_FEEDBACK: [f32; 2] = [0.88, 0.97];

impl TaaConfig {
    pub const OURS: TaaConfig = TaaConfig {
        inside: false,
        length: 8,
        alpha: 0.1,
        alpha_max: 0.5,
        speed: 1.0,
        gamma: 1.0,
        depth_tolerance: 0.05,
        mean: false,
        lod_bias: -1.0,
        dilation: true,
        surface_velocity: true,
        reactive: true,
        clip: true,
        ids: true,
        depth: true,
        catmull: true,
        sharp: 0.5,
        filter: false,
        count: true,
        luma: true,
        adaptive: false,
        cycle: true,
        cycle_tolerance: 0.01,
        unjitter: true,
        motion_lod: false,
        unjitter_speed: None,
        interior_speed: None,
        interior: None,
        centred_reset: true,
        locks: true,
    };

    pub const INSIDE: TaaConfig = TaaConfig {
        inside: true,
        length: 16,
        ids: false,
        depth: false,
        catmull: false,
        sharp: 0.0,
        filter: false,
        count: false,
        luma: false,
        adaptive: false,
        cycle: false,
        unjitter: false,
        interior: Some(false),
        surface_velocity: false,
        reactive: false,
        centred_reset: false,
        locks: false,
        ..TaaConfig::OURS
    };

    pub fn parse(params: &[&str]) -> std::result::Result<TaaConfig, String> {
        let inside = params.contains(&"inside");
        let mut c = if inside {
            TaaConfig::INSIDE
        } else {
            TaaConfig::OURS
        };
        let num = |p: &str, v: &str, lo: f32, hi: f32| -> std::result::Result<f32, String> {
            match v.parse::<f32>() {
                Ok(x) if (lo..=hi).contains(&x) => Ok(x),
                _ => Err(format!("taa `{p}` (a number from {lo} to {hi})")),
            }
        };
        for p in params {
            let ours_only = |what: &str| -> std::result::Result<(), String> {
                match inside {
                    true => Err(format!("taa `{p}`: INSIDE's TAA has no {what}")),
                    false => Ok(()),
                }
            };
            if let Some((_, what, switch)) = OURS_SWITCHES.iter().find(|s| s.0 == *p) {
                ours_only(what)?;
                switch(&mut c);
                continue;
            }
            match *p {
                "inside" => {}
                "8" => c.length = 8,
                "16" => c.length = 16,
                "mean" => {
                    c.mean = true;
                    c.adaptive = false;
                    c.cycle = false
                }
                "filter" => {
                    ours_only("current-sample filter")?;
                    c.filter = true;
                    c.adaptive = false
                }
                "adaptive" => {
                    ours_only("adaptive current-sample filter")?;
                    c.adaptive = !c.mean && !c.filter
                }
                "without-dilation" => c.dilation = false,
                "without-clip" => c.clip = false,
                _ => match p.split_once('=') {
                    Some(("alpha", v)) => {
                        ours_only("alpha (its feedback is 0.88-0.97)")?;
                        c.alpha = num(p, v, 0.001, 1.0)?
                    }
                    Some(("gamma", v)) => {
                        ours_only("variance gamma (it clips to min-max)")?;
                        c.gamma = num(p, v, 0.0, 8.0)?
                    }
                    Some(("lod", v)) => c.lod_bias = num(p, v, -4.0, 4.0)?,
                    Some(("amax", v)) => {
                        ours_only("speed-dependent weight")?;
                        c.alpha_max = num(p, v, 0.001, 1.0)?
                    }
                    Some(("speed", v)) => {
                        ours_only("speed-dependent weight")?;
                        c.speed = num(p, v, 0.0, 1000.0)?
                    }
                    Some(("tol", v)) => {
                        ours_only("depth test")?;
                        c.depth_tolerance = num(p, v, 0.0, 1.0)?
                    }
                    Some(("ispeed", v)) => {
                        ours_only("moving interiors' current frame")?;
                        c.interior_speed = Some(num(p, v, 0.001, 1000.0)?)
                    }
                    Some(("uspeed", v)) => {
                        ours_only("moving fragments shaded at the pixel centre")?;
                        c.unjitter_speed = Some(num(p, v, 0.001, 1000.0)?)
                    }
                    Some(("sharp", v)) => {
                        ours_only("Lanczos-3 history")?;
                        c.sharp = num(p, v, 0.0, 1.0)?
                    }
                    Some(("ctol", v)) => {
                        ours_only("still pixels' jitter cycle")?;
                        c.cycle_tolerance = num(p, v, 0.0, 1.0)?
                    }
                    _ => {
                        return Err(crate::technique::unknown_param(
                            "taa",
                            p,
                            "inside, 8, 16, alpha=A, amax=A, speed=V, uspeed=V, gamma=G, tol=T, ctol=T, \
                             lod=B, sharp=S, \
                             mean, without-dilation, without-surface-velocity, without-clip, without-ids, without-depth, \
                             without-lanczos, without-catmull, without-speed, without-count, without-luma, \
                             without-cycle, without-centred-reset, without-interior, without-locks, \
                             without-unjitter, ispeed=V, unjitter, interior, \
                             motionlod, \
                             adaptive, filter",
                        ));
                    }
                },
            }
        }
        if c.mean {
            c.cycle = false;
        }
        Ok(c)
    }

    /// The speed at and above which `unjitter` shades a moving fragment wholly at the pixel
    /// centre (`uspeed`, else [`CENTRING_SPEED`]; 0: never, as with `without-speed`).
    pub fn unjitter_speed(&self) -> f32 {
        match self.speed > 0.0 {
            true => self.unjitter_speed.unwrap_or(CENTRING_SPEED),
            false => 0.0,
        }
    }

    /// Whether moving interiors take the current frame (`interior`): as set, else with
    /// `motionlod` only. With the LOD bias kept (`unjitter` alone) a moving fragment is centred
    /// only in its share of the jitter below `uspeed` and its texture is a level sharper, so the
    /// history is what averages it: measured worse there on every scene (docs/post-aa.md,
    /// "Moving interiors under `unjitter`").
    pub fn interior(&self) -> bool {
        self.interior.unwrap_or(self.motion_lod)
    }

    /// The speed at which a moving interior's current-frame weight reaches 1 (`ispeed`, else
    /// [`CENTRING_SPEED`]).
    pub fn interior_speed(&self) -> f32 {
        self.interior_speed.unwrap_or(CENTRING_SPEED)
    }

    /// The history's kernel: [`HISTORY_BILINEAR`], [`HISTORY_CATMULL`] or [`HISTORY_MIXED`].
    pub fn history_kernel(&self) -> u32 {
        match (self.catmull, self.sharp > 0.0) {
            (false, _) => HISTORY_BILINEAR,
            (true, false) => HISTORY_CATMULL,
            (true, true) => HISTORY_MIXED,
        }
    }

    fn flags(&self) -> u32 {
        let mut f = 0;
        for (on, bit) in [
            (self.dilation, F_DILATION),
            (self.clip, F_CLIP),
            (self.ids, F_IDS),
            (self.depth, F_DEPTH),
            (self.mean, F_MEAN),
            (self.filter, F_FILTER),
            (self.count, F_COUNT),
            (self.luma, F_LUMA),
            (self.adaptive, F_ADAPTIVE),
            (self.cycle, F_CYCLE),
            (self.centred_reset, F_CENTRED),
            (self.unjitter && self.interior() && self.speed > 0.0, F_INTERIOR),
            (self.locks, F_LOCK),
            (self.motion_lod, F_SHED),
            (self.surface_velocity, F_SURFACE),
            (self.reactive, F_REACTIVE),
        ] {
            if on {
                f |= bit;
            }
        }
        f
    }
}

pub const F_RESET: u32 = 1;
pub const F_DILATION: u32 = 2;
pub const F_CLIP: u32 = 4;
pub const F_IDS: u32 = 8;
pub const F_DEPTH: u32 = 16;
pub const F_MEAN: u32 = 64;
pub const F_FILTER: u32 = 128;
pub const F_COUNT: u32 = 256;
pub const F_LUMA: u32 = 512;
pub const F_ADAPTIVE: u32 = 1024;
pub const F_CYCLE: u32 = 2048;
pub const F_CENTRED: u32 = 4096;
pub const F_INTERIOR: u32 = 8192;
pub const F_LOCK: u32 = 16384;
pub const F_SHED: u32 = 32768;
pub const F_SURFACE: u32 = 65536;
pub const F_REACTIVE: u32 = 131072;

/// The radical inverse of `i` in `base` (the Halton sequence's element i).
pub fn halton(mut i: u32, base: u32) -> f32 {
    let (mut f, mut r) = (1.0f64, 0.0f64);
    while i > 0 {
        f /= f64::from(base);
        r += f * f64::from(i % base);
        i /= base;
    }
    r as f32
}

/// The jitter of frame `frame` in pixels: Halton(2, 3) elements 1..=length, centred on 0.
pub fn jitter(length: u32, frame: u32) -> [f32; 2] {
    let i = frame % length + 1;
    [halton(i, 2) - 0.5, halton(i, 3) - 0.5]
}

crate::push_constants! {
    struct Push {
        /// W, H (of the output and the geometry), 0, 0.
        size: [i32; 4],
        /// x: F_*, y: n (frames accumulated since the reset), z: the jitter cycle's length.
        flags: [u32; 4],
        /// alpha (current-frame weight), gamma, depth tolerance, exposure scale.
        params: [f32; 4],
        /// INSIDE feedback min, max; still threshold (pixels); the cycle's change tolerance.
        feedback_still: [f32; 4],
        /// x: current-frame weight at and above speed y (pixels per frame; 0: off); zw: the
        /// frame's jitter (pixels).
        speed_jitter: [f32; 4],
        /// x: the speed (pixels per frame) at which a moving interior's current-frame weight
        /// reaches 1 (`interior`; `ispeed`, else `speed`); y: the history kernel's Lanczos-3
        /// share (`sharp`).
        interior: [f32; 4],
    }
}

/// The history's resampling kernel ([`TaaConfig::history_kernel`], the shader's HISTORY): one
/// bilinear tap (`without-catmull`, INSIDE's), Karis' 5-tap Catmull-Rom (`without-lanczos`), or
/// (1 - sharp) Catmull-Rom + sharp Lanczos-3 over 6x6 texels. A define, not a flag: llvmpipe
/// runs both sides of a branch even on a uniform flag (the mixed kernel's 36 reads cost every
/// variant 75 ms a frame at 1280x720, docs/post-aa.md).
pub const HISTORY_BILINEAR: u32 = 0;
pub const HISTORY_CATMULL: u32 = 1;
pub const HISTORY_MIXED: u32 = 2;

/// The pass (shaders/post/taa.comp): `c.inside` picks the mode, `c`'s history kernel the
/// HISTORY define; `packed` geometry is the checkerboard resolve's (object ID | moved,
/// reverse-Z depth bits in one RG32UI image).
pub fn decl(c: &TaaConfig, packed: bool) -> ComputeDecl {
    ComputeDecl::new("taa", "post/taa.comp")
        .define("MODE", u32::from(c.inside))
        .define("PACKED", u32::from(packed))
        .define("HISTORY", c.history_kernel())
        .constants(&[
            ("F_RESET", F_RESET),
            ("F_DILATION", F_DILATION),
            ("F_CLIP", F_CLIP),
            ("F_IDS", F_IDS),
            ("F_DEPTH", F_DEPTH),
            ("F_MEAN", F_MEAN),
            ("F_FILTER", F_FILTER),
            ("F_COUNT", F_COUNT),
            ("F_LUMA", F_LUMA),
            ("F_ADAPTIVE", F_ADAPTIVE),
            ("F_CYCLE", F_CYCLE),
            ("F_CENTRED", F_CENTRED),
            ("F_INTERIOR", F_INTERIOR),
            ("F_LOCK", F_LOCK),
            ("F_SHED", F_SHED),
            ("F_SURFACE", F_SURFACE),
            ("F_REACTIVE", F_REACTIVE),
            ("MOVED", MOVED),
            ("ID_MASK", !MOVED),
            ("HIST_ID_MASK", HIST_ID_MASK),
            ("COUNT_SHIFT", COUNT_SHIFT),
            ("COUNT_MAX", COUNT_MAX),
        ])
        .bindings(&[
            Binding::sampled("cur"),
            Binding::sampled("velocity"),
            Binding::sampled("depth"),
            Binding::sampled("ids"),
            Binding::sampled_with("hist", Filter::Linear),
            Binding::sampled("hist_geom"),
            Binding::image("out_hist", Use::Write),
            Binding::image("out_geom", Use::Write),
            Binding::sampled("cycle"),
            Binding::sampled("range"),
            Binding::image("out_cycle", Use::Write),
            Binding::image("out_range", Use::Write),
            Binding::buffer("turns", Use::Read),
        ])
        .push::<Push>()
}

/// The history: colour (linear HDR), geometry (object ID | [`MOVED`], depth bits) and the still
/// pixels' jitter cycle (its mean so far and sample count; the luma ranges of the last complete
/// cycle and of this one).
fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    let turns = u64::from(crate::gpu_scene::MAX_TURN_IDS) * 4;
    vec![
        ResourceDecl::upload_buffer("turns", turns),
        ResourceDecl::image("history", COLOR_FORMAT, w, h).history(),
        ResourceDecl::image("history_geom", vk::Format::R32G32_UINT, w, h).history(),
        ResourceDecl::image("history_cycle", vk::Format::R32G32B32A32_SFLOAT, w, h).history(),
        ResourceDecl::image("history_range", vk::Format::R16G16B16A16_SFLOAT, w, h).history(),
    ]
}

pub struct Taa {
    config: TaaConfig,
    pass: ComputePass,
    res: Resources,
    push: Push,
    /// Frames accumulated since the last reset (the `mean` weight).
    accumulated: u32,
}

impl Taa {
    fn new(ctx: &PostBuildCtx, c: TaaConfig) -> Result<Taa> {
        let geo: &[Geometry] = ctx.geometry;
        let Some(g0) = geo.first() else {
            return Err(GpuError::Other(
                "taa needs the frame's geometry (velocity, depth, IDs)".into(),
            ));
        };
        if (g0.velocity.width, g0.velocity.height) != (ctx.width, ctx.height) {
            return Err(GpuError::Other(format!(
                "taa needs the geometry at the output resolution {}x{} (it is {}x{})",
                ctx.width, ctx.height, g0.velocity.width, g0.velocity.height
            )));
        }
        let push = Push {
            size: [ctx.width as i32, ctx.height as i32, 0, 0],
            flags: [c.flags(), 0, c.length, 0],
            params: [
                c.alpha,
                c.gamma,
                c.depth_tolerance,
                ctx.exposure_stops.exp2(),
            ],
            feedback_still: [
                INSIDE_FEEDBACK[0],
                INSIDE_FEEDBACK[1],
                STILL_THRESHOLD,
                c.cycle_tolerance,
            ],
            speed_jitter: [c.alpha_max, c.speed, 0.0, 0.0],
            interior: [c.interior_speed(), c.sharp, 0.0, 0.0],
        };
        Ok(Taa {
            config: c,
            pass: decl(&c, g0.packed).build(ctx.gpu, ctx.shaders)?,
            res: Resources::new(ctx.gpu, "taa", &resources(ctx.width, ctx.height))?,
            push,
            accumulated: 0,
        })
    }
}

impl PostPass for Taa {
    fn record(
        &mut self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        frame: &PostFrame,
        input: &Image,
    ) -> Result<()> {
        let f = frame.frame;
        self.accumulated = if frame.reset { 0 } else { self.accumulated + 1 };
        let mut push = self.push;
        push.flags[0] |= if frame.reset { F_RESET } else { 0 };
        push.flags[1] = self.accumulated;
        push.speed_jitter[2] = frame.jitter[0];
        push.speed_jitter[3] = frame.jitter[1];
        crate::gpu_scene::write_turns(self.res.buffer_mut("turns")?, frame.turns)?;
        let g = frame
            .geometry
            .as_ref()
            .ok_or_else(|| GpuError::Other("taa: the frame has no geometry".into()))?;
        let binds = Binds::new()
            .image("cur", input)
            .image("velocity", g.velocity)
            .image("depth", g.depth)
            .image("ids", g.ids)
            .history(self.res.history("history")?, f, "hist", "out_hist")
            .history(
                self.res.history("history_geom")?,
                f,
                "hist_geom",
                "out_geom",
            )
            .history(self.res.history("history_cycle")?, f, "cycle", "out_cycle")
            .history(self.res.history("history_range")?, f, "range", "out_range")
            .buffer("turns", self.res.buffer("turns")?);
        let size = (push.size[0] as u32, push.size[1] as u32);
        self.pass.dispatch_2d(cmd, profiler, &binds, &push, size)
    }

    /// The history slot written this frame is the output.
    fn output(&self, frame: u32) -> Result<&Image> {
        Ok(self.res.history("history")?.write(frame))
    }

    fn jitter(&self, frame: u32) -> Option<[f32; 2]> {
        Some(jitter(self.config.length, frame))
    }

    fn lod_bias(&self) -> f32 {
        self.config.lod_bias
    }

    fn lod_turn(&self) -> f32 {
        match self.config.reactive {
            true => self.config.lod_bias,
            false => 0.0,
        }
    }

    fn reactive(&self) -> bool {
        self.config.reactive
    }

    fn lod_speed(&self) -> f32 {
        match self.config.unjitter {
            true => self.config.unjitter_speed(),
            false => 0.0,
        }
    }

    fn lod_shed(&self) -> f32 {
        match self.config.motion_lod {
            true => self.config.lod_bias,
            false => 0.0,
        }
    }

    fn centred_at_reset(&self) -> bool {
        self.config.centred_reset
    }
}

// ---- The CPU reference ----------------------------------------------------------------------

/// The previous output colour and its geometry (object ID | [`MOVED`], linear depth).
pub type RefHistory<'a> = (&'a [[f32; 3]], &'a [(u32, f32)]);

/// One frame's inputs to [`reference`], all at the output resolution, rows top to bottom.
pub struct RefInputs<'a> {
    pub width: usize,
    pub height: usize,
    /// The technique's colour this frame (linear HDR).
    pub color: &'a [[f32; 3]],
    /// Pixels moved since the previous frame (current - previous).
    pub velocity: &'a [[f32; 2]],
    /// View distance along the camera axis (linear; +inf where nothing was drawn). The shader
    /// compares reverse-Z `near / z`: every test here is the same in linear depth (relative
    /// differences are symmetric, the order reverses), so the two agree up to rounding.
    pub depth: &'a [f32],
    /// Object IDs.
    pub ids: &'a [u32],
    /// The previous output and its geometry (object ID | [`MOVED`], linear depth); `None`: reset.
    pub history: Option<RefHistory<'a>>,
    /// Frames accumulated since the reset (the `mean` weight 1 / (n + 1)).
    pub n: u32,
    /// 2^exposure stops.
    pub exposure_scale: f32,
    /// The frame's jitter (pixels), for the current-sample filter.
    pub jitter: [f32; 2],
    /// The previous frame's still-pixel cycles ([`reference_cycle`]'s third output); `None`:
    /// none (every pixel starts its cycle).
    pub cycle: Option<&'a [CycleState]>,
    /// Each object's turn by object ID (the reactive rule); `None`: none turns.
    pub turns: Option<&'a [f32]>,
}

/// A pixel's jitter cycle (the `history_cycle` and `history_range` images), or a moving pixel's
/// lock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleState {
    /// The mean of this cycle's samples so far (linear HDR, f32).
    pub mean: V3,
    /// Samples in it (0: none).
    pub k: u32,
    /// Perceptual luma range: [lo, hi] of the last complete cycle (lo > hi: none) and of this
    /// one, each rounded to f16 as the RGBA16F image stores it.
    pub range: [f32; 4],
    /// A moving pixel's lock life (`locks`; 0: none): `history_cycle`'s x, a moving pixel
    /// having no cycle.
    pub lock: f32,
}

impl CycleState {
    pub const NONE: CycleState = CycleState {
        mean: [0.0; 3],
        k: 0,
        range: [1.0, 0.0, 1.0, 0.0],
        lock: 0.0,
    };
    fn complete(&self) -> bool {
        self.range[0] <= self.range[1]
    }
}

fn f16_round(v: f32) -> f32 {
    half::f16::from_f32(v).to_f32()
}

const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];
use crate::cpu_math::OFF_3X3 as OFF;

use crate::cpu_math::{V3, catmull_rom, lanczos3_weights};

fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn map3(a: V3, f: impl Fn(f32) -> f32) -> V3 {
    [f(a[0]), f(a[1]), f(a[2])]
}
fn zip3(a: V3, b: V3, f: impl Fn(f32, f32) -> f32) -> V3 {
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])]
}

/// Linear HDR to the perceptual YCoCg the shader compares in (`to_p`), and back (`from_p`):
/// inc/perceptual.glsl's maps (cpu_math), taau's space too.
pub fn to_p(c: V3, e: f32) -> V3 {
    crate::cpu_math::perceptual(c, e)
}
pub fn from_p(y: V3, e: f32) -> V3 {
    crate::cpu_math::linear_from_perceptual(y, e)
}

use crate::cpu_math::clip_towards;

/// |a - b| / max(a, b) (the shader's `depth_rel_diff`, here of linear depths).
fn rel_diff(a: f32, b: f32) -> f32 {
    let m = a.max(b);
    if m > 0.0 && m.is_finite() {
        (a - b).abs() / m
    } else if a == b {
        0.0
    } else {
        1.0
    }
}

fn moving(v: [f32; 2]) -> bool {
    (v[0] * v[0] + v[1] * v[1]).sqrt() > STILL_THRESHOLD
}

/// The CPU reference of shaders/post/taa.comp: (output colour, output geometry).
pub fn reference(c: &TaaConfig, i: &RefInputs) -> (Vec<V3>, Vec<(u32, f32)>) {
    let (o, g, _) = reference_cycle(c, i);
    (o, g)
}

/// [`reference_cycle`]'s output: colour, history geometry, the still pixels' cycles.
pub type RefOutput = (Vec<V3>, Vec<(u32, f32)>, Vec<CycleState>);

/// [`reference`] with the still pixels' cycles it writes (the next frame's [`RefInputs::cycle`]).
pub fn reference_cycle(c: &TaaConfig, i: &RefInputs) -> RefOutput {
    let (w, h) = (i.width as i32, i.height as i32);
    let e = i.exposure_scale;
    let at = |p: [i32; 2]| (p[1].clamp(0, h - 1) * w + p[0].clamp(0, w - 1)) as usize;
    let finite = |v: V3| v.iter().all(|x| x.is_finite());
    let mut out = Vec::with_capacity(i.color.len());
    let mut geom = Vec::with_capacity(i.color.len());
    let mut cycles = Vec::with_capacity(i.color.len());
    for y in 0..h {
        for x in 0..w {
            let cs: Vec<V3> = OFF
                .iter()
                .map(|o| i.color[at([x + o[0], y + o[1]])])
                .collect();
            let ok: Vec<bool> = cs.iter().map(|&v| finite(v)).collect();
            let (mut sum, mut n_ok) = ([0.0f32; 3], 0.0f32);
            for k in 0..9 {
                if ok[k] {
                    sum = zip3(sum, cs[k], |a, b| a + b);
                    n_ok += 1.0;
                }
            }
            let c0 = if ok[4] {
                cs[4]
            } else if n_ok > 0.0 {
                map3(sum, |v| v / n_ok)
            } else {
                [0.0; 3]
            };
            let mut c0 = c0;
            let mut cf = c0;
            if c.filter || c.adaptive {
                let (mut acc, mut ws) = ([0.0f32; 3], 0.0f32);
                for k in 0..9 {
                    if !ok[k] {
                        continue;
                    }
                    let d = [
                        OFF[k][0] as f32 - i.jitter[0],
                        OFF[k][1] as f32 - i.jitter[1],
                    ];
                    let wt = (-2.29 * (d[0] * d[0] + d[1] * d[1])).exp();
                    acc = zip3(acc, cs[k], |a, b| a + wt * b);
                    ws += wt;
                }
                if ws > 0.0 {
                    cf = map3(acc, |a| a / ws);
                }
            }
            if c.filter {
                c0 = cf;
            }
            let y0 = to_p(c0, e);
            let lumas: [f32; 9] = std::array::from_fn(|k| match ok[k] {
                true => to_p(cs[k], e)[0],
                false => y0[0],
            });
            // Geometry: nearest of the 3x3 (smallest linear depth), IDs, depth span.
            let (mut best, mut z_best) = (at([x, y]), f32::INFINITY);
            let (mut lo, mut hi) = (f32::INFINITY, -f32::INFINITY);
            let mut nid = [0u32; 9];
            let mut nz = [0.0f32; 9];
            let mut any = false;
            for (k, o) in OFF.iter().enumerate() {
                let t = at([x + o[0], y + o[1]]);
                let z = i.depth[t];
                nid[k] = i.ids[t];
                nz[k] = z;
                lo = lo.min(z);
                hi = hi.max(z);
                if !any || z < z_best {
                    (best, z_best, any) = (t, z, true);
                }
            }
            // The 3x3 is one plane (see the shader): 1 / depth (reverse-Z's shape) affine on the
            // four lines through the centre (OFF[k], OFF[8 - k]).
            let plane = crate::cpu_math::depth_plane(&nz.map(|z| 1.0 / z), c.depth_tolerance);
            // Dilation, except on a surface (`surface_velocity`): the pixel's own velocity.
            let dilate = c.dilation && !(c.surface_velocity && plane);
            let v = i.velocity[if dilate { best } else { at([x, y]) }];
            let q = [x as f32 + 0.5 - v[0], y as f32 + 0.5 - v[1]];
            let mut result = if c.adaptive { cf } else { c0 };
            // Frames the output holds (see the shader).
            let mut count = 1u32;
            // The pixel's cycle goes on (see the shader), from this state at its history texel.
            let (mut cycling, mut cyc) = (false, CycleState::NONE);
            let mut hist_texel = [0.0f32; 3];
            // The lock's life (`locks`, see the shader): 1 on a thin feature, else the history's
            // less 1 / L.
            let mut life = match c.locks && !c.inside && crate::cpu_math::thin_feature(&lumas) {
                true => 1.0f32,
                false => 0.0,
            };
            if let Some((hist, hgeom)) = i.history {
                let mut use_h = q[0] >= 0.0 && q[1] >= 0.0 && q[0] < w as f32 && q[1] < h as f32;
                let (hid, hz) = match use_h {
                    true => hgeom[at([q[0].floor() as i32, q[1].floor() as i32])],
                    false => (0, 0.0),
                };
                let still = !moving(v) && hid & MOVED == 0;
                if c.cycle && !c.inside && use_h && still {
                    let t = at([q[0].floor() as i32, q[1].floor() as i32]);
                    cyc = i.cycle.map_or(CycleState::NONE, |s| s[t]);
                    hist_texel = hist[t];
                    let (r, tol) = (cyc.range, c.cycle_tolerance);
                    let changed = cyc.complete() && (y0[0] < r[0] - tol || y0[0] > r[1] + tol);
                    use_h = !changed;
                    cycling = !changed;
                }
                let held = (hid >> COUNT_SHIFT) & COUNT_MAX;
                if c.locks && !c.inside && life < 1.0 && use_h && hid & MOVED != 0 {
                    let t = at([q[0].floor() as i32, q[1].floor() as i32]);
                    let prev = i.cycle.map_or(0.0, |s| s[t].lock);
                    life = (prev - 1.0 / c.length as f32).max(0.0);
                }
                // The lock holds on a surface only (see the shader).
                let lock_hold = if plane { life } else { 0.0 };
                let seen = nid.contains(&(hid & HIST_ID_MASK));
                if use_h && !still && (c.ids || c.depth) {
                    if c.ids && lock_hold <= 0.0 {
                        use_h = use_h && seen;
                    }
                    if c.depth {
                        let tol = c.depth_tolerance;
                        use_h = use_h
                            && ((hz >= lo && hz <= hi)
                                || rel_diff(hz, lo) <= tol
                                || rel_diff(hz, hi) <= tol);
                    }
                }
                let fetch = |p: [i32; 2]| hist[at(p)];
                let bilinear = |q: [f32; 2]| -> V3 {
                    let g = [q[0] - 0.5, q[1] - 0.5];
                    let b = [g[0].floor(), g[1].floor()];
                    let f = [g[0] - b[0], g[1] - b[1]];
                    let (bx, by) = (b[0] as i32, b[1] as i32);
                    let mut acc = [0.0f32; 3];
                    for (dx, dy, wt) in [
                        (0, 0, (1.0 - f[0]) * (1.0 - f[1])),
                        (1, 0, f[0] * (1.0 - f[1])),
                        (0, 1, (1.0 - f[0]) * f[1]),
                        (1, 1, f[0] * f[1]),
                    ] {
                        acc = zip3(acc, fetch([bx + dx, by + dy]), |a, s| a + wt * s);
                    }
                    acc
                };
                let mut hc = [0.0f32; 3];
                if use_h {
                    let mixed = |sh: f32| {
                        // (1 - sh) Catmull-Rom (its 4x4, padded to 6x6) + sh Lanczos-3 (its
                        // weights renormalised) over the 6x6 texels, one sum, clamped at 0.
                        let g = [q[0] - 0.5, q[1] - 0.5];
                        let b = [g[0].floor(), g[1].floor()];
                        let f = [g[0] - b[0], g[1] - b[1]];
                        let (lx, ly) = (lanczos3_weights(f[0]), lanczos3_weights(f[1]));
                        let pad = |c: [f32; 4]| [0.0, c[0], c[1], c[2], c[3], 0.0];
                        let (cx, cy) = (pad(catmull_rom(f[0])), pad(catmull_rom(f[1])));
                        let ls = sh / (lx.iter().sum::<f32>() * ly.iter().sum::<f32>());
                        let (bx, by) = (b[0] as i32, b[1] as i32);
                        let mut acc = [0.0f32; 3];
                        for ty in 0..6 {
                            for tx in 0..6 {
                                let wt = (1.0 - sh) * cx[tx] * cy[ty] + ls * lx[tx] * ly[ty];
                                let t = fetch([bx + tx as i32 - 2, by + ty as i32 - 2]);
                                acc = zip3(acc, t, |a, s| a + wt * s);
                            }
                        }
                        map3(acc, |a| a.max(0.0))
                    };
                    let catmull = || {
                        let g = [q[0] - 0.5, q[1] - 0.5];
                        let b = [g[0].floor(), g[1].floor()];
                        let f = [g[0] - b[0], g[1] - b[1]];
                        let (wx, wy) = (catmull_rom(f[0]), catmull_rom(f[1]));
                        let w12 = [wx[1] + wx[2], wy[1] + wy[2]];
                        let c12 = [b[0] + 0.5 + wx[2] / w12[0], b[1] + 0.5 + wy[2] / w12[1]];
                        let c0 = [b[0] - 0.5, b[1] - 0.5];
                        let c3 = [b[0] + 2.5, b[1] + 2.5];
                        let taps = [
                            (w12[0] * wy[0], [c12[0], c0[1]]),
                            (wx[0] * w12[1], [c0[0], c12[1]]),
                            (w12[0] * w12[1], c12),
                            (wx[3] * w12[1], [c3[0], c12[1]]),
                            (w12[0] * wy[3], [c12[0], c3[1]]),
                        ];
                        let (mut acc, mut ws) = ([0.0f32; 3], 0.0f32);
                        for (wt, p) in taps {
                            acc = zip3(acc, bilinear(p), |a, s| a + wt * s);
                            ws += wt;
                        }
                        map3(acc, |a| (a / ws).max(0.0))
                    };
                    // The history's kernel (see the shader's HISTORY).
                    hc = match c.history_kernel() {
                        HISTORY_BILINEAR => bilinear(q),
                        HISTORY_CATMULL => catmull(),
                        _ => mixed(c.sharp),
                    };
                    use_h = finite(hc);
                }
                // The shader tests the history's finiteness before the cycle is read.
                cycling = cycling && use_h;
                if use_h {
                    count = (held + 1).min(COUNT_MAX);
                    let yk: Vec<V3> = (0..9)
                        .map(|k| if ok[k] { to_p(cs[k], e) } else { y0 })
                        .collect();
                    if !c.inside {
                        // Still pixels keep their history unclipped (see the shader).
                        if c.clip && !still {
                            let (mut m1, mut m2) = ([0.0f32; 3], [0.0f32; 3]);
                            for yv in &yk {
                                m1 = zip3(m1, *yv, |a, b| a + b);
                                m2 = zip3(m2, *yv, |a, b| a + b * b);
                            }
                            let mu = map3(m1, |v| v / 9.0);
                            let sigma = zip3(m2, mu, |a, m| (a / 9.0 - m * m).max(0.0).sqrt());
                            let g = c.gamma;
                            let yp = to_p(hc, e);
                            let lo = zip3(mu, sigma, |m, s| m - g * s);
                            let hi = zip3(mu, sigma, |m, s| m + g * s);
                            // Inside the box the history is kept as it is (see the shader).
                            if (0..3).any(|k| yp[k] < lo[k] || yp[k] > hi[k]) {
                                let yh = clip_towards(mu, yp, lo, hi);
                                hc = from_p(zip3(yh, yp, |a, b| a * (1.0 - lock_hold) + b * lock_hold), e);
                            }
                        }
                        result = if c.mean {
                            let wt = 1.0 / (i.n + 1) as f32;
                            zip3(hc, c0, |a, b| a + (b - a) * wt)
                        } else {
                            let mut a = c.alpha;
                            // A moving interior rises to 1 (`interior`, see the shader): one
                            // plane, no other object in the 3x3, no lock holding (under
                            // `motionlod`: no lock holding a history of an object it does not
                            // show).
                            let edge = !plane
                                || (lock_hold > 0.0 && (!seen || !c.motion_lod))
                                || nid.iter().any(|&n| n != nid[4]);
                            let (amax, ramp) = match c.unjitter && c.interior() && !edge {
                                true => (1.0, c.interior_speed()),
                                false => (c.alpha_max, c.speed),
                            };
                            if c.speed > 0.0 {
                                let s = (v[0] * v[0] + v[1] * v[1]).sqrt() / ramp;
                                a += (amax - a) * s.min(1.0);
                            }
                            // The reactive rule: the weight of a turning object's pixel, or of a
                            // pixel whose history shows one, goes on to 1.
                            if c.reactive {
                                let turn_of = |id: u32| {
                                    i.turns
                                        .and_then(|t| t.get(id as usize).copied())
                                        .unwrap_or(0.0)
                                };
                                let turn = turn_of(nid[4]).max(turn_of(hid & HIST_ID_MASK));
                                a += (1.0 - a) * turn;
                            }
                            if c.count {
                                a = a.max(1.0 / count as f32);
                            }
                            let cc = match c.adaptive {
                                true => zip3(c0, cf, |p, f| p + (f - p) * (1.0 / count as f32)),
                                false => c0,
                            };
                            let (mut wc, mut wh) = (a, 1.0 - a);
                            if c.luma {
                                wc /= 1.0 + dot(map3(cc, |v| v * e), LUMA);
                                wh /= 1.0 + dot(map3(hc, |v| v * e), LUMA);
                            }
                            // h + (c - h) t: h itself where c = h (see the shader).
                            zip3(cc, hc, |a, b| b + (a - b) * (wc / (wc + wh)))
                        };
                    } else {
                        let (mut mn, mut mx, mut avg) = ([f32::MAX; 3], [f32::MIN; 3], [0.0f32; 3]);
                        let (mut mn5, mut mx5, mut avg5) =
                            ([f32::MAX; 3], [f32::MIN; 3], [0.0f32; 3]);
                        for (k, yv) in yk.iter().enumerate() {
                            mn = zip3(mn, *yv, f32::min);
                            mx = zip3(mx, *yv, f32::max);
                            avg = zip3(avg, *yv, |a, b| a + b);
                            if matches!(k, 1 | 3 | 4 | 5 | 7) {
                                mn5 = zip3(mn5, *yv, f32::min);
                                mx5 = zip3(mx5, *yv, f32::max);
                                avg5 = zip3(avg5, *yv, |a, b| a + b);
                            }
                        }
                        mn = zip3(mn, mn5, |a, b| 0.5 * (a + b));
                        mx = zip3(mx, mx5, |a, b| 0.5 * (a + b));
                        avg = zip3(avg, avg5, |a, b| 0.5 * (a / 9.0 + b / 5.0));
                        let ext = 0.125 * (mx[0] - mn[0]);
                        for k in 1..3 {
                            mn[k] = y0[k] - ext;
                            mx[k] = y0[k] + ext;
                            avg[k] = y0[k];
                        }
                        let mut yh = to_p(hc, e);
                        if c.clip {
                            let centre = [0, 1, 2].map(|k| avg[k].clamp(mn[k], mx[k]));
                            yh = clip_towards(centre, yh, mn, mx);
                        }
                        let (l0, l1) = (y0[0], yh[0]);
                        let diff = (l0 - l1).abs() / l0.max(l1.max(0.2));
                        let wgt = (1.0 - diff) * (1.0 - diff);
                        let [fmin, fmax] = INSIDE_FEEDBACK;
                        let feedback = fmin + (fmax - fmin) * wgt;
                        result = from_p(zip3(y0, yh, |a, b| a + (b - a) * feedback), e);
                    }
                }
            }
            let mut next = CycleState::NONE;
            // A centred reset frame is no phase of the jitter cycle: the cycle starts after it.
            let centred = c.centred_reset && i.history.is_none();
            if c.cycle && !c.inside && !moving(v) && !centred {
                let l = y0[0];
                if cycling && cyc.k > 0 {
                    let k = cyc.k + 1;
                    let m = zip3(cyc.mean, c0, |m, s| m + (s - m) / k as f32);
                    let cur = [cyc.range[2].min(l), cyc.range[3].max(l)];
                    if k >= c.length {
                        result = m;
                        next.range = [cur[0], cur[1], 1.0, 0.0];
                    } else {
                        if cyc.complete() {
                            result = hist_texel;
                        }
                        next = CycleState {
                            mean: m,
                            k,
                            range: [cyc.range[0], cyc.range[1], cur[0], cur[1]],
                            lock: 0.0,
                        };
                    }
                } else {
                    let keep = cycling && cyc.complete();
                    if keep {
                        result = hist_texel;
                    }
                    next = CycleState {
                        mean: c0,
                        k: 1,
                        range: match keep {
                            true => [cyc.range[0], cyc.range[1], l, l],
                            false => [1.0, 0.0, l, l],
                        },
                        lock: 0.0,
                    };
                }
                next.range = next.range.map(f16_round);
            }
            if !c.inside && moving(v) {
                next.lock = life;
            }
            cycles.push(next);
            out.push(result);
            let centre = at([x, y]);
            geom.push((hist_geom_x(i.ids[centre], count, moving(v)), i.depth[centre]));
        }
    }
    (out, geom, cycles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_jitter_is_the_published_sequence() {
        // Halton(2): 1/2, 1/4, 3/4, 1/8; Halton(3): 1/3, 2/3, 1/9, 4/9.
        let j: Vec<[f32; 2]> = (0..4).map(|f| jitter(8, f)).collect();
        let want = [
            [0.0, 1.0 / 3.0 - 0.5],
            [-0.25, 2.0 / 3.0 - 0.5],
            [0.25, 1.0 / 9.0 - 0.5],
            [-0.375, 4.0 / 9.0 - 0.5],
        ];
        for (a, b) in j.iter().zip(&want) {
            assert!(
                (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6,
                "{a:?}"
            );
        }
        assert_eq!(jitter(8, 8), jitter(8, 0), "length 8 repeats");
        assert_ne!(jitter(16, 8), jitter(16, 0));
        // The jitters of one cycle average to about the pixel centre.
        let m: f32 = (0..16).map(|f| jitter(16, f)[0]).sum::<f32>() / 16.0;
        assert!(m.abs() < 0.05, "{m}");
    }

    #[test]
    fn parameters_parse_and_inside_refuses_ours() {
        assert_eq!(TaaConfig::parse(&[]), Ok(TaaConfig::OURS));
        assert_eq!(TaaConfig::parse(&["inside"]), Ok(TaaConfig::INSIDE));
        let c = TaaConfig::parse(&["16", "gamma=1.5", "without-clip", "without-ids"]).unwrap();
        assert!(c.length == 16 && c.gamma == 1.5 && !c.clip && !c.ids && c.depth);
        assert!(TaaConfig::parse(&["inside", "without-ids"]).is_err());
        assert!(TaaConfig::parse(&["inside", "alpha=0.2"]).is_err());
        assert!(TaaConfig::parse(&["inside", "filter"]).is_err());
        assert!(TaaConfig::parse(&["inside", "without-count"]).is_err());
        let a = TaaConfig::parse(&["adaptive", "without-count", "without-luma"]).unwrap();
        assert!(a.adaptive && !a.count && !a.luma && !TaaConfig::OURS.adaptive);
        assert!(!TaaConfig::parse(&["mean", "adaptive"]).unwrap().adaptive);
        assert!(TaaConfig::parse(&["filter"]).unwrap().filter && !TaaConfig::OURS.filter);
        let s = TaaConfig::parse(&["speed=4", "amax=0.7", "lod=-2"]).unwrap();
        assert!(s.speed == 4.0 && s.alpha_max == 0.7 && s.lod_bias == -2.0);
        assert_eq!(TaaConfig::parse(&["without-speed"]).unwrap().speed, 0.0);
        assert!(TaaConfig::parse(&["gamma=-1"]).is_err());
        assert!(TaaConfig::parse(&["12"]).is_err());
        assert!(TaaConfig::parse(&["without-sharpness"]).is_err());
        // The jitter cycle: ours by default, off with `mean`, in INSIDE's mode, with
        // `without-cycle`; its tolerance; the LOD bias withdrawn with motion, opt-in.
        const { assert!(TaaConfig::OURS.cycle && !TaaConfig::INSIDE.cycle) };
        assert!(!TaaConfig::parse(&["mean"]).unwrap().cycle);
        assert!(!TaaConfig::parse(&["without-cycle"]).unwrap().cycle);
        assert_eq!(TaaConfig::parse(&["ctol=0.05"]).unwrap().cycle_tolerance, 0.05);
        assert!(TaaConfig::parse(&["ctol=2"]).is_err());
        assert!(TaaConfig::parse(&["motionlod"]).unwrap().motion_lod && !TaaConfig::OURS.motion_lod);
        for p in ["without-cycle", "ctol=0.1", "motionlod"] {
            assert!(TaaConfig::parse(&["inside", p]).is_err(), "inside takes {p}");
        }
    }

    #[test]
    fn perceptual_space_round_trips() {
        for c in [
            [0.0, 0.0, 0.0],
            [1.0, 0.5, 0.25],
            [40.0, 3.0, 0.01],
            [0.02, 0.9, 7.0],
        ] {
            let back = from_p(to_p(c, 2.0), 2.0);
            for k in 0..3 {
                assert!(
                    (back[k] - c[k]).abs() <= 1e-4 * (1.0 + c[k]),
                    "{c:?} -> {back:?}"
                );
            }
        }
    }

    fn flat(w: usize, h: usize, c: V3) -> Vec<V3> {
        vec![c; w * h]
    }

    /// A frame's colour, velocity, depth and IDs.
    type Frame<'a> = (&'a [V3], &'a [[f32; 2]], &'a [f32], &'a [u32]);

    /// A frame's inputs with a history of 20 frames, exposure 1 and no jitter: the frame, the
    /// history, the previous frame's cycles and locks.
    fn moving_frame<'a>(
        (width, height): (usize, usize),
        (color, velocity, depth, ids): Frame<'a>,
        history: RefHistory<'a>,
        cycle: Option<&'a [CycleState]>,
    ) -> RefInputs<'a> {
        RefInputs {
            width,
            height,
            color,
            velocity,
            depth,
            ids,
            history: Some(history),
            n: 20,
            exposure_scale: 1.0,
            jitter: [0.0; 2],
            cycle,
            turns: None,
        }
    }

    /// The jitter cycle on a 6x5 still frame whose colour alternates 1, 2 (what jitter does to
    /// a pixel), with frame 0 jittered too (`without-centred-reset`; ours starts the cycle at
    /// frame 1, after the centred reset, and completes it at frame 8): frame 7 completes the
    /// first cycle and shows its mean 1.5, frames 8-11 hold it bit for bit; frame 12's sample 5
    /// lies outside the cycle's luma range, so the history is
    /// rejected (the output is the sample, 5, one frame held) and its cycle restarts; with a
    /// tolerance wider than the change it holds 1.5, and with `without-cycle` it blends.
    #[test]
    fn the_jitter_cycle_holds_its_mean_and_restarts_on_a_change() {
        let (w, h) = (6, 5);
        let vel = vec![[0.0f32; 2]; w * h];
        let depth = vec![2.0f32; w * h];
        let ids = vec![1u32; w * h];
        let colour = |f: u32| match f {
            12 => 5.0,
            _ => 1.0 + (f % 2) as f32,
        };
        let run = |c: &TaaConfig| -> Vec<(V3, CycleState)> {
            let mut state: Option<RefOutput> = None;
            let mut seen = Vec::new();
            for f in 0..13u32 {
                let cur = flat(w, h, [colour(f); 3]);
                let i = RefInputs {
                    width: w,
                    height: h,
                    color: &cur,
                    velocity: &vel,
                    depth: &depth,
                    ids: &ids,
                    history: state.as_ref().map(|(o, g, _)| (&o[..], &g[..])),
                    n: f,
                    exposure_scale: 1.0,
                    jitter: [0.0; 2],
                    cycle: state.as_ref().map(|(_, _, s)| &s[..]),
                    turns: None,
                };
                let next = reference_cycle(c, &i);
                seen.push((next.0[0], next.2[0]));
                state = Some(next);
            }
            seen
        };
        // Ours renders frame 0 (the reset) centred: it is no phase of the cycle, which then runs
        // over frames 1-8 (its mean 1.5 at frame 8).
        let centred = run(&TaaConfig::OURS);
        assert_eq!(centred[0].1, CycleState::NONE, "a centred reset starts no cycle");
        assert_eq!(centred[1].1.k, 1, "the cycle starts after it");
        assert_eq!(centred[7].1.k, 7);
        assert_eq!(centred[8].0, [1.5; 3], "frame 8: the cycle's mean");
        // The rest on frames jittered from frame 0 on (`without-centred-reset`).
        let ours = run(&TaaConfig::parse(&["without-centred-reset"]).expect("config"));
        assert_eq!(ours[7].0, [1.5; 3], "frame 7: the cycle's mean");
        assert_eq!(ours[7].1.k, 0, "a complete cycle starts the next");
        let l = |v: f32| f16_round(to_p([v; 3], 1.0)[0]);
        assert_eq!(ours[7].1.range[..2], [l(1.0), l(2.0)], "its luma range");
        for (f, (o, s)) in ours.iter().enumerate().take(12).skip(8) {
            assert_eq!(*o, [1.5; 3], "frame {f} holds the mean");
            assert_eq!(s.k, f as u32 - 7);
        }
        assert!((ours[6].0[0] - 1.5).abs() > 1e-3, "before: the blend");
        assert!((ours[12].0[0] - 5.0).abs() < 1e-5, "changed: {:?}", ours[12].0);
        assert_eq!(ours[12].1.k, 1, "the cycle restarts");
        assert_eq!(ours[12].0, [5.0; 3], "the history is rejected");
        assert!(!ours[12].1.complete());
        let wide = TaaConfig {
            cycle_tolerance: 1.0,
            ..TaaConfig::OURS
        };
        assert_eq!(run(&wide)[12].0, [1.5; 3], "inside the tolerance: held");
        let off = run(&TaaConfig {
            cycle: false,
            ..TaaConfig::OURS
        });
        assert!((off[11].0[0] - off[10].0[0]).abs() > 1e-3, "without-cycle blends");
        assert!(off.iter().all(|(_, s)| *s == CycleState::NONE));
    }

    /// A w x h frame of two objects (1 in the left half, 2 in the right) moving 2 px a frame
    /// down, the current colour 1 over a history of 3 whose geometry holds each pixel's object
    /// (20 frames, moved): its colour, velocity, IDs, history and history geometry.
    #[allow(clippy::type_complexity)]
    fn two_objects_moving(
        w: usize,
        h: usize,
    ) -> (Vec<V3>, Vec<[f32; 2]>, Vec<u32>, Vec<V3>, Vec<(u32, f32)>) {
        let ids: Vec<u32> = (0..w * h).map(|i| if i % w < 3 { 1 } else { 2 }).collect();
        let hg = ids
            .iter()
            .map(|&id| (hist_geom_x(id, 20, true), 2.0))
            .collect();
        (
            flat(w, h, [1.0; 3]),
            vec![[0.0f32, 2.0]; w * h],
            ids,
            flat(w, h, [3.0; 3]),
            hg,
        )
    }

    /// The reactive rule: on the 6x5 frame below moving 2 px a frame (past `speed`), a history
    /// of 3 against a current frame of 1 (linear blend, no clipping): object 1 turning fully
    /// takes the current frame alone, turning half blends half way from amax's 2 to 1; object
    /// 2 (not turning), `without-reactive` or no turns keep amax's blend.
    #[test]
    fn a_turning_object_takes_the_current_frame() {
        let (w, h) = (6usize, 5usize);
        let (cur, vel, ids, hist, hg) = two_objects_moving(w, h);
        let depth = vec![2.0f32; w * h];
        let c = TaaConfig {
            clip: false,
            luma: false,
            ..TaaConfig::OURS
        };
        let run = |c: &TaaConfig, turns: Option<&[f32]>| {
            let i = RefInputs {
                turns,
                ..moving_frame((w, h), (&cur, &vel, &depth, &ids), (&hist, &hg), None)
            };
            reference(c, &i).0
        };
        let (one, two) = (3 * w, 3 * w + 5);
        let full = run(&c, Some(&[0.0, 1.0, 0.0]));
        assert_eq!(full[one], [1.0; 3], "turning fully: the current frame");
        assert!((full[two][0] - 2.0).abs() < 1e-6, "not turning: amax {:?}", full[two]);
        let half = run(&c, Some(&[0.0, 0.5, 0.0]));
        assert!((half[one][0] - 1.5).abs() < 1e-6, "turning half: {:?}", half[one]);
        let off = TaaConfig {
            reactive: false,
            ..c
        };
        for o in [run(&off, Some(&[0.0, 1.0, 0.0])), run(&c, None)] {
            assert!((o[one][0] - 2.0).abs() < 1e-6, "{:?}", o[one]);
        }
        assert!(!TaaConfig::parse(&["inside"]).expect("inside").reactive);
        assert!(!TaaConfig::parse(&["without-reactive"]).expect("ok").reactive);
    }

    /// The reactive rule reads the history's object too: on the frame above, the pixel of object
    /// 2 beside object 1 (its 3x3 meets both, so the ID test keeps a history of either) whose
    /// history texel shows object 1 takes the current frame alone when object 1 turns, and
    /// amax's blend when it does not; its neighbour of object 2 with object 2's history keeps
    /// amax's blend while object 1 turns (where an object uncovers the background, no trail of
    /// it is kept).
    #[test]
    fn a_history_of_a_turning_object_takes_the_current_frame() {
        let (w, h) = (6usize, 5usize);
        let (cur, vel, ids, hist, mut hg) = two_objects_moving(w, h);
        let depth = vec![2.0f32; w * h];
        let c = TaaConfig {
            clip: false,
            luma: false,
            ..TaaConfig::OURS
        };
        // Pixel (3, 3) is object 2; moving 2 px down a frame, its history texel is (3, 1).
        let (pixel, beside) = (3 * w + 3, 3 * w + 4);
        hg[w + 3] = (hist_geom_x(1, 20, true), 2.0);
        let run = |turns: &[f32]| {
            let i = RefInputs {
                turns: Some(turns),
                ..moving_frame((w, h), (&cur, &vel, &depth, &ids), (&hist, &hg), None)
            };
            reference(&c, &i).0
        };
        let turning = run(&[0.0, 1.0, 0.0]);
        assert_eq!(turning[pixel], [1.0; 3], "a turning object's history");
        assert!((turning[beside][0] - 2.0).abs() < 1e-6, "{:?}", turning[beside]);
        let still = run(&[0.0, 0.0, 0.0]);
        assert!((still[pixel][0] - 2.0).abs() < 1e-6, "{:?}", still[pixel]);
    }

    /// The history's kernel: (1 - sharp) x Catmull-Rom + sharp x Lanczos-3. A history of a
    /// vertical step (0 left of x = 8, 1 from it) reprojected half a pixel: each kernel gives its
    /// own weights' sums at the step (`sharp=0` Catmull-Rom's, `sharp=1` Lanczos-3's, overshoot
    /// included), the default the mean of the two, each clamped at 0, and at rest (a
    /// whole-pixel motion) every kernel returns the history itself.
    #[test]
    fn the_history_kernel_mixes_catmull_rom_and_lanczos3() {
        let (w, h) = (16usize, 4usize);
        let hist: Vec<V3> = (0..w * h).map(|i| [if i % w < 8 { 0.0 } else { 1.0 }; 3]).collect();
        let cur = flat(w, h, [0.5; 3]);
        let ids = vec![1u32; w * h];
        let depth = vec![2.0f32; w * h];
        let hg: Vec<(u32, f32)> = ids.iter().map(|&id| (hist_geom_x(id, 20, true), 2.0)).collect();
        let at = |sharp: f32, v: [f32; 2]| {
            let vel = vec![v; w * h];
            let c = TaaConfig {
                clip: false,
                luma: false,
                alpha: 0.001,
                speed: 0.0,
                count: false,
                locks: false,
                sharp,
                ..TaaConfig::OURS
            };
            let i = moving_frame((w, h), (&cur, &vel, &depth, &ids), (&hist, &hg), None);
            let out = reference(&c, &i).0;
            // Undo the blend with the current frame: out = h + (0.5 - h) 0.001.
            std::array::from_fn::<f32, 3, _>(|x| (out[w + 6 + x][0] - 0.0005) / 0.999)
        };
        // Pixels 6, 7, 8 sample the history at x + 0.5 + 0.5: between texels 6|7, 7|8, 8|9.
        let v = [-0.5, 0.0];
        let l = lanczos3_weights(0.5);
        let cr = catmull_rom(0.5);
        // Unclamped: taps j = -2..3 around texel 6 + k, the ones at or past x = 8 are 1.
        let want_l = |k: usize| -> f32 {
            let s: f32 = (0..6).filter(|&j| 6 + k + j >= 10).map(|j| l[j]).sum();
            s / l.iter().sum::<f32>()
        };
        // The motion is along x only, so Jimenez's five taps are Catmull-Rom's four along x
        // (the dropped corners weigh 0 at f = 0 along y); its weights sum to 1.
        let want_c = |k: usize| -> f32 { (0..4).filter(|&j| 6 + k + j >= 9).map(|j| cr[j]).sum::<f32>() };
        for k in 0..3 {
            let (c0, l1, m) = (at(0.0, v)[k], at(1.0, v)[k], at(0.5, v)[k]);
            let (c, l, mix) = (want_c(k), want_l(k), 0.5 * (want_c(k) + want_l(k)));
            assert!((c0 - c.max(0.0)).abs() < 1e-4, "Catmull-Rom {k}: {c0} against {c}");
            assert!((l1 - l.max(0.0)).abs() < 1e-4, "Lanczos-3 {k}: {l1} against {l}");
            assert!((m - mix.max(0.0)).abs() < 1e-4, "the mix {k}: {m} against {mix}");
        }
        assert!(at(1.0, v)[2] > 1.0, "Lanczos-3 overshoots past the step");
        for sharp in [0.0, 0.5, 1.0] {
            assert_eq!(at(sharp, [-1.0, 0.0]).map(|x| x.round()), [0.0, 1.0, 1.0], "{sharp}");
        }
        assert_eq!(TaaConfig::OURS.sharp, 0.5);
        assert_eq!(TaaConfig::parse(&["without-lanczos"]).expect("ok").sharp, 0.0);
        assert_eq!(TaaConfig::parse(&["sharp=1"]).expect("ok").sharp, 1.0);
        assert!(TaaConfig::parse(&["sharp=2"]).is_err());
        assert!(TaaConfig::parse(&["inside", "sharp=1"]).is_err());
    }

    /// Moving interiors (`interior`: on with `motionlod`, off with `unjitter` alone unless set):
    /// on a 6x5 frame moving 2 px a frame (the default `speed`, so amax applies in full), left
    /// half object 1, right half object 2, a history of 3 against a current frame of 1 (linear
    /// blend, no clipping): a pixel whose 3x3 is one object on one plane takes the current frame
    /// alone (1), also where the plane recedes (depth 2 to 3 over the 3x3, affine in 1 / depth);
    /// one whose 3x3 meets the other object, or a depth 50% farther off that plane, blends with
    /// amax (2); `without-interior`, plain `unjitter` and the jittered path blend everywhere.
    #[test]
    fn moving_interiors_take_the_current_frame_under_motionlod() {
        let (w, h) = (6usize, 5usize);
        let (cur, vel, ids, hist, hg) = two_objects_moving(w, h);
        // The previous frame's locks (`CycleState::lock`), where a case gives them.
        let run_cycle =
            |c: &TaaConfig, depth: &[f32], hg: &[(u32, f32)], cycle: Option<&[CycleState]>| {
                let i = moving_frame((w, h), (&cur, &vel, depth, &ids), (&hist, hg), cycle);
                reference(c, &i).0
            };
        let run_with = |c: &TaaConfig, depth: &[f32], hg: &[(u32, f32)]| run_cycle(c, depth, hg, None);
        let run = |c: &TaaConfig, depth: &[f32]| run_with(c, depth, &hg);
        let base = TaaConfig {
            clip: false,
            luma: false,
            unjitter: false,
            ..TaaConfig::OURS
        };
        let ml = TaaConfig {
            motion_lod: true,
            unjitter: true,
            ..base
        };
        let flat_depth = vec![2.0f32; w * h];
        // (0, 3): its 3x3 (clamped) is object 1 only; (2, 3) meets object 2 at x = 3. Both
        // histories (2 rows up) show object 1.
        let (interior, edge) = (3 * w, 3 * w + 2);
        let o = run(&ml, &flat_depth);
        assert_eq!(o[interior], [1.0; 3], "a moving interior: the current frame");
        assert!((o[edge][0] - 2.0).abs() < 1e-6, "an edge blends: {:?}", o[edge]);
        for c in [
            TaaConfig {
                interior: Some(false),
                ..ml
            },
            base,
        ] {
            let o = run(&c, &flat_depth);
            assert!((o[interior][0] - 2.0).abs() < 1e-6, "{:?}", o[interior]);
        }
        // A depth 50% farther in (0, 3)'s 3x3: an edge too.
        let mut deeper = flat_depth.clone();
        deeper[4 * w + 1] = 3.0;
        assert!((run(&ml, &deeper)[interior][0] - 2.0).abs() < 1e-6);
        // A receding plane: 1 / depth affine in y, from 1/2 at row 2 to 1/3 at row 4 (its span
        // over the 3x3, 50%, is far over the tolerance): still an interior. Each history texel
        // holds the depth its point has now, 2 rows down (the camera moved), so the history's
        // depth test keeps it: `without-interior` blends it.
        let z = |row: usize| 1.0 / (0.5 - row as f32 / 12.0 + 2.0 / 12.0);
        let recede: Vec<f32> = (0..w * h).map(|k| z(k / w)).collect();
        let hg_recede: Vec<(u32, f32)> = ids
            .iter()
            .enumerate()
            .map(|(k, &id)| (hist_geom_x(id, 20, true), z(k / w + 2)))
            .collect();
        let o = run_with(&ml, &recede, &hg_recede);
        assert_eq!(o[interior], [1.0; 3], "a receding plane's interior");
        let without = TaaConfig {
            interior: Some(false),
            ..ml
        };
        let kept = run_with(&without, &recede, &hg_recede)[interior];
        assert!((kept[0] - 2.0).abs() < 1e-6, "its history is kept: {kept:?}");
        // `unjitter` (no LOD shed, the default) blends its interiors; with `interior` it has the
        // same rule.
        let unjitter = TaaConfig::parse(&["unjitter"]).expect("unjitter");
        assert!(unjitter.unjitter && !unjitter.motion_lod && !unjitter.interior());
        let plain = |c: TaaConfig| TaaConfig {
            clip: false,
            luma: false,
            ..c
        };
        let o = run(&plain(unjitter), &flat_depth);
        assert!((o[interior][0] - 2.0).abs() < 1e-6, "`unjitter` blends: {:?}", o[interior]);
        let with = TaaConfig::parse(&["interior"]).expect("interior");
        assert!(with.unjitter && !with.motion_lod && with.interior());
        let o = run(&plain(with), &flat_depth);
        assert_eq!(o[interior], [1.0; 3], "`unjitter:interior`: the current frame");
        // A lock on the interior's history texel (life 7/8 after aging): with the bias kept
        // (`unjitter`) the lock keeps the history that averages the sharper sample (amax, 2);
        // with it shed (`motionlod`) the sample is native's own and the interior takes it (1),
        // unless the locked history shows an object the 3x3 does not (a sub-pixel feature this
        // frame missed; the ID test skipped for the lock): then amax again.
        let locked: Vec<CycleState> = (0..w * h)
            .map(|_| CycleState {
                lock: 1.0,
                ..CycleState::NONE
            })
            .collect();
        let run_locked =
            |c: &TaaConfig, hg: &[(u32, f32)]| run_cycle(c, &flat_depth, hg, Some(&locked))[interior];
        let uj = TaaConfig {
            motion_lod: false,
            interior: Some(true),
            ..ml
        };
        assert!((run_locked(&uj, &hg)[0] - 2.0).abs() < 1e-6, "unjitter: locked, amax");
        assert_eq!(run_locked(&ml, &hg), [1.0; 3], "motionlod: the interior's own sample");
        let other: Vec<(u32, f32)> = hg.iter().map(|_| (hist_geom_x(3, 20, true), 2.0)).collect();
        let o = run_locked(&ml, &other);
        assert!((o[0] - 2.0).abs() < 1e-6, "a locked history of another object: {o:?}");
        let without = TaaConfig::parse(&["without-interior", "motionlod"]).expect("parse");
        assert!(without.motion_lod && !without.interior(), "without-interior wins in any order");
        assert!(TaaConfig::parse(&["inside", "without-interior"]).is_err());
        assert!(TaaConfig::parse(&["inside", "interior"]).is_err());
    }

    /// A surface keeps its own velocity (`surface_velocity`): on a 7x6 frame of a floor
    /// receding upwards (1 / depth affine in y, nearer below) whose velocity grows with y, as a
    /// camera's parallax gives, and a near post (object 2, depth 0.5, its own velocity) in column
    /// 6. The history is a gradient in x and y (bilinear, no clip, no tests), so the output
    /// shows where it was fetched. The floor's interior takes its own velocity, as without
    /// dilation (the nearest texel, the one below, moves faster); the pixel beside the post takes
    /// the post's, as with dilation; `without-surface-velocity` dilates everywhere.
    #[test]
    fn a_surface_keeps_its_own_velocity() {
        let (w, h) = (7usize, 6usize);
        let cur = flat(w, h, [0.0; 3]);
        let post = |k: usize| k % w == 6;
        let z = |row: usize| 1.0 / (0.2 + 0.05 * row as f32);
        let depth: Vec<f32> = (0..w * h)
            .map(|k| if post(k) { 0.5 } else { z(k / w) })
            .collect();
        let vel: Vec<[f32; 2]> = (0..w * h)
            .map(|k| match post(k) {
                true => [-1.5, 0.0],
                false => [0.3 + 0.2 * (k / w) as f32, 0.5],
            })
            .collect();
        let ids: Vec<u32> = (0..w * h).map(|k| if post(k) { 2 } else { 1 }).collect();
        let hist: Vec<V3> = (0..w * h)
            .map(|k| [(k % w) as f32 + 1.0, (k / w) as f32 + 1.0, 0.0])
            .collect();
        let hg: Vec<(u32, f32)> = ids.iter().map(|&id| (hist_geom_x(id, 20, true), 2.0)).collect();
        let run = |c: &TaaConfig| {
            reference(c, &moving_frame((w, h), (&cur, &vel, &depth, &ids), (&hist, &hg), None)).0
        };
        let base = TaaConfig {
            clip: false,
            luma: false,
            catmull: false,
            ids: false,
            depth: false,
            ..TaaConfig::OURS
        };
        let own = run(&TaaConfig {
            dilation: false,
            ..base
        });
        let dilated = run(&TaaConfig {
            surface_velocity: false,
            ..base
        });
        let ours = run(&base);
        assert!(TaaConfig::parse(&[]).expect("ours").surface_velocity);
        assert!(!TaaConfig::parse(&["inside"]).expect("inside").surface_velocity);
        let (floor, beside) = (2 * w + 2, 2 * w + 5);
        assert_ne!(own[floor], dilated[floor], "the floor's nearest texel moves faster");
        assert_eq!(ours[floor], own[floor], "the floor's own velocity");
        assert_ne!(own[beside], dilated[beside], "the post's velocity differs");
        assert_eq!(ours[beside], dilated[beside], "beside the post: the post's velocity");
    }

    /// Thin features' locks (`locks`), on a 6x7 frame panning 1 px a frame over a plane of 0.2
    /// (object 1, depth 2). The history holds a 1 px line of 1.0 on row 3 (a decal, object 2,
    /// at the plane's depth) that this frame's jitter missed, locked last frame: its history is
    /// kept (the ID test skipped, the clip relaxed by the lock's life 7/8), where without locks
    /// the ID test drops it for the plane. The lock ages by 1/8 a frame and dies; a history
    /// nearer than the tolerance (a disocclusion) is dropped, locked or not; a lock holds on a
    /// surface only (with the row below 50% farther, the 3x3 is no plane: a silhouette); and
    /// this frame's own thin line sets a lock on its row only.
    #[test]
    fn a_locked_thin_feature_keeps_its_history() {
        let (w, h) = (6usize, 7usize);
        let plane = [0.2f32; 3];
        let cur = flat(w, h, plane);
        let vel = vec![[1.0f32, 0.0]; w * h];
        let depth = vec![2.0f32; w * h];
        let ids = vec![1u32; w * h];
        let hist: Vec<V3> = (0..w * h)
            .map(|k| if k / w == 3 { [1.0; 3] } else { plane })
            .collect();
        let hg = |z: f32| -> Vec<(u32, f32)> {
            (0..w * h)
                .map(|k| match k / w == 3 {
                    true => (hist_geom_x(2, 20, true), z),
                    false => (hist_geom_x(1, 20, true), 2.0),
                })
                .collect()
        };
        let locks = |life: f32| -> Vec<CycleState> {
            (0..w * h)
                .map(|k| CycleState {
                    lock: if k / w == 3 { life } else { 0.0 },
                    ..CycleState::NONE
                })
                .collect()
        };
        let run_at = |c: &TaaConfig,
                      color: &[V3],
                      depth: &[f32],
                      hg: &[(u32, f32)],
                      cyc: &[CycleState]| {
            let i = moving_frame((w, h), (color, &vel, depth, &ids), (&hist, hg), Some(cyc));
            reference_cycle(c, &i)
        };
        let run = |c: &TaaConfig, color: &[V3], hg: &[(u32, f32)], cyc: &[CycleState]| {
            run_at(c, color, &depth, hg, cyc)
        };
        let near = |a: V3| a.iter().all(|v| (v - plane[0]).abs() < 1e-5);
        // The weight ramp of 2 px (1 px a frame: the current frame at 0.3), so that the kept
        // history shows over 0.5.
        let ours = TaaConfig {
            speed: 2.0,
            ..TaaConfig::OURS
        };
        let p = 3 * w + 3;
        let (o, _, next) = run(&ours, &cur, &hg(2.0), &locks(1.0));
        assert!(o[p][0] > 0.5, "the locked line keeps its history: {:?}", o[p]);
        assert_eq!(next[p].lock, 1.0 - 1.0 / 8.0, "the lock ages by 1 / L");
        assert!(near(o[p + w]), "the plane around it: {:?}", o[p + w]);
        let without = TaaConfig {
            speed: 2.0,
            ..TaaConfig::parse(&["without-locks"]).expect("without-locks")
        };
        assert!(!without.locks && ours.locks);
        let (o, _, next) = run(&without, &cur, &hg(2.0), &locks(1.0));
        assert!(near(o[p]), "without locks the ID test drops it: {:?}", o[p]);
        assert_eq!(next[p].lock, 0.0);
        // A lock at its last 1/L is gone this frame.
        assert!(near(run(&ours, &cur, &hg(2.0), &locks(1.0 / 8.0)).0[p]));
        // Nearer by 50% (a disocclusion): dropped, locked or not.
        assert!(near(run(&ours, &cur, &hg(1.0), &locks(1.0)).0[p]));
        // A silhouette: no plane, no hold (the lock itself lives on).
        let step: Vec<f32> = (0..w * h)
            .map(|k| if k / w == 4 { 3.0 } else { 2.0 })
            .collect();
        let (o, _, next) = run_at(&ours, &cur, &step, &hg(2.0), &locks(1.0));
        assert!(near(o[p]), "a silhouette's lock does not hold: {:?}", o[p]);
        assert_eq!(next[p].lock, 1.0 - 1.0 / 8.0);
        // The ID test alone off, the clip keeps the line only in the lock's proportion.
        let no_ids = TaaConfig { ids: false, ..ours };
        let kept = run(&no_ids, &cur, &hg(2.0), &locks(1.0)).0[p][0];
        let clipped = run(&TaaConfig { locks: false, ..no_ids }, &cur, &hg(2.0), &locks(1.0)).0[p];
        assert!(kept > 0.5 && (clipped[0] - 0.2).abs() < 1e-3, "{kept} {clipped:?}");
        // This frame's own line (a ridge, no similar 2x2): locked at life 1 on its row alone.
        let (_, _, next) = run(&ours, &hist, &hg(2.0), &locks(0.0));
        for (k, s) in next.iter().enumerate() {
            assert_eq!(s.lock, if k / w == 3 { 1.0 } else { 0.0 }, "pixel {k}");
        }
        assert!(TaaConfig::parse(&["inside", "without-locks"]).is_err());
        assert!(!TaaConfig::parse(&["inside"]).expect("inside").locks);
    }

    /// Known answers on a 6x5 frame: a reset passes the current frame through; a static
    /// history is blended with weight alpha (luminance-weighted) or 1 / (n + 1) with `mean`;
    /// a history showing an object the neighbourhood does not is rejected; a NaN never leaves.
    #[test]
    fn known_answers_on_small_frames() {
        let (w, h) = (6, 5);
        let cur = flat(w, h, [1.0, 1.0, 1.0]);
        let vel = vec![[0.0f32; 2]; w * h];
        let depth = vec![2.0f32; w * h];
        let ids = vec![1u32; w * h];
        let base = RefInputs {
            width: w,
            height: h,
            color: &cur,
            velocity: &vel,
            depth: &depth,
            ids: &ids,
            history: None,
            n: 0,
            exposure_scale: 1.0,
            jitter: [0.0; 2],
            cycle: None,
            turns: None,
        };
        let (o, g) = reference(&TaaConfig::OURS, &base);
        assert!(o.iter().all(|c| *c == [1.0; 3]) && g.iter().all(|g| *g == (hist_geom_x(1, 1, false), 2.0)));
        // Mean weight, clipping off: 1/(n+1) of the current frame.
        let hist = flat(w, h, [3.0, 3.0, 3.0]);
        // Histories of 20 frames: past the running mean (1 / 21 < alpha).
        let hg: Vec<(u32, f32)> = vec![(hist_geom_x(1, 20, false), 2.0); w * h];
        let c = TaaConfig {
            mean: true,
            clip: false,
            ..TaaConfig::OURS
        };
        let i = RefInputs {
            history: Some((&hist, &hg)),
            n: 3,
            ..base
        };
        let (o, _) = reference(&c, &i);
        assert!(o.iter().all(|c| (c[0] - 2.5).abs() < 1e-6), "{:?}", o[0]);
        // Clipping on, history texel moved: a flat neighbourhood has a zero-width box, the
        // history clips to it.
        let hg_moved: Vec<(u32, f32)> = vec![(hist_geom_x(1, 20, true), 2.0); w * h];
        let moved = RefInputs {
            history: Some((&hist, &hg_moved)),
            ..i
        };
        let (o, _) = reference(&TaaConfig::OURS, &moved);
        assert!(o.iter().all(|c| (c[0] - 1.0).abs() < 1e-5), "{:?}", o[0]);
        // Clipping on, everything still: the history is kept unclipped (only the jitter would
        // change the box there), so the result is the unclipped blend below.
        let (o, _) = reference(&TaaConfig::OURS, &i);
        let blend = (0.1 / 2.0 * 1.0 + 0.9 / 4.0 * 3.0) / (0.1 / 2.0 + 0.9 / 4.0);
        assert!(o.iter().all(|c| (c[0] - blend).abs() < 1e-5), "{:?}", o[0]);
        // Without clipping: Karis's luminance weights, alpha 0.1: (0.1/2 * 1 + 0.9/4 * 3) / (0.1/2 + 0.9/4).
        // (The jittered path: `unjitter`'s interiors have their own weight, tested below.)
        let c = TaaConfig {
            clip: false,
            speed: 0.0,
            unjitter: false,
            ..TaaConfig::OURS
        };
        let (o, _) = reference(&c, &i);
        let want = (0.05 + 0.225 * 3.0) / (0.05 + 0.225);
        assert!((o[0][0] - want).abs() < 1e-5, "{} vs {want}", o[0][0]);
        // With the speed term, 1 px per frame of 2: alpha = 0.1 + (0.5 - 0.1) / 2 = 0.3.
        let one = vec![[0.6f32, 0.8]; w * h];
        let fast = TaaConfig { speed: 2.0, ..c };
        let (o, _) = reference(
            &fast,
            &RefInputs {
                velocity: &one,
                ..i
            },
        );
        let want_fast = (0.3 / 2.0 + 0.7 / 4.0 * 3.0) / (0.3 / 2.0 + 0.7 / 4.0);
        let centre = 2 * w + 2;
        assert!(
            (o[centre][0] - want_fast).abs() < 1e-4,
            "{} vs {want_fast}",
            o[centre][0]
        );
        // A history of object 7, seen nowhere in the 3x3: kept while everything is still (a
        // jittered sub-pixel feature), rejected once the pixel moves (a quarter pixel), and
        // when the history texel moved.
        let hg7: Vec<(u32, f32)> = vec![(hist_geom_x(7, 20, false), 2.0); w * h];
        let i7 = RefInputs {
            history: Some((&hist, &hg7)),
            ..i
        };
        let (o, _) = reference(&c, &i7);
        assert!((o[0][0] - want).abs() < 1e-5, "still: kept");
        let slow = vec![[0.25f32, 0.0]; w * h];
        let i7m = RefInputs {
            velocity: &slow,
            ..i7
        };
        let (o, g) = reference(&c, &i7m);
        assert!(o.iter().all(|c| *c == [1.0; 3]), "moving: rejected");
        assert!(
            g.iter().all(|g| g.0 == hist_geom_x(1, 1, true)),
            "moving pixels carry the bit"
        );
        let hg7m: Vec<(u32, f32)> = vec![(hist_geom_x(7, 20, true), 2.0); w * h];
        let (o, _) = reference(
            &c,
            &RefInputs {
                history: Some((&hist, &hg7m)),
                ..i
            },
        );
        assert!(o.iter().all(|c| *c == [1.0; 3]), "history moved: rejected");
        let no_ids = TaaConfig { ids: false, ..c };
        let (o, _) = reference(&no_ids, &i7m);
        assert!((o[0][0] - want).abs() < 1e-5, "without-ids keeps it");
        // A history 50% farther than the neighbourhood: rejected by the depth test.
        let hg_far: Vec<(u32, f32)> = vec![(hist_geom_x(1, 20, false), 3.0); w * h];
        let far = RefInputs {
            velocity: &slow,
            history: Some((&hist, &hg_far)),
            ..i
        };
        assert!(reference(&c, &far).0.iter().all(|c| *c == [1.0; 3]));
        let no_depth = TaaConfig { depth: false, ..c };
        assert!((reference(&no_depth, &far).0[0][0] - want).abs() < 1e-5);
        // The frame count: a history of one frame takes the current one at weight 1/2 (the
        // running mean; linear without the luminance weights), and the output holds two frames;
        // rejected, it holds one; at COUNT_MAX it stays there.
        let lin = TaaConfig { luma: false, ..c };
        let hg1: Vec<(u32, f32)> = vec![(hist_geom_x(1, 1, false), 2.0); w * h];
        let (o, g) = reference(
            &lin,
            &RefInputs {
                history: Some((&hist, &hg1)),
                ..i
            },
        );
        assert!(o.iter().all(|c| (c[0] - 2.0).abs() < 1e-6), "{:?}", o[0]);
        assert!(g.iter().all(|g| g.0 == hist_geom_x(1, 2, false)));
        let no_count = TaaConfig { count: false, ..lin };
        let (o, _) = reference(
            &no_count,
            &RefInputs {
                history: Some((&hist, &hg1)),
                ..i
            },
        );
        assert!(o.iter().all(|c| (c[0] - 2.8).abs() < 1e-5), "alpha 0.1: {:?}", o[0]);
        let hg_max: Vec<(u32, f32)> = vec![(hist_geom_x(1, COUNT_MAX, false), 2.0); w * h];
        let (_, g) = reference(
            &lin,
            &RefInputs {
                history: Some((&hist, &hg_max)),
                ..i
            },
        );
        assert!(g.iter().all(|g| g.0 == hist_geom_x(1, COUNT_MAX, false)));
        let (_, g) = reference(&c, &i7m);
        assert!(g.iter().all(|g| (g.0 >> COUNT_SHIFT) & COUNT_MAX == 1), "rejected: one frame");
        // A NaN in the current frame: replaced by its neighbours' mean, never output.
        let mut nan = cur.clone();
        nan[2 * w + 3] = [f32::NAN, 1.0, 1.0];
        nan[2 * w + 4] = [f32::INFINITY, 0.0, 0.0];
        let (o, _) = reference(
            &TaaConfig::OURS,
            &RefInputs {
                color: &nan,
                ..moved
            },
        );
        assert!(o.iter().all(|c| c.iter().all(|v| v.is_finite())));
        assert!((o[2 * w + 3][0] - 1.0).abs() < 1e-5);
        // Catmull-Rom at texel centres (no motion) returns the history texel itself.
        let ramp: Vec<V3> = (0..w * h)
            .map(|k| [k as f32, (k % 7) as f32, 0.5])
            .collect();
        let keep = TaaConfig {
            clip: false,
            mean: true,
            ..TaaConfig::OURS
        };
        let i = RefInputs {
            history: Some((&ramp, &hg)),
            n: 1_000_000,
            ..base
        };
        let (o, _) = reference(&keep, &i);
        for (k, (a, b)) in o.iter().zip(&ramp).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-4 * (1.0 + b[c]),
                    "pixel {k}: {a:?} vs {b:?}"
                );
            }
        }
    }
}
