//! `cbr render` as a library: a scene's frames to EXR (all layers) + PNG (display) and run.json
//! (its schema is here), beside [`crate::run`] for `cbr bench`. What a technique adds (its layers
//! in the EXR, its statistics and settings in run.json: [`layers`]; its debug PNGs: [`pngs`]) is
//! written from its registration's declarations, naming no technique; the shorthand flags are in
//! [`flags`].

pub mod device;
pub mod flags;
pub mod layers;
pub mod pngs;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::{FrameLayers, write_bytes, write_frame_exr, write_png_rgba8};
use cbr_render::cache::default_dir as default_cache_dir;
use cbr_render::{RenderSettings, Renderer};
use cbr_scene::{LoadOptions, MissingTextures, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::stats::summarize;
pub use flags::{Shorthand, finite_f32};

/// `--technique`'s help.
pub fn technique_help() -> String {
    format!(
        "Technique spec: {}. The flags below are shorthand that edits the spec; run.json \
         records the result",
        crate::help::registered()
    )
}

/// Everything a render run takes (the binary fills it from its arguments).
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Scene: a .toml description, an .obj file, or builtin:NAME.
    pub scene: String,
    /// Output folder (created if missing).
    pub out: PathBuf,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Frames of the scene's camera path (default: the scene's).
    pub frames: Option<u32>,
    /// The technique spec, before the shorthand flags edit it.
    pub technique: String,
    pub shorthand: Shorthand,
    /// Device index or name substring.
    pub device: Option<String>,
    /// Validation layers on (also with CBR_VALIDATION=1); messages counted in run.json.
    pub validation: bool,
    /// Texture LOD bias (default: the technique's matching bias).
    pub lod_bias: Option<f32>,
    /// Count shaded fragments exactly.
    pub count_shaded: bool,
    /// Also time the copy kernel of the technique's bandwidth floor.
    pub bandwidth_floor: bool,
    /// Display exposure in stops (PNG only; default: the scene's).
    pub exposure: Option<f32>,
    /// Render cacheable techniques afresh instead of reading the frame cache.
    pub no_cache: bool,
    /// The frame cache's folder (default cbr_render::cache::default_dir).
    pub cache_dir: Option<PathBuf>,
    pub missing_textures: Option<MissingTextures>,
    /// Anisotropic texture filtering's most lookups (1 to 16; default: the scene's).
    pub anisotropy: Option<u32>,
}

/// What a finished render wrote.
pub struct RenderResult {
    pub frames: u32,
    pub scene: String,
    /// Validation messages (listed in run.json).
    pub validation_messages: usize,
    pub run_json: PathBuf,
}

fn env_flag(name: &str) -> bool {
    std::env::var(name)
        .map(|v| v == "1" || v.eq_ignore_ascii_case("true"))
        .unwrap_or(false)
}

/// Renders every frame, then writes run.json (schema below; fields are only ever added).
pub fn run(a: &RenderOptions) -> Result<RenderResult> {
    let started = Instant::now();
    let opts = LoadOptions {
        missing_textures: a.missing_textures,
    };
    let mut scene = cbr_scene::load(&a.scene, &opts)?;
    let s = &mut scene.settings;
    s.width = a.width.unwrap_or(s.width);
    s.height = a.height.unwrap_or(s.height);
    s.frames = a.frames.unwrap_or(s.frames);
    if let Some(e) = a.exposure {
        s.exposure = e;
    }
    if let Some(n) = a.anisotropy {
        cbr_scene::check_anisotropy(n).map_err(|e| anyhow::anyhow!("--anisotropy: {e}"))?;
        s.anisotropy = n;
    }
    check_resolution(s.width, s.height).map_err(anyhow::Error::msg)?;
    if s.frames == 0 {
        bail!("--frames must be at least 1");
    }
    for w in &scene.stats.warnings {
        tracing::warn!("{w}");
    }

    let validation = a.validation || env_flag("CBR_VALIDATION");
    let gpu = Gpu::new(&GpuOptions {
        device: a.device.clone(),
        validation,
    })?;
    let shaders = cbr_render::shader_library();
    let spec = a.shorthand.apply(&a.technique)?;
    let mut settings = RenderSettings::new(scene.settings.width, scene.settings.height, spec);
    settings.lod_bias = a.lod_bias;
    settings.count_shaded = a.count_shaded;
    settings.instrument = a.bandwidth_floor;
    settings.cache = (!a.no_cache).then(|| a.cache_dir.clone().unwrap_or_else(default_cache_dir));
    let mut renderer = Renderer::new(&gpu, &shaders, &scene, settings.clone())
        .with_context(|| format!("setting up `{}` on {}", settings.spec, gpu.info().name))?;

    if let Some(dir) = renderer.cache_dir() {
        eprintln!("frame cache: {} (--no-cache renders afresh)", dir.display());
    }
    renderer.set_progress(crate::sample_progress(format!("{} samples", settings.spec)));
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create the output folder {}", a.out.display()))?;
    let display = DisplayTransform {
        exposure_stops: scene.settings.exposure,
    };
    let frames = scene.settings.frames;
    let bar = ProgressBar::new(u64::from(frames)).with_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} frames {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(format!("render {}", scene.name));
    let mut frame_records = Vec::new();
    let mut pass_times: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for f in 0..frames {
        let out = renderer.render(&scene, f)?;
        let exr = a.out.join(format!("frame_{f:04}.exr"));
        let png = a.out.join(format!("frame_{f:04}.png"));
        let meta = vec![
            ("cbr.scene".to_string(), scene.source.clone()),
            ("cbr.technique".to_string(), settings.spec.to_string()),
            ("cbr.frame".to_string(), f.to_string()),
            ("cbr.time".to_string(), format!("{}", out.time)),
            ("cbr.device".to_string(), gpu.info().name.clone()),
        ];
        write_frame_exr(
            &exr,
            &FrameLayers {
                width: out.width,
                height: out.height,
                color: &out.color,
                depth: &out.depth,
                velocity: &out.velocity,
                ids: &out.ids,
                extra: layers::exr_layers(&out)?,
                metadata: meta,
            },
        )?;
        write_png_rgba8(&png, out.width, out.height, &display.to_rgba8(&out.color))?;
        if let Some(n) = out.nonfinite_fragments.filter(|&n| n > 0) {
            bar.suspend(|| {
                eprintln!(
                    "warning: frame {f}: {n} fragment(s) shaded to NaN or infinity, written black \
                     (run.json: nonfinite_fragments)"
                )
            });
        }
        pngs::write(
            &a.out,
            f,
            &settings.spec,
            &out,
            &display.to_rgba8(&out.color),
        )?;
        for t in &out.timings {
            pass_times.entry(t.name.clone()).or_default().push(t.gpu_ms);
        }
        let mut record = json!({
            "index": f,
            "time": out.time,
            "exr": file_name(&exr),
            "png": file_name(&png),
            "passes": out.timings,
            "cached": out.cached,
            "shaded_fragments": out.shaded_fragments,
            "nonfinite_fragments": out.nonfinite_fragments,
        });
        // The technique's statistics: `parity`, `resolve_reset`, `analytic`, ... (every
        // registration's, `null` where this frame has none).
        layers::add_stats(&out, &mut record);
        frame_records.push(record);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let messages = gpu.validation().messages();
    let passes: Vec<serde_json::Value> = pass_times
        .iter()
        .map(|(name, v)| json!({"name": name, "gpu_ms": summarize(v)}))
        .collect();
    let mut run = json!({
        "cbr_version": env!("CARGO_PKG_VERSION"),
        "command": std::env::args().collect::<Vec<_>>(),
        "created_unix_s": std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
        "device": gpu.info(),
        "scene": {
            "name": scene.name,
            "source": scene.source,
            "objects": scene.objects.len(),
            "triangles": scene.triangle_count(),
            "materials": scene.materials.len(),
            "textures": scene.textures.len(),
            "directional_lights": scene.directional.len(),
            "point_lights": scene.points.len(),
            "load": scene.stats,
        },
        "settings": {
            "technique": settings.spec,
            "target_bytes": renderer.target_bytes(),
            "width": settings.width,
            "height": settings.height,
            "frames": frames,
            "fps": scene.settings.fps,
            "lod_bias": renderer.lod_bias(),
            "anisotropy": scene.settings.anisotropy,
            "count_shaded": settings.count_shaded,
            "cache": renderer.cache_dir(),
            "depth": "reverse-Z D32 with an infinite far plane; the EXR depth layer holds view-space distance along the camera axis (+inf where empty)",
            "velocity": "pixels, current minus previous position, x right, y down",
            "ids": "object ID = object index + 1 (0 = background); primitive ID = triangle index within the object",
            "display": display.describe(),
        },
        "passes": passes,
        "frames": frame_records,
        "validation": {"enabled": validation, "messages": messages.len(), "list": messages},
        "wall_s": started.elapsed().as_secs_f64(),
    });
    layers::add_settings(&settings.spec, &mut run["settings"]);
    let run_json = a.out.join("run.json");
    write_bytes(&run_json, serde_json::to_string_pretty(&run)?.as_bytes())?;
    Ok(RenderResult {
        frames,
        scene: scene.name.clone(),
        validation_messages: messages.len(),
        run_json,
    })
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
