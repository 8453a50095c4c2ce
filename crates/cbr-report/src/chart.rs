//! The speed-vs-error chart: GPU time against FLIP mean, log-log, labelled points, the Pareto
//! front dashed, and the data behind it as CSV.

use std::fmt::Write as _;

use base64::Engine as _;
use serde_json::Value;

use crate::ticks;
use crate::util::{esc, num};

/// Speed (x, log) against FLIP mean against `reference` (y, log), labelled points, the Pareto
/// front dashed.
pub(crate) fn chart(html: &mut String, g: &[&Value], reference: &str) {
    let r = esc(reference);
    let vs = format!("vs {r}");
    let pts: Vec<(f64, f64, &str, bool)> = g
        .iter()
        .filter_map(|r| {
            Some((
                num(&r["frame_ms"]["median"])?,
                num(&r["error"]["flip_mean"])?,
                r["config"].as_str().unwrap_or(""),
                r["pareto"].as_bool().unwrap_or(false),
            ))
        })
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    if pts.is_empty() {
        html.push_str("<p class=\"muted\">No configuration with both a time and an error.</p>");
        return;
    }
    let (w, h, ml, mr, mt, mb) = (720.0, 420.0, 60.0, 200.0, 14.0, 40.0);
    let lo_x = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) / 1.3;
    let hi_x = pts.iter().map(|p| p.0).fold(0.0, f64::max) * 1.3;
    let lo_y = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) / 1.3;
    let hi_y = pts.iter().map(|p| p.1).fold(0.0, f64::max) * 1.3;
    let sx =
        |x: f64| ml + (x.log10() - lo_x.log10()) / (hi_x.log10() - lo_x.log10()) * (w - ml - mr);
    let sy = |y: f64| {
        h - mb - (y.log10() - lo_y.log10()) / (hi_y.log10() - lo_y.log10()) * (h - mt - mb)
    };
    let _ = writeln!(
        html,
        "<svg class=\"chart\" width=\"{w}\" height=\"{h}\" role=\"img\" aria-label=\"speed against error\">"
    );
    // Grid lines, tick marks and labels: at least three per axis (crate::ticks).
    for t in ticks::log_ticks(lo_x, hi_x) {
        let x = sx(t);
        let _ = writeln!(
            html,
            "<line class=\"gridline\" x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{mt}\" y2=\"{:.1}\"/><line class=\"axis\" x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{:.1}\" y2=\"{:.1}\"/><text class=\"xtick\" x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            h - mb,
            h - mb,
            h - mb + 4.0,
            h - mb + 15.0,
            ticks::label(t)
        );
    }
    for t in ticks::log_ticks(lo_y, hi_y) {
        let y = sy(t);
        let _ = writeln!(
            html,
            "<line class=\"gridline\" x1=\"{ml}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\"/><line class=\"axis\" x1=\"{:.1}\" x2=\"{ml}\" y1=\"{y:.1}\" y2=\"{y:.1}\"/><text class=\"ytick\" x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            w - mr,
            ml - 4.0,
            ml - 6.0,
            y + 4.0,
            ticks::label(t)
        );
    }
    let _ = writeln!(
        html,
        "<line class=\"axis\" x1=\"{ml}\" x2=\"{:.1}\" y1=\"{:.1}\" y2=\"{:.1}\"/><line class=\"axis\" x1=\"{ml}\" x2=\"{ml}\" y1=\"{mt}\" y2=\"{:.1}\"/>",
        w - mr,
        h - mb,
        h - mb,
        h - mb
    );
    let _ = writeln!(
        html,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">GPU ms per frame (median, log scale)</text><text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">FLIP mean {vs} (log scale)</text>",
        (ml + w - mr) / 2.0,
        h - 4.0,
        (mt + h - mb) / 2.0,
        (mt + h - mb) / 2.0
    );
    let mut front: Vec<&(f64, f64, &str, bool)> = pts.iter().filter(|p| p.3).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    if front.len() > 1 {
        let d: Vec<String> = front
            .iter()
            .map(|p| format!("{:.1},{:.1}", sx(p.0), sy(p.1)))
            .collect();
        let _ = writeln!(
            html,
            "<polyline class=\"front\" points=\"{}\"/>",
            d.join(" ")
        );
    }
    for p in &pts {
        let (x, y) = (sx(p.0), sy(p.1));
        let _ = writeln!(
            html,
            "<circle class=\"pt{}\" cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"4\"><title>{}: {:.3} ms, FLIP {vs} {:.4}</title></circle><text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            if p.3 { " onfront" } else { "" },
            esc(p.2),
            p.0,
            p.1,
            x + 6.0,
            y - 5.0,
            esc(p.2)
        );
    }
    html.push_str("</svg>\n");
    let mut csv = String::from("config,frame_ms_median,flip_mean,pareto,reference\n");
    for p in &pts {
        let _ = writeln!(csv, "{},{},{},{},{reference}", p.2, p.0, p.1, p.3);
    }
    let _ = writeln!(
        html,
        "<p><a download=\"chart.csv\" href=\"data:text/csv;base64,{}\">the data behind this chart (CSV)</a>; red: the Pareto front (no configuration is both faster and closer to {r}).</p>",
        base64::engine::general_purpose::STANDARD.encode(csv)
    );
}
