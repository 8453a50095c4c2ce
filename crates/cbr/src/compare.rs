//! `cbr compare`: the image-diff harness (pbrt's `imgtool diff` contract): metrics, error maps,
//! thresholds; exit 0 when every threshold holds, 1 when one fails, 2 on errors.

mod print;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use cbr_metrics::io::write_png_rgba8;
use cbr_metrics::{
    CompareOptions, DisplayTransform, Metric, PairResult, compare_images, compare_sequences,
    heatmap,
};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Reference image (EXR, PNG, JPEG) or folder of frames.
    reference: PathBuf,
    /// Test image or folder of frames (matched to the reference's by file name).
    test: PathBuf,
    /// Metrics to compute: psnr, ssim, flip, hdrflip, mse, relmse.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "psnr,ssim,flip,hdrflip,mse,relmse"
    )]
    metrics: Vec<String>,
    /// EXR layer to read (default: color, else the first layer with R, G, B).
    #[arg(long)]
    layer: Option<String>,
    /// EXR channels to read: three (R,G,B) or one (shown as grey).
    #[arg(long, value_delimiter = ',')]
    channels: Option<Vec<String>>,
    /// Compare only this rectangle: x,y,w,h.
    #[arg(long, value_delimiter = ',', num_args = 1)]
    crop: Option<Vec<usize>>,
    /// Write the FLIP error map (magma, colour bar on the right) to this PNG.
    #[arg(long)]
    heatmap: Option<PathBuf>,
    /// Write the absolute-difference map (display values, x4) to this PNG.
    #[arg(long)]
    diff: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Fail (exit 1) when METRIC is worse than VALUE: above it for errors (flip, hdrflip, mse,
    /// relmse; FLIP = mean), below it for psnr and ssim. Repeatable.
    #[arg(long = "fail-above", value_name = "METRIC=VALUE")]
    fail_above: Vec<String>,
    /// Frames to skip at the start of sequences before averaging.
    #[arg(long, default_value_t = 0)]
    warmup: usize,
    /// Display exposure in stops for HDR inputs (PSNR, SSIM, LDR-FLIP and the maps).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::finite_f32)]
    exposure: f32,
    /// FLIP's pixels per degree (default 67.02: a 0.7 m wide 4K display at 0.7 m).
    #[arg(long)]
    ppd: Option<f32>,
}

fn thresholds(specs: &[String]) -> Result<Vec<(Metric, f64)>> {
    specs
        .iter()
        .map(|s| {
            let (m, v) = s
                .split_once('=')
                .ok_or_else(|| anyhow!("--fail-above `{s}`: expected METRIC=VALUE"))?;
            let metric = Metric::parse(m)
                .ok_or_else(|| anyhow!("--fail-above `{s}`: unknown metric `{m}`"))?;
            let value: f64 = v
                .trim()
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| anyhow!("--fail-above `{s}`: `{v}` is not a finite number"))?;
            Ok((metric, value))
        })
        .collect()
}

fn options(a: &CompareArgs) -> Result<CompareOptions> {
    let mut metrics = Vec::new();
    for m in &a.metrics {
        metrics.push(Metric::parse(m).ok_or_else(|| {
            anyhow!("unknown metric `{m}` (psnr, ssim, flip, hdrflip, mse, relmse)")
        })?);
    }
    let crop = match &a.crop {
        None => None,
        Some(v) if v.len() == 4 => Some([v[0], v[1], v[2], v[3]]),
        Some(v) => bail!("--crop takes x,y,w,h (4 numbers), got {}", v.len()),
    };
    let mut o = CompareOptions {
        metrics,
        crop,
        display: DisplayTransform {
            exposure_stops: a.exposure,
        },
        keep_maps: a.heatmap.is_some() || a.diff.is_some(),
        ..Default::default()
    };
    if let Some(p) = a.ppd {
        if !(p.is_finite() && p > 0.0) {
            bail!("--ppd must be positive");
        }
        o.ppd = p;
    }
    Ok(o)
}

/// Runs the comparison; `Ok(false)` when a threshold failed.
pub fn run(a: &CompareArgs) -> Result<bool> {
    let o = options(a)?;
    let limits = thresholds(&a.fail_above)?;
    let load = |p: &Path| cbr_metrics::input::load(p, a.layer.as_deref(), a.channels.as_deref());
    let (values, json) = if a.reference.is_dir() && a.test.is_dir() {
        if a.heatmap.is_some() || a.diff.is_some() {
            bail!("--heatmap and --diff apply to image pairs, not folders");
        }
        let seq = compare_sequences(&a.reference, &a.test, load, &o, a.warmup)?;
        if !a.json {
            print::sequence(&seq, &o);
        }
        let values: Vec<(Metric, f64)> = o
            .metrics
            .iter()
            .filter_map(|m| seq.mean.get(m.name()).map(|d| (*m, d.0)))
            .collect();
        (values, serde_json::to_value(&seq)?)
    } else if a.reference.is_dir() || a.test.is_dir() {
        bail!("compare two images or two folders of frames, not one of each");
    } else {
        let (r, t) = (load(&a.reference)?, load(&a.test)?);
        let res = compare_images(&r, &t, &o)?;
        write_maps(a, &res)?;
        if !a.json {
            print::pair(&res, &o);
        }
        let values: Vec<(Metric, f64)> = o
            .metrics
            .iter()
            .filter_map(|m| res.value(*m).map(|v| (*m, v)))
            .collect();
        (values, serde_json::to_value(&res)?)
    };
    let mut ok = true;
    let mut failures = Vec::new();
    for (m, limit) in &limits {
        let Some(&(_, v)) = values.iter().find(|(vm, _)| vm == m) else {
            bail!(
                "--fail-above {}: that metric was not computed (add it to --metrics)",
                m.name()
            );
        };
        let worse = if m.higher_is_better() {
            v < *limit
        } else {
            v > *limit
        };
        if worse {
            ok = false;
            failures.push(format!(
                "{} = {v} is {} the limit {limit}",
                m.name(),
                if m.higher_is_better() {
                    "below"
                } else {
                    "above"
                }
            ));
        }
    }
    if a.json {
        let mut j = json;
        j["display"] = serde_json::json!(o.display.describe());
        j["relmse_eps"] = serde_json::json!(o.relmse_eps);
        j["flip_ppd"] = serde_json::json!(o.ppd);
        j["thresholds_failed"] = serde_json::json!(failures);
        println!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        for f in &failures {
            println!("FAIL: {f}");
        }
    }
    Ok(ok)
}

fn write_maps(a: &CompareArgs, res: &PairResult) -> Result<()> {
    if let Some(path) = &a.heatmap {
        let map = res
            .flip_map
            .as_ref()
            .ok_or_else(|| anyhow!("--heatmap needs flip or hdrflip in --metrics"))?;
        let (w, h, px) = heatmap::flip_heatmap(map);
        write_png_rgba8(path, w as u32, h as u32, &px).with_context(|| "writing the heatmap")?;
    }
    if let (Some(path), Some(map)) = (&a.diff, &res.diff_map) {
        write_png_rgba8(
            path,
            map.width as u32,
            map.height as u32,
            &heatmap::difference_image(map),
        )?;
    }
    Ok(())
}
