//! `cbr gpu-stats`: every pipeline of the specs compiled by AMD's compiler (ACO) on RADV's null
//! device per GPU family, its statistics and a static cost model ([`cbr_bench::gpu_stats`];
//! docs/gpu-isa.md).

use std::path::PathBuf;

use anyhow::{Context, Result};
use cbr_bench::gpu_stats::{self, DEFAULT_FAMILIES, GpuStatsOptions};

#[derive(clap::Args)]
pub struct GpuStatsArgs {
    /// Scene: a .toml description, an .obj file, or builtin:NAME.
    #[arg(default_value = "builtin:demo")]
    scene: String,
    /// Technique specs, comma-separated (default: every registered technique by its bare name).
    #[arg(long, value_delimiter = ',')]
    techniques: Vec<String>,
    /// Mesa's GPU family names (RADV_FORCE_FAMILY), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_FAMILIES.iter().map(|s| s.to_string()))]
    families: Vec<String>,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Also write each pass's GCN/RDNA disassembly under DIR/disassembly/FAMILY/SPEC/.
    #[arg(long)]
    disassembly: bool,
    /// Trace the frame without the scene's objects (no raster): compute passes get their model,
    /// raster passes say they need the scene.
    #[arg(long)]
    model_only: bool,
    /// The device the frame is traced on (index or name substring; see `cbr info`).
    #[arg(long)]
    device: Option<String>,
    /// Output folder (or, for --child, the answer file).
    #[arg(short, long, default_value = "out/gpu-stats")]
    out: PathBuf,
    /// Internal: compile for this family in this process (its null device) and answer in --out.
    #[arg(long, hide = true)]
    child: Option<String>,
    /// Internal (--child): the scene's material feature combinations.
    #[arg(long, hide = true, value_delimiter = ',')]
    materials: Vec<u32>,
    /// Internal (--child): do not also compile compute as wave32.
    #[arg(long, hide = true)]
    no_wave32: bool,
    /// Internal (--child): pipelines not to compile, as SPEC|PASS (the driver crashed on them).
    #[arg(long, hide = true, value_delimiter = ',')]
    skip: Vec<String>,
}

pub fn run(a: &GpuStatsArgs) -> Result<()> {
    if let Some(family) = &a.child {
        return gpu_stats::child(&gpu_stats::ChildArgs {
            family: family.clone(),
            specs: a.techniques.clone(),
            size: (a.width.unwrap_or(64), a.height.unwrap_or(36)),
            materials: a.materials.clone(),
            disassembly: a.disassembly,
            wave32: !a.no_wave32,
            skip: a.skip.clone(),
            file: a.out.clone(),
        });
    }
    let exe = std::env::current_exe().context("cannot find the cbr executable")?;
    let table = gpu_stats::run(&GpuStatsOptions {
        scene: a.scene.clone(),
        specs: a.techniques.clone(),
        families: a.families.clone(),
        width: a.width,
        height: a.height,
        disassembly: a.disassembly,
        model_only: a.model_only,
        out: a.out.clone(),
        device: a.device.clone(),
        exe,
    })?;
    print!("{table}");
    println!("written to {}", a.out.display());
    Ok(())
}
