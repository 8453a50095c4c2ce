//! `cbr slurm SWEEP.toml --shards N -o DIR`: a sweep as a Slurm job array (one `cbr bench
//! --shard K/N` per task, into DIR/shard-K) and a merge-and-report job that waits for it
//! (`--dependency=afterok`); `--submit` hands both to `sbatch` (docs/cluster.md).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, anyhow, bail};

#[derive(clap::Args)]
pub struct SlurmArgs {
    /// The sweep file: `scenes = [...]` and any other sweep key (`cbr bench --sweep`).
    sweep: PathBuf,
    /// Tasks of the job array: the run split this many ways.
    #[arg(long)]
    shards: u32,
    /// The partition both jobs run in (sbatch --partition).
    #[arg(long)]
    partition: Option<String>,
    /// GPUs per task (sbatch --gpus-per-task; the cluster needs GPUs as a gres).
    #[arg(long, value_name = "G")]
    gpus_per_task: Option<u32>,
    /// CPUs per task (sbatch --cpus-per-task).
    #[arg(long, value_name = "C")]
    cpus_per_task: Option<u32>,
    /// Wall-time limit of each task (sbatch --time).
    #[arg(long, default_value = "04:00:00")]
    time: String,
    /// The frame cache all tasks share: a folder every node sees [default: DIR/cache].
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Submit the two jobs with sbatch (else write the scripts and print how to submit them).
    #[arg(long)]
    submit: bool,
    /// The run's folder (on a filesystem every node sees): DIR/shard-K/, DIR/logs/,
    /// DIR/slurm/, and after the merge DIR/bench.json, DIR/bench.csv, DIR/report.html.
    #[arg(short, long)]
    out: PathBuf,
}

/// A word for a POSIX shell, single-quoted.
fn quote(p: &Path) -> String {
    format!("'{}'", p.to_string_lossy().replace('\'', r"'\''"))
}

/// The task script: shard $SLURM_ARRAY_TASK_ID of N. A task whose shard folder already holds a
/// bench.json (a finished shard of an earlier submission) does nothing.
fn array_script(a: &SlurmArgs, exe: &Path, sweep: &Path, out: &Path, cache: &Path) -> String {
    let mut s = String::from("#!/bin/bash\n#SBATCH --job-name=cbr-bench\n");
    s += &format!("#SBATCH --array=0-{}\n", a.shards - 1);
    s += &format!("#SBATCH --output={}/logs/shard-%a.out\n", out.display());
    s += &format!("#SBATCH --time={}\n", a.time);
    // One task per array element (--gpus-per-task counts per task).
    s += "#SBATCH --ntasks=1\n";
    if let Some(p) = &a.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(g) = a.gpus_per_task {
        s += &format!("#SBATCH --gpus-per-task={g}\n");
    }
    if let Some(c) = a.cpus_per_task {
        s += &format!("#SBATCH --cpus-per-task={c}\n");
    }
    s += "set -euo pipefail\n";
    s += &format!("out={}/shard-\"$SLURM_ARRAY_TASK_ID\"\n", quote(out));
    s += "if [ -f \"$out/bench.json\" ]; then echo \"shard $SLURM_ARRAY_TASK_ID: finished before ($out/bench.json)\"; exit 0; fi\n";
    s += &format!("export CBR_CACHE_DIR={}\n", quote(cache));
    s += &format!(
        "exec {} bench --sweep {} --shard \"$SLURM_ARRAY_TASK_ID/{}\" --cache-dir {} -o \"$out\"\n",
        quote(exe),
        quote(sweep),
        a.shards,
        quote(cache)
    );
    s
}

/// The merge job: the shard folders into DIR's bench.json and bench.csv, then report.html.
fn merge_script(a: &SlurmArgs, exe: &Path, out: &Path) -> String {
    let mut s = String::from("#!/bin/bash\n#SBATCH --job-name=cbr-merge\n");
    s += &format!("#SBATCH --output={}/logs/merge.out\n", out.display());
    s += "#SBATCH --time=01:00:00\n";
    if let Some(p) = &a.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    s += "set -euo pipefail\n";
    let shards: Vec<String> = (0..a.shards)
        .map(|k| quote(&out.join(format!("shard-{k}"))))
        .collect();
    s += &format!(
        "{} bench --merge {} -o {}\n",
        quote(exe),
        shards.join(" "),
        quote(out)
    );
    s += &format!(
        "{} report {} -o {}\n",
        quote(exe),
        quote(out),
        quote(&out.join("report.html"))
    );
    s
}

/// `sbatch --parsable ARGS...`: the job id.
fn sbatch(args: &[&str]) -> Result<String> {
    let o = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .map_err(|e| anyhow!("cannot run sbatch (is Slurm installed and on PATH?): {e}"))?;
    if !o.status.success() {
        bail!(
            "sbatch {} failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        );
    }
    let text = String::from_utf8_lossy(&o.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        bail!("sbatch {}: no job id in `{}`", args.join(" "), text.trim());
    }
    Ok(id)
}

pub fn run(a: &SlurmArgs) -> Result<()> {
    if a.shards == 0 {
        bail!("--shards must be at least 1");
    }
    crate::bench::check_sweep(&a.sweep)?;
    let sweep = cbr_bench::read_sweep(&a.sweep)?;
    if sweep.scenes.as_ref().is_none_or(Vec::is_empty) {
        bail!(
            "{}: `scenes`: a sweep for Slurm names its scenes (scenes = [\"...\"])",
            a.sweep.display()
        );
    }
    let abs = |p: &Path| std::path::absolute(p).with_context(|| format!("{}", p.display()));
    let out = abs(&a.out)?;
    let sweep_path = abs(&a.sweep)?;
    let cache = abs(&a.cache_dir.clone().unwrap_or_else(|| out.join("cache")))?;
    let exe = std::env::current_exe().context("cannot find the cbr binary's path")?;
    let scripts = out.join("slurm");
    for d in [&scripts, &out.join("logs"), &cache] {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    let array = scripts.join("array.sbatch");
    let merge = scripts.join("merge.sbatch");
    let write = |p: &Path, text: String| cbr_metrics::io::write_bytes(p, text.as_bytes());
    write(&array, array_script(a, &exe, &sweep_path, &out, &cache))?;
    write(&merge, merge_script(a, &exe, &out))?;
    if !a.submit {
        println!("{}\n{}", array.display(), merge.display());
        println!(
            "submit: id=$(sbatch --parsable {}) && sbatch --dependency=afterok:$id {}",
            array.display(),
            merge.display()
        );
        return Ok(());
    }
    let id = sbatch(&[&array.to_string_lossy()])?;
    let after = format!("--dependency=afterok:{id}");
    let merge_id = sbatch(&[&after, &merge.to_string_lossy()])?;
    write(
        &scripts.join("jobs.txt"),
        format!("array {id}\nmerge {merge_id}\n"),
    )?;
    println!("array job {id} ({} tasks), merge job {merge_id}", a.shards);
    Ok(())
}
