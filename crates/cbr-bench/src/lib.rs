//! `cbr bench` as a library: every configuration over the scene's camera path, GPU timestamps
//! per pass (median, p5, p95 after warm-up), pipeline statistics, the resolve's copy-kernel
//! floor, and the error of every frame against a reference (`native`, or a supersampled ground
//! truth such as `ssaa:16`) at the same resolution, whole frame, edge pixels and disoccluded
//! pixels, and the frame-to-frame change of the error beside the reference's own. Writes
//! bench.json (schema cbr.bench/1) and bench.csv with device, driver, resolution and settings on
//! every row. DESIGN.md "Benchmark protocol"; docs/bench-and-report.md.
#![forbid(unsafe_code)]
// bench.json's rows are one json! literal each, deeper than serde_json's default macro depth.
#![recursion_limit = "256"]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod analytic_attribution;
pub mod attribution;
pub mod config;
pub mod equal_error;
pub mod measure;
pub mod output;
pub mod stats;
pub mod temporal;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::write_bytes;
use cbr_render::{Mapping, Renderer, Spec};
use cbr_scene::{LoadOptions, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

pub use config::{Config, SweepFile, checkerboard, expand, parse_resolution, parse_spec};
pub use measure::{RefFrame, edge_mask, masked_mean};
pub use output::{CSV_COLUMNS, pareto_front, worst_windows};
pub use temporal::{DEFAULT_DISOCCLUSION_FRAMES, disocclusion_mask};

use measure::{NOT_TECHNIQUE, Role, mean, measure};
use output::{csv, finite_or_null, git_commit, save_snapshot, summary_json};
use stats::summarize;

/// Everything a bench run takes (the binary fills it from its arguments).
#[derive(Clone, Debug, Default)]
pub struct BenchOptions {
    /// Scene: a .toml description, an .obj file, or builtin:demo.
    pub scene: String,
    /// Configurations, comma-separated technique specs (`cbr info` lists the registered ones):
    /// native, ssaa:N, msaa:N[:sample][:hdr], upscale:bilinear|bicubic,
    /// checkerboard:LAYOUT[:MODE][:pixel|quad][:8|16][:fp16][:prepass][:locations] (MODE: ours,
    /// pq4k, intel, spatial, temporal; default ours, quad, 8), each with post passes (+sharpen).
    /// The reference and native are always run.
    pub techniques: Vec<String>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Frames rendered before measuring.
    pub warmup: Option<u32>,
    /// Measured frames (the protocol asks for at least 50; fewer is allowed for quick looks).
    pub frames: Option<u32>,
    /// Sweep: resolutions WxH (replace --width/--height).
    pub resolutions: Vec<String>,
    /// Sweep: resolve mappings for every checkerboard configuration that does not name one.
    pub mappings: Vec<String>,
    /// Sweep: resolve group sizes for every checkerboard configuration that does not name one.
    pub groups: Vec<u32>,
    /// Sweep: texture LOD biases for checkerboard configurations (default: each layout's own).
    pub lod_biases: Vec<f32>,
    /// A TOML file with any of: techniques, resolutions, mappings, groups, lod_biases, warmup,
    /// frames (command-line values win).
    pub sweep: Option<PathBuf>,
    /// Crop windows for the report, x,y,w,h (repeatable, at most 4); default: the three windows
    /// with the highest FLIP.
    pub crops: Vec<String>,
    /// The reference every error is measured against: `native` (reconstruction error) or a
    /// supersampled ground truth such as `ssaa:16` (then native gets an error row too). Its frames
    /// are cached on disk (see --no-cache).
    pub reference: String,
    /// Render cacheable references afresh instead of reading the frame cache.
    pub no_cache: bool,
    /// Render and time cacheable techniques among the rows instead of reading the frame cache.
    pub time_cached_rows: bool,
    /// Time the passes only: no error is measured, no frame kept, no image written (GPU
    /// studies at 4K, where the per-frame metrics would take most of the run). The reference
    /// must be `native`, which is then timed as a row like the others.
    pub timing_only: bool,
    /// k of the disocclusion FLIP: a pixel counts when its reference object ID differs from its
    /// ID in any of the k frames before (default 4).
    pub disocclusion_frames: Option<u32>,
    /// Device index or name substring.
    pub device: Option<String>,
    /// Validation layers on (slower; messages counted in bench.json).
    pub validation: bool,
    pub out: PathBuf,
}

/// The protocol's error entries in a `--timing-only` run.
const NOT_MEASURED: &str = "not measured (--timing-only)";

/// What a finished run wrote.
pub struct BenchResult {
    pub configurations: usize,
    pub resolutions: usize,
    pub scene: String,
    pub bench_json: PathBuf,
}

/// A progress callback for many-pass frames (ssaa): a bar of the frame's samples, shown once
/// the frame has taken more than a second.
pub fn sample_progress(label: String) -> impl FnMut(u32, u32) + 'static {
    let mut started = Instant::now();
    let mut bar: Option<ProgressBar> = None;
    move |done, total| {
        if done <= 1 {
            started = Instant::now();
        }
        if bar.is_none() && started.elapsed().as_secs_f64() > 1.0 && done < total {
            let b = ProgressBar::new(u64::from(total)).with_style(
                ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {elapsed}/{eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b.set_prefix(label.clone());
            bar = Some(b);
        }
        if let Some(b) = &bar {
            b.set_position(u64::from(done));
            if done >= total {
                b.finish_and_clear();
                bar = None;
            }
        }
    }
}

pub fn run(a: &BenchOptions) -> Result<BenchResult> {
    let started = Instant::now();
    let sweep: SweepFile = match &a.sweep {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            let de = toml::Deserializer::parse(&text)
                .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
            serde_path_to_error::deserialize(de)
                .map_err(|e| anyhow::anyhow!("{}: {}: {}", p.display(), e.path(), e.inner()))?
        }
        None => SweepFile::default(),
    };
    let mut scene = cbr_scene::load(&a.scene, &LoadOptions::default())?;
    let techniques = if a.techniques != ["native"] || sweep.techniques.is_none() {
        a.techniques.clone()
    } else {
        sweep.techniques.clone().unwrap_or_default()
    };
    let pick = |cli: &Vec<String>, file: &Option<Vec<String>>| {
        if cli.is_empty() {
            file.clone().unwrap_or_default()
        } else {
            cli.clone()
        }
    };
    let mut resolutions: Vec<(u32, u32)> = pick(&a.resolutions, &sweep.resolutions)
        .iter()
        .map(|s| parse_resolution(s))
        .collect::<Result<_>>()?;
    if resolutions.is_empty() {
        let (w, h) = (
            a.width.unwrap_or(scene.settings.width),
            a.height.unwrap_or(scene.settings.height),
        );
        check_resolution(w, h).map_err(anyhow::Error::msg)?;
        resolutions.push((w, h));
    }
    let mappings: Vec<Mapping> = pick(&a.mappings, &sweep.mappings)
        .iter()
        .map(|m| match m.as_str() {
            "pixel" => Ok(Mapping::Pixel),
            "quad" => Ok(Mapping::Quad),
            o => bail!("mapping `{o}` (pixel or quad)"),
        })
        .collect::<Result<_>>()?;
    let groups = if a.groups.is_empty() {
        sweep.groups.clone().unwrap_or_default()
    } else {
        a.groups.clone()
    };
    if let Some(g) = groups.iter().find(|g| **g != 8 && **g != 16) {
        bail!("resolve group {g} (8 or 16)");
    }
    let lod_biases = if a.lod_biases.is_empty() {
        sweep.lod_biases.clone().unwrap_or_default()
    } else {
        a.lod_biases.clone()
    };
    let fixed_crops: Vec<[usize; 4]> = a
        .crops
        .iter()
        .map(|c| {
            let v: Vec<usize> = c
                .split(',')
                .map(|x| x.trim().parse::<usize>())
                .collect::<std::result::Result<_, _>>()
                .with_context(|| format!("--crop {c}: expected X,Y,W,H"))?;
            match v[..] {
                [x, y, w, h] if w > 0 && h > 0 => Ok([x, y, w, h]),
                _ => bail!("--crop {c}: expected X,Y,W,H with W, H > 0"),
            }
        })
        .collect::<Result<_>>()?;
    if fixed_crops.len() > 4 {
        bail!("at most 4 --crop windows");
    }
    let warmup = a.warmup.or(sweep.warmup).unwrap_or(4);
    let frames = a.frames.or(sweep.frames).unwrap_or(50);
    if frames == 0 {
        bail!("--frames must be at least 1");
    }
    let k = a.disocclusion_frames.unwrap_or(DEFAULT_DISOCCLUSION_FRAMES);
    if k == 0 {
        bail!("--disocclusion-frames must be at least 1");
    }
    let reference = match (&sweep.reference, a.reference.as_str()) {
        (Some(r), "native") => r.clone(),
        _ => a.reference.clone(),
    };
    Spec::parse(&reference).map_err(|e| anyhow::anyhow!("--reference: {e}"))?;
    if a.timing_only && reference != "native" {
        bail!(
            "--timing-only measures no error, so it takes no reference: drop --reference {reference} (native is timed as a row)"
        );
    }
    let mut plan = Vec::new();
    for &(w, h) in &resolutions {
        let mut configs: Vec<Config> = expand(&techniques, w, h, &mappings, &groups, &lod_biases)?
            .into_iter()
            .filter(|c| c.name != reference)
            .collect();
        // Native is always measured: as the reference, or against it.
        if reference != "native" && !configs.iter().any(|c| c.name == "native") {
            configs.insert(
                0,
                expand(&["native".into()], w, h, &[], &[], &[])?.remove(0),
            );
        }
        plan.push(((w, h), configs));
    }
    let gpu = Gpu::new(&GpuOptions {
        device: a.device.clone(),
        validation: a.validation,
    })?;
    // Every configuration, the reference's included, is refused now if it cannot run here (an
    // unknown spec, a missing device feature, memory the device cannot hold), before anything
    // is rendered or written.
    for ((w, h), configs) in &plan {
        let r = expand(std::slice::from_ref(&reference), *w, *h, &[], &[], &[])?.remove(0);
        for c in std::iter::once(&r).chain(configs) {
            Renderer::check(&gpu, &scene, &c.settings)?;
        }
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create the output folder {}", a.out.display()))?;
    let total_frames: u64 = plan
        .iter()
        .map(|(_, c)| (c.len() as u64 + 1) * u64::from(warmup + frames))
        .sum();
    let bar = ProgressBar::new(total_frames).with_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} frames {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(format!("bench {}", scene.name));
    let info = gpu.info().clone();
    let mut rows = Vec::new();
    let mut id_sources = Vec::new();
    for ((w, h), configs) in &plan {
        scene.settings.width = *w;
        scene.settings.height = *h;
        let mut ref_config =
            expand(std::slice::from_ref(&reference), *w, *h, &[], &[], &[])?.remove(0);
        // Timing only: nothing is read from or written to the frame cache (a cached frame is not
        // timed, and no frame is kept).
        let cache = (!a.no_cache && !a.timing_only).then(cbr_render::cache::default_dir);
        ref_config.settings.cache = cache.clone();
        if let Some(dir) = &ref_config.settings.cache
            && reference != "native"
        {
            eprintln!(
                "reference frame cache: {} (--no-cache renders afresh)",
                dir.display()
            );
        }
        bar.set_message(format!("reference {reference} {w}x{h}"));
        let role = if a.timing_only {
            Role::Timing
        } else {
            Role::Reference {
                disocclusion_frames: k,
            }
        };
        let (rm, ref_frames) = measure(&gpu, &scene, &ref_config, (warmup, frames), role, &bar)?;
        if let Some(s) = &rm.id_stand_in
            && s.mismatched_pixels > 0
        {
            eprintln!(
                "warning: the native raster's object IDs differ from {reference}'s at {} of {} pixels of frame {}: the disocclusion masks of the first measured frames are approximate",
                s.mismatched_pixels, s.pixels, s.native_frames[1]
            );
        }
        if !a.timing_only {
            id_sources.push(json!({
                "width": w,
                "height": h,
                "source": match &rm.id_stand_in {
                    Some(_) => "reference, with a native raster at the reference's LOD bias for the warm-up frames the reference skipped",
                    None => "reference",
                },
                "native": rm.id_stand_in,
            }));
        }
        let mut all = vec![(ref_config, rm)];
        for c in configs {
            bar.set_message(format!("{} {w}x{h}", c.name));
            // Cacheable techniques (ssaa) among the rows share the reference's cache, unless
            // their time is wanted (--time-cached-rows).
            let mut c = c.clone();
            c.settings.cache = if a.time_cached_rows || a.timing_only {
                None
            } else {
                cache.clone()
            };
            let role = if a.timing_only {
                Role::Timing
            } else {
                Role::Against {
                    name: &reference,
                    frames: &ref_frames,
                }
            };
            let (m, _) = measure(&gpu, &scene, &c, (warmup, frames), role, &bar)?;
            all.push((c, m));
        }
        let display = DisplayTransform {
            exposure_stops: scene.settings.exposure,
        };
        let maps: Vec<&cbr_metrics::planes::Plane> = all
            .iter()
            .filter_map(|(_, m)| m.snapshot.as_ref().and_then(|s| s.flip_map.as_ref()))
            .collect();
        let crops = if fixed_crops.is_empty() {
            worst_windows(&maps, 3)
        } else {
            let fits = |c: &[usize; 4]| c[0] + c[2] <= *w as usize && c[1] + c[3] <= *h as usize;
            if let Some(c) = fixed_crops.iter().find(|c| !fits(c)) {
                bail!("--crop {c:?} does not fit in {w}x{h}");
            }
            fixed_crops.clone()
        };
        for (c, m) in all {
            let images = match &m.snapshot {
                Some(snap) => save_snapshot(&a.out, (*w, *h), &c.name, snap, &display)?,
                None => json!(null),
            };
            let s = &c.settings;
            let cb = checkerboard(s);
            let resolve = cb.and_then(|c| c.resolve);
            let resolve = resolve.as_ref();
            let passes: serde_json::Map<String, serde_json::Value> = m
                .passes
                .iter()
                .map(|(k, v)| (k.clone(), summary_json(summarize(v))))
                .collect();
            let fragments: serde_json::Map<String, serde_json::Value> = m
                .fragments
                .iter()
                .map(|(k, v)| (k.clone(), json!(crate::stats::percentile(v, 50.0))))
                .collect();
            let is_reference = c.name == reference;
            let opt = |v: Option<f64>| v.map(finite_or_null).unwrap_or(json!(null));
            rows.push(json!({
                "scene": scene.name,
                "config": c.name,
                "technique": s.spec.technique.name,
                "spec": s.spec,
                "resolve": resolve.map(|r| r.mode.name()),
                "mapping": resolve.map(|r| if r.mapping == Mapping::Pixel { "pixel" } else { "quad" }),
                "group": resolve.map(|r| r.group),
                "fp16": resolve.map(|r| r.fp16),
                "id_prepass": cb.is_some_and(|c| c.prepass),
                "lod_bias": m.lod_bias,
                "width": w,
                "height": h,
                "device": info.name,
                "driver": info.driver_info,
                "warmup": warmup,
                "frames": frames,
                "disocclusion_frames": k,
                "frame_ms": summary_json(summarize(&m.frame_ms)),
                "cached_frames": m.cached_frames,
                "setup_s": m.setup_s,
                "frames_wall_s": m.frames_wall_s,
                "passes": passes,
                "fragment_invocations_median": fragments,
                "images": images,
                "crops": crops,
                "copy_floor_ms": summary_json(summarize(m.passes.get("resolve.copy_floor").map(Vec::as_slice).unwrap_or(&[]))),
                "reference": reference,
                "error": if is_reference || a.timing_only { json!(null) } else { json!({
                    "psnr_mean": opt(mean(&m.psnr)),
                    "ssim_mean": opt(mean(&m.ssim)),
                    "flip_mean": opt(mean(&m.flip)),
                    "flip_median_mean": opt(mean(&m.flip_median)),
                    "flip_edge_mean": opt(mean(&m.flip_edge)),
                    "flip_interior_mean": opt(mean(&m.flip_interior)),
                    "flip_disocc_mean": opt(mean(&m.flip_disocc)),
                    "disocc_fraction_mean": opt(mean(&m.disocc_fraction)),
                    "relmse_mean": opt(mean(&m.relmse)),
                    "flicker_mean": opt(mean(&m.flicker)),
                    "change_mean": opt(mean(&m.change)),
                    "ref_change_mean": opt(mean(&m.ref_change)),
                    "attribution": m.attribution.as_ref().map(|a| a.to_json()),
                    "analytic_attribution": m.analytic_attribution.as_ref().map(|a| a.to_json()),
                    "per_frame": m.errors,
                })},
            }));
        }
    }
    bar.finish_and_clear();
    let reference_images: serde_json::Map<String, serde_json::Value> = rows
        .iter()
        .filter(|r| r["config"] == reference.as_str())
        .map(|r| {
            (
                format!("{}x{}", r["width"], r["height"]),
                r["images"].clone(),
            )
        })
        .collect();
    // The Pareto front per scene and resolution: frame time median against FLIP mean.
    let key = |r: &serde_json::Value| (r["width"].as_u64(), r["height"].as_u64());
    let mut on_front = vec![false; rows.len()];
    let mut groups_seen: Vec<(Option<u64>, Option<u64>)> = Vec::new();
    for r in &rows {
        if !groups_seen.contains(&key(r)) {
            groups_seen.push(key(r));
        }
    }
    for g in groups_seen {
        let idx: Vec<usize> = (0..rows.len())
            .filter(|&i| key(&rows[i]) == g && rows[i]["config"] != reference.as_str())
            .collect();
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| {
                (
                    rows[i]["frame_ms"]["median"].as_f64().unwrap_or(f64::NAN),
                    rows[i]["error"]["flip_mean"].as_f64().unwrap_or(f64::NAN),
                )
            })
            .collect();
        for k in pareto_front(&pts) {
            on_front[idx[k]] = true;
        }
    }
    for (r, f) in rows.iter_mut().zip(&on_front) {
        r["pareto"] = json!(f);
    }
    // Each row's error placed on the run's own supersampling ladder (its ssaa:N rows), if any.
    equal_error::annotate(&mut rows);
    let messages = gpu.validation().messages();
    // The protocol's error entries, or what a timing-only run says instead.
    let measured = |text: &str| if a.timing_only { NOT_MEASURED } else { text }.to_string();
    let bench = json!({
        "schema": "cbr.bench/1",
        "cbr_version": env!("CARGO_PKG_VERSION"),
        "git_commit": git_commit(),
        "created_unix_s": std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
        "command": std::env::args().collect::<Vec<_>>(),
        "device": info,
        "scene": {"name": scene.name, "source": scene.source, "triangles": scene.triangle_count()},
        "protocol": {
            "warmup_frames": warmup,
            "measured_frames": frames,
            "timing": "GPU timestamps per pass; compute passes bracketed by barriers (lavapipe); median, p5, p95 over the measured frames",
            "frame_ms": format!("sum of the technique's passes per frame (not {})", NOT_TECHNIQUE.join(", ")),
            "reference": if a.timing_only { "none: --timing-only (no error measured)".to_string() } else { format!("{reference} at the same resolution and frame") },
            "timing_only": a.timing_only,
            "edge_pixels": measured("FLIP mean over the reference's edge pixels: more than one object ID among a supersampled reference's samples (its coverage layer), or for a one-sample reference an object ID that differs from a 4-neighbour's"),
            "disocclusion_frames": k,
            "disocclusion_pixels": measured(&format!("FLIP mean over the pixels whose reference object ID differs from their ID in any of the k = {k} frames before (frames before frame 0 do not exist); frames whose mask is empty are left out of the mean")),
            "disocclusion_ids": id_sources,
            "temporal": measured("over consecutive measured frames, display values: flicker = mean |e_t - e_(t-1)| with e = test - reference (cbr compare's flicker), change = mean |x_t - x_(t-1)| of the test, ref_change = the same of the reference"),
            "display": DisplayTransform { exposure_stops: scene.settings.exposure }.describe(),
            "metrics": measured("PSNR and SSIM on display values, LDR-FLIP (67.02 ppd), relMSE on linear HDR (eps 0.01)"),
        },
        "reference": reference,
        "reference_images": reference_images,
        "rows": rows,
        "validation": {"enabled": a.validation, "messages": messages.len()},
        "wall_s": started.elapsed().as_secs_f64(),
    });
    write_bytes(
        &a.out.join("bench.json"),
        serde_json::to_string_pretty(&bench)?.as_bytes(),
    )?;
    write_bytes(&a.out.join("bench.csv"), csv(&bench).as_bytes())?;
    Ok(BenchResult {
        configurations: plan.first().map(|p| p.1.len() + 1).unwrap_or(0),
        resolutions: plan.len(),
        scene: scene.name.clone(),
        bench_json: a.out.join("bench.json"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cbr_render::ResolveMode;

    #[test]
    fn pareto_front_keeps_the_undominated() {
        // (time, error)
        let pts = [
            (1.0, 0.5),      // fastest: front
            (2.0, 0.2),      // front
            (2.5, 0.3),      // dominated by (2.0, 0.2)
            (4.0, 0.1),      // front
            (4.0, 0.1),      // a tie: neither dominates the other, both on the front
            (5.0, 0.1),      // dominated (slower, same error)
            (f64::NAN, 0.0), // unmeasured: never on the front
        ];
        assert_eq!(pareto_front(&pts), vec![0, 1, 3, 4]);
        assert_eq!(pareto_front(&[]), Vec::<usize>::new());
        assert_eq!(pareto_front(&[(3.0, 3.0)]), vec![0]);
    }

    #[test]
    fn crop_windows_find_the_worst_regions_without_overlap() {
        let (w, h) = (96, 60);
        let mut m = cbr_metrics::planes::Plane::new(w, h);
        // Two hot spots; the brighter one first.
        for y in 40..50 {
            for x in 70..80 {
                m.data[y * w + x] = 1.0;
            }
        }
        for y in 5..12 {
            for x in 5..12 {
                m.data[y * w + x] = 0.5;
            }
        }
        let c = worst_windows(&[&m], 3);
        assert_eq!(c.len(), 3);
        let side = 10; // min(96, 60) / 6
        assert!(c.iter().all(|r| r[2] == side && r[3] == side));
        let covers = |r: &[usize; 4], x: usize, y: usize| {
            x >= r[0] && x < r[0] + r[2] && y >= r[1] && y < r[1] + r[3]
        };
        assert!(covers(&c[0], 75, 45), "{c:?}");
        assert!(covers(&c[1], 8, 8), "{c:?}");
        for i in 0..3 {
            for j in i + 1..3 {
                let (a, b) = (c[i], c[j]);
                assert!(
                    a[0] + a[2] <= b[0]
                        || b[0] + b[2] <= a[0]
                        || a[1] + a[3] <= b[1]
                        || b[1] + b[3] <= a[1]
                );
            }
        }
        assert!(worst_windows(&[], 3).is_empty());
    }

    #[test]
    fn specs_and_sweeps_expand_to_the_cross_product() {
        let specs = [
            "native".to_string(),
            "checkerboard:rotated:pq4k".to_string(),
            "checkerboard:split:ours:pixel".to_string(),
            "upscale:bicubic".to_string(),
        ];
        let c = expand(
            &specs,
            64,
            36,
            &[Mapping::Pixel, Mapping::Quad],
            &[8, 16],
            &[],
        )
        .unwrap();
        let names: Vec<&str> = c.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "native",
                "checkerboard:rotated:pq4k:pixel:8",
                "checkerboard:rotated:pq4k:pixel:16",
                "checkerboard:rotated:pq4k:quad:8",
                "checkerboard:rotated:pq4k:quad:16",
                "checkerboard:split:ours:pixel:8",
                "checkerboard:split:ours:pixel:16",
                "upscale:bicubic",
            ]
        );
        let r = checkerboard(&c[2].settings)
            .and_then(|c| c.resolve)
            .expect("resolve");
        assert_eq!(
            (r.mode, r.mapping, r.group),
            (ResolveMode::Pq4k, Mapping::Pixel, 16)
        );
        assert!(c[2].settings.instrument);
        let (s, _, _) = parse_spec("checkerboard:masked:none", 8, 8).unwrap();
        assert!(checkerboard(&s).expect("checkerboard").resolve.is_none());
        let (s, _, _) =
            parse_spec("checkerboard:rotated:intel:quad:16:fp16:prepass", 8, 8).unwrap();
        let c = checkerboard(&s).expect("checkerboard");
        let r = c.resolve.expect("resolve");
        assert!(r.fp16 && c.prepass && r.mode == ResolveMode::Intel && r.group == 16);
        for bad in [
            "checkerboard:hexagon",
            "checkerboard:rotated:magic",
            "taa",
            "upscale:lanczos",
        ] {
            assert!(parse_spec(bad, 8, 8).is_err(), "{bad}");
        }
        assert!(parse_resolution("1920x1080").is_ok());
        assert!(parse_resolution("1920").is_err());
        assert!(parse_resolution("0x10").is_err());
    }
}
