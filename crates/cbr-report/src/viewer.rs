//! The synchronised viewer: reference, every technique and every FLIP map zoom and pan together;
//! a wipe between a technique and the reference; the FLIP colour bar.

use std::fmt::Write as _;

use serde_json::Value;

use crate::Result;
use crate::bench::{BenchDir, Group};
use crate::crops;
use crate::files::Ctx;
use crate::util::esc;

/// The images of one scene and resolution, each stored once in the context.
pub(crate) struct Panels {
    /// (name, image id): the reference first, then the techniques, then the FLIP maps.
    pub panels: Vec<(String, String)>,
    /// (name, image id) of the techniques (keys 1-9).
    pub techs: Vec<(String, String)>,
    /// The reference's image id.
    pub reference: String,
    /// What the reference is (a technique spec: native, ssaa:16).
    pub reference_name: String,
    /// The frame the images show.
    pub frame: Option<u64>,
}

/// The viewer's panels, or None when there is no reference image: the reference's own snapshot
/// (`reference_images`), else the image of the row whose configuration is the reference (older
/// files: native).
pub(crate) fn panels(
    ctx: &mut Ctx,
    bench: usize,
    b: &BenchDir,
    g: &Group,
) -> Result<Option<Panels>> {
    let (scene, w, h) = (&g.key.0, g.key.1, g.key.2);
    let reference_name = format!("{} (reference)", g.reference);
    let mut panels: Vec<(String, String)> = Vec::new(); // (name, image id)
    let mut techs: Vec<(String, String)> = Vec::new();
    let mut reference: Option<String> = None;
    let mut frame = None;
    if let Some(img) = b.reference_file(scene, w, h, "image") {
        let id = ctx.image(bench, &b.dir, img)?;
        reference = Some(id.clone());
        panels.push((reference_name.clone(), id));
    }
    for r in &g.rows {
        let name = r["config"].as_str().unwrap_or("").to_string();
        let Some(img) = r["images"]["image"].as_str() else {
            continue;
        };
        frame = frame.or(r["images"]["frame"].as_u64());
        if name == g.reference {
            if reference.is_none() {
                let id = ctx.image(bench, &b.dir, img)?;
                reference = Some(id.clone());
                panels.insert(0, (reference_name.clone(), id));
            }
        } else {
            let id = ctx.image(bench, &b.dir, img)?;
            techs.push((name.clone(), id.clone()));
            panels.push((name, id));
        }
    }
    for r in &g.rows {
        if let Some(flip) = r["images"]["flip"].as_str() {
            let id = ctx.image(bench, &b.dir, flip)?;
            let name = r["config"].as_str().unwrap_or("");
            panels.push((format!("FLIP {name} vs {}", g.reference), id));
        }
    }
    Ok(reference.map(|reference| Panels {
        panels,
        techs,
        reference,
        reference_name: g.reference.to_string(),
        frame,
    }))
}

/// The comparison (wipe and flip), the readout and the grid of panels; crop windows are outlined
/// on the reference.
pub(crate) fn viewer(html: &mut String, p: &Panels, w: u64, h: u64, crops: &[[u64; 4]]) {
    let techs_json = Value::Array(
        p.techs
            .iter()
            .map(|t| serde_json::json!({"name": t.0, "im": t.1}))
            .collect(),
    );
    let _ = writeln!(
        html,
        "<h3>Viewer (frame {}, reference: {})</h3><p class=\"muted\">Wheel: zoom (all panels together), drag: pan, <kbd>1</kbd>-<kbd>9</kbd>: technique in the comparison, hold <kbd>F</kbd>: flip to the reference, <kbd>R</kbd>: reset. The slider wipes between technique (left) and reference (right). Values under the cursor are display sRGB.</p>",
        p.frame.map(|f| f.to_string()).unwrap_or_default(),
        esc(&p.reference_name)
    );
    let _ = writeln!(
        html,
        "<div class=\"viewer\" data-w=\"{w}\" data-h=\"{h}\" data-techs=\"{}\">",
        esc(&techs_json.to_string())
    );
    let ref_id = &p.reference;
    let first = p.techs.first().map(|t| &t.1).unwrap_or(ref_id);
    let _ = writeln!(
        html,
        "<div class=\"compare\"><div class=\"vp\"><div class=\"layer\"><img alt=\"reference\" data-im=\"{ref_id}\" width=\"{w}\" height=\"{h}\"></div><div class=\"top\"><div class=\"layer\"><img alt=\"technique\" data-im=\"{first}\" width=\"{w}\" height=\"{h}\"></div></div></div><div class=\"cap\"><span class=\"cmpname\"></span> <input class=\"slider\" type=\"range\" min=\"0\" max=\"100\" value=\"50\" aria-label=\"wipe\"></div></div>"
    );
    html.push_str(
        "<div class=\"readout\">move the cursor over an image</div>\n<div class=\"grid\">\n",
    );
    for (i, (name, id)) in p.panels.iter().enumerate() {
        let outlines = if i == 0 {
            crops::outlines(crops)
        } else {
            String::new()
        };
        let _ = writeln!(
            html,
            "<div class=\"panel\" data-name=\"{}\"><div class=\"vp\"><div class=\"layer\"><img alt=\"{}\" data-im=\"{id}\" width=\"{w}\" height=\"{h}\">{outlines}</div></div><div class=\"cap\">{}{}</div></div>",
            esc(name),
            esc(name),
            if i > 0 && i <= p.techs.len() {
                format!("<kbd>{i}</kbd> ")
            } else {
                String::new()
            },
            esc(name)
        );
    }
    html.push_str("</div></div>\n");
}

/// The FLIP colour map from 0 to 1.
pub(crate) fn colour_bar(html: &mut String, stops: &[[u8; 3]]) {
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
