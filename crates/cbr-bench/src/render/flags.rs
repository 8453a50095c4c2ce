//! `cbr render`'s shorthand flags of particular techniques (`--layout`, `--resolve`, `--filter`,
//! `--sample-shading`, `--taa-without`, ...): their clap definitions, flattened into the
//! binary's arguments. What each flag does to the spec is the technique's own:
//! `CheckerboardShorthand::apply`, `upscale::apply_shorthand`, `msaa::apply_shorthand`,
//! `taa::apply_shorthand` in cbr-render.

use cbr_gpu::Layout;
use cbr_render::post::taa;
use cbr_render::techniques::checkerboard::config::CheckerboardShorthand;
use cbr_render::techniques::{msaa, upscale};
use cbr_render::{LodMode, Mapping, ResolveMode, Spec};

/// A command-line number that must be finite (`nan` and `inf` parse as f32).
pub fn finite_f32(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err("not a finite number".into()),
        Err(e) => Err(e.to_string()),
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum FilterArg {
    Bilinear,
    /// Catmull-Rom.
    Bicubic,
    /// AMD FSR 1: EASU then RCAS.
    Fsr1,
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
    /// A surface's own velocity (the 3x3 one plane): the nearest neighbour's, as at silhouettes.
    SurfaceVelocity,
    /// A turning object's current frame rising to weight 1 (and a history showing one), its
    /// LOD bias withdrawn and its raster unjittered by its turn (the reactive rule): blended,
    /// biased and jittered as everything else.
    Reactive,
    /// YCoCg variance clipping of the history.
    Clip,
    /// Rejection of history showing an object none of the 3x3 shows.
    Ids,
    /// Rejection of history outside the 3x3's depth span.
    Depth,
    /// Lanczos-3 in the history's kernel: Karis' 5-tap Catmull-Rom alone.
    Lanczos,
    /// Catmull-Rom history fetch: bilinear instead.
    Catmull,
    /// The current-frame weight rising with speed: alpha everywhere.
    Speed,
    /// The per-pixel frame count (the weight at least 1 / (m + 1)).
    Count,
    /// Karis' luminance weights in the blend: a linear blend.
    Luma,
    /// Still pixels held at the mean of their last jitter cycle.
    Cycle,
    /// A frame without history rendered centred: jittered like every other.
    CentredReset,
    /// A moving interior's current frame rising to weight 1 (`motionlod`, `interior`): to
    /// `amax`, as at edges.
    Interior,
    /// Thin features' locks: a sub-pixel feature's history clipped like any other.
    Locks,
    /// Moving fragments shaded at the pixel centre: the jittered path (also drops `motionlod`).
    Unjitter,
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

/// The shorthand flags; each edits the spec `--technique` names (run.json records the result).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct Shorthand {
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
    #[arg(long, value_parser = finite_f32)]
    depth_tolerance: Option<f32>,
    /// Switch parts of the spec's `+taa` off for ablation (comma-separated): adds
    /// `without-X` parameters to it.
    #[arg(long, value_enum, value_delimiter = ',')]
    taa_without: Vec<TaaAblationArg>,
    /// Upscale filter (default bilinear).
    #[arg(long, value_enum)]
    filter: Option<FilterArg>,
    /// How texture LOD follows the checkerboard layout's sample spacing (default: gradients on
    /// rotated, bias on the others).
    #[arg(long, value_enum)]
    lod_mode: Option<LodModeArg>,
    /// Checkerboard: a native-resolution depth + ID pass first, no shading (EXR layers
    /// prepass_depth, prepass_object_id, prepass_primitive_id).
    #[arg(long)]
    id_prepass: bool,
    /// msaa: shade every sample (sampleRateShading, minSampleShading = 1, sample-interpolated
    /// inputs); shorthand for `msaa:N:sample`.
    #[arg(long)]
    sample_shading: bool,
}

fn parse_group(s: &str) -> std::result::Result<u32, String> {
    match s {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("{s} (the resolve group is 8 or 16)")),
    }
}

/// A flag value's name as clap spells it (`CentredReset` -> `centred-reset`), the name of the
/// spec parameter it stands for.
fn lower(v: &impl clap::ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

impl Shorthand {
    /// The spec `text` names, edited by the flags. A flag that contradicts a parameter the spec
    /// names, or that does not apply to the technique, is a `GpuError::Config` naming the spec.
    pub fn apply(&self, text: &str) -> anyhow::Result<Spec> {
        let mut spec = Spec::parse(text).map_err(anyhow::Error::msg)?;
        self.checkerboard().apply(&mut spec)?;
        msaa::apply_shorthand(&mut spec, self.sample_shading)?;
        upscale::apply_shorthand(
            &mut spec,
            self.filter.map(|f| match f {
                FilterArg::Bilinear => upscale::UpscaleFilter::Bilinear,
                FilterArg::Bicubic => upscale::UpscaleFilter::Bicubic,
                FilterArg::Fsr1 => upscale::UpscaleFilter::Fsr1,
            }),
        )?;
        let without: Vec<String> = self.taa_without.iter().map(lower).collect();
        let without: Vec<&str> = without.iter().map(String::as_str).collect();
        taa::apply_shorthand(&mut spec, &without)?;
        Ok(spec)
    }

    fn checkerboard(&self) -> CheckerboardShorthand {
        CheckerboardShorthand {
            layout: self.layout.map(|l| match l {
                LayoutArg::Msaa2x => Layout::Msaa2x,
                LayoutArg::Rotated => Layout::Rotated,
                LayoutArg::Split => Layout::Split,
                LayoutArg::Masked => Layout::Masked,
            }),
            resolve: self.resolve.map(|r| match r {
                ResolveArg::None => None,
                ResolveArg::Ours => Some(ResolveMode::Ours),
                ResolveArg::Pq4k => Some(ResolveMode::Pq4k),
                ResolveArg::Intel => Some(ResolveMode::Intel),
                ResolveArg::Spatial => Some(ResolveMode::Spatial),
                ResolveArg::Temporal => Some(ResolveMode::Temporal),
            }),
            mapping: self.resolve_mapping.map(|m| match m {
                MappingArg::Pixel => Mapping::Pixel,
                MappingArg::Quad => Mapping::Quad,
            }),
            group: self.resolve_group,
            fp16: self.resolve_fp16,
            f32_history: self.resolve_f32_history,
            debug: self.resolve_debug,
            without: self.resolve_without.iter().map(lower).collect(),
            depth_tolerance: self.depth_tolerance,
            prepass: self.id_prepass,
            locations: self.msaa2x_sample_locations,
            lod_mode: self.lod_mode.map(|m| match m {
                LodModeArg::Bias => LodMode::Bias,
                LodModeArg::Gradients => LodMode::Gradients,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Args {
        #[command(flatten)]
        s: Shorthand,
    }

    fn spec(text: &str, flags: &[&str]) -> Result<String, cbr_gpu::GpuError> {
        let args = Args::try_parse_from(std::iter::once("t").chain(flags.iter().copied()))
            .expect("flags parse");
        match args.s.apply(text) {
            Ok(s) => Ok(s.to_string()),
            Err(e) => Err(e.downcast::<cbr_gpu::GpuError>().expect("a GpuError")),
        }
    }

    #[test]
    fn flags_edit_the_spec_of_their_technique() {
        for (text, flags, want) in [
            ("checkerboard", &[][..], "checkerboard:rotated:ours"),
            (
                "checkerboard",
                &[
                    "--layout",
                    "split",
                    "--id-prepass",
                    "--resolve-without",
                    "ids",
                ],
                "checkerboard:split:ours:prepass:without-ids",
            ),
            ("upscale", &[], "upscale:bilinear"),
            ("upscale", &["--filter", "bicubic"], "upscale:bicubic"),
            ("upscale:0.5", &["--filter", "fsr1"], "upscale:fsr1:0.5"),
            ("msaa:4", &["--sample-shading"], "msaa:4:sample"),
            (
                "native+taa",
                &["--taa-without", "clip,speed"],
                "native+taa:without-clip:without-speed",
            ),
            (
                "native+taa",
                &["--taa-without", "count,luma,cycle,centred-reset"],
                "native+taa:without-count:without-luma:without-cycle:without-centred-reset",
            ),
        ] {
            match spec(text, flags) {
                Ok(s) => assert_eq!(s, want, "{text} {flags:?}"),
                Err(e) => panic!("{text} {flags:?}: {e}"),
            }
        }
    }

    /// `--taa-without` offers exactly `+taa`'s ablations, and each one parses.
    #[test]
    fn taa_without_offers_every_ablation() {
        use clap::ValueEnum;
        let offered: Vec<String> = TaaAblationArg::value_variants().iter().map(lower).collect();
        let mut want: Vec<String> = taa::ABLATIONS.iter().map(|a| a.to_string()).collect();
        let mut got = offered.clone();
        want.sort();
        got.sort();
        assert_eq!(got, want);
        for a in &offered {
            let s = spec("native+taa", &["--taa-without", a]).expect(a);
            assert_eq!(s, format!("native+taa:without-{a}"));
        }
    }

    #[test]
    fn refusals_are_config_errors_naming_the_spec_and_the_flag() {
        for (text, flags, says) in [
            (
                "checkerboard:split",
                &["--layout", "rotated"][..],
                "--layout rotated contradicts",
            ),
            (
                "checkerboard:split:ours",
                &["--resolve", "intel"],
                "--resolve contradicts",
            ),
            ("native", &["--layout", "split"], "--layout applies to"),
            (
                "native",
                &["--resolve-group", "16"],
                "--resolve-group applies to",
            ),
            ("ssaa:4", &["--filter", "bicubic"], "--filter applies to"),
            (
                "upscale:bilinear",
                &["--filter", "bicubic"],
                "--filter bicubic contradicts",
            ),
            (
                "native",
                &["--sample-shading"],
                "--sample-shading applies to",
            ),
            ("native", &["--taa-without", "ids"], "needs `+taa`"),
            (
                "checkerboard:split",
                &["--msaa2x-sample-locations"],
                "msaa2x",
            ),
        ] {
            match spec(text, flags) {
                Err(cbr_gpu::GpuError::Config { spec, message }) => {
                    assert_eq!(spec, text, "{flags:?}");
                    assert!(message.contains(says), "{text} {flags:?}: {message}");
                }
                other => panic!("{text} {flags:?}: {other:?}"),
            }
        }
    }
}
