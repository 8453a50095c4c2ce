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
}

/// (scene, width, height).
pub(crate) type GroupKey = (String, u64, u64);

/// Rows of one bench folder grouped by (scene, width, height), in order of appearance.
pub(crate) fn groups(rows: &[Value]) -> Vec<(GroupKey, Vec<&Value>)> {
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
