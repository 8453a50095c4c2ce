//! `cbr report DIR... -o report.html`: one self-contained HTML file from `cbr bench` folders
//! (crates/cbr-report).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};

#[derive(clap::Args)]
pub struct ReportArgs {
    /// `cbr bench` output folders (each with bench.json); the shard folders of one run
    /// (`--shard K/N`, all N of them) are merged first.
    dirs: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(short, long, default_value = "out/report.html")]
    out: PathBuf,
    /// Copy the images into this folder (linked relatively) instead of embedding them.
    #[arg(long)]
    assets_dir: Option<PathBuf>,
}

/// UTC date and time of a Unix time (civil-from-days, Howard Hinnant's algorithm).
pub fn utc(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

pub fn run(a: &ReportArgs) -> Result<()> {
    if a.dirs.is_empty() {
        bail!("name at least one `cbr bench` output folder");
    }
    let mut benches = a
        .dirs
        .iter()
        .map(|d| cbr_report::BenchDir::load(d))
        .collect::<Result<Vec<_>, _>>()?;
    // Shard folders of one run (`cbr bench --shard K/N`) are merged into one, in the place of
    // the first; each row's images stay in its shard's folder.
    let shards: Vec<PathBuf> = benches
        .iter()
        .filter(|b| cbr_bench::merge::is_shard(&b.json))
        .map(|b| std::path::absolute(&b.dir).unwrap_or_else(|_| b.dir.clone()))
        .collect();
    if !shards.is_empty() {
        let merged = cbr_bench::merge::merge(&shards)?;
        let first = benches
            .iter()
            .position(|b| cbr_bench::merge::is_shard(&b.json))
            .unwrap_or(0);
        benches.retain(|b| !cbr_bench::merge::is_shard(&b.json));
        let json = cbr_bench::merge::with_shard_paths(&merged);
        let dir = shards[0].clone();
        benches.insert(first.min(benches.len()), cbr_report::BenchDir { dir, json });
    }
    if let Some(parent) = a.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create the folder of {}", a.out.display()))?;
    }
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let opts = cbr_report::Options {
        out: a.out.clone(),
        assets_dir: a.assets_dir.clone(),
        colormap: (0..=10)
            .map(|i| cbr_metrics::heatmap::magma(i as f32 / 10.0))
            .collect(),
        created: utc(now),
    };
    // cbr's atomic write: a Ctrl-C lets it finish, a failure leaves no partial file.
    let html = cbr_report::render(&benches, &opts)?;
    cbr_metrics::io::write_bytes(&a.out, html.as_bytes())?;
    println!("{}", a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn utc_dates() {
        assert_eq!(super::utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(super::utc(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(super::utc(1_795_300_000), "2026-11-21 22:26:40 UTC");
    }
}
