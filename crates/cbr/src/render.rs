//! `cbr render`: a scene's frames to EXR (all layers) + PNG (display) and run.json.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cbr_gpu::Layout;
use cbr_gpu::{Gpu, GpuOptions};
use cbr_metrics::DisplayTransform;
use cbr_metrics::io::{FrameLayers, write_bytes, write_frame_exr, write_png_rgba8};
use cbr_render::cache::default_dir as default_cache_dir;
use cbr_render::resolve::DEBUG_VIEWS;
use cbr_render::{
    CheckerboardConfig, FrameOutput, LodMode, Mapping, RenderSettings, Renderer, ResolveMode,
    ResolveSettings, Spec,
};
use cbr_scene::{LoadOptions, MissingTextures, check_resolution};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use cbr_bench::stats::summarize;

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

/// Parts of `+taa` that `--taa-without` switches off.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum TaaAblationArg {
    /// Velocity of the nearest 3x3 neighbour: the pixel's own instead.
    Dilation,
    /// YCoCg variance clipping of the history.
    Clip,
    /// Rejection of history showing an object none of the 3x3 shows.
    Ids,
    /// Rejection of history outside the 3x3's depth span.
    Depth,
    /// Catmull-Rom history fetch: bilinear instead.
    Catmull,
    /// The current-frame weight rising with speed: alpha everywhere.
    Speed,
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
    /// The default on masked, split and msaa2x.
    Bias,
    /// Derivatives scaled to full-resolution pixels (textureGrad), times 2^--lod-bias (default
    /// 0). The default on rotated.
    Gradients,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MissingTexturesArg {
    Error,
    Fallback,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene: a .toml description, an .obj file (framed automatically), or builtin:NAME (`cbr info` lists them).
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
    /// Technique spec: native, ssaa:N, msaa:N, checkerboard[:LAYOUT[:MODE...]],
    /// upscale[:FILTER], interlaced[:OPTION...], then post passes (+sharpen); `cbr info` lists
    /// them all. The flags below are shorthand that edits the spec; run.json records the result.
    #[arg(long, default_value = "native")]
    technique: String,
    /// Device index or name substring (see `cbr info`).
    #[arg(long)]
    device: Option<String>,
    /// Enable the validation layer and synchronization validation; messages are counted in run.json.
    #[arg(long)]
    validation: bool,
    /// Checkerboard layout (default rotated).
    #[arg(long, value_enum)]
    layout: Option<LayoutArg>,
    /// msaa2x: odd frames move the two samples with VK_EXT_sample_locations instead of shifting
    /// the viewport by half a pixel (needs the extension; `cbr info` says).
    #[arg(long)]
    msaa2x_sample_locations: bool,
    /// How checkerboard frames are reconstructed (docs/resolve.md; default ours).
    #[arg(long, value_enum)]
    resolve: Option<ResolveArg>,
    /// Resolve thread mapping (default quad).
    #[arg(long, value_enum)]
    resolve_mapping: Option<MappingArg>,
    /// Resolve workgroup side, 8 (default) or 16.
    #[arg(long, value_parser = clap::builder::ValueParser::new(parse_group))]
    resolve_group: Option<u32>,
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
    /// Relative linear-depth tolerance of the history validation (default 0.05).
    #[arg(long, value_parser = crate::finite_f32)]
    depth_tolerance: Option<f32>,
    /// Switch parts of the spec's `+taa` off for ablation (comma-separated): adds
    /// `without-X` parameters to it.
    #[arg(long, value_enum, value_delimiter = ',')]
    taa_without: Vec<TaaAblationArg>,
    /// Also time a copy kernel moving the resolve's minimum bytes (its bandwidth floor).
    #[arg(long)]
    bandwidth_floor: bool,
    /// Upscale filter (default bilinear).
    #[arg(long, value_enum)]
    filter: Option<FilterArg>,
    /// Texture LOD bias added to every lookup (default: the technique's matching bias).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::finite_f32)]
    lod_bias: Option<f32>,
    /// How texture LOD follows the checkerboard layout's sample spacing (default: gradients on
    /// rotated, bias on the others).
    #[arg(long, value_enum)]
    lod_mode: Option<LodModeArg>,
    /// Count shaded fragments exactly (atomic counter; reported per frame in run.json).
    #[arg(long)]
    count_shaded: bool,
    /// Checkerboard: a native-resolution depth + ID pass first, no shading (EXR layers
    /// prepass_depth, prepass_object_id, prepass_primitive_id).
    #[arg(long)]
    id_prepass: bool,
    /// Display exposure in stops (PNG only; EXR stays linear). Default: the scene's.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::finite_f32)]
    exposure: Option<f32>,
    /// msaa: shade every sample (sampleRateShading, minSampleShading = 1, sample-interpolated
    /// inputs); shorthand for `msaa:N:sample`.
    #[arg(long)]
    sample_shading: bool,
    /// Render cacheable techniques (ssaa) afresh instead of reading the frame cache.
    #[arg(long)]
    no_cache: bool,
    /// The frame cache folder (default $CBR_CACHE_DIR, else $XDG_CACHE_HOME/cbr, else
    /// ~/.cache/cbr).
    #[arg(long)]
    cache_dir: Option<PathBuf>,
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
    let spec = a.spec()?;
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
    renderer.set_progress(cbr_bench::sample_progress(format!(
        "{} samples",
        settings.spec
    )));
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
        if let Some(n) = out.nonfinite_fragments.filter(|&n| n > 0) {
            bar.suspend(|| {
                eprintln!(
                    "warning: frame {f}: {n} fragment(s) shaded to NaN or infinity, written black \
                     (run.json: nonfinite_fragments)"
                )
            });
        }
        write_debug_pngs(&a.out, f, &out)?;
        write_seed_figure(&a.out, f, &out, &display.to_rgba8(&out.color))?;
        write_interleaved_pngs(&a.out, f, &out)?;
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
            "cached": out.cached,
            "shaded_fragments": out.shaded_fragments,
            "nonfinite_fragments": out.nonfinite_fragments,
            "analytic": analytic_summary(&out),
            "interleaved": interleaved_summary(&out),
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
            "technique": settings.spec,
            "target_bytes": renderer.target_bytes(),
            "width": settings.width,
            "height": settings.height,
            "frames": frames,
            "fps": scene.settings.fps,
            "lod_bias": renderer.lod_bias(),
            "checkerboard": checkerboard_json(&settings.spec),
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

/// The checkerboard configuration of a spec, for run.json (layout, LOD mode, resolve settings).
fn checkerboard_json(spec: &Spec) -> serde_json::Value {
    if spec.technique.name != "checkerboard" {
        return json!(null);
    }
    match CheckerboardConfig::parse(&spec.technique.params()) {
        Ok(c) => json!({
            "layout": c.layout.name(),
            "lod_mode": c.lod_mode,
            "resolve": c.resolve,
            "id_prepass": c.prepass,
            "sample_locations": c.locations,
        }),
        Err(_) => json!(null),
    }
}

impl RenderArgs {
    /// The spec `--technique` names, edited by the shorthand flags (`--layout`, `--resolve`,
    /// `--filter`, ...). A flag that contradicts a parameter the spec names, or that does not
    /// apply to the technique, is an error.
    pub fn spec(&self) -> Result<Spec> {
        let mut spec = Spec::parse(&self.technique).map_err(anyhow::Error::msg)?;
        let name = spec.technique.name.clone();
        let given = |flag: &str, set: bool| -> Result<()> {
            if set && name != "checkerboard" {
                bail!("{flag} applies to the checkerboard technique, not `{name}`");
            }
            Ok(())
        };
        given("--layout", self.layout.is_some())?;
        given("--resolve", self.resolve.is_some())?;
        given("--resolve-mapping", self.resolve_mapping.is_some())?;
        given("--resolve-group", self.resolve_group.is_some())?;
        given("--resolve-fp16", self.resolve_fp16)?;
        given("--resolve-f32-history", self.resolve_f32_history)?;
        given("--resolve-debug", self.resolve_debug)?;
        given("--resolve-without", !self.resolve_without.is_empty())?;
        given("--depth-tolerance", self.depth_tolerance.is_some())?;
        given("--id-prepass", self.id_prepass)?;
        given("--msaa2x-sample-locations", self.msaa2x_sample_locations)?;
        given("--lod-mode", self.lod_mode.is_some())?;
        if self.sample_shading {
            if name != "msaa" {
                bail!("--sample-shading applies to the msaa technique, not `{name}`");
            }
            if !spec.has("sample") {
                spec = spec.with("sample");
            }
        }
        if self.filter.is_some() && name != "upscale" {
            bail!("--filter applies to the upscale technique, not `{name}`");
        }
        if !self.taa_without.is_empty() {
            let text = spec.to_string();
            let taa = spec
                .post
                .iter_mut()
                .find(|p| p.name == "taa")
                .ok_or_else(|| {
                    anyhow::anyhow!("--taa-without needs `+taa` in the spec `{text}`")
                })?;
            for a in &self.taa_without {
                let p = format!("without-{}", format!("{a:?}").to_lowercase());
                if !taa.params.contains(&p) {
                    taa.params.push(p);
                }
            }
            let params = taa.params();
            cbr_render::post::taa::TaaConfig::parse(&params)
                .map_err(|e| anyhow::anyhow!("--taa-without: {e}"))?;
        }
        match name.as_str() {
            "checkerboard" => spec.technique.params = self.edit_checkerboard(&spec)?.params(),
            "upscale" => {
                if let Some(f) = self.filter {
                    let f = match f {
                        FilterArg::Bilinear => "bilinear",
                        FilterArg::Bicubic => "bicubic",
                    };
                    match spec.technique.params.first() {
                        Some(p) if p != f => bail!("--filter {f} contradicts `{spec}`"),
                        _ => spec.technique.params = vec![f.to_string()],
                    }
                }
                if spec.technique.params.is_empty() {
                    spec.technique.params = vec!["bilinear".into()];
                }
            }
            _ => {}
        }
        Ok(spec)
    }

    fn edit_checkerboard(&self, spec: &Spec) -> Result<CheckerboardConfig> {
        let params = spec.technique.params();
        let mut c = CheckerboardConfig::parse(&params).map_err(anyhow::Error::msg)?;
        if let Some(l) = self.layout {
            let layout = match l {
                LayoutArg::Msaa2x => Layout::Msaa2x,
                LayoutArg::Rotated => Layout::Rotated,
                LayoutArg::Split => Layout::Split,
                LayoutArg::Masked => Layout::Masked,
            };
            if !params.is_empty() && c.layout != layout {
                bail!("--layout {} contradicts `{spec}`", layout.name());
            }
            if c.layout != layout {
                c.lod_mode = LodMode::default_for(layout);
            }
            c.layout = layout;
        }
        if let Some(r) = self.resolve {
            let mode = match r {
                ResolveArg::None => None,
                ResolveArg::Ours => Some(ResolveMode::Ours),
                ResolveArg::Pq4k => Some(ResolveMode::Pq4k),
                ResolveArg::Intel => Some(ResolveMode::Intel),
                ResolveArg::Spatial => Some(ResolveMode::Spatial),
                ResolveArg::Temporal => Some(ResolveMode::Temporal),
            };
            if params.len() > 1 && c.resolve.map(|r| r.mode) != mode {
                bail!("--resolve contradicts `{spec}`");
            }
            c.resolve = mode.map(|mode| ResolveSettings {
                mode,
                ..c.resolve.unwrap_or_default()
            });
        }
        if let Some(r) = c.resolve.as_mut() {
            if let Some(m) = self.resolve_mapping {
                r.mapping = match m {
                    MappingArg::Pixel => Mapping::Pixel,
                    MappingArg::Quad => Mapping::Quad,
                };
            }
            r.group = self.resolve_group.unwrap_or(r.group);
            r.fp16 |= self.resolve_fp16;
            r.f32_history |= self.resolve_f32_history;
            r.debug |= self.resolve_debug;
            r.depth_tolerance = self.depth_tolerance.unwrap_or(r.depth_tolerance);
            let off = |x| self.resolve_without.contains(&x);
            let ab = &mut r.ablation;
            ab.velocity &= !off(AblationArg::Velocity);
            ab.depth &= !off(AblationArg::Depth);
            ab.ids &= !off(AblationArg::Ids);
            ab.clamp &= !off(AblationArg::Clamp);
            ab.prepass &= !off(AblationArg::Prepass);
            r.validate().map_err(anyhow::Error::msg)?;
        }
        c.prepass |= self.id_prepass;
        c.locations |= self.msaa2x_sample_locations;
        match self.lod_mode {
            Some(LodModeArg::Gradients) => c.lod_mode = LodMode::Gradients,
            Some(LodModeArg::Bias) => c.lod_mode = LodMode::Bias,
            None => {}
        }
        // The edited configuration must still read back (e.g. locations on msaa2x only).
        CheckerboardConfig::parse(&c.params().iter().map(String::as_str).collect::<Vec<_>>())
            .map_err(anyhow::Error::msg)?;
        Ok(c)
    }
}

/// The resolve's debug views as EXR layers: one 0/1 layer per bit (`resolve_parity`,
/// `resolve_missing`, ...), `resolve_velocity` (X, Y) and `resolve_object_id` is the raw layer.
fn debug_layers(out: &FrameOutput) -> Vec<cbr_metrics::io::ExtraLayer> {
    let mut layers = Vec::new();
    if let Some(c) = &out.coverage {
        // `coverage`: edge (1 where the pixel's samples saw several object IDs) and fraction (of
        // the samples on geometry).
        layers.push((
            "coverage".to_string(),
            vec![
                (
                    "edge".to_string(),
                    c.edge.iter().map(|&e| f32::from(e)).collect(),
                ),
                ("fraction".to_string(), c.fraction.clone()),
            ],
        ));
    }
    if let Some(a) = &out.analytic {
        // `analytic`: per pixel the fragments that touched it, those beyond the K kept
        // (overflow), those that contributed, (analytic:seed) where the shortcut is off by more
        // than 1e-3, and where a kept fragment's shading was not finite.
        let f = |v: &[u32]| v.iter().map(|&x| x as f32).collect();
        layers.push((
            "analytic".to_string(),
            vec![
                ("fragments".to_string(), f(&a.fragments)),
                ("overflow".to_string(), f(&a.overflow)),
                ("visible".to_string(), f(&a.visible)),
                (
                    "seed_differs".to_string(),
                    a.seed_differs.iter().map(|&x| f32::from(x)).collect(),
                ),
                (
                    "nonfinite".to_string(),
                    a.nonfinite.iter().map(|&x| f32::from(x)).collect(),
                ),
            ],
        ));
    }
    if let Some(i) = &out.interleaved {
        // `interleaved:...:debug`: per pixel its VPL subset, the edge mask (the filter's window
        // holds another surface; `seed`: the seed's edge test) and the subsets it shaded itself.
        let f = |v: &[u8]| v.iter().map(|&x| f32::from(x)).collect();
        layers.push((
            "interleaved".to_string(),
            vec![
                ("subset".to_string(), f(&i.subset)),
                ("edge".to_string(), f(&i.edge)),
                ("fallback".to_string(), f(&i.fallback)),
            ],
        ));
    }
    let Some(r) = &out.resolve else {
        return layers;
    };
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

/// `analytic` frames in run.json: fragments kept per pixel (K), fragments that touched pixels,
/// and pixel counts: edge pixels (a visible fragment covers part of the pixel or the background
/// shows), overflow (more fragments than K), non-finite shading, and with `analytic:seed` where
/// the shortcut's area is off by more than 1e-3 and that count's share of the edge pixels.
fn analytic_summary(out: &FrameOutput) -> serde_json::Value {
    let (Some(a), Some(c)) = (&out.analytic, &out.coverage) else {
        return json!(null);
    };
    let count = |v: &[u8]| v.iter().filter(|&&x| x != 0).count();
    let edge = count(&c.edge);
    let seed = a
        .seed_differs
        .iter()
        .zip(&c.edge)
        .filter(|&(&s, &e)| s != 0 && e != 0)
        .count();
    json!({
        "kept_per_pixel": a.kept_per_pixel,
        "tail_fragments": a.tail_fragments,
        "albedo_jobs": a.albedo_jobs,
        "fragments": a.fragments.iter().map(|&f| u64::from(f)).sum::<u64>(),
        "edge_pixels": edge,
        "overflow_pixels": a.overflow.iter().filter(|&&o| o > 0).count(),
        "nonfinite_pixels": count(&a.nonfinite),
        "seed_differs_pixels": count(&a.seed_differs),
        "seed_differs_edge_fraction": if edge > 0 { seed as f64 / edge as f64 } else { 0.0 },
    })
}

/// `interleaved:...:debug` frames in run.json: M x N, pixels on a surface, edge pixels, pixels
/// that shaded a subset themselves and the mean number of subsets they shaded, and the pixels where
/// the split G-buffer gathered back differs from the G-buffer (0 unless the passes are broken).
fn interleaved_summary(out: &FrameOutput) -> serde_json::Value {
    let Some(i) = &out.interleaved else {
        return json!(null);
    };
    let drawn: Vec<bool> = out.ids.iter().map(|id| id[0] != 0).collect();
    let count = |v: &[u8]| v.iter().zip(&drawn).filter(|&(&x, &d)| x != 0 && d).count();
    let visible = drawn.iter().filter(|&&d| d).count();
    let shaded: u64 = i.fallback.iter().map(|&x| u64::from(x)).sum();
    json!({
        "tile": [i.tile.0, i.tile.1],
        "visible_pixels": visible,
        "edge_pixels": count(&i.edge),
        "fallback_pixels": count(&i.fallback),
        "fallback_subsets_per_visible_pixel":
            if visible > 0 { shaded as f64 / visible as f64 } else { 0.0 },
        "roundtrip_mismatches": i.roundtrip_mismatches,
    })
}

/// `interleaved:...:debug`: debug/frame_NNNN_interleaved_{mosaic,subset,edges,fallback}.png: the
/// split mosaic of the subset estimates (x / (1 + x), sRGB-like 1/2.2; not with `implicit`), the
/// subset index (grey k / (M N - 1)), the edge mask (white) and the fallback (black none, then
/// dark red to yellow as the subsets shaded at the pixel go from 1 to M N).
fn write_interleaved_pngs(dir: &Path, f: u32, out: &FrameOutput) -> Result<()> {
    let Some(i) = &out.interleaved else {
        return Ok(());
    };
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let png = |name: &str, w: u32, h: u32, rgba: Vec<u8>| {
        write_png_rgba8(
            &dbg.join(format!("frame_{f:04}_interleaved_{name}.png")),
            w,
            h,
            &rgba,
        )
    };
    if let Some((w, h, texels)) = &i.mosaic {
        // Its own curve, not the frame's display transform: the mosaic holds irradiance without
        // albedo, dim at the frame's exposure (lit sub-images then read as black).
        let tone = |x: f32| {
            let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
            ((x / (1.0 + x)).powf(1.0 / 2.2) * 255.0).round() as u8
        };
        let rgba = texels
            .iter()
            .flat_map(|t| [tone(t[0]), tone(t[1]), tone(t[2]), 255])
            .collect();
        png("mosaic", *w, *h, rgba)?;
    }
    let (w, h) = (out.width, out.height);
    let subsets = (i.tile.0 * i.tile.1).max(2) - 1;
    let grey = |v: u8| [v, v, v, 255];
    png(
        "subset",
        w,
        h,
        i.subset
            .iter()
            .flat_map(|&k| grey((u32::from(k) * 255 / subsets) as u8))
            .collect(),
    )?;
    png(
        "edges",
        w,
        h,
        i.edge.iter().flat_map(|&e| grey(e * 255)).collect(),
    )?;
    let all = (i.tile.0 * i.tile.1) as f32;
    let heat = |n: u8| {
        if n == 0 {
            return [0, 0, 0, 255];
        }
        let t = f32::from(n) / all;
        [
            (128.0 + 127.0 * t.min(0.5) * 2.0) as u8,
            (255.0 * ((t - 0.5).max(0.0) * 2.0)) as u8,
            0,
            255,
        ]
    };
    png(
        "fallback",
        w,
        h,
        i.fallback.iter().flat_map(|&n| heat(n)).collect(),
    )?;
    Ok(())
}

/// `analytic:seed`: debug/frame_NNNN_seed_differs.png, the frame with the pixels where the seed's
/// shortcut is off the exact area by more than 1e-3 in red (docs/analytic.md's figure).
fn write_seed_figure(dir: &Path, f: u32, out: &FrameOutput, rgba: &[u8]) -> Result<()> {
    let Some(a) = &out.analytic else {
        return Ok(());
    };
    if !a.seed_differs.iter().any(|&s| s != 0) {
        return Ok(());
    }
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let marked: Vec<u8> = rgba
        .chunks_exact(4)
        .zip(&a.seed_differs)
        .flat_map(|(p, &s)| {
            if s != 0 {
                [255, 0, 0, 255]
            } else {
                // The rest dimmed, so the marks stand out.
                [p[0] / 3, p[1] / 3, p[2] / 3, 255]
            }
        })
        .collect();
    write_png_rgba8(
        &dbg.join(format!("frame_{f:04}_seed_differs.png")),
        out.width,
        out.height,
        &marked,
    )?;
    Ok(())
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
