//! `cbr bench`: arguments and the closing line; the work is in the cbr-bench crate.

use std::path::PathBuf;

use anyhow::Result;
use cbr_bench::BenchOptions;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene: a .toml description, an .obj file, or builtin:demo.
    scene: String,
    /// Configurations, comma-separated technique specs (`cbr info` lists the registered ones):
    /// native, ssaa:N, msaa:N[:sample][:hdr], upscale:bilinear|bicubic,
    /// checkerboard:LAYOUT[:MODE][:pixel|quad][:8|16][:fp16][:prepass][:locations] (MODE: ours,
    /// pq4k, intel, spatial, temporal; default ours, quad, 8), each with post passes (+sharpen).
    /// The reference and native are always run.
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
    /// Render and time cacheable techniques among the rows (ssaa:N) instead of reading their
    /// frames from the cache; the reference still comes from the cache.
    #[arg(long)]
    time_cached_rows: bool,
    /// k of the disocclusion FLIP: the error over pixels whose reference object ID differs from
    /// their ID in any of the k frames before [default: 4].
    #[arg(long, value_name = "K")]
    disocclusion_frames: Option<u32>,
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
impl BenchArgs {
    fn options(&self) -> BenchOptions {
        BenchOptions {
            scene: self.scene.clone(),
            techniques: self.techniques.clone(),
            width: self.width,
            height: self.height,
            warmup: self.warmup,
            frames: self.frames,
            resolutions: self.resolutions.clone(),
            mappings: self.mappings.clone(),
            groups: self.groups.clone(),
            lod_biases: self.lod_biases.clone(),
            sweep: self.sweep.clone(),
            crops: self.crops.clone(),
            reference: self.reference.clone(),
            no_cache: self.no_cache,
            time_cached_rows: self.time_cached_rows,
            disocclusion_frames: self.disocclusion_frames,
            device: self.device.clone(),
            validation: self.validation,
            out: self.out.clone(),
        }
    }
}

pub fn run(a: &BenchArgs) -> Result<()> {
    let r = cbr_bench::run(&a.options())?;
    println!(
        "{} configuration(s) x {} resolution(s) of {}: {}",
        r.configurations,
        r.resolutions,
        r.scene,
        r.bench_json.display()
    );
    Ok(())
}
