//! One `cbr bench` folder: loading bench.json and grouping its rows.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::{ReportError, Result};

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

    /// The rows of bench.json (empty when missing).
    pub(crate) fn rows(&self) -> &[Value] {
        self.json["rows"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or(&[])
    }

    /// The technique every error of this folder is measured against: `reference` (a technique
    /// spec such as `native` or `ssaa:16`), else the rows' `reference`; bench.json files from
    /// before the field: native.
    pub(crate) fn reference(&self) -> &str {
        self.recorded_reference().unwrap_or("native")
    }

    /// The reference as bench.json records it (top level, else on the rows); None in files from
    /// before the field.
    pub(crate) fn recorded_reference(&self) -> Option<&str> {
        self.json["reference"]
            .as_str()
            .or_else(|| self.rows().iter().find_map(|r| r["reference"].as_str()))
    }

    /// The reference's own snapshot at `w`x`h` (`reference_images`, path relative to the
    /// folder), with key `image` or `exr`. Older files have none: the native row's images are the
    /// reference.
    /// Runs of several scenes key it `SCENE/WxH`.
    pub(crate) fn reference_file(&self, scene: &str, w: u64, h: u64, key: &str) -> Option<&str> {
        let refs = &self.json["reference_images"];
        refs[format!("{scene}/{w}x{h}")][key]
            .as_str()
            .or_else(|| refs[format!("{w}x{h}")][key].as_str())
    }

    /// Rows grouped by (scene, width, height), in order of appearance.
    pub(crate) fn groups(&self) -> Vec<Group<'_>> {
        let mut out: Vec<Group> = Vec::new();
        for r in self.rows() {
            let key = (
                r["scene"].as_str().unwrap_or("").to_string(),
                r["width"].as_u64().unwrap_or(0),
                r["height"].as_u64().unwrap_or(0),
            );
            match out.iter_mut().find(|g| g.key == key) {
                Some(g) => g.rows.push(r),
                None => out.push(Group {
                    key,
                    rows: vec![r],
                    reference: self.reference(),
                }),
            }
        }
        out
    }
}

/// (scene, width, height).
pub(crate) type GroupKey = (String, u64, u64);

/// The rows of one scene at one resolution of a bench folder.
pub(crate) struct Group<'a> {
    pub key: GroupKey,
    pub rows: Vec<&'a Value>,
    /// What the rows' errors are measured against (the folder's reference).
    pub reference: &'a str,
}
