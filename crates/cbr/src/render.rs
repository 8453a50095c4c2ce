//! `cbr render`: a scene's frames to EXR (all layers) + PNG (display) and run.json.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::Layout;
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::{FrameLayers, write_bytes, write_frame_exr, write_png_rgba8};
use cbr_render::{LodMode, RenderSettings, Renderer};
use cbr_scene::{LoadOptions, MissingTextures, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::stats::summarize;

#[derive(Clone, Copy, Debug, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Technique {
    /// Full resolution, one sample at each pixel centre: the reference.
    Native,
    /// Half the pixels per frame, alternating parity (`--layout`, `--resolve`).
    Checkerboard,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum LayoutArg {
    /// Quarter-resolution 2x MSAA (needs 2x MSAA: GPUs, not lavapipe).
    Msaa2x,
    /// Decima's tangram: an L x L 45-degree lattice.
    Rotated,
    /// Two half-resolution layers, one per sample of each 2x2 quad.
    Split,
    /// Full resolution, the other parity discarded (the correctness reference).
    Masked,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ResolveArg {
    /// The raw checkerboard frame at full resolution: missing pixels have alpha 0, and a `mask` layer.
    None,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum LodModeArg {
    /// A mip bias (--lod-bias; default per layout: 0 masked, -1 split and msaa2x, -0.5 rotated).
    Bias,
    /// Derivatives scaled to full-resolution pixels (textureGrad).
    Gradients,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MissingTexturesArg {
    Error,
    Fallback,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene: a .toml description, an .obj file (framed automatically), or builtin:demo.
    scene: String,
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "out/render")]
    out: PathBuf,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Number of frames of the scene's camera path to render (default: the scene's).
    #[arg(long)]
    frames: Option<u32>,
    #[arg(long, value_enum, default_value = "native")]
    technique: Technique,
    /// Device index or name substring (see `cbr info`).
    #[arg(long)]
    device: Option<String>,
    /// Enable the validation layer and synchronization validation; messages are counted in run.json.
    #[arg(long)]
    validation: bool,
    /// Checkerboard layout.
    #[arg(long, value_enum, default_value = "rotated")]
    layout: LayoutArg,
    /// How checkerboard frames are reconstructed (the resolve comes with a later issue).
    #[arg(long, value_enum, default_value = "none")]
    resolve: ResolveArg,
    /// Texture LOD bias added to every lookup (default: the technique's matching bias).
    #[arg(long, allow_hyphen_values = true)]
    lod_bias: Option<f32>,
    /// How texture LOD follows the layout's sample spacing.
    #[arg(long, value_enum, default_value = "bias")]
    lod_mode: LodModeArg,
    /// Count shaded fragments exactly (atomic counter; reported per frame in run.json).
    #[arg(long)]
    count_shaded: bool,
    /// Checkerboard: a native-resolution depth + ID pass first, no shading (EXR layers
    /// prepass_depth, prepass_object_id, prepass_primitive_id).
    #[arg(long)]
    id_prepass: bool,
    /// Display exposure in stops (PNG only; EXR stays linear). Default: the scene's.
    #[arg(long, allow_hyphen_values = true)]
    exposure: Option<f32>,
    /// What to do when a texture named by an MTL cannot be read.
    #[arg(long, value_enum)]
    missing_textures: Option<MissingTexturesArg>,
}

fn env_flag(name: &str) -> bool {
    std::env::var(name)
        .map(|v| v == "1" || v.eq_ignore_ascii_case("true"))
        .unwrap_or(false)
}

pub fn run(a: &RenderArgs) -> Result<()> {
    let started = Instant::now();
    let opts = LoadOptions {
        missing_textures: a.missing_textures.map(|m| match m {
            MissingTexturesArg::Error => MissingTextures::Error,
            MissingTexturesArg::Fallback => MissingTextures::Fallback,
        }),
    };
    let mut scene = cbr_scene::load(&a.scene, &opts)?;
    let s = &mut scene.settings;
    s.width = a.width.unwrap_or(s.width);
    s.height = a.height.unwrap_or(s.height);
    s.frames = a.frames.unwrap_or(s.frames);
    if let Some(e) = a.exposure {
        s.exposure = e;
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
    let technique = match a.technique {
        Technique::Native => cbr_render::Technique::Native,
        Technique::Checkerboard => cbr_render::Technique::Checkerboard {
            layout: match a.layout {
                LayoutArg::Msaa2x => Layout::Msaa2x,
                LayoutArg::Rotated => Layout::Rotated,
                LayoutArg::Split => Layout::Split,
                LayoutArg::Masked => Layout::Masked,
            },
            lod_mode: match a.lod_mode {
                LodModeArg::Bias => LodMode::Bias,
                LodModeArg::Gradients => LodMode::Gradients,
            },
        },
    };
    let settings = RenderSettings {
        width: scene.settings.width,
        height: scene.settings.height,
        technique,
        lod_bias: a.lod_bias,
        count_shaded: a.count_shaded,
        debug_lod: false,
        id_prepass: a.id_prepass,
    };
    let mut renderer =
        Renderer::new(&gpu, &shaders, &scene, settings.clone()).with_context(|| {
            format!(
                "setting up the {} technique on {}",
                settings.technique.name(),
                gpu.info().name
            )
        })?;

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
            ("cbr.technique".to_string(), settings.technique.name()),
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
                mask: out.mask.as_deref(),
                prepass: out
                    .prepass
                    .as_ref()
                    .map(|(d, i)| (d.as_slice(), i.as_slice())),
                metadata: meta,
            },
        )?;
        write_png_rgba8(&png, out.width, out.height, &display.to_rgba8(&out.color))?;
        for t in &out.timings {
            pass_times.entry(t.name.clone()).or_default().push(t.gpu_ms);
        }
        frame_records.push(json!({
            "index": f,
            "time": out.time,
            "exr": file_name(&exr),
            "png": file_name(&png),
            "passes": out.timings,
            "parity": out.parity,
            "shaded_fragments": out.shaded_fragments,
        }));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let messages = gpu.validation().messages();
    let passes: Vec<serde_json::Value> = pass_times
        .iter()
        .map(|(name, v)| json!({"name": name, "gpu_ms": summarize(v)}))
        .collect();
    let run = json!({
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
            "technique": settings.technique.name(),
            "target_bytes": renderer.target_bytes(),
            "layout_settings": settings.technique,
            "width": settings.width,
            "height": settings.height,
            "frames": frames,
            "fps": scene.settings.fps,
            "lod_bias": settings.effective_lod_bias(),
            "lod_mode": a.lod_mode_name(),
            "resolve": if matches!(a.technique, Technique::Checkerboard) { "none" } else { "-" },
            "count_shaded": settings.count_shaded,
            "id_prepass": settings.id_prepass,
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
    write_bytes(
        &a.out.join("run.json"),
        serde_json::to_string_pretty(&run)?.as_bytes(),
    )?;
    if !messages.is_empty() {
        eprintln!(
            "warning: {} validation message(s); see run.json",
            messages.len()
        );
    }
    println!(
        "{} frame(s) of {} written to {}",
        frames,
        scene.name,
        a.out.display()
    );
    Ok(())
}

impl RenderArgs {
    fn lod_mode_name(&self) -> &'static str {
        match self.lod_mode {
            LodModeArg::Bias => "bias",
            LodModeArg::Gradients => "gradients",
        }
    }
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
