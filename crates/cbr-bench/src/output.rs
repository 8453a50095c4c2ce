//! What a bench run writes: the last frame of each configuration for the report, worst-FLIP
//! crop windows, the Pareto front, bench.csv, provenance helpers.

use anyhow::Result;
use cbr_metrics::DisplayTransform;
use serde_json::json;

use crate::measure::Snapshot;
use crate::stats::Summary;

pub fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes the last measured frame of a configuration for the report: the display PNG, the FLIP
/// map as a magma PNG (same size; the report draws the colour bar) and the EXR with all layers.
/// `sub`: the folder below images/ and frames/ (crate::assemble::sub_folder). Returns the paths
/// relative to the bench folder.
pub fn save_snapshot(
    dir: &std::path::Path,
    sub: &str,
    name: &str,
    snap: &Snapshot,
    display: &DisplayTransform,
) -> Result<serde_json::Value> {
    let base = slug(name);
    let img = format!("images/{sub}/{base}.png");
    let exr = format!("frames/{sub}/{base}.exr");
    std::fs::create_dir_all(dir.join("images").join(sub))?;
    std::fs::create_dir_all(dir.join("frames").join(sub))?;
    let o = &snap.out;
    cbr_metrics::io::write_png_rgba8(
        &dir.join(&img),
        o.width,
        o.height,
        &display.to_rgba8(&o.color),
    )?;
    cbr_metrics::io::write_frame_exr(
        &dir.join(&exr),
        &cbr_metrics::io::FrameLayers {
            width: o.width,
            height: o.height,
            color: &o.color,
            depth: &o.depth,
            velocity: &o.velocity,
            ids: &o.ids,
            // Of the technique's layers, the snapshot keeps the shaded-pixel mask only.
            extra: match o.layer("mask") {
                Some(l) => crate::render::layers::exr_layer(l)?.into_iter().collect(),
                None => Vec::new(),
            },
            metadata: vec![
                ("cbr.config".to_string(), name.to_string()),
                ("cbr.frame".to_string(), o.index.to_string()),
            ],
        },
    )?;
    let flip = match &snap.flip_map {
        Some(map) => {
            let path = format!("images/{sub}/{base}.flip.png");
            let rgba: Vec<u8> = map
                .data
                .iter()
                .flat_map(|&v| {
                    let c = cbr_metrics::heatmap::magma(v);
                    [c[0], c[1], c[2], 255]
                })
                .collect();
            cbr_metrics::io::write_png_rgba8(&dir.join(&path), o.width, o.height, &rgba)?;
            json!(path)
        }
        None => json!(null),
    };
    Ok(json!({"frame": o.index, "image": img, "flip": flip, "exr": exr}))
}

/// The candidate windows of a `w`x`h` frame, in scan order: (x, y, side).
fn windows(w: usize, h: usize) -> Vec<(usize, usize, usize)> {
    let side = (w.min(h) / 6).max(8).min(w).min(h);
    let stride = (side / 2).max(1);
    let mut out = Vec::new();
    let mut y = 0;
    while y + side <= h {
        let mut x = 0;
        while x + side <= w {
            out.push((x, y, side));
            x += stride;
        }
        y += stride;
    }
    out
}

/// One FLIP map's sum over each candidate window (in [`windows`] order): what [`pick_windows`]
/// adds up over a group's maps. A shard keeps these per row, so that merged shards choose the
/// unsharded run's windows.
pub fn window_scores(m: &cbr_metrics::planes::Plane) -> Vec<f64> {
    let w = m.width;
    windows(m.width, m.height)
        .into_iter()
        .map(|(x, y, side)| {
            let mut sum = 0.0f64;
            for yy in y..y + side {
                sum += m.data[yy * w + x..yy * w + x + side]
                    .iter()
                    .map(|&v| f64::from(v))
                    .sum::<f64>();
            }
            sum
        })
        .collect()
}

/// Up to `count` non-overlapping windows of a `w`x`h` frame with the highest summed scores
/// (`scores`: one [`window_scores`] per map, added in order). [x, y, w, h] each.
pub fn pick_windows(w: usize, h: usize, scores: &[Vec<f64>], count: usize) -> Vec<[usize; 4]> {
    let Some(first) = scores.first() else {
        return Vec::new();
    };
    let mut total = first.clone();
    for s in &scores[1..] {
        for (t, v) in total.iter_mut().zip(s) {
            *t += v;
        }
    }
    let mut scored: Vec<(f64, usize, usize, usize)> = windows(w, h)
        .into_iter()
        .zip(total)
        .map(|((x, y, side), s)| (s, x, y, side))
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut picked: Vec<[usize; 4]> = Vec::new();
    for (_, x, y, side) in scored {
        let overlaps = picked
            .iter()
            .any(|p| x < p[0] + p[2] && p[0] < x + side && y < p[1] + p[3] && p[1] < y + side);
        if !overlaps {
            picked.push([x, y, side, side]);
            if picked.len() == count {
                break;
            }
        }
    }
    picked
}

/// Up to `count` non-overlapping square windows (side ~ 1/6 of the short side) with the highest
/// mean of the given FLIP maps: where the techniques err most. [x, y, w, h] each.
pub fn worst_windows(maps: &[&cbr_metrics::planes::Plane], count: usize) -> Vec<[usize; 4]> {
    let Some(first) = maps.first() else {
        return Vec::new();
    };
    let scores: Vec<Vec<f64>> = maps.iter().map(|m| window_scores(m)).collect();
    pick_windows(first.width, first.height, &scores, count)
}

pub fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() { json!(x) } else { json!(null) }
}

pub fn summary_json(s: Option<Summary>) -> serde_json::Value {
    s.map(|s| json!(s)).unwrap_or(json!(null))
}

pub fn git_commit() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

/// Indices of the rows on the speed-vs-error Pareto front (lower time and lower error are
/// better): no other row is at least as good in both and better in one.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| {
            let (ti, ei) = points[i];
            ti.is_finite()
                && ei.is_finite()
                && !points
                    .iter()
                    .enumerate()
                    .any(|(j, &(tj, ej))| j != i && tj <= ti && ej <= ei && (tj < ti || ej < ei))
        })
        .collect()
}

/// Columns of bench.csv: every row carries device, driver, resolution and settings. Columns added
/// later go at the end, so older columns keep their positions.
pub const CSV_COLUMNS: [&str; 33] = [
    "scene",
    "config",
    "technique",
    "resolve",
    "mapping",
    "group",
    "fp16",
    "id_prepass",
    "lod_bias",
    "width",
    "height",
    "device",
    "driver",
    "warmup",
    "frames",
    "frame_ms_median",
    "frame_ms_p5",
    "frame_ms_p95",
    "copy_floor_ms_median",
    "psnr_mean",
    "ssim_mean",
    "flip_mean",
    "flip_edge_mean",
    "flip_interior_mean",
    "relmse_mean",
    "reference",
    "pareto",
    "disocclusion_frames",
    "flip_disocc_mean",
    "disocc_fraction_mean",
    "flicker_mean",
    "change_mean",
    "ref_change_mean",
];

pub fn csv(bench: &serde_json::Value) -> String {
    let mut out = CSV_COLUMNS.join(",") + "\n";
    let empty = vec![];
    for r in bench["rows"].as_array().unwrap_or(&empty) {
        let cell = |v: &serde_json::Value| match v {
            serde_json::Value::Null => String::new(),
            serde_json::Value::String(s) => {
                if s.contains([',', '"']) {
                    format!("\"{}\"", s.replace('"', "\"\""))
                } else {
                    s.clone()
                }
            }
            other => other.to_string(),
        };
        let vals = [
            &r["scene"],
            &r["config"],
            &r["technique"],
            &r["resolve"],
            &r["mapping"],
            &r["group"],
            &r["fp16"],
            &r["id_prepass"],
            &r["lod_bias"],
            &r["width"],
            &r["height"],
            &r["device"],
            &r["driver"],
            &r["warmup"],
            &r["frames"],
            &r["frame_ms"]["median"],
            &r["frame_ms"]["p5"],
            &r["frame_ms"]["p95"],
            &r["copy_floor_ms"]["median"],
            &r["error"]["psnr_mean"],
            &r["error"]["ssim_mean"],
            &r["error"]["flip_mean"],
            &r["error"]["flip_edge_mean"],
            &r["error"]["flip_interior_mean"],
            &r["error"]["relmse_mean"],
            &r["reference"],
            &r["pareto"],
            &r["disocclusion_frames"],
            &r["error"]["flip_disocc_mean"],
            &r["error"]["disocc_fraction_mean"],
            &r["error"]["flicker_mean"],
            &r["error"]["change_mean"],
            &r["error"]["ref_change_mean"],
        ];
        out += &vals.map(cell).join(",");
        out.push('\n');
    }
    out
}
