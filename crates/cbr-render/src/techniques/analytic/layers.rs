//! What `analytic` adds to a frame: `coverage` (techniques::Coverage: the edge flag and the
//! exact covered fraction), the `analytic` layer (per pixel: the fragments that touched it, the
//! overflow beyond the K kept, the fragments that contributed, with `:seed` where the
//! shortcut's area is off the exact one by more than 1e-3, and where a kept fragment's shading
//! was not finite), the `analytic.*` statistics of run.json, and `:seed`'s debug figure.

use cbr_gpu::Result;

use crate::frame::{DebugPng, ExrType, FrameOutput, LayerDecl, SampleType, Stat, StatDecl};
use crate::techniques::{COVERAGE_LAYER, Coverage};

/// The `analytic` layer (counts and 0/1 flags, u32 on the host, floats in the EXR).
pub const ANALYTIC_LAYER: LayerDecl = LayerDecl {
    name: "analytic",
    channels: &[
        "fragments",
        "overflow",
        "visible",
        "seed_differs",
        "nonfinite",
    ],
    samples: SampleType::U32,
    exr: Some(ExrType::Float),
    about: "per pixel: fragments that touched it, those beyond the K kept (overflow), those \
            that contributed (visible), 1 where the seed's shortcut is off by more than 1e-3 \
            (`:seed`), 1 where a kept fragment's shading was not finite",
};

/// Its layers in the frame's order.
pub const LAYERS: [LayerDecl; 2] = [COVERAGE_LAYER, ANALYTIC_LAYER];

/// run.json's per-frame `analytic` object.
pub const STATS: [StatDecl; 9] = [
    StatDecl {
        name: "analytic.kept_per_pixel",
        about: "fragments kept per pixel (K)",
    },
    StatDecl {
        name: "analytic.tail_fragments",
        about: "fragments beyond their pixel's K that no occluder hid (lit into the tails)",
    },
    StatDecl {
        name: "analytic.albedo_jobs",
        about: "textured fragments whose albedo the albedo pass filtered",
    },
    StatDecl {
        name: "analytic.fragments",
        about: "fragments that touched pixels",
    },
    StatDecl {
        name: "analytic.edge_pixels",
        about: "pixels a visible fragment covers in part, or where the background shows",
    },
    StatDecl {
        name: "analytic.overflow_pixels",
        about: "pixels with more fragments than K",
    },
    StatDecl {
        name: "analytic.nonfinite_pixels",
        about: "pixels where a kept fragment's shading was not finite",
    },
    StatDecl {
        name: "analytic.seed_differs_pixels",
        about: "(`:seed`) pixels where the shortcut's area is off by more than 1e-3",
    },
    StatDecl {
        name: "analytic.seed_differs_edge_fraction",
        about: "(`:seed`) that count among the edge pixels, as a share of them",
    },
];

/// The `analytic` layer and statistics, typed.
#[derive(Clone, Debug, Default)]
pub struct AnalyticLayers {
    pub fragments: Vec<u32>,
    pub overflow: Vec<u32>,
    pub visible: Vec<u32>,
    pub seed_differs: Vec<u8>,
    /// 1 where a kept fragment's shading was not finite (it was dropped, not composited).
    pub nonfinite: Vec<u8>,
    /// Fragments kept per pixel (K) this frame was built with.
    pub kept_per_pixel: u32,
    /// Fragments beyond their pixel's K that no occluder hid: lit by the tail pass and merged
    /// into the tails.
    pub tail_fragments: u64,
    /// Textured fragments (kept or in a tail) whose albedo the albedo pass filtered.
    pub albedo_jobs: u64,
}

impl AnalyticLayers {
    /// Writes `coverage` and these into `out`: the two layers and the statistics (the edge
    /// pixels are `coverage`'s).
    pub fn write(&self, coverage: &Coverage, out: &mut FrameOutput) -> Result<()> {
        let (w, h) = (out.width, out.height);
        out.layers.push(coverage.layer(w, h)?);
        let flags = |v: &[u8]| v.iter().map(|&x| u32::from(x)).collect::<Vec<u32>>();
        let planes = vec![
            self.fragments.clone(),
            self.overflow.clone(),
            self.visible.clone(),
            flags(&self.seed_differs),
            flags(&self.nonfinite),
        ];
        out.layers.push(ANALYTIC_LAYER.layer(w, h, planes)?);
        let count = |v: &[u8]| v.iter().filter(|&&x| x != 0).count() as u64;
        let edge = count(&coverage.edge);
        let seed = self
            .seed_differs
            .iter()
            .zip(&coverage.edge)
            .filter(|&(&s, &e)| s != 0 && e != 0)
            .count();
        let stats = [
            Stat::Count(u64::from(self.kept_per_pixel)),
            Stat::Count(self.tail_fragments),
            Stat::Count(self.albedo_jobs),
            Stat::Count(self.fragments.iter().map(|&f| u64::from(f)).sum()),
            Stat::Count(edge),
            Stat::Count(self.overflow.iter().filter(|&&o| o > 0).count() as u64),
            Stat::Count(count(&self.nonfinite)),
            Stat::Count(count(&self.seed_differs)),
            Stat::Real(if edge > 0 {
                seed as f64 / edge as f64
            } else {
                0.0
            }),
        ];
        for (d, s) in STATS.iter().zip(stats) {
            out.set_stat(d.name, s);
        }
        Ok(())
    }

    /// A frame's `analytic` layer and counts, when it has them.
    pub fn from_frame(out: &FrameOutput) -> Option<AnalyticLayers> {
        let l = out.layer(ANALYTIC_LAYER.name)?;
        let ch = |c: &str| l.channel::<u32>(c);
        let flags = |c: &str| Some(ch(c)?.iter().map(|&x| x as u8).collect());
        Some(AnalyticLayers {
            fragments: ch("fragments")?.to_vec(),
            overflow: ch("overflow")?.to_vec(),
            visible: ch("visible")?.to_vec(),
            seed_differs: flags("seed_differs")?,
            nonfinite: flags("nonfinite")?,
            kept_per_pixel: u32::try_from(out.count("analytic.kept_per_pixel")?).ok()?,
            tail_fragments: out.count("analytic.tail_fragments")?,
            albedo_jobs: out.count("analytic.albedo_jobs")?,
        })
    }
}

/// `analytic:seed`: `seed_differs`, the frame as displayed with the pixels where the seed's
/// shortcut is off the exact area by more than 1e-3 in red (docs/analytic.md's figure); none
/// where no pixel is.
pub fn debug_pngs(out: &FrameOutput, display: &[u8]) -> Vec<DebugPng> {
    let Some(seed) = out.channel::<u32>(ANALYTIC_LAYER.name, "seed_differs") else {
        return Vec::new();
    };
    if !seed.iter().any(|&s| s != 0) {
        return Vec::new();
    }
    let marked: Vec<u8> = display
        .chunks_exact(4)
        .zip(seed)
        .flat_map(|(p, &s)| {
            if s != 0 {
                [255, 0, 0, 255]
            } else {
                // The rest dimmed, so the marks stand out.
                [p[0] / 3, p[1] / 3, p[2] / 3, 255]
            }
        })
        .collect();
    vec![DebugPng {
        name: "seed_differs".to_string(),
        width: out.width,
        height: out.height,
        rgba: marked,
    }]
}
