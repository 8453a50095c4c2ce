//! Error attribution by pixel class (issue 17): where a resolved checkerboard frame's error comes
//! from. Each pixel falls in one class by the resolve's debug bits (the spec's `:debug`, or
//! `cbr bench --attribution`), in this order of precedence:
//!
//! - `rendered`: shaded this frame (with `fused`, blended into its history);
//! - `rejected_id`: missing, its history rejected by the object-ID test (then filled spatially);
//! - `rejected_depth`: missing, its history rejected by the depth test (then filled spatially);
//! - `clamped_history`: missing, filled from a valid history that the neighbourhood clamp moved;
//! - `history`: missing, filled from a valid history as it was (or, in `ours`' moving path,
//!   blended with the spatial fill);
//! - `spatial`: missing and filled from its neighbours alone for any other reason (first frame,
//!   off-screen history, a mode without history).
//!
//! And, across the classes, `disoccluded`: pixels whose reference object ID differs from theirs in
//! any of the k frames before (the disocclusion mask of the bench). Per class: its share of the
//! pixels, its share of the frame's total error and its mean error, where a pixel's error is the
//! mean absolute difference of its three channels after the display transform (per pixel, no
//! neighbourhood), and its mean FLIP. FLIP's maps are filtered over a few pixels (its contrast
//! sensitivity and feature filters), so on a checkerboard, where the classes alternate from pixel
//! to pixel, FLIP spreads a missing pixel's error onto its rendered neighbours (measured: rendered
//! pixels' mean FLIP equals the frame's); the shares therefore use the per-pixel error.

use serde_json::json;

use cbr_render::resolve::{
    DBG_CLAMPED, DBG_REJECT_DEPTH, DBG_REJECT_ID, DBG_RENDERED, DBG_REPROJECTED, DBG_STILL,
};

pub const CLASSES: [&str; 6] = [
    "rendered",
    "rejected_id",
    "rejected_depth",
    "clamped_history",
    "history",
    "spatial",
];

/// The class (index into [`CLASSES`]) of a pixel with resolve debug bits `bits`.
pub fn class_of(bits: u32) -> usize {
    if bits & DBG_RENDERED != 0 {
        0
    } else if bits & DBG_REJECT_ID != 0 {
        1
    } else if bits & DBG_REJECT_DEPTH != 0 {
        2
    } else if bits & (DBG_REPROJECTED | DBG_STILL) != 0 && bits & DBG_CLAMPED != 0 {
        3
    } else if bits & (DBG_REPROJECTED | DBG_STILL) != 0 {
        4
    } else {
        5
    }
}

/// Pixel counts, error and FLIP sums over N classes and the disoccluded pixels, summed over the
/// measured frames: what every class attribution of bench.json holds (this one, the motion
/// classes of crate::motion_attribution).
#[derive(Clone, Debug, PartialEq)]
pub struct ClassSums<const N: usize> {
    pub pixels: [u64; N],
    pub error: [f64; N],
    pub flip: [f64; N],
    pub disocc_pixels: u64,
    pub disocc_error: f64,
    pub disocc_flip: f64,
    pub total_pixels: u64,
    pub total_error: f64,
}

impl<const N: usize> Default for ClassSums<N> {
    fn default() -> Self {
        ClassSums {
            pixels: [0; N],
            error: [0.0; N],
            flip: [0.0; N],
            disocc_pixels: 0,
            disocc_error: 0.0,
            disocc_flip: 0.0,
            total_pixels: 0,
            total_error: 0.0,
        }
    }
}

impl<const N: usize> ClassSums<N> {
    /// Adds one frame: each pixel's class, per-pixel error, FLIP map and the reference's
    /// disocclusion mask.
    pub fn add_classes(
        &mut self,
        classes: impl Iterator<Item = usize>,
        error: &[f32],
        flip: &[f32],
        disocc: &[bool],
    ) {
        for (((c, &e), &f), &d) in classes.zip(error).zip(flip).zip(disocc) {
            let (e, f) = (f64::from(e), f64::from(f));
            self.pixels[c] += 1;
            self.error[c] += e;
            self.flip[c] += f;
            if d {
                self.disocc_pixels += 1;
                self.disocc_error += e;
                self.disocc_flip += f;
            }
            self.total_pixels += 1;
            self.total_error += e;
        }
    }

    /// Per class (named by `names`) and `disoccluded`: `pixels` and `error` (shares of the
    /// frame's pixels and of its error sum), `error_mean` and `flip_mean` (null for an empty
    /// class).
    pub fn to_json(&self, names: &[&str; N]) -> serde_json::Value {
        let entry = |n: u64, e: f64, f: f64| {
            let share = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
            let mean = |v: f64| {
                if n > 0 {
                    json!(v / n as f64)
                } else {
                    json!(null)
                }
            };
            json!({
                "pixels": share(n as f64, self.total_pixels as f64),
                "error": share(e, self.total_error),
                "error_mean": mean(e),
                "flip_mean": mean(f),
            })
        };
        let mut m = serde_json::Map::new();
        for (k, name) in names.iter().enumerate() {
            m.insert(
                (*name).into(),
                entry(self.pixels[k], self.error[k], self.flip[k]),
            );
        }
        m.insert(
            "disoccluded".into(),
            entry(self.disocc_pixels, self.disocc_error, self.disocc_flip),
        );
        serde_json::Value::Object(m)
    }
}

/// The resolve's classes, summed over the measured frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attribution(pub ClassSums<{ CLASSES.len() }>);

impl Attribution {
    /// Adds one frame: its debug bits, per-pixel error, FLIP map and the reference's
    /// disocclusion mask.
    pub fn add(&mut self, bits: &[u32], error: &[f32], flip: &[f32], disocc: &[bool]) {
        self.0
            .add_classes(bits.iter().map(|&b| class_of(b)), error, flip, disocc);
    }

    /// bench.json's `attribution` ([`ClassSums::to_json`] over [`CLASSES`]).
    pub fn to_json(&self) -> serde_json::Value {
        self.0.to_json(&CLASSES)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cbr_render::resolve::{DBG_MISSING, DBG_SPATIAL};

    #[test]
    fn classes_follow_their_precedence() {
        assert_eq!(class_of(DBG_RENDERED | DBG_REPROJECTED | DBG_CLAMPED), 0);
        assert_eq!(
            class_of(DBG_MISSING | DBG_REJECT_ID | DBG_REJECT_DEPTH | DBG_SPATIAL),
            1
        );
        assert_eq!(class_of(DBG_MISSING | DBG_REJECT_DEPTH | DBG_SPATIAL), 2);
        assert_eq!(class_of(DBG_MISSING | DBG_REPROJECTED | DBG_CLAMPED), 3);
        assert_eq!(class_of(DBG_MISSING | DBG_STILL | DBG_CLAMPED), 3);
        assert_eq!(class_of(DBG_MISSING | DBG_REPROJECTED | DBG_SPATIAL), 4);
        assert_eq!(class_of(DBG_MISSING | DBG_STILL), 4);
        assert_eq!(class_of(DBG_MISSING | DBG_SPATIAL), 5);
        assert_eq!(class_of(DBG_MISSING), 5);
    }

    #[test]
    fn shares_add_up_and_name_the_error() {
        let bits = [
            DBG_RENDERED,
            DBG_MISSING | DBG_REPROJECTED,
            DBG_MISSING | DBG_REJECT_ID | DBG_SPATIAL,
            DBG_MISSING | DBG_SPATIAL,
        ];
        let err = [0.0, 0.1, 0.6, 0.3];
        let flip = [0.5; 4];
        let disocc = [false, false, true, true];
        let mut a = Attribution::default();
        a.add(&bits, &err, &flip, &disocc);
        a.add(&bits, &err, &flip, &disocc);
        let j = a.to_json();
        let total: f64 = CLASSES
            .iter()
            .map(|c| j[c]["pixels"].as_f64().unwrap())
            .sum();
        assert!((total - 1.0).abs() < 1e-12);
        let err: f64 = CLASSES
            .iter()
            .map(|c| j[c]["error"].as_f64().unwrap())
            .sum();
        assert!((err - 1.0).abs() < 1e-12);
        assert!((j["rejected_id"]["error"].as_f64().unwrap() - 0.6).abs() < 1e-6);
        assert!((j["rejected_id"]["error_mean"].as_f64().unwrap() - 0.6).abs() < 1e-6);
        assert!((j["rejected_id"]["flip_mean"].as_f64().unwrap() - 0.5).abs() < 1e-6);
        assert!(j["clamped_history"]["error_mean"].is_null());
        assert!((j["disoccluded"]["pixels"].as_f64().unwrap() - 0.5).abs() < 1e-12);
        assert!((j["disoccluded"]["error"].as_f64().unwrap() - 0.9).abs() < 1e-6);
    }
}
