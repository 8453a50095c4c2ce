//! Per-frame error curves: FLIP mean of every measured frame, one line per configuration.

use std::fmt::Write as _;

use serde_json::Value;

use crate::util::{PALETTE, esc, num};

/// FLIP mean against `reference` per frame; the legend and the y axis name the reference.
pub(crate) fn error_curves(html: &mut String, g: &[&Value], reference: &str) {
    let series: Vec<(&str, Vec<(f64, f64)>)> = g
        .iter()
        .filter_map(|r| {
            let pf = r["error"]["per_frame"].as_array()?;
            let v: Vec<(f64, f64)> = pf
                .iter()
                .filter_map(|f| Some((num(&f["frame"])?, num(&f["flip_mean"])?)))
                .collect();
            (!v.is_empty()).then(|| (r["config"].as_str().unwrap_or(""), v))
        })
        .collect();
    if series.is_empty() {
        return;
    }
    let (w, h, ml, mr, mt, mb) = (720.0, 260.0, 60.0, 220.0, 10.0, 30.0);
    let all = series.iter().flat_map(|s| s.1.iter());
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y1 = y1.max(y);
    }
    let x1 = if x1 > x0 { x1 } else { x0 + 1.0 };
    let y1 = (y1 * 1.1).max(1e-6);
    let sx = |x: f64| ml + (x - x0) / (x1 - x0) * (w - ml - mr);
    let sy = |y: f64| h - mb - y / y1 * (h - mt - mb);
    let vs = format!("vs {}", esc(reference));
    let _ = writeln!(
        html,
        "<svg width=\"{w}\" height=\"{h}\" role=\"img\" aria-label=\"FLIP per frame {vs}\">"
    );
    let _ = writeln!(
        html,
        "<text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">FLIP mean {vs}</text><text x=\"{:.1}\" y=\"{:.1}\">FLIP mean {vs}:</text>",
        (mt + h - mb) / 2.0,
        (mt + h - mb) / 2.0,
        w - mr + 8.0,
        mt + 12.0
    );
    let _ = writeln!(
        html,
        "<line class=\"axis\" x1=\"{ml}\" x2=\"{:.1}\" y1=\"{:.1}\" y2=\"{:.1}\"/><line class=\"axis\" x1=\"{ml}\" x2=\"{ml}\" y1=\"{mt}\" y2=\"{:.1}\"/><text x=\"{ml}\" y=\"{:.1}\">frame {x0}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">frame {x1}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{:.3}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">0</text>",
        w - mr,
        h - mb,
        h - mb,
        h - mb,
        h - 8.0,
        w - mr,
        h - 8.0,
        ml - 4.0,
        mt + 8.0,
        y1,
        ml - 4.0,
        h - mb
    );
    for (k, (name, pts)) in series.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let d: Vec<String> = pts
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
            .collect();
        let _ = writeln!(
            html,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"1.5\" points=\"{}\"/><text x=\"{:.1}\" y=\"{:.1}\" fill=\"{c}\">{}</text>",
            d.join(" "),
            w - mr + 8.0,
            mt + 26.0 + 14.0 * k as f64,
            esc(name)
        );
    }
    html.push_str("</svg>\n");
}
