//! `cbr report`: one self-contained HTML file from `cbr bench` folders (docs/report.md):
//! provenance, a sortable summary with the best values marked, speed-vs-error charts with the
//! Pareto front, per scene a synchronised zoom/pan viewer (reference, techniques, FLIP maps;
//! slider, hold-to-flip, keys 1-9 and R, pixel readout), worst-FLIP crops, timing bars and
//! per-frame error curves, and links to the raw files. Images are embedded as data URIs, or
//! copied next to the report with `assets_dir`.
#![forbid(unsafe_code)]

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

use base64::Engine as _;
use serde_json::Value;

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("{path}: {msg}")]
    Input { path: PathBuf, msg: String },
    #[error("{path}: {msg}")]
    Write { path: PathBuf, msg: String },
}

type Result<T> = std::result::Result<T, ReportError>;

/// One `cbr bench` output folder.
pub struct BenchDir {
    pub dir: PathBuf,
    pub json: Value,
}

impl BenchDir {
    pub fn load(dir: &Path) -> Result<BenchDir> {
        let path = dir.join("bench.json");
        let err = |msg: String| ReportError::Input {
            path: path.clone(),
            msg,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| err(format!("cannot read: {e}")))?;
        let json: Value =
            serde_json::from_str(&text).map_err(|e| err(format!("not bench JSON: {e}")))?;
        if json["schema"] != "cbr.bench/1" {
            return Err(err(format!(
                "schema {} (expected cbr.bench/1)",
                json["schema"]
            )));
        }
        if !json["rows"].is_array() {
            return Err(err("no rows".into()));
        }
        Ok(BenchDir {
            dir: dir.to_path_buf(),
            json,
        })
    }
}

pub struct Options {
    /// Where report.html goes (links to raw files are relative to its folder).
    pub out: PathBuf,
    /// Copy images here (relative links) instead of embedding them.
    pub assets_dir: Option<PathBuf>,
    /// The FLIP colour map, sampled at 0, 0.1, ..., 1 (for the colour bars).
    pub colormap: Vec<[u8; 3]>,
    /// When the report was made (shown in the provenance).
    pub created: String,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `to` relative to the folder `from` (both made absolute against the working directory).
pub fn relative(from: &Path, to: &Path) -> PathBuf {
    let abs = |p: &Path| {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                Component::ParentDir => {
                    out.pop();
                }
                Component::CurDir => {}
                c => out.push(c),
            }
        }
        out
    };
    let (f, t) = (abs(from), abs(to));
    let fc: Vec<_> = f.components().collect();
    let tc: Vec<_> = t.components().collect();
    let common = fc.iter().zip(&tc).take_while(|(a, b)| a == b).count();
    let mut r = PathBuf::new();
    for _ in common..fc.len() {
        r.push("..");
    }
    for c in &tc[common..] {
        r.push(c);
    }
    r
}

fn url(p: &Path) -> String {
    p.components()
        .map(|c| c.as_os_str().to_string_lossy().replace(' ', "%20"))
        .collect::<Vec<_>>()
        .join("/")
}

struct Ctx<'a> {
    opts: &'a Options,
    out_dir: PathBuf,
    /// Every image once: (id, src); the page's script puts them into `img` and crop elements
    /// carrying `data-im="id"`, so a data URI is never repeated.
    store: Vec<(String, String)>,
    images: BTreeMap<PathBuf, String>, // path -> id
}

impl Ctx<'_> {
    /// The id under which an image file's `src` is stored.
    fn image(&mut self, bench: usize, dir: &Path, rel: &str) -> Result<String> {
        let path = dir.join(rel);
        if let Some(v) = self.images.get(&path) {
            return Ok(v.clone());
        }
        let bytes = std::fs::read(&path).map_err(|e| ReportError::Input {
            path: path.clone(),
            msg: format!("cannot read image: {e}"),
        })?;
        let src = match &self.opts.assets_dir {
            None => format!(
                "data:image/png;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&bytes)
            ),
            Some(assets) => {
                let dst = assets.join(format!("b{bench}")).join(rel);
                if let Some(parent) = dst.parent() {
                    std::fs::create_dir_all(parent).map_err(|e| ReportError::Write {
                        path: parent.to_path_buf(),
                        msg: e.to_string(),
                    })?;
                }
                std::fs::write(&dst, &bytes).map_err(|e| ReportError::Write {
                    path: dst.clone(),
                    msg: e.to_string(),
                })?;
                url(&relative(&self.out_dir, &dst))
            }
        };
        let id = format!("im{}", self.store.len());
        self.store.push((id.clone(), src));
        self.images.insert(path, id.clone());
        Ok(id)
    }

    fn link(&self, dir: &Path, rel: &str) -> String {
        url(&relative(&self.out_dir, &dir.join(rel)))
    }
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite())
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

/// (scene, width, height).
type GroupKey = (String, u64, u64);

/// Rows of one bench folder grouped by (scene, width, height), in order of appearance.
fn groups(rows: &[Value]) -> Vec<(GroupKey, Vec<&Value>)> {
    let mut out: Vec<(GroupKey, Vec<&Value>)> = Vec::new();
    for r in rows {
        let k = (
            r["scene"].as_str().unwrap_or("").to_string(),
            r["width"].as_u64().unwrap_or(0),
            r["height"].as_u64().unwrap_or(0),
        );
        match out.iter_mut().find(|(g, _)| *g == k) {
            Some((_, v)) => v.push(r),
            None => out.push((k, vec![r])),
        }
    }
    out
}

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
    /// Some(true): higher is better; Some(false): lower is better; None: not ranked.
    higher: Option<bool>,
}

const COLS: [Col; 8] = [
    Col {
        key: "frame_ms",
        title: "GPU ms (median)",
        get: |r| num(&r["frame_ms"]["median"]),
        digits: 3,
        higher: Some(false),
    },
    Col {
        key: "raster_ms",
        title: "raster ms",
        get: raster_ms,
        digits: 3,
        higher: None,
    },
    Col {
        key: "recon_ms",
        title: "resolve / upscale ms",
        get: recon_ms,
        digits: 3,
        higher: None,
    },
    Col {
        key: "psnr",
        title: "PSNR dB",
        get: |r| num(&r["error"]["psnr_mean"]),
        digits: 2,
        higher: Some(true),
    },
    Col {
        key: "ssim",
        title: "SSIM",
        get: |r| num(&r["error"]["ssim_mean"]),
        digits: 4,
        higher: Some(true),
    },
    Col {
        key: "flip_mean",
        title: "FLIP mean",
        get: |r| num(&r["error"]["flip_mean"]),
        digits: 4,
        higher: Some(false),
    },
    Col {
        key: "flip_median",
        title: "FLIP median",
        get: |r| num(&r["error"]["flip_median_mean"]),
        digits: 4,
        higher: Some(false),
    },
    Col {
        key: "relmse",
        title: "relMSE",
        get: |r| num(&r["error"]["relmse_mean"]),
        digits: 4,
        higher: Some(false),
    },
];

fn summary_table(html: &mut String, benches: &[BenchDir]) {
    html.push_str("<h2 id=\"summary\">Summary</h2>\n<p class=\"muted\">Click a column to sort. Best value per scene and resolution in bold green (time: lowest frame time; errors against native, so native has none). GPU ms = the technique's passes per frame, median [p5-p95] over the measured frames.</p>\n");
    html.push_str("<table class=\"sortable\" id=\"summary-table\"><thead><tr><th class=\"t\" data-key=\"scene\">scene</th><th class=\"t\" data-key=\"res\">resolution</th><th class=\"t\" data-key=\"config\">configuration</th>");
    for c in &COLS {
        let _ = write!(html, "<th data-key=\"{}\">{}</th>", c.key, c.title);
    }
    html.push_str("<th data-key=\"pareto\">Pareto</th></tr></thead><tbody>\n");
    for b in benches {
        let rows = b.json["rows"].as_array().map(Vec::as_slice).unwrap_or(&[]);
        for (_, g) in groups(rows) {
            let best: Vec<Option<f64>> = COLS
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
                for (c, b) in COLS.iter().zip(&best) {
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
    }
    html.push_str("</tbody></table>\n");
}

/// log10 axis ticks covering [lo, hi]: 1, 2, 5 x powers of ten.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut t = Vec::new();
    let mut e = lo.log10().floor() as i32;
    while 10f64.powi(e) <= hi * 1.0001 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(e);
            if v >= lo * 0.9999 && v <= hi * 1.0001 {
                t.push(v);
            }
        }
        e += 1;
    }
    t
}

/// Speed (x, log) against FLIP mean (y, log), labelled points, the Pareto front dashed.
fn chart(html: &mut String, g: &[&Value]) {
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
    for t in log_ticks(lo_x, hi_x) {
        let x = sx(t);
        let _ = writeln!(
            html,
            "<line class=\"gridline\" x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{mt}\" y2=\"{:.1}\"/><text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            h - mb,
            h - mb + 14.0,
            t
        );
    }
    for t in log_ticks(lo_y, hi_y) {
        let y = sy(t);
        let _ = writeln!(
            html,
            "<line class=\"gridline\" x1=\"{ml}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            w - mr,
            ml - 4.0,
            y + 4.0,
            t
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
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">GPU ms per frame (median, log)</text><text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">FLIP mean (log)</text>",
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
            "<circle class=\"pt{}\" cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"4\"><title>{}: {:.3} ms, FLIP {:.4}</title></circle><text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
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
    let mut csv = String::from("config,frame_ms_median,flip_mean,pareto\n");
    for p in &pts {
        let _ = writeln!(csv, "{},{},{},{}", p.2, p.0, p.1, p.3);
    }
    let _ = writeln!(
        html,
        "<p><a download=\"chart.csv\" href=\"data:text/csv;base64,{}\">the data behind this chart (CSV)</a>; red: the Pareto front (no configuration is both faster and more accurate).</p>",
        base64::engine::general_purpose::STANDARD.encode(csv)
    );
}

const PASS_COLOURS: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
];

fn timing_bars(html: &mut String, g: &[&Value]) {
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
                    PASS_COLOURS[k % PASS_COLOURS.len()],
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
            PASS_COLOURS[k % PASS_COLOURS.len()],
            cx + 16.0,
            esc(name)
        );
    }
    html.push_str("</svg>\n");
}

fn error_curves(html: &mut String, g: &[&Value]) {
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
    let _ = writeln!(
        html,
        "<svg width=\"{w}\" height=\"{h}\" role=\"img\" aria-label=\"FLIP per frame\">"
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
        let c = PASS_COLOURS[k % PASS_COLOURS.len()];
        let d: Vec<String> = pts
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
            .collect();
        let _ = writeln!(
            html,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"1.5\" points=\"{}\"/><text x=\"{:.1}\" y=\"{:.1}\" fill=\"{c}\">{}</text>",
            d.join(" "),
            w - mr + 8.0,
            mt + 12.0 + 14.0 * k as f64,
            esc(name)
        );
    }
    html.push_str("</svg>\n");
}

fn colour_bar(html: &mut String, stops: &[[u8; 3]]) {
    html.push_str("<svg width=\"300\" height=\"34\" role=\"img\" aria-label=\"FLIP colour bar\"><defs><linearGradient id=\"magma\">");
    let n = stops.len().max(2) - 1;
    for (i, c) in stops.iter().enumerate() {
        let _ = write!(
            html,
            "<stop offset=\"{:.3}\" stop-color=\"rgb({},{},{})\"/>",
            i as f64 / n as f64,
            c[0],
            c[1],
            c[2]
        );
    }
    html.push_str("</linearGradient></defs><rect x=\"10\" y=\"2\" width=\"280\" height=\"14\" fill=\"url(#magma)\"/><text x=\"10\" y=\"30\">0</text><text x=\"150\" y=\"30\" text-anchor=\"middle\">FLIP 0.5</text><text x=\"290\" y=\"30\" text-anchor=\"end\">1</text></svg>\n");
}

fn scene_section(
    ctx: &mut Ctx,
    html: &mut String,
    bench: usize,
    b: &BenchDir,
    key: &GroupKey,
    g: &[&Value],
    viewer_id: usize,
) -> Result<()> {
    let (scene, w, h) = key;
    let _ = writeln!(
        html,
        "<h2 id=\"scene-{viewer_id}\">{} at {w}x{h}</h2>",
        esc(scene)
    );
    chart(html, g);
    // The viewer: reference, each technique, each FLIP map.
    let mut panels: Vec<(String, String)> = Vec::new(); // (name, image id)
    let mut techs: Vec<(String, String)> = Vec::new();
    let mut reference: Option<String> = None;
    let mut frame = None;
    for r in g {
        let name = r["config"].as_str().unwrap_or("").to_string();
        let Some(img) = r["images"]["image"].as_str() else {
            continue;
        };
        let id = ctx.image(bench, &b.dir, img)?;
        frame = frame.or(r["images"]["frame"].as_u64());
        if name == "native" {
            reference = Some(id.clone());
            panels.insert(0, ("native (reference)".into(), id));
        } else {
            techs.push((name.clone(), id.clone()));
            panels.push((name, id));
        }
    }
    for r in g {
        if let Some(flip) = r["images"]["flip"].as_str() {
            let id = ctx.image(bench, &b.dir, flip)?;
            panels.push((format!("FLIP {}", r["config"].as_str().unwrap_or("")), id));
        }
    }
    let Some(ref_id) = reference else {
        html.push_str("<p class=\"muted\">No images in this bench folder.</p>");
        return Ok(());
    };
    let crops: Vec<[u64; 4]> = g
        .first()
        .and_then(|r| r["crops"].as_array())
        .map(|a| {
            a.iter()
                .filter_map(|c| {
                    let v: Vec<u64> = c.as_array()?.iter().filter_map(Value::as_u64).collect();
                    (v.len() == 4).then(|| [v[0], v[1], v[2], v[3]])
                })
                .collect()
        })
        .unwrap_or_default();
    let techs_json = Value::Array(
        techs
            .iter()
            .map(|t| serde_json::json!({"name": t.0, "im": t.1}))
            .collect(),
    );
    let _ = writeln!(
        html,
        "<h3>Viewer (frame {})</h3><p class=\"muted\">Wheel: zoom (all panels together), drag: pan, <kbd>1</kbd>-<kbd>9</kbd>: technique in the comparison, hold <kbd>F</kbd>: flip to the reference, <kbd>R</kbd>: reset. The slider wipes between technique (left) and reference (right). Values under the cursor are display sRGB.</p>",
        frame.map(|f| f.to_string()).unwrap_or_default()
    );
    let _ = writeln!(
        html,
        "<div class=\"viewer\" data-w=\"{w}\" data-h=\"{h}\" data-techs=\"{}\">",
        esc(&techs_json.to_string())
    );
    let first = techs.first().map(|t| t.1.clone()).unwrap_or(ref_id.clone());
    let _ = writeln!(
        html,
        "<div class=\"compare\"><div class=\"vp\"><div class=\"layer\"><img alt=\"reference\" data-im=\"{ref_id}\" width=\"{w}\" height=\"{h}\"></div><div class=\"top\"><div class=\"layer\"><img alt=\"technique\" data-im=\"{first}\" width=\"{w}\" height=\"{h}\"></div></div></div><div class=\"cap\"><span class=\"cmpname\"></span> <input class=\"slider\" type=\"range\" min=\"0\" max=\"100\" value=\"50\" aria-label=\"wipe\"></div></div>"
    );
    html.push_str(
        "<div class=\"readout\">move the cursor over an image</div>\n<div class=\"grid\">\n",
    );
    for (i, (name, id)) in panels.iter().enumerate() {
        let outlines: String = if i == 0 {
            crops
                .iter()
                .map(|c| {
                    format!(
                        "<div class=\"crop-outline\" style=\"left:{}px;top:{}px;width:{}px;height:{}px\"></div>",
                        c[0], c[1], c[2], c[3]
                    )
                })
                .collect()
        } else {
            String::new()
        };
        let _ = writeln!(
            html,
            "<div class=\"panel\" data-name=\"{}\"><div class=\"vp\"><div class=\"layer\"><img alt=\"{}\" data-im=\"{id}\" width=\"{w}\" height=\"{h}\">{outlines}</div></div><div class=\"cap\">{}{}</div></div>",
            esc(name),
            esc(name),
            if i > 0 && i <= techs.len() {
                format!("<kbd>{i}</kbd> ")
            } else {
                String::new()
            },
            esc(name)
        );
    }
    html.push_str("</div></div>\n");
    colour_bar(html, &ctx.opts.colormap);
    if !crops.is_empty() {
        html.push_str(
            "<h3>Crops: the windows with the highest FLIP (outlined in the reference)</h3>\n",
        );
        for c in &crops {
            let mag = (240 / c[2].max(1)).clamp(4, 8);
            let _ = writeln!(
                html,
                "<p class=\"muted\">x {} y {}, {}x{} pixels, x{mag}</p><div class=\"crops\">",
                c[0], c[1], c[2], c[3]
            );
            for (name, id) in &panels {
                let _ = writeln!(
                    html,
                    "<div class=\"cropcell\"><div class=\"crop\" data-im=\"{id}\" style=\"width:{}px;height:{}px;background-size:{}px {}px;background-position:-{}px -{}px\"></div>{}</div>",
                    c[2] * mag,
                    c[3] * mag,
                    w * mag,
                    h * mag,
                    c[0] * mag,
                    c[1] * mag,
                    esc(name)
                );
            }
            html.push_str("</div>\n");
        }
    }
    html.push_str("<h3>GPU time per pass (medians)</h3>\n");
    timing_bars(html, g);
    html.push_str("<h3>FLIP per frame</h3>\n");
    error_curves(html, g);
    html.push_str("<h3>Raw files</h3><ul>");
    let _ = write!(
        html,
        "<li><a href=\"{}\">bench.json</a>, <a href=\"{}\">bench.csv</a></li>",
        ctx.link(&b.dir, "bench.json"),
        ctx.link(&b.dir, "bench.csv")
    );
    for r in g {
        if let Some(exr) = r["images"]["exr"].as_str() {
            let _ = write!(
                html,
                "<li><a href=\"{}\">{}</a> (EXR, all layers)</li>",
                ctx.link(&b.dir, exr),
                esc(r["config"].as_str().unwrap_or(""))
            );
        }
    }
    html.push_str("</ul>\n");
    Ok(())
}

fn provenance(html: &mut String, benches: &[BenchDir], created: &str) {
    let _ = writeln!(
        html,
        "<h2 id=\"provenance\">Provenance</h2><p>Report made {}.</p>",
        esc(created)
    );
    for b in benches {
        let j = &b.json;
        let p = &j["protocol"];
        let row =
            |k: &str, v: String| format!("<tr><th class=\"t\">{}</th><td>{}</td></tr>", k, esc(&v));
        let s = |v: &Value| {
            v.as_str()
                .map(str::to_string)
                .unwrap_or_else(|| v.to_string())
        };
        let cmd = j["command"]
            .as_array()
            .map(|a| a.iter().map(s).collect::<Vec<_>>().join(" "))
            .unwrap_or_default();
        let _ = writeln!(
            html,
            "<table class=\"prov\">{}{}{}{}{}{}{}{}{}{}</table>",
            row("bench folder", b.dir.display().to_string()),
            row("command", cmd),
            row("git commit", s(&j["git_commit"])),
            row("cbr version", s(&j["cbr_version"])),
            row(
                "device / driver",
                format!(
                    "{} / {}",
                    s(&j["device"]["name"]),
                    s(&j["device"]["driver_info"])
                )
            ),
            row(
                "scene",
                format!(
                    "{} ({}, {} triangles)",
                    s(&j["scene"]["name"]),
                    s(&j["scene"]["source"]),
                    s(&j["scene"]["triangles"])
                )
            ),
            row(
                "frames",
                format!(
                    "{} warm-up, {} measured",
                    s(&p["warmup_frames"]),
                    s(&p["measured_frames"])
                )
            ),
            row(
                "timing",
                format!("{}; {}", s(&p["timing"]), s(&p["frame_ms"]))
            ),
            row("display transform", s(&p["display"])),
            row(
                "metrics",
                format!("{}; reference: {}", s(&p["metrics"]), s(&p["reference"]))
            ),
        );
    }
}

/// The report for `benches` as one HTML string (writing image assets when `assets_dir` is set).
pub fn render(benches: &[BenchDir], opts: &Options) -> Result<String> {
    let out_dir = opts
        .out
        .parent()
        .map(Path::to_path_buf)
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or_else(|| PathBuf::from("."));
    let mut ctx = Ctx {
        opts,
        out_dir,
        store: Vec::new(),
        images: BTreeMap::new(),
    };
    let mut body = String::new();
    provenance(&mut body, benches, &opts.created);
    summary_table(&mut body, benches);
    let mut viewer_id = 0;
    for (i, b) in benches.iter().enumerate() {
        let rows = b.json["rows"].as_array().map(Vec::as_slice).unwrap_or(&[]);
        for (key, g) in groups(rows) {
            scene_section(&mut ctx, &mut body, i, b, &key, &g, viewer_id)?;
            viewer_id += 1;
        }
    }
    let title = benches
        .iter()
        .map(|b| b.json["scene"]["name"].as_str().unwrap_or("?").to_string())
        .collect::<Vec<_>>()
        .join(", ");
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>cbr report: {t}</title>\n<style>\n{css}</style></head>\n<body>\n<h1>cbr report: {t}</h1>\n<p class=\"muted\">Speed against error of checkerboard rendering techniques, each against native at the same resolution. <a href=\"#summary\">Summary</a> · <a href=\"#provenance\">Provenance</a></p>\n{body}\n<script>\nconst IMAGES = {images};\n{js}\n</script>\n</body></html>\n",
        t = esc(&title),
        css = include_str!("assets/report.css"),
        images = serde_json::Value::Object(
            ctx.store
                .into_iter()
                .map(|(k, v)| (k, serde_json::Value::String(v)))
                .collect()
        ),
        js = include_str!("assets/report.js"),
    ))
}

/// Writes the report atomically (temporary name, then rename).
pub fn write(benches: &[BenchDir], opts: &Options) -> Result<()> {
    let html = render(benches, opts)?;
    let tmp = opts.out.with_extension("html.tmp");
    let werr = |e: std::io::Error| ReportError::Write {
        path: opts.out.clone(),
        msg: e.to_string(),
    };
    std::fs::write(&tmp, html).map_err(werr)?;
    std::fs::rename(&tmp, &opts.out).map_err(werr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_and_ticks() {
        assert_eq!(
            relative(Path::new("/a/b"), Path::new("/a/c/d.png")),
            PathBuf::from("../c/d.png")
        );
        assert_eq!(
            relative(Path::new("/a"), Path::new("/a/x.json")),
            PathBuf::from("x.json")
        );
        assert_eq!(log_ticks(0.8, 30.0), vec![1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(esc("<a&\"b\">"), "&lt;a&amp;&quot;b&quot;&gt;");
    }
}
