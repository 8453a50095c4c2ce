//! The sortable summary table: times and error means per configuration, best values marked.

use std::fmt::Write as _;

use serde_json::Value;

use crate::bench::{BenchDir, Group};
use crate::util::{esc, fmt, num};

/// The main technique pass of a row: the resolve or the upscale.
fn recon_ms(r: &Value) -> Option<f64> {
    num(&r["passes"]["resolve"]["median"]).or_else(|| num(&r["passes"]["upscale"]["median"]))
}

fn raster_ms(r: &Value) -> Option<f64> {
    r["passes"].as_object().and_then(|p| {
        p.iter()
            .find(|(k, _)| k.ends_with(".raster") && !k.starts_with("id_prepass"))
            .and_then(|(_, v)| num(&v["median"]))
    })
}

struct Col {
    key: &'static str,
    title: &'static str,
    get: fn(&Value) -> Option<f64>,
    digits: usize,
    /// An error against the reference (the header names it).
    error: bool,
    /// Some(true): higher is better; Some(false): lower is better; None: not ranked.
    higher: Option<bool>,
}

const COLS: [Col; 9] = [
    Col {
        key: "frame_ms",
        title: "GPU ms (median)",
        get: |r| num(&r["frame_ms"]["median"]),
        digits: 3,
        error: false,
        higher: Some(false),
    },
    Col {
        key: "raster_ms",
        title: "raster ms",
        get: raster_ms,
        digits: 3,
        error: false,
        higher: None,
    },
    Col {
        key: "recon_ms",
        title: "resolve / upscale ms",
        get: recon_ms,
        digits: 3,
        error: false,
        higher: None,
    },
    Col {
        key: "psnr",
        title: "PSNR dB",
        get: |r| num(&r["error"]["psnr_mean"]),
        digits: 2,
        error: true,
        higher: Some(true),
    },
    Col {
        key: "ssim",
        title: "SSIM",
        get: |r| num(&r["error"]["ssim_mean"]),
        digits: 4,
        error: true,
        higher: Some(true),
    },
    Col {
        key: "flip_mean",
        title: "FLIP mean",
        get: |r| num(&r["error"]["flip_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
    },
    Col {
        key: "flip_median",
        title: "FLIP median",
        get: |r| num(&r["error"]["flip_median_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
    },
    Col {
        key: "flip_edge",
        title: "edge FLIP",
        get: |r| num(&r["error"]["flip_edge_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
    },
    Col {
        key: "relmse",
        title: "relMSE",
        get: |r| num(&r["error"]["relmse_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
    },
];

/// The summary: one sortable table, or one per reference when the bench folders were measured
/// against different references (their errors do not compare).
pub(crate) fn summary_table(html: &mut String, benches: &[BenchDir]) {
    let mut tables: Vec<(&str, Vec<Group>)> = Vec::new();
    for b in benches {
        for g in b.groups() {
            match tables.iter_mut().find(|t| t.0 == g.reference) {
                Some(t) => t.1.push(g),
                None => tables.push((g.reference, vec![g])),
            }
        }
    }
    html.push_str("<h2 id=\"summary\">Summary</h2>\n<p class=\"muted\">Click a column to sort. Best value per scene and resolution in bold green (time: lowest frame time; errors: against the reference named in the column header, which has no error itself). GPU ms = the technique's passes per frame, median [p5-p95] over the measured frames.");
    if tables.len() > 1 {
        html.push_str(" The bench folders were measured against different references, so there is one table per reference.");
    }
    html.push_str("</p>\n");
    for (i, (reference, groups)) in tables.iter().enumerate() {
        if tables.len() > 1 {
            let _ = writeln!(html, "<h3>Errors against {}</h3>", esc(reference));
        }
        table(html, reference, groups, i == 0);
    }
}

/// One sortable table of the groups measured against `reference`; the edge FLIP column only when
/// some row has it.
fn table(html: &mut String, reference: &str, groups: &[Group], first: bool) {
    let has_edge = groups
        .iter()
        .flat_map(|g| &g.rows)
        .any(|r| num(&r["error"]["flip_edge_mean"]).is_some());
    let cols: Vec<&Col> = COLS
        .iter()
        .filter(|c| has_edge || c.key != "flip_edge")
        .collect();
    let vs = format!("<br><span class=\"vs\">vs {}</span>", esc(reference));
    let _ = write!(
        html,
        "<table class=\"sortable\"{}><thead><tr><th class=\"t\" data-key=\"scene\">scene</th><th class=\"t\" data-key=\"res\">resolution</th><th class=\"t\" data-key=\"config\">configuration</th>",
        if first { " id=\"summary-table\"" } else { "" }
    );
    for c in &cols {
        let _ = write!(
            html,
            "<th data-key=\"{}\">{}{}</th>",
            c.key,
            c.title,
            if c.error { vs.as_str() } else { "" }
        );
    }
    let _ = writeln!(
        html,
        "<th data-key=\"pareto\">Pareto{vs}</th></tr></thead><tbody>"
    );
    for g in groups {
        let g = &g.rows;
        let best: Vec<Option<f64>> = cols
            .iter()
            .map(|c| {
                let vals = g.iter().filter_map(|r| (c.get)(r));
                match c.higher {
                    Some(true) => vals.max_by(f64::total_cmp),
                    Some(false) => vals.min_by(f64::total_cmp),
                    None => None,
                }
            })
            .collect();
        for r in g {
            let _ = write!(
                html,
                "<tr><td class=\"t\">{}</td><td class=\"t\" data-v=\"{}\">{}x{}</td><td class=\"t\">{}</td>",
                esc(r["scene"].as_str().unwrap_or("")),
                r["width"].as_u64().unwrap_or(0) * r["height"].as_u64().unwrap_or(0),
                r["width"],
                r["height"],
                esc(r["config"].as_str().unwrap_or("")),
            );
            for (c, b) in cols.iter().zip(&best) {
                let v = (c.get)(r);
                let class = if v.is_some() && v == *b {
                    " class=\"best\""
                } else {
                    ""
                };
                let text = if c.key == "frame_ms" {
                    format!(
                        "{} [{}-{}]",
                        fmt(v, c.digits),
                        fmt(num(&r["frame_ms"]["p5"]), c.digits),
                        fmt(num(&r["frame_ms"]["p95"]), c.digits)
                    )
                } else {
                    fmt(v, c.digits)
                };
                let _ = write!(
                    html,
                    "<td{class} data-v=\"{}\">{text}</td>",
                    v.map(|x| x.to_string()).unwrap_or_default()
                );
            }
            let p = r["pareto"].as_bool().unwrap_or(false);
            let _ = writeln!(
                html,
                "<td data-v=\"{}\">{}</td></tr>",
                u8::from(p),
                if p { "on front" } else { "" }
            );
        }
    }
    html.push_str("</tbody></table>\n");
}
