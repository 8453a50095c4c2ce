//! `cbr report`: one self-contained HTML file from `cbr bench` folders
//! (docs/bench-and-report.md): provenance, a sortable summary with the best values marked,
//! speed-vs-error charts with the Pareto front, per scene a synchronised zoom/pan viewer
//! (reference, techniques, FLIP maps; slider, hold-to-flip, keys 1-9 and R, pixel readout),
//! worst-FLIP crops, the error by pixel class (`attribution`), timing bars and per-frame error
//! curves, and links to the raw files. Images
//! are embedded as data URIs, or copied next to the report with `assets_dir`.
//!
//! Modules by what they draw: `provenance`, `summary` (the sortable table), `chart` (speed
//! against error; axis ticks in `ticks`), `viewer` (panels, wipe, colour bar), `crops`,
//! `timing` (per-pass bars), `gpu_isa` (the static cost model of `cbr gpu-stats` beside the
//! lavapipe medians, where the folder has a gpu-stats.json), `curves` (per-frame error); `bench` reads bench.json, `files`
//! embeds images and links raw files, `util` holds the shared helpers.
#![forbid(unsafe_code)]

use std::fmt::Write as _;
use std::path::PathBuf;

mod attribution;
mod bench;
mod chart;
mod crops;
mod curves;
mod files;
mod gpu_isa;
mod provenance;
mod summary;
#[cfg(test)]
mod tests;
mod ticks;
mod timing;
mod util;
mod viewer;

pub use bench::BenchDir;
pub use util::relative;

use bench::Group;
use files::Ctx;
use util::esc;

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("{path}: {msg}")]
    Input { path: PathBuf, msg: String },
    #[error("{path}: {msg}")]
    Write { path: PathBuf, msg: String },
}

type Result<T> = std::result::Result<T, ReportError>;

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

/// One scene at one resolution of one bench folder: chart, viewer, crops, timing bars, error
/// curves and raw files; every error names the group's reference.
fn scene_section(
    ctx: &mut Ctx,
    html: &mut String,
    bench: usize,
    b: &BenchDir,
    g: &Group,
    viewer_id: usize,
) -> Result<()> {
    let (scene, w, h) = &g.key;
    let _ = writeln!(
        html,
        "<h2 id=\"scene-{viewer_id}\">{} at {w}x{h}, errors vs {}</h2>",
        esc(scene),
        esc(g.reference)
    );
    chart::chart(html, &g.rows, g.reference);
    let Some(panels) = viewer::panels(ctx, bench, b, g)? else {
        html.push_str("<p class=\"muted\">No images in this bench folder.</p>");
        return Ok(());
    };
    let windows = crops::windows(&g.rows);
    viewer::viewer(html, &panels, *w, *h, &windows);
    viewer::colour_bar(html, &ctx.opts.colormap);
    crops::crops(html, g.reference, &windows, &panels.panels, *w, *h);
    attribution::attribution(html, &g.rows, g.reference);
    html.push_str("<h3>GPU time per pass (medians)</h3>\n");
    timing::timing_bars(html, &g.rows);
    gpu_isa::gpu_isa(html, &b.dir, &g.rows, (*w, *h))?;
    let _ = writeln!(html, "<h3>FLIP per frame vs {}</h3>", esc(g.reference));
    curves::error_curves(html, &g.rows, g.reference);
    files::raw_files(ctx, html, b, g);
    Ok(())
}

/// The report for `benches` as one HTML string (writing image assets when `assets_dir` is set).
pub fn render(benches: &[BenchDir], opts: &Options) -> Result<String> {
    let mut ctx = Ctx::new(opts);
    let mut body = String::new();
    provenance::provenance(&mut body, benches, &opts.created);
    summary::summary_table(&mut body, benches);
    let mut viewer_id = 0;
    for (i, b) in benches.iter().enumerate() {
        for g in b.groups() {
            scene_section(&mut ctx, &mut body, i, b, &g, viewer_id)?;
            viewer_id += 1;
        }
    }
    let title = benches
        .iter()
        .map(|b| b.json["scene"]["name"].as_str().unwrap_or("?").to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let mut references: Vec<&str> = Vec::new();
    for g in benches.iter().flat_map(BenchDir::groups) {
        if !references.contains(&g.reference) {
            references.push(g.reference);
        }
    }
    let against = match references.as_slice() {
        [] => "the reference".to_string(),
        [r] => esc(r),
        rs => format!(
            "{} (per bench folder)",
            rs.iter().map(|r| esc(r)).collect::<Vec<_>>().join(" or ")
        ),
    };
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>cbr report: {t}</title>\n<style>\n{css}</style></head>\n<body>\n<h1>cbr report: {t}</h1>\n<p class=\"muted\">Speed against error of checkerboard rendering techniques, each against {against} at the same resolution. <a href=\"#summary\">Summary</a> · <a href=\"#provenance\">Provenance</a></p>\n{body}\n<script>\nconst IMAGES = {images};\n{js}\n</script>\n</body></html>\n",
        t = esc(&title),
        css = include_str!("assets/report.css"),
        images = ctx.images_json(),
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
