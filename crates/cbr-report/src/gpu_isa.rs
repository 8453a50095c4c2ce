//! The static cost model of `cbr gpu-stats` beside the measured lavapipe times: where a bench
//! folder also holds a gpu-stats.json (`cbr gpu-stats ... -o DIR`, docs/gpu-isa.md), per
//! configuration and pass the lavapipe median and the model's prediction on each GPU, labelled
//! as static estimates.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::Value;

use crate::util::{esc, fmt, num};
use crate::{ReportError, Result};

/// The model's frames (wave64) of `config`, one per family, in the file's family order.
fn frames<'a>(study: &'a Value, config: &str) -> Vec<&'a Value> {
    study["frames"]
        .as_array()
        .map(|f| {
            f.iter()
                .filter(|x| x["spec"] == config && x["wave"] == 64)
                .collect()
        })
        .unwrap_or_default()
}

pub(crate) fn gpu_isa(
    html: &mut String,
    dir: &Path,
    rows: &[&Value],
    size: (u64, u64),
) -> Result<()> {
    let path = dir.join("gpu-stats.json");
    if !path.is_file() {
        return Ok(());
    }
    let err = |msg: String| ReportError::Input {
        path: path.clone(),
        msg,
    };
    let text = std::fs::read_to_string(&path).map_err(|e| err(e.to_string()))?;
    let study: Value = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
    html.push_str("<h3>Static GPU cost model (cbr gpu-stats) beside lavapipe</h3>\n");
    let modelled = (study["width"].as_u64(), study["height"].as_u64());
    if modelled != (Some(size.0), Some(size.1)) {
        let _ = writeln!(
            html,
            "<p class=\"muted\">gpu-stats.json models {}x{}, not this group's {}x{}: run <code>cbr gpu-stats --width {} --height {} -o {}</code>.</p>",
            modelled.0.unwrap_or(0),
            modelled.1.unwrap_or(0),
            size.0,
            size.1,
            size.0,
            size.1,
            esc(&dir.display().to_string())
        );
        return Ok(());
    }
    let families: Vec<(String, String)> = study["families"]
        .as_array()
        .map(|f| {
            f.iter()
                .filter_map(|x| {
                    Some((
                        x["family"].as_str()?.to_string(),
                        x["gpu"].as_str()?.to_string(),
                    ))
                })
                .collect()
        })
        .unwrap_or_default();
    let _ = writeln!(
        html,
        "<p class=\"muted\">Predicted microseconds per pass: max(ALU from ACO's inverse throughput, declared bytes / DRAM bandwidth) on each GPU's published figures (a = ALU-bound, m = memory-bound). Static estimates from AMD's compiler on RADV's null device, not timings; lavapipe medians are this bench's, on this machine's CPU.</p>"
    );
    html.push_str("<table class=\"gpu-isa\"><thead><tr><th>configuration</th><th>pass</th><th>lavapipe ms</th>");
    for (family, gpu) in &families {
        let _ = write!(html, "<th>{} ({}) us</th>", esc(gpu), esc(family));
    }
    html.push_str("</tr></thead><tbody>\n");
    let mut any = false;
    for r in rows {
        let config = r["config"].as_str().unwrap_or("");
        let fr = frames(&study, config);
        if fr.is_empty() {
            continue;
        }
        any = true;
        let mut passes: Vec<String> = Vec::new();
        for f in &fr {
            for p in f["passes"].as_array().into_iter().flatten() {
                if let Some(n) = p["pass"].as_str()
                    && !passes.iter().any(|x| x == n)
                {
                    passes.push(n.to_string());
                }
            }
        }
        let cell = |f: &Value, pass: &str| {
            f["passes"]
                .as_array()
                .and_then(|ps| ps.iter().find(|p| p["pass"] == pass))
                .map(|p| {
                    format!(
                        "{} {}",
                        fmt(num(&p["predicted_us"]), 1),
                        &p["bound"].as_str().unwrap_or("?")[..1]
                    )
                })
                .unwrap_or_else(|| "-".into())
        };
        for pass in &passes {
            let _ = write!(
                html,
                "<tr><td>{}</td><td>{}</td><td>{}</td>",
                esc(config),
                esc(pass),
                fmt(num(&r["passes"][pass.as_str()]["median"]), 3)
            );
            for (family, _) in &families {
                let f = fr.iter().find(|f| f["family"] == family.as_str());
                let _ = write!(html, "<td>{}</td>", f.map_or("-".into(), |f| cell(f, pass)));
            }
            html.push_str("</tr>\n");
        }
        let total: f64 = passes
            .iter()
            .filter_map(|p| num(&r["passes"][p.as_str()]["median"]))
            .sum();
        let _ = write!(
            html,
            "<tr class=\"total\"><td>{}</td><td>frame (these passes)</td><td>{total:.3}</td>",
            esc(config)
        );
        for (family, _) in &families {
            let f = fr.iter().find(|f| f["family"] == family.as_str());
            let _ = write!(
                html,
                "<td>{}</td>",
                f.map_or("-".into(), |f| fmt(num(&f["predicted_us"]), 1))
            );
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</tbody></table>\n");
    if !any {
        html.push_str(
            "<p class=\"muted\">gpu-stats.json models none of this group's configurations.</p>\n",
        );
    }
    Ok(())
}
