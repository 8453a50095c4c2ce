//! Rendering one configuration over the camera path: GPU times per pass, fragment counts and
//! the error of every measured frame against the reference frames (whole frame and edge pixels).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result};
use cbr_gpu::Gpu;
use cbr_metrics::{CompareOptions, DisplayTransform, Metric, compare_images};
use cbr_render::{
    AnalyticLayers, Coverage, FrameOutput, InterleavedLayers, Renderer, ResolveOutput,
};
use cbr_scene::Scene;
use indicatif::ProgressBar;
use serde_json::json;

use crate::Config;
use crate::output::finite_or_null;
use crate::temporal::{IdHistory, IdStandIn, Stability, fraction, native_ids, object_ids};

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

/// A reference frame: its colour, its edge mask (pixels with more than one object ID among the
/// reference's samples: `coverage.edge` of a supersampled reference; for a one-sample reference,
/// pixels whose object ID differs from a 4-neighbour's) and its disocclusion mask (pixels whose
/// object ID differs from theirs in any of the k frames before: crate::temporal).
pub struct RefFrame {
    color: Vec<half::f16>,
    edge: Vec<bool>,
    disocc: Vec<bool>,
    disocc_fraction: f64,
}

pub fn edge_mask(out: &FrameOutput) -> Vec<bool> {
    if let Some(c) = Coverage::from_frame(out) {
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
    /// Wall-clock seconds of setting the renderer up (shaders, pipelines, allocations, the
    /// scene's upload) and of all its frames (warm-up, readbacks and metrics included): where a
    /// run's time goes beside the GPU's passes (the GPU study's machine spent most of it there).
    pub setup_s: f64,
    pub frames_wall_s: f64,
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
    /// FLIP mean over the pixels that are not edge pixels.
    pub flip_interior: Vec<f64>,
    pub flip_disocc: Vec<f64>,
    pub disocc_fraction: Vec<f64>,
    pub relmse: Vec<f64>,
    /// Per measured frame after the first (crate::temporal::Change).
    pub flicker: Vec<f64>,
    pub change: Vec<f64>,
    pub ref_change: Vec<f64>,
    /// The reference only: the native raster that gave the IDs of the frames it skipped.
    pub id_stand_in: Option<IdStandIn>,
    /// Error by pixel class, for resolves that write their debug bits (`:debug`).
    pub attribution: Option<crate::attribution::Attribution>,
    /// `analytic` frames: error by what the resolve composited per pixel.
    pub analytic_attribution: Option<crate::analytic_attribution::AnalyticAttribution>,
    /// `interleaved:...:debug` frames: cost and error by what the filter did per pixel.
    pub interleaved_attribution: Option<crate::interleaved_attribution::InterleavedAttribution>,
    /// Error by how far each pixel moved (techniques whose frames carry a velocity).
    pub motion_attribution: Option<crate::motion_attribution::MotionAttribution>,
}

pub fn mean(v: &[f64]) -> Option<f64> {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    (!f.is_empty()).then(|| f.iter().sum::<f64>() / f.len() as f64)
}

/// How a configuration is measured: against the reference's frames, or as the reference itself
/// (keeping its frames and the object IDs of the `disocclusion_frames` frames before each).
#[derive(Clone, Copy)]
pub enum Role<'a> {
    Reference {
        disocclusion_frames: u32,
    },
    Against {
        name: &'a str,
        frames: &'a [RefFrame],
    },
    /// Timed only (`--timing-only`): no comparison, no frames or snapshot kept.
    Timing,
}

/// One frame of a configuration, rendered under a symbol of its own. On lavapipe the frame's
/// GPU work runs inside this call (render submits and waits), so `scripts/work-count.py` runs
/// the bench under callgrind with `--dump-before` on this function and on [`counted_frame_end`],
/// which it calls when the frame is done: each dump that the second one triggers holds one
/// rendered frame's instructions, lavapipe's JIT code apart (docs/bench-and-report.md, "Work
/// counts"). Never inlined: the names must survive into the binary. Outside valgrind it is the
/// plain call.
#[inline(never)]
pub fn counted_frame(
    r: &mut Renderer,
    scene: &Scene,
    frame: u32,
) -> Result<FrameOutput, cbr_gpu::GpuError> {
    let out = r.render(scene, frame);
    counted_frame_end();
    out
}

/// The end of [`counted_frame`]'s frame, for callgrind's `--dump-before` (a dump when a
/// function is left misses a call that ends in a jump). Does nothing.
#[inline(never)]
pub fn counted_frame_end() {
    std::hint::black_box(());
}

pub fn measure(
    gpu: &Gpu,
    scene: &Scene,
    config: &Config,
    (warmup, frames): (u32, u32),
    role: Role,
    bar: &ProgressBar,
) -> Result<(Measured, Vec<RefFrame>)> {
    let shaders = cbr_render::shader_library();
    let started = std::time::Instant::now();
    let mut r = Renderer::new(gpu, &shaders, scene, config.settings.clone())
        .with_context(|| format!("setting up {} on {}", config.name, gpu.info().name))?;
    let setup_s = started.elapsed().as_secs_f64();
    let keep = matches!(role, Role::Reference { .. });
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
        setup_s,
        ..Measured::default()
    };
    let mut kept = Vec::new();
    // A cacheable technique (ssaa) has no history: its warm-up frames would cost N^2 rasters
    // each for nothing.
    let first = if r.cache_dir().is_some() { warmup } else { 0 };
    let mut ids = match role {
        Role::Reference {
            disocclusion_frames: k,
        } => {
            let (h, check, stand_in) = id_history(gpu, scene, config, m.lod_bias, k, first)?;
            m.id_stand_in = stand_in;
            Some((h, check))
        }
        Role::Against { .. } | Role::Timing => None,
    };
    let mut stability = Stability::default();
    bar.inc(u64::from(first));
    for f in first..warmup + frames {
        let out = counted_frame(&mut r, scene, f)?;
        bar.inc(1);
        if out.timings.is_empty() && out.cached.is_some() && f >= warmup {
            m.cached_frames += 1;
        }
        if f < warmup {
            if let Some((h, _)) = &mut ids {
                h.push(object_ids(&out));
            }
            continue;
        }
        record_timings(&mut m, &out);
        let last = f + 1 == warmup + frames;
        let mut flip_map = None;
        if let Role::Against { name, frames: refs } = role {
            let map = compare_frame(
                &mut m,
                &mut stability,
                &refs[(f - warmup) as usize],
                (name, &config.name),
                &out,
                &options,
            )?;
            if last {
                flip_map = map;
            }
        }
        // The reference keeps only colour and its masks (what the comparison reads).
        if let Some((h, check)) = &mut ids {
            let now = object_ids(&out);
            if let (Some(c), Some(s)) = (check.take(), m.id_stand_in.as_mut()) {
                s.mismatched_pixels = c.iter().zip(&now).filter(|(a, b)| a != b).count();
            }
            let disocc = h.next(now);
            kept.push(RefFrame {
                color: out.color.clone(),
                edge: edge_mask(&out),
                disocc_fraction: fraction(&disocc),
                disocc,
            });
        }
        if last && !matches!(role, Role::Timing) {
            m.snapshot = Some(Snapshot { out, flip_map });
        }
    }
    m.frames_wall_s = started.elapsed().as_secs_f64() - setup_s;
    let line = format!(
        "{} {}x{}: set up in {:.1} s, {} frames in {:.1} s (wall clock)",
        config.name,
        scene.settings.width,
        scene.settings.height,
        m.setup_s,
        warmup + frames,
        m.frames_wall_s
    );
    if bar.is_hidden() {
        eprintln!("{line}");
    } else {
        bar.println(line);
    }
    Ok((m, kept))
}

/// The reference's ID history before its first rendered frame `first`: empty when it renders
/// from frame 0; else (a cached reference skips its warm-up frames) the IDs of the k frames
/// before from a native raster at the reference's LOD bias, with that raster's IDs of frame
/// `first` to check them against the reference's, and what was rendered.
fn id_history(
    gpu: &Gpu,
    scene: &Scene,
    config: &Config,
    lod_bias: f32,
    k: u32,
    first: u32,
) -> Result<(IdHistory, Option<Vec<u32>>, Option<IdStandIn>)> {
    let mut history = IdHistory::new(k);
    if first == 0 {
        return Ok((history, None, None));
    }
    let from = first.saturating_sub(k);
    let (w, h) = (config.settings.width, config.settings.height);
    let mut native = native_ids(gpu, scene, (w, h), lod_bias, from, first)?;
    let check = native.pop();
    for ids in native {
        history.push(ids);
    }
    let stand_in = IdStandIn {
        native_frames: [from, first],
        lod_bias,
        mismatched_pixels: 0,
        pixels: (w * h) as usize,
    };
    Ok((history, check, Some(stand_in)))
}

/// A measured frame's GPU times per pass, frame time and fragment counts.
fn record_timings(m: &mut Measured, out: &FrameOutput) {
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
}

/// The errors of one measured frame against the reference's same frame; returns its FLIP map.
fn compare_frame(
    m: &mut Measured,
    stability: &mut Stability,
    rf: &RefFrame,
    (ref_name, name): (&str, &str),
    out: &FrameOutput,
    options: &CompareOptions,
) -> Result<Option<cbr_metrics::planes::Plane>> {
    // The FLIP map of every frame: the edge and disocclusion means need it.
    let o = CompareOptions {
        keep_maps: true,
        ..options.clone()
    };
    let (w, h) = (out.width, out.height);
    let (ri, ti) = (
        to_input(w, h, &rf.color, ref_name),
        to_input(w, h, &out.color, name),
    );
    let mut p = compare_images(&ri, &ti, &o)?;
    let map = p.flip_map.take();
    let masked = |mask: &[bool]| {
        map.as_ref()
            .map(|m| masked_mean(m, mask))
            .unwrap_or(f64::NAN)
    };
    let (flip_edge, flip_disocc) = (masked(&rf.edge), masked(&rf.disocc));
    let interior: Vec<bool> = rf.edge.iter().map(|&e| !e).collect();
    let flip_interior = masked(&interior);
    // Per-pixel error for the attributions: mean |display(test) - display(ref)| over RGB.
    let pixel_error = || -> Vec<f32> {
        let d = &options.display;
        out.color
            .chunks(4)
            .zip(rf.color.chunks(4))
            .map(|(t, r)| {
                (0..3)
                    .map(|k| (d.apply(t[k].to_f32()) - d.apply(r[k].to_f32())).abs())
                    .sum::<f32>()
                    / 3.0
            })
            .collect()
    };
    let bits = ResolveOutput::from_frame(out).and_then(|r| r.debug_bits);
    if let (Some(bits), Some(map)) = (bits, map.as_ref()) {
        m.attribution
            .get_or_insert_default()
            .add(&bits, &pixel_error(), &map.data, &rf.disocc);
    }
    if let Some(map) = map
        .as_ref()
        .filter(|_| out.velocity.len() == rf.disocc.len())
    {
        m.motion_attribution.get_or_insert_default().add(
            &out.velocity,
            &pixel_error(),
            &map.data,
            &rf.disocc,
        );
    }
    if let (Some(layers), Some(cov), Some(map)) = (
        AnalyticLayers::from_frame(out),
        Coverage::from_frame(out),
        map.as_ref(),
    ) {
        m.analytic_attribution.get_or_insert_default().add(
            &layers,
            &cov.edge,
            &pixel_error(),
            &map.data,
            &rf.edge,
        );
    }
    if let (Some(layers), Some(map)) = (InterleavedLayers::from_frame(out), map.as_ref()) {
        let drawn: Vec<bool> = out.ids.iter().map(|id| id[0] != 0).collect();
        m.interleaved_attribution.get_or_insert_default().add(
            &layers,
            &drawn,
            out.width as usize,
            &pixel_error(),
            &map.data,
            &rf.edge,
        );
    }
    let change = stability.next(&ri, &ti, options)?;
    let v = |k| p.value(k).unwrap_or(f64::NAN);
    let flip_median = p.flip.map(|x| x.weighted_median).unwrap_or(f64::NAN);
    m.psnr.push(v(Metric::Psnr));
    m.ssim.push(v(Metric::Ssim));
    m.flip.push(v(Metric::Flip));
    m.flip_median.push(flip_median);
    m.flip_edge.push(flip_edge);
    m.flip_interior.push(flip_interior);
    m.flip_disocc.push(flip_disocc);
    m.disocc_fraction.push(rf.disocc_fraction);
    m.relmse.push(v(Metric::RelMse));
    if let Some(c) = change {
        m.flicker.push(c.flicker);
        m.change.push(c.change);
        m.ref_change.push(c.ref_change);
    }
    let opt = |x: Option<f64>| x.map(finite_or_null).unwrap_or(json!(null));
    m.errors.push(json!({
        "frame": out.index,
        "psnr": finite_or_null(v(Metric::Psnr)),
        "ssim": v(Metric::Ssim),
        "flip_mean": v(Metric::Flip),
        "flip_median": flip_median,
        "flip_edge": finite_or_null(flip_edge),
        "flip_interior": finite_or_null(flip_interior),
        "flip_disocc": finite_or_null(flip_disocc),
        "disocc_fraction": rf.disocc_fraction,
        "relmse": v(Metric::RelMse),
        "flicker": opt(change.map(|c| c.flicker)),
        "change": opt(change.map(|c| c.change)),
        "ref_change": opt(change.map(|c| c.ref_change)),
    }));
    Ok(map)
}
