//! Error attribution for `analytic` frames (issue 14): where its error comes from, by what the
//! resolve composited in each pixel (the `analytic` layers), in this order of precedence:
//!
//! - `empty`: no fragment composited (the background alone);
//! - `overflow`: fragments beyond the K kept were merged into the tails;
//! - `one_full`: one fragment covering the whole pixel (texture filtering and shading alone);
//! - `one_partial`: one fragment and the background;
//! - `two`: two fragments composited (abutting triangles of one mesh, or two surfaces);
//! - `three_plus`: three or more.
//!
//! Per class, over all pixels and over the reference's edge pixels (the pixels of the bench's
//! edge FLIP): its share of the pixels, its share of the error and its mean FLIP. The error of a
//! pixel is the attribution's (crate::attribution): the mean absolute difference of its three
//! channels after the display transform.

use serde_json::json;

use cbr_render::AnalyticLayers;

pub const CLASSES: [&str; 6] = [
    "empty",
    "overflow",
    "one_full",
    "one_partial",
    "two",
    "three_plus",
];

/// The class (index into [`CLASSES`]) of a pixel: fragments composited, fragments beyond K, and
/// the coverage layer's edge flag (a composited fragment covers the pixel partly, or the
/// background shows).
pub fn class_of(visible: u32, overflow: u32, edge: bool) -> usize {
    match (visible, overflow, edge) {
        (0, _, _) => 0,
        (_, o, _) if o > 0 => 1,
        (1, _, false) => 2,
        (1, _, true) => 3,
        (2, _, _) => 4,
        _ => 5,
    }
}

/// Pixel counts, error and FLIP sums per class, over all pixels and over the reference's edge
/// pixels, summed over the measured frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnalyticAttribution {
    /// [all pixels, the reference's edge pixels] x class.
    pub pixels: [[u64; CLASSES.len()]; 2],
    pub error: [[f64; CLASSES.len()]; 2],
    pub flip: [[f64; CLASSES.len()]; 2],
}

impl AnalyticAttribution {
    /// Adds one frame: its analytic layers and coverage edge flags, the per-pixel error, the FLIP
    /// map and the reference's edge mask.
    pub fn add(
        &mut self,
        layers: &AnalyticLayers,
        own_edge: &[u8],
        error: &[f32],
        flip: &[f32],
        ref_edge: &[bool],
    ) {
        for i in 0..error.len() {
            let c = class_of(layers.visible[i], layers.overflow[i], own_edge[i] != 0);
            let (e, f) = (f64::from(error[i]), f64::from(flip[i]));
            for set in 0..2 {
                if set == 1 && !ref_edge[i] {
                    continue;
                }
                self.pixels[set][c] += 1;
                self.error[set][c] += e;
                self.flip[set][c] += f;
            }
        }
    }

    /// bench.json's `analytic_attribution`: for `all` pixels and for the reference's `edge`
    /// pixels, per class `pixels` and `error` (shares of the set's pixels and error sum) and
    /// `flip_mean` (null for an empty class).
    pub fn to_json(&self) -> serde_json::Value {
        let set = |s: usize| {
            let (n_all, e_all) = (
                self.pixels[s].iter().sum::<u64>() as f64,
                self.error[s].iter().sum::<f64>(),
            );
            let share = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
            let mut m = serde_json::Map::new();
            for (k, name) in CLASSES.iter().enumerate() {
                let n = self.pixels[s][k];
                m.insert(
                    (*name).into(),
                    json!({
                        "pixels": share(n as f64, n_all),
                        "error": share(self.error[s][k], e_all),
                        "flip_mean": if n > 0 { json!(self.flip[s][k] / n as f64) } else { json!(null) },
                    }),
                );
            }
            serde_json::Value::Object(m)
        };
        json!({"all": set(0), "edge": set(1)})
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_follow_their_precedence() {
        assert_eq!(class_of(0, 3, true), 0);
        assert_eq!(class_of(2, 1, false), 1);
        assert_eq!(class_of(1, 0, false), 2);
        assert_eq!(class_of(1, 0, true), 3);
        assert_eq!(class_of(2, 0, true), 4);
        assert_eq!(class_of(3, 0, false), 5);
        assert_eq!(class_of(9, 0, true), 5);
    }

    #[test]
    fn shares_add_up_over_all_and_over_edge_pixels() {
        let layers = AnalyticLayers {
            visible: vec![1, 1, 2, 0],
            overflow: vec![0, 0, 0, 0],
            fragments: vec![1, 1, 2, 0],
            ..Default::default()
        };
        let own_edge = [0u8, 1, 1, 1];
        let err = [0.1f32, 0.3, 0.6, 0.0];
        let flip = [0.2f32, 0.4, 0.8, 0.0];
        let ref_edge = [false, true, true, false];
        let mut a = AnalyticAttribution::default();
        a.add(&layers, &own_edge, &err, &flip, &ref_edge);
        let j = a.to_json();
        for set in ["all", "edge"] {
            let p: f64 = CLASSES
                .iter()
                .map(|c| j[set][c]["pixels"].as_f64().unwrap())
                .sum();
            let e: f64 = CLASSES
                .iter()
                .map(|c| j[set][c]["error"].as_f64().unwrap())
                .sum();
            assert!(
                (p - 1.0).abs() < 1e-12 && (e - 1.0).abs() < 1e-12,
                "{set}: {j}"
            );
        }
        assert!((j["all"]["one_full"]["pixels"].as_f64().unwrap() - 0.25).abs() < 1e-12);
        assert!((j["all"]["two"]["error"].as_f64().unwrap() - 0.6).abs() < 1e-6);
        assert!(j["edge"]["one_full"]["flip_mean"].is_null());
        assert!((j["edge"]["two"]["error"].as_f64().unwrap() - 2.0 / 3.0).abs() < 1e-6);
        assert!((j["edge"]["one_partial"]["flip_mean"].as_f64().unwrap() - 0.4).abs() < 1e-6);
    }
}
