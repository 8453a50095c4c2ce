//! Error attribution by motion (issue 55): where a frame's error comes from, by how far each
//! pixel moved since the previous frame (the technique's own velocity, so `native` and
//! `native+taa` fall into the same classes pixel for pixel). A temporal pass treats the three
//! classes differently (docs/post-aa.md: TAA keeps a still pixel's history unclipped, and the
//! current frame's weight rises with the speed up to 2 px per frame):
//!
//! - `still`: at most 1/64 px (TAA's still threshold);
//! - `slow`: up to 2 px per frame;
//! - `fast`: more than 2 px per frame.
//!
//! And, across the classes, `disoccluded`: pixels whose reference object ID differs from theirs
//! in any of the k frames before (the bench's disocclusion mask). Per class the same entries as
//! the resolve's attribution (crate::attribution): share of the pixels, share of the error sum
//! (the per-pixel error: mean |display(test) - display(reference)| over RGB), mean error and
//! mean FLIP. Unlike a checkerboard's classes, these are regions (an object, a wall), so the
//! mean FLIP of a class is meaningful and is what the docs compare between techniques.

pub const CLASSES: [&str; 3] = ["still", "slow", "fast"];

/// Up to this speed (pixels per frame) a pixel is still (cbr_render::post::taa's threshold).
pub const STILL: f32 = 1.0 / 64.0;
/// Above this speed a pixel is fast (TAA's full current-frame weight).
pub const FAST: f32 = 2.0;

/// The class (index into [`CLASSES`]) of a pixel that moved by `v` pixels.
pub fn class_of(v: [f32; 2]) -> usize {
    let s = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if s <= STILL {
        0
    } else if s <= FAST {
        1
    } else {
        2
    }
}

/// The motion classes, summed over the measured frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MotionAttribution(pub crate::attribution::ClassSums<{ CLASSES.len() }>);

impl MotionAttribution {
    /// Adds one frame: the technique's velocity, per-pixel error, FLIP map and the reference's
    /// disocclusion mask.
    pub fn add(&mut self, velocity: &[[f32; 2]], error: &[f32], flip: &[f32], disocc: &[bool]) {
        self.0
            .add_classes(velocity.iter().map(|&v| class_of(v)), error, flip, disocc);
    }

    /// bench.json's `motion_attribution` (the entries of crate::attribution's, over
    /// [`CLASSES`]).
    pub fn to_json(&self) -> serde_json::Value {
        self.0.to_json(&CLASSES)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_split_at_the_taa_thresholds() {
        assert_eq!(class_of([0.0, 0.0]), 0);
        assert_eq!(class_of([STILL, 0.0]), 0);
        assert_eq!(class_of([0.02, 0.0]), 1);
        assert_eq!(class_of([1.2, 1.6]), 1);
        assert_eq!(class_of([0.0, -2.01]), 2);
    }

    #[test]
    fn shares_add_up_and_means_are_per_class() {
        let v = [[0.0, 0.0], [0.5, 0.0], [3.0, 0.0], [3.0, 4.0]];
        let err = [0.1, 0.2, 0.3, 0.4];
        let flip = [0.5, 0.25, 0.125, 0.375];
        let disocc = [false, false, true, true];
        let mut a = MotionAttribution::default();
        a.add(&v, &err, &flip, &disocc);
        let j = a.to_json();
        let total: f64 = CLASSES
            .iter()
            .map(|c| j[c]["pixels"].as_f64().unwrap())
            .sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert!((j["fast"]["pixels"].as_f64().unwrap() - 0.5).abs() < 1e-12);
        assert!((j["fast"]["error"].as_f64().unwrap() - 0.7).abs() < 1e-6);
        assert!((j["fast"]["flip_mean"].as_f64().unwrap() - 0.25).abs() < 1e-6);
        assert!((j["still"]["flip_mean"].as_f64().unwrap() - 0.5).abs() < 1e-6);
        assert!((j["disoccluded"]["error_mean"].as_f64().unwrap() - 0.35).abs() < 1e-6);
        let empty = MotionAttribution::default().to_json();
        assert!(empty["slow"]["flip_mean"].is_null());
    }
}
