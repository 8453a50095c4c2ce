//! Shard folders (`cbr bench --shard K/N`) into one result: the unsharded run's rows in its
//! order (`cbr bench --merge DIR... -o DIR`, and `cbr report` given shard folders). Folders of
//! different runs (protocol, reference, device, commit, plan) are refused naming the field; a
//! missing shard is named.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};

use crate::{assemble, machine};

/// Merged shards: bench.json, and the files its rows name (source, path relative to bench.json).
pub struct Merged {
    pub json: Value,
    pub files: Vec<(PathBuf, String)>,
}

/// Whether a bench folder is a shard's (its bench.json has a `shard` section).
pub fn is_shard(json: &Value) -> bool {
    json["shard"].is_object()
}

/// What must be equal in every shard of one run (`protocol` without `disocclusion_ids`, which
/// each shard holds for the groups it measured).
const SAME: [&str; 9] = [
    "schema",
    "cbr_version",
    "git_commit",
    "device",
    "reference",
    "scenes",
    "protocol",
    "shard.units",
    "shard.fixed_crops",
];

fn at<'a>(v: &'a Value, dotted: &str) -> &'a Value {
    dotted.split('.').fold(v, |v, k| &v[k])
}

/// The first place two values differ, as a dotted path with both values.
fn difference(a: &Value, b: &Value, path: &str) -> Option<(String, String, String)> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            keys.into_iter().find_map(|k| {
                let null = Value::Null;
                difference(
                    x.get(k).unwrap_or(&null),
                    y.get(k).unwrap_or(&null),
                    &format!("{path}.{k}"),
                )
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (p, q))| difference(p, q, &format!("{path}[{i}]"))),
        _ if a == b => None,
        _ => {
            let short = |v: &Value| {
                let s = v.to_string();
                if s.len() > 80 {
                    format!("{}...", &s[..77])
                } else {
                    s
                }
            };
            Some((path.to_string(), short(a), short(b)))
        }
    }
}

fn load(dir: &Path) -> Result<Value> {
    let path = dir.join("bench.json");
    if !path.is_file() {
        bail!(
            "{}: no bench.json: the shard did not finish (or this is not a shard folder)",
            dir.display()
        );
    }
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let json: Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not bench JSON", path.display()))?;
    if !is_shard(&json) {
        bail!(
            "{}: not a shard's bench.json (no `shard` section: made without --shard)",
            path.display()
        );
    }
    Ok(json)
}

/// Loads and checks shard folders (any order) and merges them.
pub fn merge(dirs: &[PathBuf]) -> Result<Merged> {
    if dirs.is_empty() {
        bail!("--merge: name the shard folders");
    }
    let shards: Vec<Value> = dirs.iter().map(|d| load(d)).collect::<Result<_>>()?;
    let count = shards[0]["shard"]["count"].as_u64().unwrap_or(0);
    let mut by_index: BTreeMap<u64, usize> = BTreeMap::new();
    for (i, s) in shards.iter().enumerate() {
        let c = s["shard"]["count"].as_u64().unwrap_or(0);
        if c != count {
            bail!(
                "{} and {} differ in `shard.count` ({count} against {c}): shards of different runs",
                dirs[0].display(),
                dirs[i].display()
            );
        }
        for field in SAME {
            let (mut a, mut b) = (at(&shards[0], field).clone(), at(s, field).clone());
            if field == "protocol" {
                for v in [&mut a, &mut b] {
                    if let Some(o) = v.as_object_mut() {
                        o.remove("disocclusion_ids");
                    }
                }
            }
            if let Some((path, x, y)) = difference(&a, &b, field) {
                bail!(
                    "{} and {} differ in `{path}` ({x} against {y}): shards of different runs cannot be merged",
                    dirs[0].display(),
                    dirs[i].display()
                );
            }
        }
        let k = s["shard"]["index"].as_u64().unwrap_or(u64::MAX);
        if let Some(j) = by_index.insert(k, i) {
            bail!(
                "{} and {} are both shard {k} of {count}",
                dirs[j].display(),
                dirs[i].display()
            );
        }
    }
    let missing: Vec<String> = (0..count)
        .filter(|k| !by_index.contains_key(k))
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() {
        bail!(
            "shard {} of {count} missing: none of the {} folder(s) given holds it",
            missing.join(", "),
            dirs.len()
        );
    }
    // Rows in the plan's order: each shard's rows are its row units in that order.
    let units = shards[0]["shard"]["units"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let mut next: Vec<usize> = vec![0; shards.len()];
    let mut rows = Vec::new();
    let mut files = Vec::new();
    for u in units.iter().filter(|u| u["work"] == "row") {
        let k = u["shard"].as_u64().unwrap_or(u64::MAX);
        let Some(&i) = by_index.get(&k) else {
            bail!("the plan names shard {k}, beyond {count}");
        };
        let Some(r) = shards[i]["rows"].get(next[i]) else {
            bail!(
                "{}: fewer rows than its plan gives shard {k}",
                dirs[i].display()
            );
        };
        if (&r["scene"], &r["width"], &r["height"], &r["config"])
            != (&u["scene"], &u["width"], &u["height"], &u["config"])
        {
            bail!(
                "{}: row {} is {} {}x{} `{}`, its plan says {} {}x{} `{}`",
                dirs[i].display(),
                next[i],
                r["scene"],
                r["width"],
                r["height"],
                r["config"],
                u["scene"],
                u["width"],
                u["height"],
                u["config"]
            );
        }
        next[i] += 1;
        for key in ["image", "flip", "exr"] {
            if let Some(rel) = r["images"][key].as_str() {
                files.push((dirs[i].join(rel), rel.to_string()));
            }
        }
        rows.push(r.clone());
    }
    for (i, s) in shards.iter().enumerate() {
        let n = s["rows"].as_array().map_or(0, Vec::len);
        if n != next[i] {
            bail!(
                "{}: {n} rows, its plan gives it {}",
                dirs[i].display(),
                next[i]
            );
        }
    }
    let first = &shards[by_index[&0]];
    let reference = first["reference"].as_str().unwrap_or("native").to_string();
    let several = first["scenes"].as_array().is_some_and(|s| s.len() > 1);
    let fixed = first["shard"]["fixed_crops"].as_bool().unwrap_or(false);
    let reference_images = assemble::finish(&mut rows, &reference, fixed, false, several);
    // Each group's ID source once, in the rows' order.
    let mut ids: Vec<Value> = Vec::new();
    for r in &rows {
        let key = (&r["scene"], &r["width"], &r["height"]);
        if ids
            .iter()
            .any(|d| (&d["scene"], &d["width"], &d["height"]) == key)
        {
            continue;
        }
        if let Some(d) = shards
            .iter()
            .flat_map(|s| {
                s["protocol"]["disocclusion_ids"]
                    .as_array()
                    .into_iter()
                    .flatten()
            })
            .find(|d| (&d["scene"], &d["width"], &d["height"]) == key)
        {
            ids.push(d.clone());
        }
    }
    let mut json = first.clone();
    let max = |field: &str| {
        shards
            .iter()
            .filter_map(|s| s[field].as_f64())
            .fold(0.0f64, f64::max)
    };
    json["rows"] = Value::Array(rows);
    json["reference_images"] = reference_images;
    json["protocol"]["disocclusion_ids"] = Value::Array(ids);
    json["command"] = json!(std::env::args().collect::<Vec<_>>());
    json["created_unix_s"] = json!(max("created_unix_s") as u64);
    json["wall_s"] = json!(max("wall_s"));
    json["validation"]["messages"] = json!(
        shards
            .iter()
            .filter_map(|s| s["validation"]["messages"].as_u64())
            .sum::<u64>()
    );
    json["merged_from"] = json!(
        by_index
            .iter()
            .map(|(k, &i)| json!({
                "shard": k,
                "dir": dirs[i],
                "host": shards[i]["shard"]["host"],
                "machine": shards[i]["machine"],
                "wall_s": shards[i]["wall_s"],
                "estimated_cost_s": shards[i]["shard"]["estimated_cost_s"][*k as usize],
                "reference_frames": shards[i]["shard"]["reference_frames"],
                "command": shards[i]["command"],
            }))
            .collect::<Vec<_>>()
    );
    // The shards' machine when they all ran on one kind (CPU, logical CPUs, SIMD, memory; each
    // shard's hostname and load average are in `merged_from`), else null: then the rows' times
    // are of different machines and not comparable as one run's.
    let kind = machine::identity(&first["machine"]);
    json["machine"] = if shards
        .iter()
        .all(|s| machine::identity(&s["machine"]) == kind)
    {
        let mut m = kind;
        m["per_shard"] = json!("hostname and load average: merged_from");
        m
    } else {
        Value::Null
    };
    if let Some(o) = json.as_object_mut() {
        o.remove("shard");
    }
    Ok(Merged { json, files })
}

/// The merged bench.json with every image path made the file's own path in its shard folder
/// (for a report straight from shard folders).
pub fn with_shard_paths(m: &Merged) -> Value {
    let map: BTreeMap<&str, String> = m
        .files
        .iter()
        .map(|(src, rel)| (rel.as_str(), src.to_string_lossy().into_owned()))
        .collect();
    let mut json = m.json.clone();
    let fix = |images: &mut Value| {
        for key in ["image", "flip", "exr"] {
            if let Some(p) = images[key].as_str().and_then(|rel| map.get(rel)) {
                images[key] = json!(p);
            }
        }
    };
    if let Some(rows) = json["rows"].as_array_mut() {
        for r in rows {
            fix(&mut r["images"]);
        }
    }
    if let Some(refs) = json["reference_images"].as_object_mut() {
        for v in refs.values_mut() {
            fix(v);
        }
    }
    json
}

/// Writes merged shards into `out`: the rows' files (each copied under a temporary name and
/// renamed), then bench.csv and bench.json last, so a folder with bench.json is complete.
pub fn write(m: &Merged, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create the output folder {}", out.display()))?;
    for (src, rel) in &m.files {
        let dst = out.join(rel);
        if let Some(p) = dst.parent() {
            std::fs::create_dir_all(p)?;
        }
        cbr_metrics::io::write_atomic(&dst, |tmp| {
            std::fs::copy(src, tmp)
                .map(|_| ())
                .map_err(|e| format!("cannot copy {}: {e}", src.display()))
        })?;
    }
    cbr_metrics::io::write_bytes(
        &out.join("bench.csv"),
        crate::output::csv(&m.json).as_bytes(),
    )?;
    cbr_metrics::io::write_bytes(
        &out.join("bench.json"),
        serde_json::to_string_pretty(&m.json)?.as_bytes(),
    )?;
    Ok(())
}
