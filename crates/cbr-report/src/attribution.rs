//! The error-attribution panel: for each configuration whose bench row has an `attribution`
//! (checkerboard resolves run with `:debug`), each pixel class's share of the pixels and of the
//! error as stacked bars, with the numbers in a table (cbr-bench's attribution module defines
//! the classes and the per-pixel error).

use std::fmt::Write as _;

use serde_json::Value;

use crate::util::{PALETTE, esc, num};

const CLASSES: [&str; 6] = [
    "rendered",
    "history",
    "clamped_history",
    "rejected_id",
    "rejected_depth",
    "spatial",
];

/// Writes the panel when any row has an attribution; nothing otherwise.
pub(crate) fn attribution(html: &mut String, g: &[&Value], reference: &str) {
    let rows: Vec<&Value> = g
        .iter()
        .copied()
        .filter(|r| r["error"]["attribution"].is_object())
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        html,
        "<h3>Error by pixel class vs {} (per-pixel display-space error; share of pixels | share of error)</h3>",
        esc(reference)
    );
    let (w, row, label) = (900.0, 26.0, 300.0);
    let half = (w - label - 20.0) / 2.0;
    let h = row * rows.len() as f64 + 44.0;
    let _ = writeln!(
        html,
        "<svg width=\"{w}\" height=\"{h:.0}\" role=\"img\" aria-label=\"error by pixel class\">"
    );
    for (i, r) in rows.iter().enumerate() {
        let y = 4.0 + i as f64 * row;
        let _ = write!(
            html,
            "<text x=\"{:.0}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            label - 6.0,
            y + 15.0,
            esc(r["config"].as_str().unwrap_or(""))
        );
        let a = &r["error"]["attribution"];
        for (side, key) in ["pixels", "error"].iter().enumerate() {
            let mut x = label + side as f64 * (half + 20.0);
            for (k, class) in CLASSES.iter().enumerate() {
                let share = num(&a[class][key]).unwrap_or(0.0);
                let bw = share * half;
                let _ = write!(
                    html,
                    "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{bw:.1}\" height=\"{:.0}\" fill=\"{}\"><title>{class}: {:.1}% of the {key}</title></rect>",
                    row - 8.0,
                    PALETTE[k % PALETTE.len()],
                    100.0 * share
                );
                x += bw;
            }
        }
    }
    for (k, class) in CLASSES.iter().enumerate() {
        let cx = 10.0 + k as f64 * 148.0;
        let cy = row * rows.len() as f64 + 30.0;
        let _ = writeln!(
            html,
            "<rect x=\"{cx}\" y=\"{:.1}\" width=\"12\" height=\"12\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{cy:.1}\">{class}</text>",
            cy - 10.0,
            PALETTE[k % PALETTE.len()],
            cx + 16.0
        );
    }
    html.push_str("</svg>\n<table class=\"attribution\"><tr><th>configuration</th>");
    for class in CLASSES.iter().chain(["disoccluded"].iter()) {
        let _ = write!(html, "<th>{class}<br>pixels / error / mean</th>");
    }
    html.push_str("</tr>\n");
    for r in &rows {
        let a = &r["error"]["attribution"];
        let _ = write!(
            html,
            "<tr><td>{}</td>",
            esc(r["config"].as_str().unwrap_or(""))
        );
        for class in CLASSES.iter().chain(["disoccluded"].iter()) {
            let c = &a[class];
            let pct = |k: &str| num(&c[k]).map(|v| format!("{:.1}%", 100.0 * v));
            let mean = num(&c["error_mean"]).map(|v| format!("{v:.4}"));
            let _ = write!(
                html,
                "<td>{} / {} / {}</td>",
                pct("pixels").unwrap_or_else(|| "–".into()),
                pct("error").unwrap_or_else(|| "–".into()),
                mean.unwrap_or_else(|| "–".into())
            );
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</table>\n");
}
