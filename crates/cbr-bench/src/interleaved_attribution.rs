//! Cost and error attribution for `interleaved` frames (issue 57): where the lighting pass's work
//! and the error go, by what its filter did per pixel (the `interleaved` debug layer of
//! `interleaved:...:debug` rows):
//!
//! - `interior`: the filter's M x N window lies on the pixel's surface (the box of the estimates);
//! - `edge_found`: the window holds another surface, and yet no subset was shaded at the pixel
//!   (`search`, `enough=K`, or filters without a fallback);
//! - `fallback_1_4`, `fallback_5_8`, `fallback_9_16`, `fallback_17_plus`: the pixel shaded that
//!   many subsets itself (`ours`' fallback; every subset with `exact-edges`).
//!
//! Background pixels (nothing drawn) are left out. Per class, over the visible pixels and over
//! the reference's edge pixels (the bench's edge FLIP): the share of the pixels, of the subsets
//! shaded in the fallback and of the error, and the mean FLIP. Beside them the fallback's lane
//! use: the subsets the fallback shades over what lane groups of 8 consecutive pixels of a row
//! (llvmpipe's 8-wide SIMD on an 8 x 8 workgroup) pay, each group its longest list (a model of
//! the loop in shaders/interleaved/filter.glsl, not a measurement).
//!
//! The lighting pass's time by part comes from `parts=...` rows of the same run
//! ([`parts_json`], bench.json's `interleaved_parts`).

use serde_json::{Value, json};

use cbr_render::InterleavedLayers;

pub const CLASSES: [&str; 6] = [
    "interior",
    "edge_found",
    "fallback_1_4",
    "fallback_5_8",
    "fallback_9_16",
    "fallback_17_plus",
];

/// The class (index into [`CLASSES`]) of a visible pixel: its edge flag and its fallback subsets.
pub fn class_of(edge: bool, fallback: u32) -> usize {
    match (edge, fallback) {
        (false, 0) => 0,
        (true, 0) => 1,
        (_, 1..=4) => 2,
        (_, 5..=8) => 3,
        (_, 9..=16) => 4,
        _ => 5,
    }
}

/// The lanes of a SIMD group in the model of [`InterleavedAttribution::lane_use`].
pub const LANES: usize = 8;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct InterleavedAttribution {
    /// [visible pixels, the reference's edge pixels among them] x class.
    pub pixels: [[u64; CLASSES.len()]; 2],
    pub subsets: [[u64; CLASSES.len()]; 2],
    pub error: [[f64; CLASSES.len()]; 2],
    pub flip: [[f64; CLASSES.len()]; 2],
    /// The fallback's subsets, and what groups of [`LANES`] pixels of a row pay (their longest
    /// list, times the lanes).
    pub lane_subsets: u64,
    pub lane_paid: u64,
    /// What groups of [`LANES`] fallback pixels pay when the fallback pixels alone are listed
    /// (8 x 8 workgroups in row order, each's pixels in row order) and shaded [`LANES`] at a time:
    /// a model of a compacted fallback dispatch.
    pub compact_paid: u64,
}

impl InterleavedAttribution {
    /// Adds one frame: its debug layers, which pixels are drawn, the per-pixel error, the FLIP
    /// map and the reference's edge mask; `width` is the frame's.
    pub fn add(
        &mut self,
        layers: &InterleavedLayers,
        drawn: &[bool],
        width: usize,
        error: &[f32],
        flip: &[f32],
        ref_edge: &[bool],
    ) {
        let n = error.len();
        if [
            drawn.len(),
            flip.len(),
            ref_edge.len(),
            layers.edge.len(),
            layers.fallback.len(),
        ]
        .iter()
        .any(|&l| l != n)
        {
            return;
        }
        for i in 0..n {
            if !drawn[i] {
                continue;
            }
            let f = u32::from(layers.fallback[i]);
            let c = class_of(layers.edge[i] != 0, f);
            for set in 0..2 {
                if set == 1 && !ref_edge[i] {
                    continue;
                }
                self.pixels[set][c] += 1;
                self.subsets[set][c] += u64::from(f);
                self.error[set][c] += f64::from(error[i]);
                self.flip[set][c] += f64::from(flip[i]);
            }
        }
        let w = width.max(1);
        let h = n / w;
        let mut listed = Vec::new();
        for ty in (0..h).step_by(8) {
            for tx in (0..w).step_by(8) {
                for y in ty..(ty + 8).min(h) {
                    for x in tx..(tx + 8).min(w) {
                        let f = layers.fallback[y * w + x];
                        if f > 0 {
                            listed.push(f);
                        }
                    }
                }
            }
        }
        for group in listed.chunks(LANES) {
            self.compact_paid += u64::from(group.iter().copied().max().unwrap_or(0)) * LANES as u64;
        }
        for row in layers.fallback.chunks(w) {
            for group in row.chunks(LANES) {
                let longest = group.iter().copied().max().unwrap_or(0);
                self.lane_subsets += group.iter().map(|&f| u64::from(f)).sum::<u64>();
                self.lane_paid += u64::from(longest) * LANES as u64;
            }
        }
    }

    /// bench.json's `interleaved_attribution`: for the `visible` pixels and the reference's
    /// `edge` pixels, per class `pixels`, `subsets` and `error` (shares of the set's) and
    /// `flip_mean` (null for an empty class); `subsets_per_visible_pixel`; `lane_use`, the
    /// fallback's subsets over what 8-pixel row groups pay, and `lane_use_compacted` over what
    /// groups of 8 fallback pixels pay when listed apart (both null without a fallback).
    pub fn to_json(&self) -> Value {
        let share = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
        let set = |s: usize| {
            let n_all = self.pixels[s].iter().sum::<u64>() as f64;
            let sub_all = self.subsets[s].iter().sum::<u64>() as f64;
            let e_all = self.error[s].iter().sum::<f64>();
            let mut m = serde_json::Map::new();
            for (k, name) in CLASSES.iter().enumerate() {
                let n = self.pixels[s][k];
                m.insert(
                    (*name).into(),
                    json!({
                        "pixels": share(n as f64, n_all),
                        "subsets": share(self.subsets[s][k] as f64, sub_all),
                        "error": share(self.error[s][k], e_all),
                        "flip_mean": if n > 0 { json!(self.flip[s][k] / n as f64) } else { json!(null) },
                    }),
                );
            }
            m.insert("subsets_per_pixel".into(), json!(share(sub_all, n_all)));
            Value::Object(m)
        };
        json!({
            "visible": set(0),
            "edge": set(1),
            "lane_use": if self.lane_paid > 0 {
                json!(self.lane_subsets as f64 / self.lane_paid as f64)
            } else {
                json!(null)
            },
            "lane_use_compacted": if self.compact_paid > 0 {
                json!(self.lane_subsets as f64 / self.compact_paid as f64)
            } else {
                json!(null)
            },
        })
    }
}

/// The `parts=P` parameter of a spec, and the spec without it.
fn split_parts(config: &str) -> (Option<&str>, String) {
    let mut part = None;
    let kept: Vec<&str> = config
        .split(':')
        .filter(|p| match p.strip_prefix("parts=") {
            Some(v) => {
                part = Some(v);
                false
            }
            None => true,
        })
        .collect();
    (part, kept.join(":"))
}

/// The median of a row's `interleaved.lighting` pass.
fn lighting_ms(row: &Value) -> Option<f64> {
    row["passes"]["interleaved.lighting"]["median"].as_f64()
}

/// bench.json's `interleaved_parts` of an `interleaved` row, from the `parts=base`,
/// `parts=lights` and `parts=filter` rows of the same spec in `rows` (its group): the lighting
/// pass's medians by part, each the difference of two rows' medians (`base`: G-buffer fetches,
/// emission, ambient, directional lights; `lights`: the per-pixel point lights; `filter`: the
/// window's tests and fetches; `fallback`: the rest, `ours`' missing subsets). `None` unless the
/// three rows are there.
pub fn parts_json(row: &Value, rows: &[&Value]) -> Option<Value> {
    let config = row["config"].as_str()?;
    if !config.starts_with("interleaved") || split_parts(config).0.is_some() {
        return None;
    }
    let part = |name: &str| {
        rows.iter().find_map(|r| {
            let (p, base) = split_parts(r["config"].as_str()?);
            (p == Some(name) && base == config).then(|| lighting_ms(r))?
        })
    };
    let (all, base, lights, filter) = (
        lighting_ms(row)?,
        part("base")?,
        part("lights")?,
        part("filter")?,
    );
    Some(json!({
        "lighting_ms": all,
        "base_ms": base,
        "lights_ms": lights - base,
        "filter_ms": filter - lights,
        "fallback_ms": all - filter,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_by_edge_and_fallback() {
        assert_eq!(class_of(false, 0), 0);
        assert_eq!(class_of(true, 0), 1);
        assert_eq!(class_of(true, 1), 2);
        assert_eq!(class_of(true, 4), 2);
        assert_eq!(class_of(true, 5), 3);
        assert_eq!(class_of(true, 16), 4);
        assert_eq!(class_of(true, 17), 5);
    }

    #[test]
    fn shares_and_lane_use() {
        // A 10 x 1 frame: two groups (8 and 2 pixels); pixel 9 is background.
        let layers = InterleavedLayers {
            tile: (4, 4),
            edge: vec![0, 1, 1, 1, 0, 0, 0, 0, 1, 0],
            fallback: vec![0, 0, 4, 8, 0, 0, 0, 0, 2, 0],
            ..Default::default()
        };
        let drawn = [true, true, true, true, true, true, true, true, true, false];
        let err = [0.1f32, 0.1, 0.2, 0.4, 0.1, 0.1, 0.1, 0.1, 0.2, 0.0];
        let flip = err;
        let ref_edge = [
            false, true, true, true, false, false, false, false, false, false,
        ];
        let mut a = InterleavedAttribution::default();
        a.add(&layers, &drawn, 10, &err, &flip, &ref_edge);
        let j = a.to_json();
        for set in ["visible", "edge"] {
            for key in ["pixels", "error"] {
                let s: f64 = CLASSES
                    .iter()
                    .map(|c| j[set][c][key].as_f64().unwrap())
                    .sum();
                assert!((s - 1.0).abs() < 1e-9, "{set} {key}: {j}");
            }
        }
        assert!((j["visible"]["interior"]["pixels"].as_f64().unwrap() - 5.0 / 9.0).abs() < 1e-12);
        assert!((j["visible"]["subsets_per_pixel"].as_f64().unwrap() - 14.0 / 9.0).abs() < 1e-12);
        assert!(
            (j["visible"]["fallback_5_8"]["subsets"].as_f64().unwrap() - 8.0 / 14.0).abs() < 1e-12
        );
        assert!(j["edge"]["fallback_9_16"]["flip_mean"].is_null());
        // Paid: 8 x 8 (first group's longest list) + 8 x 2; shaded 14.
        assert!((j["lane_use"].as_f64().unwrap() - 14.0 / 80.0).abs() < 1e-12);
        // Compacted: the three fallback pixels (4, 8, 2) in one group of 8: 8 x 8.
        assert!((j["lane_use_compacted"].as_f64().unwrap() - 14.0 / 64.0).abs() < 1e-12);
    }

    #[test]
    fn parts_are_differences_of_the_rows() {
        let row = |c: &str, ms: f64| json!({"config": c, "passes": {"interleaved.lighting": {"median": ms}}});
        let rows = [
            row("interleaved:4x4", 100.0),
            row("interleaved:4x4:parts=base", 10.0),
            row("interleaved:4x4:parts=lights", 40.0),
            row("interleaved:4x4:parts=filter", 70.0),
            row("interleaved:4x4:direct:parts=base", 1.0),
        ];
        let refs: Vec<&Value> = rows.iter().collect();
        let p = parts_json(&rows[0], &refs).unwrap();
        assert_eq!(p["base_ms"], 10.0);
        assert_eq!(p["lights_ms"], 30.0);
        assert_eq!(p["filter_ms"], 30.0);
        assert_eq!(p["fallback_ms"], 30.0);
        assert!(parts_json(&rows[1], &refs).is_none());
        // `direct` has its base only: no attribution.
        assert!(parts_json(&row("interleaved:4x4:direct", 5.0), &refs).is_none());
    }
}
