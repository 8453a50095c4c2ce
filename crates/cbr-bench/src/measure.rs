//! Rendering one configuration over the camera path: GPU times per pass, fragment counts and
//! the error of every measured frame against the reference frames (whole frame and edge pixels).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result};
use cbr_gpu::Gpu;
use cbr_metrics::{CompareOptions, DisplayTransform, Metric, compare_images};
use cbr_render::{FrameOutput, Renderer};
use cbr_scene::Scene;
use indicatif::ProgressBar;
use serde_json::json;

use crate::Config;
use crate::output::finite_or_null;

/// Passes that instrument the run rather than belong to the technique.
pub const NOT_TECHNIQUE: [&str; 4] = [
    "readback",
    "readback.post",
    "checkerboard.unpack",
    "resolve.copy_floor",
];

/// A frame's RGBA16F colour as an image to compare.
fn to_input(width: u32, height: u32, color: &[half::f16], name: &str) -> cbr_metrics::InputImage {
    let n = (width * height) as usize;
    let rgb: Vec<f32> = (0..n)
        .flat_map(|i| {
            let c = &color[4 * i..4 * i + 3];
            [c[0].to_f32(), c[1].to_f32(), c[2].to_f32()]
        })
        .collect();
    cbr_metrics::InputImage {
        path: PathBuf::from(name),
        layer: "color".into(),
        channels: vec!["R".into(), "G".into(), "B".into()],
        rgb: cbr_metrics::Rgb::from_interleaved(width as usize, height as usize, &rgb),
        encoding: cbr_metrics::Encoding::Linear,
    }
}

/// A reference frame: its colour and its edge mask (pixels with more than one object ID among the
/// reference's samples: `coverage.edge` of a supersampled reference; for a one-sample reference,
/// pixels whose object ID differs from a 4-neighbour's).
pub struct RefFrame {
    color: Vec<half::f16>,
    edge: Vec<bool>,
}

pub fn edge_mask(out: &FrameOutput) -> Vec<bool> {
    if let Some(c) = &out.coverage {
        return c.edge.iter().map(|&e| e != 0).collect();
    }
    let (w, h) = (out.width as usize, out.height as usize);
    let id = |x: usize, y: usize| out.ids[y * w + x][0];
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let me = id(x, y);
            (x > 0 && id(x - 1, y) != me)
                || (x + 1 < w && id(x + 1, y) != me)
                || (y > 0 && id(x, y - 1) != me)
                || (y + 1 < h && id(x, y + 1) != me)
        })
        .collect()
}

/// Mean of a FLIP map over the pixels of a mask (NaN when the mask is empty).
pub fn masked_mean(map: &cbr_metrics::planes::Plane, mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (v, m) in map.data.iter().zip(mask) {
        if *m {
            sum += f64::from(*v);
            n += 1;
        }
    }
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// The last measured frame of a configuration, kept for the report.
pub struct Snapshot {
    pub out: FrameOutput,
    pub flip_map: Option<cbr_metrics::planes::Plane>,
}

#[derive(Default)]
pub struct Measured {
    pub lod_bias: f32,
    /// Frames read from the frame cache (not rendered, so not timed).
    pub cached_frames: u32,
    pub snapshot: Option<Snapshot>,
    pub passes: BTreeMap<String, Vec<f64>>,
    pub frame_ms: Vec<f64>,
    pub fragments: BTreeMap<String, Vec<f64>>,
    pub errors: Vec<serde_json::Value>,
    pub psnr: Vec<f64>,
    pub ssim: Vec<f64>,
    pub flip: Vec<f64>,
    pub flip_median: Vec<f64>,
    pub flip_edge: Vec<f64>,
    pub relmse: Vec<f64>,
}

pub fn mean(v: &[f64]) -> Option<f64> {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    (!f.is_empty()).then(|| f.iter().sum::<f64>() / f.len() as f64)
}

#[allow(clippy::too_many_arguments)]
pub fn measure(
    gpu: &Gpu,
    scene: &Scene,
    config: &Config,
    warmup: u32,
    frames: u32,
    reference: Option<(&str, &[RefFrame])>,
    keep: bool,
    bar: &ProgressBar,
) -> Result<(Measured, Vec<RefFrame>)> {
    let shaders = cbr_render::shader_library();
    let mut r = Renderer::new(gpu, &shaders, scene, config.settings.clone())
        .with_context(|| format!("setting up {} on {}", config.name, gpu.info().name))?;
    if keep && config.settings.spec.technique.name != "native" {
        let label = format!("reference {}", config.name);
        r.set_progress(crate::sample_progress(label));
    }
    let options = CompareOptions {
        metrics: vec![Metric::Psnr, Metric::Ssim, Metric::Flip, Metric::RelMse],
        display: DisplayTransform {
            exposure_stops: scene.settings.exposure,
        },
        ..CompareOptions::default()
    };
    let mut m = Measured {
        lod_bias: r.lod_bias(),
        ..Measured::default()
    };
    let mut kept = Vec::new();
    // A cacheable technique (ssaa) has no history: its warm-up frames would cost N^2 rasters
    // each for nothing.
    let first = if r.cache_dir().is_some() { warmup } else { 0 };
    bar.inc(u64::from(first));
    for f in first..warmup + frames {
        let out = r.render(scene, f)?;
        bar.inc(1);
        if out.timings.is_empty() && out.cached.is_some() && f >= warmup {
            m.cached_frames += 1;
        }
        if f < warmup {
            continue;
        }
        let mut total = 0.0;
        for t in &out.timings {
            m.passes.entry(t.name.clone()).or_default().push(t.gpu_ms);
            if !NOT_TECHNIQUE.contains(&t.name.as_str()) {
                total += t.gpu_ms;
            }
            if let Some(s) = &t.stats {
                m.fragments
                    .entry(t.name.clone())
                    .or_default()
                    .push(s.fragment_invocations as f64);
            }
        }
        if !out.timings.is_empty() {
            m.frame_ms.push(total);
        }
        let last = f + 1 == warmup + frames;
        let mut flip_map = None;
        if let Some((ref_name, refs)) = reference {
            let rf = &refs[(f - warmup) as usize];
            // The FLIP map of every frame: the edge-pixel mean needs it.
            let o = CompareOptions {
                keep_maps: true,
                ..options.clone()
            };
            let (w, h) = (out.width, out.height);
            let mut p = compare_images(
                &to_input(w, h, &rf.color, ref_name),
                &to_input(w, h, &out.color, &config.name),
                &o,
            )?;
            let map = p.flip_map.take();
            let flip_edge = map
                .as_ref()
                .map(|m| masked_mean(m, &rf.edge))
                .unwrap_or(f64::NAN);
            m.flip_edge.push(flip_edge);
            if last {
                flip_map = map;
            }
            let v = |k| p.value(k).unwrap_or(f64::NAN);
            let flip_median = p.flip.map(|x| x.weighted_median).unwrap_or(f64::NAN);
            m.psnr.push(v(Metric::Psnr));
            m.ssim.push(v(Metric::Ssim));
            m.flip.push(v(Metric::Flip));
            m.flip_median.push(flip_median);
            m.relmse.push(v(Metric::RelMse));
            m.errors.push(json!({
                "frame": f,
                "psnr": finite_or_null(v(Metric::Psnr)),
                "ssim": v(Metric::Ssim),
                "flip_mean": v(Metric::Flip),
                "flip_median": flip_median,
                "flip_edge": finite_or_null(flip_edge),
                "relmse": v(Metric::RelMse),
            }));
        }
        // The reference keeps only colour and its edge mask (what the comparison reads).
        if keep {
            kept.push(RefFrame {
                color: out.color.clone(),
                edge: edge_mask(&out),
            });
        }
        if last {
            m.snapshot = Some(Snapshot { out, flip_map });
        }
    }
    Ok((m, kept))
}
