//! `cbr`: render OBJ scenes with the registered techniques, compare, benchmark, report.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

mod bench;
mod compare;
mod gpu_stats;
mod info;
mod montage;
mod render;
mod report;
mod slurm;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// mimalloc keeps freed memory for reuse; with glibc's allocator the metrics' short-lived band
/// buffers cost ~30% of LDR-FLIP's time in page faults (docs/metrics.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(
    name = "cbr",
    version,
    about = "Headless checkerboard-rendering research renderer (Vulkan)"
)]
struct Cli {
    /// More log output (-v info, -vv debug).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (TOML, OBJ, or builtin:NAME, listed by `cbr info`) to EXR + PNG per frame and run.json.
    Render(render::RenderArgs),
    /// List Vulkan devices, the chosen one's limits, and which techniques and layouts it can run.
    Info(info::InfoArgs),
    /// Compare two images or two folders of frames: PSNR, SSIM, FLIP, HDR-FLIP, MSE, relMSE.
    /// Exit 0 when every --fail-above holds, 1 when one fails, 2 on errors.
    Compare(compare::CompareArgs),
    /// Benchmark configurations over the scene's camera path against a reference (`native`, or
    /// a supersampled `--reference`): GPU time per pass (median, p5, p95), pipeline statistics,
    /// copy-kernel floor, per-frame error; bench.json + bench.csv.
    Bench(bench::BenchArgs),
    /// One self-contained HTML report from `cbr bench` folders.
    Report(report::ReportArgs),
    /// A sweep as a Slurm job array of `cbr bench --shard K/N` tasks sharing one frame cache,
    /// and a job that merges them into one bench.json and report.html (docs/cluster.md).
    Slurm(slurm::SlurmArgs),
    /// Every pipeline of the specs compiled for AMD GPU families by their real compiler (RADV's
    /// null device, no GPU needed): ISA statistics per pass and a static cost model
    /// (gpu-stats.json, gpu-stats.csv, docs/gpu-isa.md).
    GpuStats(gpu_stats::GpuStatsArgs),
    /// Side-by-side strips of images (optionally one cropped window, enlarged) as one PNG.
    Montage(montage::MontageArgs),
}

pub use cbr_bench::render::finite_f32;

/// Exit status of a run stopped by Ctrl-C (SIGINT) or SIGTERM: 128 + SIGINT, as shells report.
const INTERRUPTED: i32 = 130;

/// Ctrl-C (and SIGTERM, SIGHUP): wait for the file being written to be complete and renamed into
/// place (or removed), write nothing more, say so, and exit. Every frame left behind is whole and
/// no temporary file remains.
fn exit_cleanly_on_interrupt() {
    let installed = ctrlc::set_handler(|| {
        cbr_metrics::io::stop_writes();
        eprintln!(
            "\nerror: interrupted; the files already written are complete, nothing else was written"
        );
        std::process::exit(INTERRUPTED);
    });
    if let Err(e) = installed {
        tracing::warn!("cannot install the Ctrl-C handler: {e}");
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help and --version print and succeed; a bad argument is an error like any other
        // (exit status 1; `compare` uses 2 for errors, 1 for a failed threshold).
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let _ = e.print();
            let compare = std::env::args()
                .skip(1)
                .find(|a| !a.starts_with('-'))
                .is_some_and(|a| a == "compare");
            return ExitCode::from(if compare { 2 } else { 1 });
        }
    };
    exit_cleanly_on_interrupt();
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("CBR_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
    let result = match cli.command {
        Command::Render(a) => render::run(&a),
        Command::Info(a) => info::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Report(a) => report::run(&a),
        Command::Montage(a) => montage::run(&a),
        Command::Slurm(a) => slurm::run(&a),
        Command::GpuStats(a) => gpu_stats::run(&a),
        Command::Compare(a) => {
            return match compare::run(&a) {
                Ok(true) => ExitCode::SUCCESS,
                Ok(false) => ExitCode::from(1),
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(2)
                }
            };
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
