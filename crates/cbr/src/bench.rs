//! `cbr bench`: every configuration over the scene's camera path, GPU timestamps per pass (median,
//! p5, p95 after warm-up), pipeline statistics, the resolve's copy-kernel floor, and the error of
//! every frame against native at the same resolution (cbr-metrics). Writes bench.json and
//! bench.csv (device, driver, resolution and settings on every row). DESIGN.md "Benchmark
//! protocol".

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::io::write_bytes;
use cbr_metrics::{CompareOptions, DisplayTransform, Metric, compare_images};
use cbr_render::{CheckerboardConfig, FrameOutput, Mapping, RenderSettings, Renderer, Spec};
use cbr_scene::{LoadOptions, Scene, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::stats::{Summary, summarize};

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene: a .toml description, an .obj file, or builtin:demo.
    scene: String,
    /// Configurations, comma-separated: native, upscale:bilinear|bicubic,
    /// checkerboard:LAYOUT[:MODE][:pixel|quad][:8|16][:fp16][:prepass][:locations] (MODE: ours, pq4k, intel,
    /// spatial, temporal; default ours, quad, 8). Native at each resolution is always run: it is
    /// the reference.
    #[arg(long, value_delimiter = ',', default_value = "native")]
    techniques: Vec<String>,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Frames rendered before measuring.
    #[arg(long)]
    warmup: Option<u32>,
    /// Measured frames (the protocol asks for at least 50; fewer is allowed for quick looks).
    #[arg(long)]
    frames: Option<u32>,
    /// Sweep: resolutions WxH (replace --width/--height).
    #[arg(long, value_delimiter = ',')]
    resolutions: Vec<String>,
    /// Sweep: resolve mappings for every checkerboard configuration that does not name one.
    #[arg(long, value_delimiter = ',')]
    mappings: Vec<String>,
    /// Sweep: resolve group sizes for every checkerboard configuration that does not name one.
    #[arg(long, value_delimiter = ',')]
    groups: Vec<u32>,
    /// Sweep: texture LOD biases for checkerboard configurations (default: each layout's own).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    lod_biases: Vec<f32>,
    /// A TOML file with any of: techniques, resolutions, mappings, groups, lod_biases, warmup,
    /// frames (command-line values win).
    #[arg(long)]
    sweep: Option<PathBuf>,
    /// Crop windows for the report, x,y,w,h (repeatable, at most 4); default: the three windows
    /// with the highest FLIP.
    #[arg(long = "crop", value_name = "X,Y,W,H")]
    crops: Vec<String>,
    /// The reference every error is measured against: `native` (reconstruction error) or a
    /// supersampled ground truth such as `ssaa:16` (then native gets an error row too). Its frames
    /// are cached on disk (see --no-cache).
    #[arg(long, default_value = "native")]
    reference: String,
    /// Render cacheable references afresh instead of reading the frame cache.
    #[arg(long)]
    no_cache: bool,
    /// Device index or name substring.
    #[arg(long)]
    device: Option<String>,
    /// Validation layers on (slower; messages counted in bench.json).
    #[arg(long)]
    validation: bool,
    #[arg(short, long, default_value = "out/bench")]
    out: PathBuf,
}

/// The sweep file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    techniques: Option<Vec<String>>,
    resolutions: Option<Vec<String>>,
    mappings: Option<Vec<String>>,
    groups: Option<Vec<u32>>,
    lod_biases: Option<Vec<f32>>,
    warmup: Option<u32>,
    frames: Option<u32>,
    reference: Option<String>,
}

/// One configuration to measure.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// The spec as written, with sweep values appended (e.g. `checkerboard:rotated:ours:pixel:16`).
    pub name: String,
    #[serde(skip)]
    pub settings: RenderSettings,
}

fn parse_resolution(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("resolution `{s}`: expected WxH, e.g. 1920x1080"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("resolution `{s}`"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("resolution `{s}`"))?;
    check_resolution(w, h).map_err(anyhow::Error::msg)?;
    Ok((w, h))
}

/// Parses one configuration spec for a resolution (any registered technique and post chain).
/// Returns the settings and whether a checkerboard spec named a mapping and a group (sweeps
/// fill the others).
pub fn parse_spec(spec: &str, w: u32, h: u32) -> Result<(RenderSettings, bool, bool)> {
    let mut s = RenderSettings::parse(w, h, spec).map_err(anyhow::Error::msg)?;
    // Benchmarks also time the resolve's copy-kernel floor.
    s.instrument = true;
    let named = |p: &[&str]| {
        s.spec
            .technique
            .params
            .iter()
            .any(|x| p.contains(&x.as_str()))
    };
    let is_cb = s.spec.technique.name == "checkerboard";
    Ok((
        s.clone(),
        is_cb && named(&["pixel", "quad"]),
        is_cb && named(&["8", "16"]),
    ))
}

/// The checkerboard configuration of settings, if they are a checkerboard spec.
fn checkerboard(s: &RenderSettings) -> Option<CheckerboardConfig> {
    (s.spec.technique.name == "checkerboard")
        .then(|| CheckerboardConfig::parse(&s.spec.technique.params()).ok())
        .flatten()
}

/// The cross product of specs and sweeps at one resolution.
pub fn expand(
    specs: &[String],
    w: u32,
    h: u32,
    mappings: &[Mapping],
    groups: &[u32],
    lod_biases: &[f32],
) -> Result<Vec<Config>> {
    let mut out = Vec::new();
    for spec in specs {
        let (base, named_mapping, named_group) = parse_spec(spec, w, h)?;
        let cb = checkerboard(&base);
        let is_resolved = cb.is_some_and(|c| c.resolve.is_some());
        let maps: Vec<Option<Mapping>> = if is_resolved && !named_mapping && !mappings.is_empty() {
            mappings.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        let grps: Vec<Option<u32>> = if is_resolved && !named_group && !groups.is_empty() {
            groups.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        let biases: Vec<Option<f32>> = if cb.is_some() && !lod_biases.is_empty() {
            lod_biases.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        for m in &maps {
            for g in &grps {
                for b in &biases {
                    let mut s = base.clone();
                    let mut name = spec.clone();
                    if let Some(mut c) = cb {
                        if let (Some(r), Some(m)) = (c.resolve.as_mut(), m) {
                            r.mapping = *m;
                            name += if *m == Mapping::Pixel {
                                ":pixel"
                            } else {
                                ":quad"
                            };
                        }
                        if let (Some(r), Some(g)) = (c.resolve.as_mut(), g) {
                            r.group = *g;
                            name += &format!(":{g}");
                        }
                        s.spec.technique.params = c.params();
                    }
                    if let Some(b) = b {
                        s.lod_bias = Some(*b);
                        name += &format!(":lod{b}");
                    }
                    out.push(Config { name, settings: s });
                }
            }
        }
    }
    Ok(out)
}

/// Passes that instrument the run rather than belong to the technique.
const NOT_TECHNIQUE: [&str; 3] = ["readback", "checkerboard.unpack", "resolve.copy_floor"];

/// Indices of the rows on the speed-vs-error Pareto front (lower time and lower error are
/// better): no other row is at least as good in both and better in one.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| {
            let (ti, ei) = points[i];
            ti.is_finite()
                && ei.is_finite()
                && !points
                    .iter()
                    .enumerate()
                    .any(|(j, &(tj, ej))| j != i && tj <= ti && ej <= ei && (tj < ti || ej < ei))
        })
        .collect()
}

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
struct Snapshot {
    out: FrameOutput,
    flip_map: Option<cbr_metrics::planes::Plane>,
}

#[derive(Default)]
struct Measured {
    lod_bias: f32,
    snapshot: Option<Snapshot>,
    passes: BTreeMap<String, Vec<f64>>,
    frame_ms: Vec<f64>,
    fragments: BTreeMap<String, Vec<f64>>,
    errors: Vec<serde_json::Value>,
    psnr: Vec<f64>,
    ssim: Vec<f64>,
    flip: Vec<f64>,
    flip_median: Vec<f64>,
    flip_edge: Vec<f64>,
    relmse: Vec<f64>,
}

fn mean(v: &[f64]) -> Option<f64> {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    (!f.is_empty()).then(|| f.iter().sum::<f64>() / f.len() as f64)
}

#[allow(clippy::too_many_arguments)]
fn measure(
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
        r.set_progress(crate::render::sample_progress(label));
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
    // A cacheable reference (ssaa) has no history: its warm-up frames would cost N^2 rasters
    // each for nothing.
    let first = if keep && r.cache_dir().is_some() {
        warmup
    } else {
        0
    };
    bar.inc(u64::from(first));
    for f in first..warmup + frames {
        let out = r.render(scene, f)?;
        bar.inc(1);
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
        m.frame_ms.push(total);
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

fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes the last measured frame of a configuration for the report: the display PNG, the FLIP
/// map as a magma PNG (same size; the report draws the colour bar) and the EXR with all layers.
/// Returns the paths relative to the bench folder.
fn save_snapshot(
    dir: &std::path::Path,
    res: (u32, u32),
    name: &str,
    snap: &Snapshot,
    display: &DisplayTransform,
) -> Result<serde_json::Value> {
    let sub = format!("{}x{}", res.0, res.1);
    let base = slug(name);
    let img = format!("images/{sub}/{base}.png");
    let exr = format!("frames/{sub}/{base}.exr");
    std::fs::create_dir_all(dir.join("images").join(&sub))?;
    std::fs::create_dir_all(dir.join("frames").join(&sub))?;
    let o = &snap.out;
    cbr_metrics::io::write_png_rgba8(
        &dir.join(&img),
        o.width,
        o.height,
        &display.to_rgba8(&o.color),
    )?;
    cbr_metrics::io::write_frame_exr(
        &dir.join(&exr),
        &cbr_metrics::io::FrameLayers {
            width: o.width,
            height: o.height,
            color: &o.color,
            depth: &o.depth,
            velocity: &o.velocity,
            ids: &o.ids,
            mask: o.mask.as_deref(),
            prepass: None,
            extra: Vec::new(),
            metadata: vec![
                ("cbr.config".to_string(), name.to_string()),
                ("cbr.frame".to_string(), o.index.to_string()),
            ],
        },
    )?;
    let flip = match &snap.flip_map {
        Some(map) => {
            let path = format!("images/{sub}/{base}.flip.png");
            let rgba: Vec<u8> = map
                .data
                .iter()
                .flat_map(|&v| {
                    let c = cbr_metrics::heatmap::magma(v);
                    [c[0], c[1], c[2], 255]
                })
                .collect();
            cbr_metrics::io::write_png_rgba8(&dir.join(&path), o.width, o.height, &rgba)?;
            json!(path)
        }
        None => json!(null),
    };
    Ok(json!({"frame": o.index, "image": img, "flip": flip, "exr": exr}))
}

/// Up to `count` non-overlapping square windows (side ~ 1/6 of the short side) with the highest
/// mean of the given FLIP maps: where the techniques err most. [x, y, w, h] each.
pub fn worst_windows(maps: &[&cbr_metrics::planes::Plane], count: usize) -> Vec<[usize; 4]> {
    let Some(first) = maps.first() else {
        return Vec::new();
    };
    let (w, h) = (first.width, first.height);
    let side = (w.min(h) / 6).max(8).min(w).min(h);
    let stride = (side / 2).max(1);
    let mut scored = Vec::new();
    let mut y = 0;
    while y + side <= h {
        let mut x = 0;
        while x + side <= w {
            let mut sum = 0.0f64;
            for m in maps {
                for yy in y..y + side {
                    sum += m.data[yy * w + x..yy * w + x + side]
                        .iter()
                        .map(|&v| f64::from(v))
                        .sum::<f64>();
                }
            }
            scored.push((sum, x, y));
            x += stride;
        }
        y += stride;
    }
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut picked: Vec<[usize; 4]> = Vec::new();
    for (_, x, y) in scored {
        let overlaps = picked
            .iter()
            .any(|p| x < p[0] + p[2] && p[0] < x + side && y < p[1] + p[3] && p[1] < y + side);
        if !overlaps {
            picked.push([x, y, side, side]);
            if picked.len() == count {
                break;
            }
        }
    }
    picked
}

fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() { json!(x) } else { json!(null) }
}

fn summary_json(s: Option<Summary>) -> serde_json::Value {
    s.map(|s| json!(s)).unwrap_or(json!(null))
}

fn git_commit() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

pub fn run(a: &BenchArgs) -> Result<()> {
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
    let reference = match (&sweep.reference, a.reference.as_str()) {
        (Some(r), "native") => r.clone(),
        _ => a.reference.clone(),
    };
    Spec::parse(&reference).map_err(|e| anyhow::anyhow!("--reference: {e}"))?;
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
    for ((w, h), configs) in &plan {
        scene.settings.width = *w;
        scene.settings.height = *h;
        let mut ref_config =
            expand(std::slice::from_ref(&reference), *w, *h, &[], &[], &[])?.remove(0);
        ref_config.settings.cache = (!a.no_cache).then(cbr_render::cache::default_dir);
        if let Some(dir) = &ref_config.settings.cache
            && reference != "native"
        {
            eprintln!(
                "reference frame cache: {} (--no-cache renders afresh)",
                dir.display()
            );
        }
        bar.set_message(format!("reference {reference} {w}x{h}"));
        let (rm, ref_frames) =
            measure(&gpu, &scene, &ref_config, warmup, frames, None, true, &bar)?;
        let mut all = vec![(ref_config, rm)];
        for c in configs {
            bar.set_message(format!("{} {w}x{h}", c.name));
            let (m, _) = measure(
                &gpu,
                &scene,
                c,
                warmup,
                frames,
                Some((&reference, &ref_frames)),
                false,
                &bar,
            )?;
            all.push((c.clone(), m));
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
                "frame_ms": summary_json(summarize(&m.frame_ms)),
                "passes": passes,
                "fragment_invocations_median": fragments,
                "images": images,
                "crops": crops,
                "copy_floor_ms": summary_json(summarize(m.passes.get("resolve.copy_floor").map(Vec::as_slice).unwrap_or(&[]))),
                "reference": reference,
                "error": if is_reference { json!(null) } else { json!({
                    "psnr_mean": opt(mean(&m.psnr)),
                    "ssim_mean": opt(mean(&m.ssim)),
                    "flip_mean": opt(mean(&m.flip)),
                    "flip_median_mean": opt(mean(&m.flip_median)),
                    "flip_edge_mean": opt(mean(&m.flip_edge)),
                    "relmse_mean": opt(mean(&m.relmse)),
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
    let messages = gpu.validation().messages();
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
            "reference": format!("{reference} at the same resolution and frame"),
            "edge_pixels": "FLIP mean over the reference's edge pixels: more than one object ID among a supersampled reference's samples (its coverage layer), or for a one-sample reference an object ID that differs from a 4-neighbour's",
            "display": DisplayTransform { exposure_stops: scene.settings.exposure }.describe(),
            "metrics": "PSNR and SSIM on display values, LDR-FLIP (67.02 ppd), relMSE on linear HDR (eps 0.01)",
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
    println!(
        "{} configuration(s) x {} resolution(s) of {}: {}",
        plan.first().map(|p| p.1.len() + 1).unwrap_or(0),
        plan.len(),
        scene.name,
        a.out.join("bench.json").display()
    );
    Ok(())
}

/// Columns of bench.csv: every row carries device, driver, resolution and settings.
pub const CSV_COLUMNS: [&str; 26] = [
    "scene",
    "config",
    "technique",
    "resolve",
    "mapping",
    "group",
    "fp16",
    "id_prepass",
    "lod_bias",
    "width",
    "height",
    "device",
    "driver",
    "warmup",
    "frames",
    "frame_ms_median",
    "frame_ms_p5",
    "frame_ms_p95",
    "copy_floor_ms_median",
    "psnr_mean",
    "ssim_mean",
    "flip_mean",
    "flip_edge_mean",
    "relmse_mean",
    "reference",
    "pareto",
];

fn csv(bench: &serde_json::Value) -> String {
    let mut out = CSV_COLUMNS.join(",") + "\n";
    let empty = vec![];
    for r in bench["rows"].as_array().unwrap_or(&empty) {
        let cell = |v: &serde_json::Value| match v {
            serde_json::Value::Null => String::new(),
            serde_json::Value::String(s) => {
                if s.contains([',', '"']) {
                    format!("\"{}\"", s.replace('"', "\"\""))
                } else {
                    s.clone()
                }
            }
            other => other.to_string(),
        };
        let vals = [
            &r["scene"],
            &r["config"],
            &r["technique"],
            &r["resolve"],
            &r["mapping"],
            &r["group"],
            &r["fp16"],
            &r["id_prepass"],
            &r["lod_bias"],
            &r["width"],
            &r["height"],
            &r["device"],
            &r["driver"],
            &r["warmup"],
            &r["frames"],
            &r["frame_ms"]["median"],
            &r["frame_ms"]["p5"],
            &r["frame_ms"]["p95"],
            &r["copy_floor_ms"]["median"],
            &r["error"]["psnr_mean"],
            &r["error"]["ssim_mean"],
            &r["error"]["flip_mean"],
            &r["error"]["flip_edge_mean"],
            &r["error"]["relmse_mean"],
            &r["reference"],
            &r["pareto"],
        ];
        out += &vals.map(cell).join(",");
        out.push('\n');
    }
    out
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
