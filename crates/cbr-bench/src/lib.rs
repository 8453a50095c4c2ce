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
pub mod assemble;
pub mod attribution;
pub mod config;
pub mod equal_error;
pub mod gpu_stats;
pub mod help;
pub mod interleaved_attribution;
pub mod machine;
pub mod measure;
pub mod merge;
pub mod motion_attribution;
pub mod output;
pub mod render;
pub mod shard;
pub mod stats;
pub mod temporal;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::write_bytes;
use cbr_render::{Mapping, Renderer, Spec};
use cbr_scene::{LoadOptions, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};

pub use config::{Config, SweepFile, checkerboard, expand, parse_resolution, parse_spec};
pub use measure::{RefFrame, edge_mask, masked_mean};
pub use output::{CSV_COLUMNS, pareto_front, worst_windows};
pub use temporal::{DEFAULT_DISOCCLUSION_FRAMES, disocclusion_mask};

use measure::{NOT_TECHNIQUE, Role, measure};
use output::{csv, git_commit, save_snapshot};
pub use shard::Shard;
use shard::{Unit, Work};

/// Everything a bench run takes (the binary fills it from its arguments).
#[derive(Clone, Debug, Default)]
pub struct BenchOptions {
    /// Scene: a .toml description, an .obj file, or builtin:demo; empty: the sweep file's
    /// `scenes`.
    pub scene: String,
    /// Configurations, comma-separated technique specs (`cbr info` lists the registered ones):
    /// native, ssaa:N, msaa:N[:sample][:hdr], upscale[:bilinear|bicubic|fsr1][:SCALE],
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
    /// Anisotropic texture filtering's most lookups for every scene (1 to 16; default: each
    /// scene's `anisotropy`).
    pub anisotropy: Option<u32>,
    /// Device index or name substring.
    pub device: Option<String>,
    /// Validation layers on (slower; messages counted in bench.json).
    pub validation: bool,
    /// `--shard K/N`: render shard K of the run split N ways (crate::shard); `None`: the whole
    /// run, as `0/1` but without the shard's plan in bench.json.
    pub shard: Option<Shard>,
    /// The frame cache's folder (`--cache-dir`; default crate cbr_render::cache::default_dir).
    pub cache_dir: Option<PathBuf>,
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

/// Reads a sweep file (unknown keys and wrong types refused with the key's path).
pub fn read_sweep(p: &Path) -> Result<SweepFile> {
    let text =
        std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
    let de =
        toml::Deserializer::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
    serde_path_to_error::deserialize(de)
        .map_err(|e| anyhow::anyhow!("{}: {}: {}", p.display(), e.path(), e.inner()))
}

/// The scenes of a run: the one named on the command line, else the sweep file's `scenes`
/// (paths relative to the sweep file's folder; `builtin:NAME` as it is).
pub fn scene_sources(
    scene: &str,
    sweep: &SweepFile,
    sweep_path: Option<&Path>,
) -> Result<Vec<String>> {
    if !scene.is_empty() {
        return Ok(vec![scene.to_string()]);
    }
    let Some(list) = sweep.scenes.as_ref().filter(|l| !l.is_empty()) else {
        bail!("no scene: name one, or list them as `scenes = [...]` in the sweep file");
    };
    let base = sweep_path.and_then(Path::parent).unwrap_or(Path::new(""));
    Ok(list
        .iter()
        .map(|s| {
            if s.starts_with("builtin:") || Path::new(s).is_absolute() {
                s.clone()
            } else {
                base.join(s).to_string_lossy().into_owned()
            }
        })
        .collect())
}

/// One scene at one resolution: its reference and the configurations measured against it.
struct Group {
    scene: usize,
    size: (u32, u32),
    reference: Config,
    configs: Vec<Config>,
}

/// The units of a run in order (per group: the reference's frames when a sharded run shares
/// them through the cache, then the rows) with their estimated costs.
fn units(groups: &[Group], (warmup, frames): (u32, u32), share_reference: bool) -> Vec<Unit> {
    let mut out = Vec::new();
    for (g, grp) in groups.iter().enumerate() {
        let r = &grp.reference.settings;
        let cacheable_ref = shard::samples_per_frame(r) > 1.0;
        if share_reference {
            for f in warmup..warmup + frames {
                out.push(Unit {
                    group: g,
                    work: Work::RefFrame(f),
                    cost: shard::render_cost(r, 1),
                });
            }
        }
        let ref_rendered = match (share_reference, cacheable_ref) {
            (true, _) => 0,
            (false, true) => frames,
            (false, false) => warmup + frames,
        };
        // Its set-up is the group's (shard::GROUP_S).
        out.push(Unit {
            group: g,
            work: Work::Row(0),
            cost: shard::render_cost(r, ref_rendered),
        });
        for (i, c) in grp.configs.iter().enumerate() {
            out.push(Unit {
                group: g,
                work: Work::Row(i + 1),
                cost: shard::row_cost(&c.settings, warmup + frames, frames),
            });
        }
    }
    out
}

pub fn run(a: &BenchOptions) -> Result<BenchResult> {
    let started = Instant::now();
    let load_at_start = machine::load_average();
    let sweep: SweepFile = match &a.sweep {
        Some(p) => read_sweep(p)?,
        None => SweepFile::default(),
    };
    let sources = scene_sources(&a.scene, &sweep, a.sweep.as_deref())?;
    let mut scenes = Vec::new();
    for src in &sources {
        let mut s = cbr_scene::load(src, &LoadOptions::default())
            .with_context(|| format!("scene {src}"))?;
        if let Some(n) = a.anisotropy {
            cbr_scene::check_anisotropy(n).map_err(|e| anyhow::anyhow!("--anisotropy: {e}"))?;
            s.settings.anisotropy = n;
        }
        if let Some(o) = scenes.iter().find(|o: &&cbr_scene::Scene| o.name == s.name) {
            bail!(
                "scenes: two scenes are named `{}` ({} and {})",
                s.name,
                o.source,
                s.source
            );
        }
        scenes.push(s);
    }
    let several_scenes = scenes.len() > 1;
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
    let named_resolutions: Vec<(u32, u32)> = pick(&a.resolutions, &sweep.resolutions)
        .iter()
        .map(|s| parse_resolution(s))
        .collect::<Result<_>>()?;
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
    let mut plan: Vec<Group> = Vec::new();
    for (si, scene) in scenes.iter().enumerate() {
        let resolutions = if named_resolutions.is_empty() {
            let (w, h) = (
                a.width.unwrap_or(scene.settings.width),
                a.height.unwrap_or(scene.settings.height),
            );
            check_resolution(w, h).map_err(anyhow::Error::msg)?;
            vec![(w, h)]
        } else {
            named_resolutions.clone()
        };
        for (w, h) in resolutions {
            let mut configs: Vec<Config> =
                expand(&techniques, w, h, &mappings, &groups, &lod_biases)?
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
            let reference =
                expand(std::slice::from_ref(&reference), w, h, &[], &[], &[])?.remove(0);
            plan.push(Group {
                scene: si,
                size: (w, h),
                reference,
                configs,
            });
        }
    }
    for g in &plan {
        let (w, h) = g.size;
        if let Some(c) = fixed_crops
            .iter()
            .find(|c| c[0] + c[2] > w as usize || c[1] + c[3] > h as usize)
        {
            bail!("--crop {c:?} does not fit in {w}x{h}");
        }
    }
    let shard = a.shard.unwrap_or(Shard::WHOLE);
    // Timing only: nothing is read from or written to the frame cache (a cached frame is not
    // timed, and no frame is kept).
    let cache = (!a.no_cache && !a.timing_only).then(|| {
        a.cache_dir
            .clone()
            .unwrap_or_else(cbr_render::cache::default_dir)
    });
    let share_reference = shard.count > 1 && cache.is_some() && reference != "native";
    let units = units(&plan, (warmup, frames), share_reference);
    let (owner, loads) = shard::assign(
        &units.iter().map(|u| (u.group, u.cost)).collect::<Vec<_>>(),
        shard.count,
    );
    let mine = |i: usize| owner[i] == shard.index;
    let plan_json: Vec<_> = units
        .iter()
        .zip(&owner)
        .map(|(u, o)| {
            let g = &plan[u.group];
            let (kind, config) = match u.work {
                Work::RefFrame(f) => (format!("reference frame {f}"), &g.reference.name),
                Work::Row(0) => ("row".to_string(), &g.reference.name),
                Work::Row(i) => ("row".to_string(), &g.configs[i - 1].name),
            };
            json!({
                "scene": scenes[g.scene].name,
                "width": g.size.0,
                "height": g.size.1,
                "config": config,
                "work": kind,
                "cost_s": u.cost,
                "shard": o,
            })
        })
        .collect();
    let gpu = Gpu::new(&GpuOptions {
        device: a.device.clone(),
        validation: a.validation,
    })?;
    // Every configuration, the references included, is refused now if it cannot run here (an
    // unknown spec, a missing device feature, memory the device cannot hold), before anything
    // is rendered or written. Every shard checks the whole run, so all refuse the same.
    for g in &plan {
        let mut scene = scenes[g.scene].clone();
        (scene.settings.width, scene.settings.height) = g.size;
        for c in std::iter::once(&g.reference).chain(&g.configs) {
            Renderer::check(&gpu, &scene, &c.settings)?;
        }
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create the output folder {}", a.out.display()))?;
    let info = gpu.info().clone();
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} frames {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(format!(
        "bench {}",
        scenes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(",")
    ));
    if let Some(dir) = &cache
        && reference != "native"
    {
        eprintln!(
            "reference frame cache: {} (--no-cache renders afresh)",
            dir.display()
        );
    }
    // Sharded: this shard's frames of the references first, into the shared cache.
    let mut ref_frames_rendered = 0u32;
    let mut ref_frames_cached = 0u32;
    for (gi, g) in plan.iter().enumerate() {
        let todo: Vec<u32> = units
            .iter()
            .enumerate()
            .filter(|(i, u)| u.group == gi && mine(*i))
            .filter_map(|(_, u)| match u.work {
                Work::RefFrame(f) => Some(f),
                Work::Row(_) => None,
            })
            .collect();
        if todo.is_empty() {
            continue;
        }
        let mut scene = scenes[g.scene].clone();
        (scene.settings.width, scene.settings.height) = g.size;
        let mut settings = g.reference.settings.clone();
        settings.cache = cache.clone();
        let shaders = cbr_render::shader_library();
        let mut r = Renderer::new(&gpu, &shaders, &scene, settings)?;
        if r.cache_dir().is_none() {
            eprintln!(
                "shard {shard}: {reference} is not cached, so every shard renders the frames it needs itself"
            );
            continue;
        }
        r.set_progress(sample_progress(format!("reference {reference}")));
        for f in todo {
            let out = r.render(&scene, f)?;
            if out.timings.is_empty() {
                ref_frames_cached += 1;
            } else {
                ref_frames_rendered += 1;
            }
        }
    }
    let total_frames: u64 = units
        .iter()
        .enumerate()
        .filter(|(i, u)| mine(*i) && matches!(u.work, Work::Row(_)))
        .map(|_| u64::from(warmup + frames))
        .sum();
    bar.set_length(total_frames);
    let mut rows = Vec::new();
    let mut id_sources = Vec::new();
    // Sharded: each finished row is also kept in rows/ with the plan it belongs to, so that a
    // rerun of a killed shard measures only the rows it had not finished.
    let resume = a.shard.map(|_| {
        let key = json!({
            "plan": plan_json,
            "protocol": [warmup, frames, k],
            "reference": reference,
            "timing_only": a.timing_only,
            "commit": git_commit(),
            "device": [&info.name, &info.driver_info],
        });
        (a.out.join("rows"), key)
    });
    let finished = |unit: usize| -> Option<Value> {
        let (dir, key) = resume.as_ref()?;
        let text = std::fs::read_to_string(dir.join(format!("{unit}.json"))).ok()?;
        let v: Value = serde_json::from_str(&text).ok()?;
        (v["key"] == *key).then_some(v)
    };
    let mut rows_resumed = 0u32;
    // The reference's measured frames that came from the cache (in rows resumed or not).
    let mut ref_measured_cached = 0u32;
    for (gi, g) in plan.iter().enumerate() {
        let my_rows: Vec<(usize, usize)> = units
            .iter()
            .enumerate()
            .filter(|(i, u)| u.group == gi && mine(*i))
            .filter_map(|(i, u)| match u.work {
                Work::Row(r) => Some((i, r)),
                Work::RefFrame(_) => None,
            })
            .collect();
        let kept: Vec<Option<Value>> = my_rows.iter().map(|(i, _)| finished(*i)).collect();
        if kept.iter().all(Option::is_some) {
            // Nothing left to measure here (or nothing of this shard's).
            for v in kept.into_iter().flatten() {
                rows.push(v["row"].clone());
                if !v["id_source"].is_null() && !id_sources.contains(&v["id_source"]) {
                    id_sources.push(v["id_source"].clone());
                }
                rows_resumed += 1;
            }
            continue;
        }
        let mut scene = scenes[g.scene].clone();
        let (w, h) = g.size;
        (scene.settings.width, scene.settings.height) = g.size;
        let mut ref_config = g.reference.clone();
        ref_config.settings.cache = cache.clone();
        bar.set_message(format!("reference {reference} {w}x{h}"));
        let role = if a.timing_only {
            Role::Timing
        } else {
            Role::Reference {
                disocclusion_frames: k,
            }
        };
        let (rm, ref_frames) = measure(&gpu, &scene, &ref_config, (warmup, frames), role, &bar)?;
        ref_measured_cached += rm.cached_frames;
        if let Some(s) = &rm.id_stand_in
            && s.mismatched_pixels > 0
        {
            eprintln!(
                "warning: the native raster's object IDs differ from {reference}'s at {} of {} pixels of frame {}: the disocclusion masks of the first measured frames are approximate",
                s.mismatched_pixels, s.pixels, s.native_frames[1]
            );
        }
        let id_source = (!a.timing_only).then(|| {
            json!({
                "scene": scene.name,
                "width": w,
                "height": h,
                "source": match &rm.id_stand_in {
                    Some(_) => "reference, with a native raster at the reference's LOD bias for the warm-up frames the reference skipped",
                    None => "reference",
                },
                "native": rm.id_stand_in,
            })
        });
        if let Some(s) = &id_source {
            id_sources.push(s.clone());
        }
        let display = DisplayTransform {
            exposure_stops: scene.settings.exposure,
        };
        let ctx = assemble::RowCtx {
            scene: &scene.name,
            size: g.size,
            device: &info,
            warmup,
            frames,
            disocclusion_frames: k,
            reference: &reference,
            timing_only: a.timing_only,
            fixed_crops: (!fixed_crops.is_empty()).then_some(fixed_crops.as_slice()),
        };
        let sub = assemble::sub_folder(&scene.name, g.size, several_scenes);
        let mut rm = Some(rm);
        for ((unit, r), kept) in my_rows.iter().zip(kept) {
            if let Some(v) = kept {
                rows.push(v["row"].clone());
                rows_resumed += 1;
                continue;
            }
            let (c, m) = if *r == 0 {
                let Some(m) = rm.take() else { continue };
                (ref_config.clone(), m)
            } else {
                let c = &g.configs[r - 1];
                bar.set_message(format!("{} {w}x{h}", c.name));
                // Cacheable techniques (ssaa) among the rows share the reference's cache,
                // unless their time is wanted (--time-cached-rows).
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
                (c, m)
            };
            let images = match &m.snapshot {
                Some(snap) => save_snapshot(&a.out, &sub, &c.name, snap, &display)?,
                None => json!(null),
            };
            let scores = m
                .snapshot
                .as_ref()
                .and_then(|s| s.flip_map.as_ref())
                .map(output::window_scores);
            let row = assemble::row(&c, &m, images, scores, &ctx);
            if let Some((dir, key)) = &resume {
                std::fs::create_dir_all(dir)?;
                let v = json!({"key": key, "row": row, "id_source": id_source});
                write_bytes(&dir.join(format!("{unit}.json")), v.to_string().as_bytes())?;
            }
            rows.push(row);
        }
    }
    bar.finish_and_clear();
    let reference_images = assemble::finish(
        &mut rows,
        &reference,
        !fixed_crops.is_empty(),
        a.shard.is_some(),
        several_scenes,
    );
    let messages = gpu.validation().messages();
    // The protocol's error entries, or what a timing-only run says instead.
    let measured = |text: &str| if a.timing_only { NOT_MEASURED } else { text }.to_string();
    let scene_json = |s: &cbr_scene::Scene| json!({"name": s.name, "source": s.source, "triangles": s.triangle_count(), "anisotropy": s.settings.anisotropy});
    let mut bench = json!({
        "schema": "cbr.bench/1",
        "cbr_version": env!("CARGO_PKG_VERSION"),
        "git_commit": git_commit(),
        "created_unix_s": std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
        "command": std::env::args().collect::<Vec<_>>(),
        "device": info,
        "machine": machine::describe(load_at_start),
        "scene": scene_json(&scenes[0]),
        "scenes": scenes.iter().map(scene_json).collect::<Vec<_>>(),
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
            "display": DisplayTransform { exposure_stops: scenes[0].settings.exposure }.describe(),
            "metrics": measured("PSNR and SSIM on display values, LDR-FLIP (67.02 ppd), relMSE on linear HDR (eps 0.01)"),
        },
        "reference": reference,
        "reference_images": reference_images,
        "rows": rows,
        "validation": {"enabled": a.validation, "messages": messages.len()},
        "wall_s": started.elapsed().as_secs_f64(),
    });
    if a.shard.is_some() {
        bench["shard"] = json!({
            "index": shard.index,
            "count": shard.count,
            "units": plan_json,
            "estimated_cost_s": loads,
            "fixed_crops": !fixed_crops.is_empty(),
            "cache": cache,
            "reference_frames": {
                "rendered": ref_frames_rendered,
                "read_from_cache": ref_frames_cached,
                "measured_from_cache": ref_measured_cached,
            },
            "rows_resumed": rows_resumed,
            "host": cbr_metrics::io::hostname(),
        });
    }
    write_bytes(
        &a.out.join("bench.json"),
        serde_json::to_string_pretty(&bench)?.as_bytes(),
    )?;
    write_bytes(&a.out.join("bench.csv"), csv(&bench).as_bytes())?;
    Ok(BenchResult {
        configurations: plan.first().map(|g| g.configs.len() + 1).unwrap_or(0),
        resolutions: plan.len() / scenes.len().max(1),
        scene: scenes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
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
