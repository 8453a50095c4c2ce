//! `+taa`: temporal anti-aliasing as a post pass (docs/post-aa.md, shaders/post/taa.comp).
//!
//! The frame is jittered by a Halton(2, 3) sequence of length 8 or 16 ([`jitter`]; the sequencer
//! applies [`PostPass::jitter`] to the projection). Each pixel blends the current sample with the
//! history reprojected through the technique's velocity:
//!
//! - `+taa` (after Karis 2014): velocity of the nearest of the 3x3 neighbours (dilation), history
//!   by a 5-tap Catmull-Rom, clipped towards the neighbourhood mean into the YCoCg variance box
//!   mean +- gamma sigma (Salvi 2016), blended with current-frame weight alpha, both weighted by
//!   1 / (1 + luma) (Karis). Beyond the published: the history is rejected where the object ID it
//!   shows is none of the current 3x3's, or its depth is outside their span (the checkerboard
//!   resolve's tests); `without-X` switches one part off (`dilation`, `clip`, `ids`, `depth`,
//!   `catmull`).
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

use std::cell::Cell;

use cbr_gpu::{
    Access, BindingDesc, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, GpuError, Image,
    PassKind, Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Write, vk,
};

use super::{PostBuildCtx, PostFrame, PostPass, PostRegistration};
use crate::technique::Geometry;

pub const REGISTRATION: PostRegistration = PostRegistration {
    name: "taa",
    grammar: "taa[:inside][:8|16][:alpha=A][:gamma=G][:tol=T][:mean][:without-X...]",
    about: "temporal AA: Halton jitter, dilated velocity, Catmull-Rom history, YCoCg variance \
            clipping, ID and depth rejection (X: dilation, clip, ids, depth, catmull); \
            `inside`: Playdead's INSIDE TAA",
    check: |p| TaaConfig::parse(p).map(|_| ()),
    geometry: true,
    build: |ctx, p, inputs| {
        let c = TaaConfig::parse(p).map_err(GpuError::Other)?;
        Ok(Box::new(Taa::new(ctx, c, inputs)?))
    },
};

/// The parts `without-X` switches off.
pub const ABLATIONS: [&str; 5] = ["dilation", "clip", "ids", "depth", "catmull"];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaaConfig {
    /// Playdead's INSIDE TAA instead of ours.
    pub inside: bool,
    /// Halton(2, 3) sequence length (8 or 16).
    pub length: u32,
    /// Current-frame blend weight (ours).
    pub alpha: f32,
    /// Variance clipping box half-width in standard deviations (ours).
    pub gamma: f32,
    /// Relative linear-depth tolerance of the history depth test (ours).
    pub depth_tolerance: f32,
    /// Blend weight 1 / (n + 1): the running mean.
    pub mean: bool,
    pub dilation: bool,
    pub clip: bool,
    pub ids: bool,
    pub depth: bool,
    pub catmull: bool,
}

/// INSIDE's feedback range (the history's weight).
pub const INSIDE_FEEDBACK: [f32; 2] = [0.88, 0.97];

impl TaaConfig {
    pub const OURS: TaaConfig = TaaConfig {
        inside: false,
        length: 8,
        alpha: 0.1,
        gamma: 1.0,
        depth_tolerance: 0.05,
        mean: false,
        dilation: true,
        clip: true,
        ids: true,
        depth: true,
        catmull: true,
    };

    pub const INSIDE: TaaConfig = TaaConfig {
        inside: true,
        length: 16,
        ids: false,
        depth: false,
        catmull: false,
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
            match *p {
                "inside" => {}
                "8" => c.length = 8,
                "16" => c.length = 16,
                "mean" => c.mean = true,
                "without-dilation" => c.dilation = false,
                "without-clip" => c.clip = false,
                "without-ids" => {
                    ours_only("ID test")?;
                    c.ids = false
                }
                "without-depth" => {
                    ours_only("depth test")?;
                    c.depth = false
                }
                "without-catmull" => {
                    ours_only("Catmull-Rom history (it is bilinear)")?;
                    c.catmull = false
                }
                _ => match p.split_once('=') {
                    Some(("alpha", v)) => {
                        ours_only("alpha (its feedback is 0.88-0.97)")?;
                        c.alpha = num(p, v, 0.001, 1.0)?
                    }
                    Some(("gamma", v)) => {
                        ours_only("variance gamma (it clips to min-max)")?;
                        c.gamma = num(p, v, 0.0, 8.0)?
                    }
                    Some(("tol", v)) => {
                        ours_only("depth test")?;
                        c.depth_tolerance = num(p, v, 0.0, 1.0)?
                    }
                    _ => {
                        return Err(crate::technique::unknown_param(
                            "taa",
                            p,
                            "inside, 8, 16, alpha=A, gamma=G, tol=T, mean, without-dilation, \
                             without-clip, without-ids, without-depth, without-catmull",
                        ));
                    }
                },
            }
        }
        Ok(c)
    }

    fn flags(&self) -> u32 {
        let mut f = 0;
        for (on, bit) in [
            (self.dilation, F_DILATION),
            (self.clip, F_CLIP),
            (self.ids, F_IDS),
            (self.depth, F_DEPTH),
            (self.catmull, F_CATMULL),
            (self.mean, F_MEAN),
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
pub const F_CATMULL: u32 = 32;
pub const F_MEAN: u32 = 64;

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

pub const BINDINGS: [BindingDesc; 9] = [
    BindingDesc::one("cur", 0, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("velocity", 1, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("depth", 2, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("ids", 3, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("hist", 4, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("hist_geom", 5, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("out_hist", 6, DescriptorKind::StorageImage),
    BindingDesc::one("out_geom", 7, DescriptorKind::StorageImage),
    BindingDesc::one("out_color", 8, DescriptorKind::StorageImage),
];

/// Push constants (shaders/post/taa.comp `Push`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    size: [i32; 4],
    flags: [u32; 4],
    params: [f32; 4],
    inside: [f32; 4],
}

pub struct Taa {
    config: TaaConfig,
    pipeline: Pipeline,
    _layout: SetLayout,
    _samplers: [Sampler; 2],
    /// One per frame parity: reads history `(f + 1) % 2`, writes history `f % 2`.
    sets: Vec<DescriptorSet>,
    history: [Image; 2],
    history_geom: [Image; 2],
    out: Image,
    push: Push,
    /// Frames accumulated since the last reset (the `mean` weight).
    accumulated: Cell<u32>,
}

impl Taa {
    fn new(ctx: &PostBuildCtx, c: TaaConfig, inputs: &[&Image]) -> Result<Taa> {
        let gpu = ctx.gpu;
        let geo: &[Geometry] = ctx.geometry;
        if geo.is_empty() {
            return Err(GpuError::Other(
                "taa needs the frame's geometry (velocity, depth, IDs)".into(),
            ));
        }
        let layout = SetLayout::new(gpu, "taa.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("MODE".into(), u32::from(c.inside).to_string()));
        defines.push(("PACKED".into(), u32::from(geo[0].packed).to_string()));
        let cs = ctx.shaders.compile("post/taa.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "taa",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: std::mem::size_of::<Push>() as u32,
            },
        )?;
        let nearest = Sampler::new(gpu, "taa.nearest", SamplerDesc::NEAREST)?;
        let linear = Sampler::new(
            gpu,
            "taa.linear",
            SamplerDesc {
                linear: true,
                ..SamplerDesc::NEAREST
            },
        )?;
        let history = [ctx.output("taa.history[0]")?, ctx.output("taa.history[1]")?];
        let history_geom = [
            ctx.image("taa.history_geom[0]", vk::Format::R32G32_UINT)?,
            ctx.image("taa.history_geom[1]", vk::Format::R32G32_UINT)?,
        ];
        let out = ctx.output("taa.out")?;
        let sets = (0..2)
            .map(|f: usize| {
                let g = &geo[f % geo.len()];
                let (read, write) = ((f + 1) % 2, f % 2);
                DescriptorSet::new(
                    gpu,
                    &format!("taa.set[{f}]"),
                    &layout,
                    &[
                        Write::Sampled(0, vec![(inputs[f % inputs.len()], &nearest)]),
                        Write::Sampled(1, vec![(g.velocity, &nearest)]),
                        Write::Sampled(2, vec![(g.depth, &nearest)]),
                        Write::Sampled(3, vec![(g.ids, &nearest)]),
                        Write::Sampled(4, vec![(&history[read], &linear)]),
                        Write::Sampled(5, vec![(&history_geom[read], &nearest)]),
                        Write::Storage(6, &history[write]),
                        Write::Storage(7, &history_geom[write]),
                        Write::Storage(8, &out),
                    ],
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let g0 = geo[0].velocity;
        let push = Push {
            size: [
                ctx.width as i32,
                ctx.height as i32,
                g0.width as i32,
                g0.height as i32,
            ],
            flags: [c.flags(), 0, 0, 0],
            params: [
                c.alpha,
                c.gamma,
                c.depth_tolerance,
                ctx.exposure_stops.exp2(),
            ],
            inside: [INSIDE_FEEDBACK[0], INSIDE_FEEDBACK[1], 0.0, 0.0],
        };
        Ok(Taa {
            config: c,
            pipeline,
            _layout: layout,
            _samplers: [nearest, linear],
            sets,
            history,
            history_geom,
            out,
            push,
            accumulated: Cell::new(0),
        })
    }
}

impl PostPass for Taa {
    fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler, frame: &PostFrame, input: &Image) {
        let f = frame.frame as usize % 2;
        let n = if frame.reset {
            0
        } else {
            self.accumulated.get() + 1
        };
        self.accumulated.set(n);
        let mut push = self.push;
        push.flags[0] |= if frame.reset { F_RESET } else { 0 };
        push.flags[1] = n;
        cmd.use_image(input, Access::ComputeSampled);
        if let Some(g) = &frame.geometry {
            for image in [g.velocity, g.depth, g.ids] {
                cmd.use_image(image, Access::ComputeSampled);
            }
        }
        cmd.use_image(&self.history[(f + 1) % 2], Access::ComputeSampled);
        cmd.use_image(&self.history_geom[(f + 1) % 2], Access::ComputeSampled);
        cmd.use_image(&self.history[f], Access::ComputeStorageWrite);
        cmd.use_image(&self.history_geom[f], Access::ComputeStorageWrite);
        cmd.use_image(&self.out, Access::ComputeStorageWrite);
        let scope = profiler.begin(cmd, "taa", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.sets[f]);
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
        cmd.dispatch(self.out.width.div_ceil(8), self.out.height.div_ceil(8), 1);
        profiler.end(cmd, scope);
    }

    fn output(&self) -> &Image {
        &self.out
    }

    fn jitter(&self, frame: u32) -> Option<[f32; 2]> {
        Some(jitter(self.config.length, frame))
    }
}
