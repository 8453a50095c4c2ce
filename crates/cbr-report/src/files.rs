//! Images (embedded once as data URIs, or copied next to the report) and links to raw files.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use serde_json::Value;

use crate::bench::{BenchDir, Group};
use crate::util::{esc, relative, url};
use crate::{Options, ReportError, Result};

pub(crate) struct Ctx<'a> {
    pub opts: &'a Options,
    out_dir: PathBuf,
    /// Every image once: (id, src); the page's script puts them into `img` and crop elements
    /// carrying `data-im="id"`, so a data URI is never repeated.
    store: Vec<(String, String)>,
    images: BTreeMap<PathBuf, String>, // path -> id
}

impl<'a> Ctx<'a> {
    pub fn new(opts: &'a Options) -> Ctx<'a> {
        let out_dir = opts
            .out
            .parent()
            .map(Path::to_path_buf)
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."));
        Ctx {
            opts,
            out_dir,
            store: Vec::new(),
            images: BTreeMap::new(),
        }
    }

    /// The id under which an image file's `src` is stored.
    pub fn image(&mut self, bench: usize, dir: &Path, rel: &str) -> Result<String> {
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

    /// A link from the report's folder to a file of a bench folder.
    pub fn link(&self, dir: &Path, rel: &str) -> String {
        url(&relative(&self.out_dir, &dir.join(rel)))
    }

    /// The `IMAGES` object of the page's script: id -> src.
    pub fn images_json(self) -> Value {
        Value::Object(
            self.store
                .into_iter()
                .map(|(k, v)| (k, Value::String(v)))
                .collect(),
        )
    }
}

/// Links to bench.json, bench.csv, the reference's EXR (when it has its own snapshot) and each
/// configuration's EXR.
pub(crate) fn raw_files(ctx: &Ctx, html: &mut String, b: &BenchDir, g: &Group) {
    html.push_str("<h3>Raw files</h3><ul>");
    let _ = write!(
        html,
        "<li><a href=\"{}\">bench.json</a>, <a href=\"{}\">bench.csv</a></li>",
        ctx.link(&b.dir, "bench.json"),
        ctx.link(&b.dir, "bench.csv")
    );
    let (scene, w, h) = (&g.key.0, g.key.1, g.key.2);
    if let Some(exr) = b.reference_file(scene, w, h, "exr") {
        let _ = write!(
            html,
            "<li><a href=\"{}\">{} (reference)</a> (EXR, all layers)</li>",
            ctx.link(&b.dir, exr),
            esc(g.reference)
        );
    }
    for r in &g.rows {
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
}
