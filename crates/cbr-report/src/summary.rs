//! The sortable summary table: times and error means per configuration, best values marked.

use std::fmt::Write as _;

use serde_json::Value;

use crate::bench::{BenchDir, Group};
use crate::util::{esc, fmt, num};

/// The main technique pass of a row: the resolve or the upscale (`upscale:fsr1`: EASU + RCAS,
/// the sum of their medians).
fn recon_ms(r: &Value) -> Option<f64> {
    let p = &r["passes"];
    let median = |name: &str| num(&p[name]["median"]);
    median("resolve")
        .or_else(|| median("upscale"))
        .or_else(|| Some(median("upscale.easu")? + median("upscale.rcas")?))
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
    /// Shown only when some row of the table has a value (bench.json from before the column
    /// lacks it).
    optional: bool,
    /// The header's tooltip.
    tip: &'static str,
}

const COLS: [Col; 16] = [
    Col {
        key: "frame_ms",
        title: "GPU ms (median)",
        get: |r| num(&r["frame_ms"]["median"]),
        digits: 3,
        error: false,
        higher: Some(false),
        optional: false,
        tip: "",
    },
    Col {
        key: "raster_ms",
        title: "raster ms",
        get: raster_ms,
        digits: 3,
        error: false,
        higher: None,
        optional: false,
        tip: "",
    },
    Col {
        key: "recon_ms",
        title: "resolve / upscale ms",
        get: recon_ms,
        digits: 3,
        error: false,
        higher: None,
        optional: false,
        tip: "",
    },
    Col {
        key: "psnr",
        title: "PSNR dB",
        get: |r| num(&r["error"]["psnr_mean"]),
        digits: 2,
        error: true,
        higher: Some(true),
        optional: false,
        tip: "",
    },
    Col {
        key: "ssim",
        title: "SSIM",
        get: |r| num(&r["error"]["ssim_mean"]),
        digits: 4,
        error: true,
        higher: Some(true),
        optional: false,
        tip: "",
    },
    Col {
        key: "flip_mean",
        title: "FLIP mean",
        get: |r| num(&r["error"]["flip_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: false,
        tip: "",
    },
    Col {
        key: "flip_median",
        title: "FLIP median",
        get: |r| num(&r["error"]["flip_median_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: false,
        tip: "",
    },
    Col {
        key: "flip_edge",
        title: "edge FLIP",
        get: |r| num(&r["error"]["flip_edge_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: true,
        tip: "FLIP mean over the reference's edge pixels: more than one object ID among its samples",
    },
    Col {
        key: "equal_ssaa",
        title: "ssaa N of equal edge FLIP",
        get: |r| num(&r["equal_error_ssaa"]["flip_edge"]["n"]),
        digits: 1,
        error: true,
        higher: Some(true),
        optional: true,
        tip: "the supersampling (N x N samples a pixel) whose edge FLIP equals this row's, interpolated on the run's own ssaa:N rows (bench.json equal_error_ssaa); blank where the row is better than the finest rung or worse than the coarsest",
    },
    Col {
        key: "equal_ssaa_speedup",
        title: "x faster than that ssaa",
        get: |r| num(&r["equal_error_ssaa"]["flip_edge"]["speedup"]),
        digits: 1,
        error: false,
        higher: Some(true),
        optional: true,
        tip: "the frame time of the supersampling of equal edge FLIP (interpolated between the rungs, same run) over this row's",
    },
    Col {
        key: "flip_interior",
        title: "interior FLIP",
        get: |r| num(&r["error"]["flip_interior_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: true,
        tip: "FLIP mean over the pixels that are not edge pixels",
    },
    Col {
        key: "flip_disocc",
        title: "disocclusion FLIP",
        get: |r| num(&r["error"]["flip_disocc_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: true,
        tip: "FLIP mean over the pixels whose reference object ID changed within the last k frames (ghosting and disocclusion error); frames with no such pixel are left out",
    },
    Col {
        key: "flicker",
        title: "flicker",
        get: |r| num(&r["error"]["flicker_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: true,
        tip: "mean |e_t - e_(t-1)| over consecutive measured frames, e = test - reference in display values: the part of the frame-to-frame change that the reference does not have",
    },
    Col {
        key: "change",
        title: "change",
        get: |r| num(&r["error"]["change_mean"]),
        digits: 4,
        error: false,
        higher: None,
        optional: true,
        tip: "the technique's own frame-to-frame change, mean |x_t - x_(t-1)| in display values; a stable technique's tracks the reference's",
    },
    Col {
        key: "ref_change",
        title: "reference change",
        get: |r| num(&r["error"]["ref_change_mean"]),
        digits: 4,
        error: false,
        higher: None,
        optional: true,
        tip: "the reference's own frame-to-frame change, mean |r_t - r_(t-1)| in display values, over the same frames",
    },
    Col {
        key: "relmse",
        title: "relMSE",
        get: |r| num(&r["error"]["relmse_mean"]),
        digits: 4,
        error: true,
        higher: Some(false),
        optional: false,
        tip: "",
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

/// One sortable table of the groups measured against `reference`; the optional columns (edge
/// and disocclusion FLIP, the temporal ones) only when some row has them.
fn table(html: &mut String, reference: &str, groups: &[Group], first: bool) {
    let rows = || groups.iter().flat_map(|g| &g.rows);
    let cols: Vec<&Col> = COLS
        .iter()
        .filter(|c| !c.optional || rows().any(|r| (c.get)(r).is_some()))
        .collect();
    // The disocclusion window of the rows (one value unless bench folders differ).
    let mut ks: Vec<u64> = rows()
        .filter_map(|r| r["disocclusion_frames"].as_u64())
        .collect();
    ks.sort_unstable();
    ks.dedup();
    let ks = ks.iter().map(u64::to_string).collect::<Vec<_>>().join(", ");
    let vs = format!("<br><span class=\"vs\">vs {}</span>", esc(reference));
    let _ = write!(
        html,
        "<table class=\"sortable\"{}><thead><tr><th class=\"t\" data-key=\"scene\">scene</th><th class=\"t\" data-key=\"res\">resolution</th><th class=\"t\" data-key=\"config\">configuration</th>",
        if first { " id=\"summary-table\"" } else { "" }
    );
    for c in &cols {
        let (title, tip) = if c.key == "flip_disocc" && !ks.is_empty() {
            (
                format!("{} (k = {ks})", c.title),
                format!("{} (k = {ks})", c.tip),
            )
        } else {
            (c.title.to_string(), c.tip.to_string())
        };
        let tip = if tip.is_empty() {
            String::new()
        } else {
            format!(" title=\"{}\"", esc(&tip))
        };
        let _ = write!(
            html,
            "<th data-key=\"{}\"{tip}>{title}{}</th>",
            c.key,
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

#[cfg(test)]
mod tests {
    #[test]
    fn the_reconstruction_time_is_the_resolve_the_upscale_or_fsr1s_two_passes() {
        let row = |passes: serde_json::Value| serde_json::json!({ "passes": passes });
        let m = |v: f64| serde_json::json!({ "median": v });
        assert_eq!(
            super::recon_ms(&row(serde_json::json!({ "resolve": m(2.0) }))),
            Some(2.0)
        );
        assert_eq!(
            super::recon_ms(&row(serde_json::json!({ "upscale": m(1.5) }))),
            Some(1.5)
        );
        let fsr = serde_json::json!({ "upscale.easu": m(1.0), "upscale.rcas": m(0.25) });
        assert_eq!(super::recon_ms(&row(fsr)), Some(1.25));
        let half = serde_json::json!({ "upscale.easu": m(1.0) });
        assert_eq!(super::recon_ms(&row(half)), None);
    }
}
