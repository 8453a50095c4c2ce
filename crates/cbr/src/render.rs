//! `cbr render`: its arguments, [`cbr_bench::render::run`] (the render loop and run.json), and
//! what it says when done. Technique-specific flags: [`cbr_bench::render::Shorthand`].

use std::path::PathBuf;

use anyhow::Result;
use cbr_bench::render::{RenderOptions, Shorthand, technique_help};
use cbr_scene::MissingTextures;

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
    #[arg(long, default_value = "native", help = technique_help())]
    technique: String,
    /// Device index or name substring (see `cbr info`).
    #[arg(long)]
    device: Option<String>,
    /// Enable the validation layer and synchronization validation; messages are counted in run.json.
    #[arg(long)]
    validation: bool,
    #[command(flatten)]
    shorthand: Shorthand,
    /// Also time a copy kernel moving the resolve's minimum bytes (its bandwidth floor).
    #[arg(long)]
    bandwidth_floor: bool,
    /// Texture LOD bias added to every lookup (default: the technique's matching bias).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::finite_f32)]
    lod_bias: Option<f32>,
    /// Count shaded fragments exactly (atomic counter; reported per frame in run.json).
    #[arg(long)]
    count_shaded: bool,
    /// Display exposure in stops (PNG only; EXR stays linear). Default: the scene's.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::finite_f32)]
    exposure: Option<f32>,
    /// Render cacheable (supersampled) techniques afresh instead of reading the frame cache.
    #[arg(long)]
    no_cache: bool,
    /// The frame cache folder (default $CBR_CACHE_DIR, else $XDG_CACHE_HOME/cbr, else
    /// ~/.cache/cbr).
    #[arg(long)]
    cache_dir: Option<PathBuf>,
    /// What to do when a texture named by an MTL cannot be read.
    #[arg(long, value_enum)]
    missing_textures: Option<MissingTexturesArg>,
    /// Anisotropic texture filtering: at most N trilinear lookups along a texture footprint's
    /// longer side, on every technique and the reference (1 = isotropic; default: the scene's
    /// `anisotropy`, else 1).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(cbr_scene::MAX_ANISOTROPY)))]
    anisotropy: Option<u32>,
}

pub fn run(a: &RenderArgs) -> Result<()> {
    let done = cbr_bench::render::run(&RenderOptions {
        scene: a.scene.clone(),
        out: a.out.clone(),
        width: a.width,
        height: a.height,
        frames: a.frames,
        technique: a.technique.clone(),
        shorthand: a.shorthand.clone(),
        device: a.device.clone(),
        validation: a.validation,
        lod_bias: a.lod_bias,
        count_shaded: a.count_shaded,
        bandwidth_floor: a.bandwidth_floor,
        exposure: a.exposure,
        no_cache: a.no_cache,
        cache_dir: a.cache_dir.clone(),
        missing_textures: a.missing_textures.map(|m| match m {
            MissingTexturesArg::Error => MissingTextures::Error,
            MissingTexturesArg::Fallback => MissingTextures::Fallback,
        }),
        anisotropy: a.anisotropy,
    })?;
    if done.validation_messages > 0 {
        eprintln!(
            "warning: {} validation message(s); see run.json",
            done.validation_messages
        );
    }
    println!(
        "{} frame(s) of {} written to {}",
        done.frames,
        done.scene,
        a.out.display()
    );
    Ok(())
}
