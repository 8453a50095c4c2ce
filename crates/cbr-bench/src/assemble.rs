//! bench.json's rows: one row per measured configuration, and what is computed over a scene and
//! resolution's rows together (crop windows, Pareto front, equal-error supersampling, the
//! reference's images). One code path for a run and for merged shards (crate::merge), so both
//! give the same rows.

use serde_json::{Value, json};

use crate::output::{finite_or_null, pareto_front, pick_windows, summary_json};
use crate::stats::summarize;
use crate::{Config, checkerboard, measure::Measured, measure::mean};
use cbr_render::Mapping;

/// What a row needs besides its configuration and measurement.
pub struct RowCtx<'a> {
    pub scene: &'a str,
    pub size: (u32, u32),
    pub device: &'a cbr_gpu::DeviceInfo,
    pub warmup: u32,
    pub frames: u32,
    pub disocclusion_frames: u32,
    pub reference: &'a str,
    pub timing_only: bool,
    /// `--crop` windows (then no window is chosen from the FLIP maps).
    pub fixed_crops: Option<&'a [[usize; 4]]>,
}

/// One row of bench.json. `window_scores`: the row's FLIP map summed over each candidate crop
/// window (crate::output::window_scores), kept on the row until [`finish`].
pub fn row(
    c: &Config,
    m: &Measured,
    images: Value,
    window_scores: Option<Vec<f64>>,
    x: &RowCtx,
) -> Value {
    let (w, h) = x.size;
    let s = &c.settings;
    let cb = checkerboard(s);
    let resolve = cb.and_then(|c| c.resolve);
    let resolve = resolve.as_ref();
    let passes: serde_json::Map<String, Value> = m
        .passes
        .iter()
        .map(|(k, v)| (k.clone(), summary_json(summarize(v))))
        .collect();
    let fragments: serde_json::Map<String, Value> = m
        .fragments
        .iter()
        .map(|(k, v)| (k.clone(), json!(crate::stats::percentile(v, 50.0))))
        .collect();
    let is_reference = c.name == x.reference;
    let opt = |v: Option<f64>| v.map(finite_or_null).unwrap_or(json!(null));
    json!({
        "scene": x.scene,
        "config": c.name,
        "technique": s.spec.technique.name,
        "spec": s.spec,
        "resolve": resolve.map(|r| r.mode.name()),
        "mapping": resolve.map(|r| if r.mapping == Mapping::Pixel { "pixel" } else { "quad" }),
        "group": resolve.map(|r| r.group),
        "fp16": resolve.map(|r| r.fp16),
        "id_prepass": cb.is_some_and(|c| c.prepass),
        "lod_bias": m.lod_bias,
        "width": w,
        "height": h,
        "device": x.device.name,
        "driver": x.device.driver_info,
        "warmup": x.warmup,
        "frames": x.frames,
        "disocclusion_frames": x.disocclusion_frames,
        "frame_ms": summary_json(summarize(&m.frame_ms)),
        "cached_frames": m.cached_frames,
        "setup_s": m.setup_s,
        "frames_wall_s": m.frames_wall_s,
        "passes": passes,
        "fragment_invocations_median": fragments,
        "images": images,
        "crops": x.fixed_crops.map(|c| json!(c)).unwrap_or(json!([])),
        "window_scores": window_scores,
        "copy_floor_ms": summary_json(summarize(m.passes.get("resolve.copy_floor").map(Vec::as_slice).unwrap_or(&[]))),
        "reference": x.reference,
        "error": if is_reference || x.timing_only { json!(null) } else { json!({
            "psnr_mean": opt(mean(&m.psnr)),
            "ssim_mean": opt(mean(&m.ssim)),
            "flip_mean": opt(mean(&m.flip)),
            "flip_median_mean": opt(mean(&m.flip_median)),
            "flip_edge_mean": opt(mean(&m.flip_edge)),
            "flip_interior_mean": opt(mean(&m.flip_interior)),
            "flip_disocc_mean": opt(mean(&m.flip_disocc)),
            "disocc_fraction_mean": opt(mean(&m.disocc_fraction)),
            "relmse_mean": opt(mean(&m.relmse)),
            "flicker_mean": opt(mean(&m.flicker)),
            "change_mean": opt(mean(&m.change)),
            "ref_change_mean": opt(mean(&m.ref_change)),
            "attribution": m.attribution.as_ref().map(|a| a.to_json()),
            "analytic_attribution": m.analytic_attribution.as_ref().map(|a| a.to_json()),
            "interleaved_attribution": m.interleaved_attribution.as_ref().map(|a| a.to_json()),
            "motion_attribution": m.motion_attribution.as_ref().map(|a| a.to_json()),
            "per_frame": m.errors,
        })},
    })
}

/// A row's group: (scene, width, height).
pub fn group_key(r: &Value) -> (Option<&str>, Option<u64>, Option<u64>) {
    (
        r["scene"].as_str(),
        r["width"].as_u64(),
        r["height"].as_u64(),
    )
}

/// The folder below images/ and frames/ of a scene at a resolution: `WxH`, or `SCENE/WxH` in
/// runs of several scenes.
pub fn sub_folder(scene: &str, (w, h): (u32, u32), several_scenes: bool) -> String {
    if several_scenes {
        format!("{}/{w}x{h}", crate::output::slug(scene))
    } else {
        format!("{w}x{h}")
    }
}

/// The key of `reference_images`: `WxH`, or `SCENE/WxH` in runs of several scenes.
pub fn reference_key(scene: &str, (w, h): (u32, u32), several_scenes: bool) -> String {
    if several_scenes {
        format!("{scene}/{w}x{h}")
    } else {
        format!("{w}x{h}")
    }
}

/// What is computed over each group's rows, in place: the crop windows chosen from the rows'
/// window scores (unless `fixed_crops`), the Pareto front, the equal-error supersampling; the
/// window scores are dropped unless `keep_scores` (a shard keeps them for the merge). Returns
/// `reference_images`: the reference row's images per group.
pub fn finish(
    rows: &mut [Value],
    reference: &str,
    fixed_crops: bool,
    keep_scores: bool,
    several_scenes: bool,
) -> Value {
    let mut groups: Vec<(Option<String>, Option<u64>, Option<u64>)> = Vec::new();
    for r in rows.iter() {
        let (s, w, h) = group_key(r);
        let k = (s.map(str::to_string), w, h);
        if !groups.contains(&k) {
            groups.push(k);
        }
    }
    let mut on_front = vec![false; rows.len()];
    for g in &groups {
        let same = |r: &Value| {
            let (s, w, h) = group_key(r);
            (s, w, h) == (g.0.as_deref(), g.1, g.2)
        };
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| same(&rows[i])).collect();
        if !fixed_crops {
            let scores: Vec<Vec<f64>> = idx
                .iter()
                .filter_map(|&i| serde_json::from_value(rows[i]["window_scores"].clone()).ok())
                .collect();
            let (w, h) = (g.1.unwrap_or(0) as usize, g.2.unwrap_or(0) as usize);
            let crops = json!(pick_windows(w, h, &scores, 3));
            for &i in &idx {
                rows[i]["crops"] = crops.clone();
            }
        }
        // `interleaved` rows: their lighting pass by part, from the group's `parts=...` rows.
        let parts: Vec<Option<Value>> = {
            let group: Vec<&Value> = idx.iter().map(|&i| &rows[i]).collect();
            idx.iter()
                .map(|&i| crate::interleaved_attribution::parts_json(&rows[i], &group))
                .collect()
        };
        for (&i, p) in idx.iter().zip(parts) {
            if let Some(p) = p {
                rows[i]["interleaved_parts"] = p;
            }
        }
        // The Pareto front: frame time median against FLIP mean, the reference left out.
        let measured: Vec<usize> = idx
            .iter()
            .copied()
            .filter(|&i| rows[i]["config"] != reference)
            .collect();
        let pts: Vec<(f64, f64)> = measured
            .iter()
            .map(|&i| {
                (
                    rows[i]["frame_ms"]["median"].as_f64().unwrap_or(f64::NAN),
                    rows[i]["error"]["flip_mean"].as_f64().unwrap_or(f64::NAN),
                )
            })
            .collect();
        for k in pareto_front(&pts) {
            on_front[measured[k]] = true;
        }
    }
    for (r, f) in rows.iter_mut().zip(&on_front) {
        r["pareto"] = json!(f);
        if let Some(o) = r.as_object_mut() {
            o.remove("equal_error_ssaa");
            if !keep_scores {
                o.remove("window_scores");
            }
        }
    }
    // Each row's error placed on its group's own supersampling ladder (its ssaa:N rows), if any.
    crate::equal_error::annotate(rows);
    let images: serde_json::Map<String, Value> = rows
        .iter()
        .filter(|r| r["config"] == reference)
        .map(|r| {
            let size = (
                r["width"].as_u64().unwrap_or(0) as u32,
                r["height"].as_u64().unwrap_or(0) as u32,
            );
            let scene = r["scene"].as_str().unwrap_or("");
            (
                reference_key(scene, size, several_scenes),
                r["images"].clone(),
            )
        })
        .collect();
    Value::Object(images)
}
