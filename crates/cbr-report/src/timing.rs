//! Per-pass GPU time bars (medians), one bar per configuration.

use std::fmt::Write as _;

use serde_json::Value;

use crate::util::{PALETTE, esc, num};

pub(crate) fn timing_bars(html: &mut String, g: &[&Value]) {
    let mut names: Vec<String> = Vec::new();
    for r in g {
        if let Some(p) = r["passes"].as_object() {
            for k in p.keys() {
                if !names.contains(k) {
                    names.push(k.clone());
                }
            }
        }
    }
    let max = g
        .iter()
        .map(|r| {
            r["passes"]
                .as_object()
                .map(|p| p.values().filter_map(|v| num(&v["median"])).sum::<f64>())
                .unwrap_or(0.0)
        })
        .fold(0.0, f64::max)
        .max(1e-9);
    let (w, row, label) = (900.0, 22.0, 300.0);
    let h = row * g.len() as f64 + 30.0 + 18.0 * names.len().div_ceil(3) as f64;
    let _ = writeln!(
        html,
        "<svg width=\"{w}\" height=\"{h:.0}\" role=\"img\" aria-label=\"per-pass GPU time\">"
    );
    for (i, r) in g.iter().enumerate() {
        let y = 4.0 + i as f64 * row;
        let _ = write!(
            html,
            "<text x=\"{:.0}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            label - 6.0,
            y + 14.0,
            esc(r["config"].as_str().unwrap_or(""))
        );
        let mut x = label;
        for (k, name) in names.iter().enumerate() {
            if let Some(ms) = num(&r["passes"][name]["median"]) {
                let bw = ms / max * (w - label - 80.0);
                let _ = write!(
                    html,
                    "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{bw:.1}\" height=\"{:.0}\" fill=\"{}\"><title>{}: {ms:.3} ms</title></rect>",
                    row - 6.0,
                    PALETTE[k % PALETTE.len()],
                    esc(name)
                );
                x += bw;
            }
        }
        let _ = writeln!(
            html,
            "<text x=\"{:.1}\" y=\"{:.1}\">{:.2} ms</text>",
            x + 4.0,
            y + 14.0,
            (x - label) / (w - label - 80.0) * max
        );
    }
    for (k, name) in names.iter().enumerate() {
        let (cx, cy) = (
            10.0 + (k % 3) as f64 * 290.0,
            row * g.len() as f64 + 20.0 + (k / 3) as f64 * 18.0,
        );
        let _ = writeln!(
            html,
            "<rect x=\"{cx}\" y=\"{:.1}\" width=\"12\" height=\"12\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{cy:.1}\">{}</text>",
            cy - 10.0,
            PALETTE[k % PALETTE.len()],
            cx + 16.0,
            esc(name)
        );
    }
    html.push_str("</svg>\n");
}
