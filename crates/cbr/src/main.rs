//! `cbr`: render OBJ scenes with checkerboard techniques, compare, benchmark, report.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

mod bench;
mod compare;
mod info;
mod render;
mod report;

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
    /// Render a scene (TOML, OBJ, or builtin:demo) to EXR + PNG per frame and run.json.
    Render(render::RenderArgs),
    /// List Vulkan devices, the chosen one's limits, and which checkerboard layouts it can run.
    Info(info::InfoArgs),
    /// Compare two images or two folders of frames: PSNR, SSIM, FLIP, HDR-FLIP, MSE, relMSE.
    /// Exit 0 when every --fail-above holds, 1 when one fails, 2 on errors.
    Compare(compare::CompareArgs),
    /// Benchmark configurations over the scene's camera path against native: GPU time per pass
    /// (median, p5, p95), pipeline statistics, copy-kernel floor, per-frame error; bench.json +
    /// bench.csv.
    Bench(bench::BenchArgs),
    /// One self-contained HTML report from `cbr bench` folders.
    Report(report::ReportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
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
