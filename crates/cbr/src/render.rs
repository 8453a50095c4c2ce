//! `cbr render`: a scene's frames to EXR (all layers) + PNG (display) and run.json.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::Layout;
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::{FrameLayers, write_bytes, write_frame_exr, write_png_rgba8};
use cbr_render::resolve::{Ablation, DEBUG_VIEWS};
use cbr_render::upscale::UpscaleFilter;
use cbr_render::{
    FrameOutput, LodMode, Mapping, RenderSettings, Renderer, ResolveMode, ResolveSettings,
};
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
    /// Render at W/sqrt(2) x H/sqrt(2) (the checkerboard's pixel count), then upscale
    /// (`--filter`): the baseline checkerboard must beat.
    Upscale,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum FilterArg {
    Bilinear,
    /// Catmull-Rom.
    Bicubic,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MappingArg {
    /// One output pixel per invocation.
    Pixel,
    /// One 2x2 quad (2 rendered + 2 missing pixels) per invocation.
    Quad,
}

#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum AblationArg {
    Velocity,
    Depth,
    Ids,
    Clamp,
    Prepass,
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
    /// History validated by object ID and depth at p - v, YCoCg clamp when moving; else an
    /// ID-aware differential blend of the neighbour pairs.
    Ours,
    /// The Stadia write-up: average of 4; history at p - v clamped and blended when moving.
    Pq4k,
    /// Camera-only reprojection from depth, depth occlusion test, Reinhard-weighted average of 4.
    Intel,
    /// No history: `ours`' spatial blend.
    Spatial,
    /// History at p - v without validation or clamp.
    Temporal,
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
    /// msaa2x: odd frames move the two samples with VK_EXT_sample_locations instead of shifting
    /// the viewport by half a pixel (needs the extension; `cbr info` says).
    #[arg(long)]
    msaa2x_sample_locations: bool,
    /// How checkerboard frames are reconstructed (docs/resolve.md).
    #[arg(long, value_enum, default_value = "ours")]
    resolve: ResolveArg,
    /// Resolve thread mapping.
    #[arg(long, value_enum, default_value = "quad")]
    resolve_mapping: MappingArg,
    /// Resolve workgroup side (8 or 16).
    #[arg(long, default_value_t = 8, value_parser = clap::builder::ValueParser::new(parse_group))]
    resolve_group: u32,
    /// Resolve colour arithmetic in float16.
    #[arg(long)]
    resolve_fp16: bool,
    /// Store the resolve's history colour as RGBA32F (default RGBA16F).
    #[arg(long)]
    resolve_f32_history: bool,
    /// Write the resolve's debug views: EXR layers resolve_* and PNGs debug/*.png.
    #[arg(long)]
    resolve_debug: bool,
    /// Switch inputs of `ours` off for ablation (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',')]
    resolve_without: Vec<AblationArg>,
    /// Relative linear-depth tolerance of the history validation.
    #[arg(long, default_value_t = 0.05)]
    depth_tolerance: f32,
    /// Also time a copy kernel moving the resolve's minimum bytes (its bandwidth floor).
    #[arg(long)]
    bandwidth_floor: bool,
    /// Upscale filter.
    #[arg(long, value_enum, default_value = "bilinear")]
    filter: FilterArg,
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

fn parse_group(s: &str) -> std::result::Result<u32, String> {
    match s {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("{s} (the resolve group is 8 or 16)")),
    }
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
        Technique::Upscale => cbr_render::Technique::Upscale {
            filter: match a.filter {
                FilterArg::Bilinear => UpscaleFilter::Bilinear,
                FilterArg::Bicubic => UpscaleFilter::Bicubic,
            },
        },
    };
    let resolve = match (a.technique, a.resolve_settings()) {
        (Technique::Checkerboard, r) => r,
        _ => None,
    };
    let settings = RenderSettings {
        width: scene.settings.width,
        height: scene.settings.height,
        technique,
        lod_bias: a.lod_bias,
        count_shaded: a.count_shaded,
        debug_lod: false,
        id_prepass: a.id_prepass,
        resolve,
        msaa2x_sample_locations: a.msaa2x_sample_locations,
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
                extra: debug_layers(&out),
                metadata: meta,
            },
        )?;
        write_png_rgba8(&png, out.width, out.height, &display.to_rgba8(&out.color))?;
        write_debug_pngs(&a.out, f, &out)?;
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
            "resolve_reset": out.resolve.as_ref().map(|r| r.reset),
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
            "resolve": settings.resolve,
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
    fn resolve_settings(&self) -> Option<ResolveSettings> {
        let mode = match self.resolve {
            ResolveArg::None => return None,
            ResolveArg::Ours => ResolveMode::Ours,
            ResolveArg::Pq4k => ResolveMode::Pq4k,
            ResolveArg::Intel => ResolveMode::Intel,
            ResolveArg::Spatial => ResolveMode::Spatial,
            ResolveArg::Temporal => ResolveMode::Temporal,
        };
        let off = |x| self.resolve_without.contains(&x);
        Some(ResolveSettings {
            mode,
            mapping: match self.resolve_mapping {
                MappingArg::Pixel => Mapping::Pixel,
                MappingArg::Quad => Mapping::Quad,
            },
            group: self.resolve_group,
            fp16: self.resolve_fp16,
            f32_history: self.resolve_f32_history,
            debug: self.resolve_debug,
            depth_tolerance: self.depth_tolerance,
            ablation: Ablation {
                velocity: !off(AblationArg::Velocity),
                depth: !off(AblationArg::Depth),
                ids: !off(AblationArg::Ids),
                clamp: !off(AblationArg::Clamp),
                prepass: !off(AblationArg::Prepass),
            },
            bandwidth_floor: self.bandwidth_floor,
            ..ResolveSettings::default()
        })
    }

    fn lod_mode_name(&self) -> &'static str {
        match self.lod_mode {
            LodModeArg::Bias => "bias",
            LodModeArg::Gradients => "gradients",
        }
    }
}

/// The resolve's debug views as EXR layers: one 0/1 layer per bit (`resolve_parity`,
/// `resolve_missing`, ...), `resolve_velocity` (X, Y) and `resolve_object_id` is the raw layer.
fn debug_layers(out: &FrameOutput) -> Vec<cbr_metrics::io::ExtraLayer> {
    let Some(r) = &out.resolve else {
        return Vec::new();
    };
    let mut layers = Vec::new();
    if let Some(bits) = &r.debug_bits {
        for (name, bit) in DEBUG_VIEWS {
            let v = bits
                .iter()
                .map(|b| f32::from(u8::from(b & bit != 0)))
                .collect();
            layers.push((format!("resolve_{name}"), vec![("Y".to_string(), v)]));
        }
    }
    if let Some(v) = &r.velocity {
        layers.push((
            "resolve_velocity".to_string(),
            vec![
                ("X".to_string(), v.iter().map(|v| v[0]).collect()),
                ("Y".to_string(), v.iter().map(|v| v[1]).collect()),
            ],
        ));
    }
    layers
}

/// PNGs of the debug views: debug/frame_NNNN_<view>.png (white where the bit is set), the
/// velocity (|v| on a log scale, 0..16 px) and the object IDs (hashed colours).
fn write_debug_pngs(dir: &Path, f: u32, out: &FrameOutput) -> Result<()> {
    let Some(r) = &out.resolve else {
        return Ok(());
    };
    let Some(bits) = &r.debug_bits else {
        return Ok(());
    };
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let (w, h) = (out.width, out.height);
    let png = |name: &str, rgba: Vec<u8>| {
        write_png_rgba8(&dbg.join(format!("frame_{f:04}_{name}.png")), w, h, &rgba)
    };
    for (name, bit) in DEBUG_VIEWS {
        let rgba = bits
            .iter()
            .flat_map(|b| {
                let v = if b & bit != 0 { 255 } else { 0 };
                [v, v, v, 255]
            })
            .collect();
        png(name, rgba)?;
    }
    if let Some(v) = &r.velocity {
        let rgba = v
            .iter()
            .flat_map(|v| {
                let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
                let t = ((1.0 + len).log2() / 17f32.log2()).clamp(0.0, 1.0);
                let g = (t * 255.0).round() as u8;
                [g, g, g, 255]
            })
            .collect();
        png("velocity", rgba)?;
    }
    let rgba = out
        .ids
        .iter()
        .flat_map(|id| {
            let hsh = id[0].wrapping_mul(2654435761);
            [(hsh >> 24) as u8, (hsh >> 16) as u8, (hsh >> 8) as u8, 255]
        })
        .collect();
    png("ids", rgba)?;
    Ok(())
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
