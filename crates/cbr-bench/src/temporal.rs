//! Temporal metrics of a bench row: the disocclusion mask (pixels whose reference object ID
//! changed within the last k frames) and the frame-to-frame change of the error (flicker), of
//! the technique and of the reference. docs/metrics.md "Bench: temporal columns".

use std::collections::VecDeque;

use anyhow::{Context, Result};
use cbr_gpu::Gpu;
use cbr_metrics::{CompareOptions, InputImage, Rgb, display_values, mean_abs_change, signed_error};
use cbr_render::{FrameOutput, RenderSettings, Renderer};
use cbr_scene::Scene;

/// Frames of ID history the disocclusion mask looks back over, unless `--disocclusion-frames`.
pub const DEFAULT_DISOCCLUSION_FRAMES: u32 = 4;

/// The object IDs (`ids[..][0]`, 0 = background) of a frame.
pub fn object_ids(out: &FrameOutput) -> Vec<u32> {
    out.ids.iter().map(|id| id[0]).collect()
}

/// Pixels whose object ID in `current` differs from their ID in any frame of `history` (the
/// frames just before, as many as there are).
pub fn disocclusion_mask<'a>(
    history: impl IntoIterator<Item = &'a Vec<u32>>,
    current: &[u32],
) -> Vec<bool> {
    let mut mask = vec![false; current.len()];
    for before in history {
        for ((m, a), b) in mask.iter_mut().zip(current).zip(before) {
            *m |= a != b;
        }
    }
    mask
}

/// The share of a mask's pixels that are set.
pub fn fraction(mask: &[bool]) -> f64 {
    if mask.is_empty() {
        return 0.0;
    }
    mask.iter().filter(|m| **m).count() as f64 / mask.len() as f64
}

/// The reference's object IDs of the last `k` frames, oldest first: each frame's mask compares
/// it with them, then it joins them.
pub struct IdHistory {
    k: usize,
    frames: VecDeque<Vec<u32>>,
}

impl IdHistory {
    pub fn new(k: u32) -> IdHistory {
        IdHistory {
            k: k as usize,
            frames: VecDeque::with_capacity(k as usize + 1),
        }
    }

    /// Frames held (fewer than k only near frame 0, which has no frames before it).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Adds the next frame's IDs (forgetting the oldest beyond k).
    pub fn push(&mut self, ids: Vec<u32>) {
        self.frames.push_back(ids);
        while self.frames.len() > self.k {
            self.frames.pop_front();
        }
    }

    /// The mask of the next frame against the held frames, then adds it.
    pub fn next(&mut self, ids: Vec<u32>) -> Vec<bool> {
        let mask = disocclusion_mask(&self.frames, &ids);
        self.push(ids);
        mask
    }
}

/// Where the IDs of the frames before the first measured one came from when the reference did
/// not render them (a cached reference skips its warm-up frames).
#[derive(Clone, Debug, serde::Serialize)]
pub struct IdStandIn {
    /// Native frames rendered for their IDs, first..=last (the last is the first measured frame).
    pub native_frames: [u32; 2],
    /// The texture LOD bias of that native raster: the reference's (alpha-tested surfaces
    /// depend on it).
    pub lod_bias: f32,
    /// On the first measured frame: pixels whose native ID differs from the reference's.
    pub mismatched_pixels: usize,
    pub pixels: usize,
}

/// The object IDs of frames `first..=last` from a native raster with the given LOD bias: the
/// pixel-centre IDs a supersampled reference (whose centre sample is that raster) gives, at the
/// cost of one native frame each.
pub fn native_ids(
    gpu: &Gpu,
    scene: &Scene,
    (width, height): (u32, u32),
    lod_bias: f32,
    first: u32,
    last: u32,
) -> Result<Vec<Vec<u32>>> {
    let mut s = RenderSettings::native(width, height);
    s.lod_bias = Some(lod_bias);
    let shaders = cbr_render::shader_library();
    let mut r = Renderer::new(gpu, &shaders, scene, s)
        .context("setting up the native raster for the disocclusion mask's IDs")?;
    (first..=last)
        .map(|f| Ok(object_ids(&r.render(scene, f)?)))
        .collect()
}

/// Per measured frame (after the first): flicker = mean |e_t - e_(t-1)| with e = test -
/// reference in display values, and how much each image changed, mean |x_t - x_(t-1)|.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Change {
    pub flicker: f64,
    pub change: f64,
    pub ref_change: f64,
}

/// The previous measured frame's display values (reference, test, error).
#[derive(Default)]
pub struct Stability {
    previous: Option<(Rgb, Rgb, Rgb)>,
}

impl Stability {
    /// Takes the next measured frame; `None` for the first.
    pub fn next(
        &mut self,
        reference: &InputImage,
        test: &InputImage,
        o: &CompareOptions,
    ) -> Result<Option<Change>> {
        let (r, x) = (display_values(reference, o), display_values(test, o));
        let e = signed_error(&r, &x);
        let change = match &self.previous {
            Some((pr, px, pe)) => Some(Change {
                flicker: mean_abs_change(&e, pe)?,
                change: mean_abs_change(&x, px)?,
                ref_change: mean_abs_change(&r, pr)?,
            }),
            None => None,
        };
        self.previous = Some((r, x, e));
        Ok(change)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4x1 frame of object IDs.
    fn f(ids: [u32; 4]) -> Vec<u32> {
        ids.to_vec()
    }

    #[test]
    fn the_mask_counts_exactly_the_pixels_whose_id_changed_within_k_frames() {
        // Pixel 0 never changes; pixel 1 changes at frame 1; pixel 2 at frame 3; pixel 3 changes
        // at frame 1 and changes back at frame 2 (covered, then uncovered).
        let seq = [
            f([1, 1, 2, 0]),
            f([1, 5, 2, 7]),
            f([1, 5, 2, 0]),
            f([1, 5, 3, 0]),
            f([1, 5, 3, 0]),
            f([1, 5, 3, 0]),
            f([1, 5, 3, 0]),
            f([1, 5, 3, 0]),
        ];
        let k = 2;
        let mut h = IdHistory::new(k);
        let masks: Vec<Vec<bool>> = seq.iter().map(|ids| h.next(ids.clone())).collect();
        let t = true;
        let o = false;
        assert_eq!(masks[0], [o, o, o, o], "frame 0 has nothing before it");
        assert_eq!(masks[1], [o, t, o, t]);
        // Frame 2 against 0 and 1: pixel 1 differs from frame 0; pixel 3 equals frame 0 but
        // differs from frame 1.
        assert_eq!(masks[2], [o, t, o, t]);
        // Frame 3 against 1 and 2 (k = 2: frame 0 is out of the window).
        assert_eq!(masks[3], [o, o, t, t]);
        assert_eq!(masks[4], [o, o, t, o]);
        // The k boundary: pixel 2 changed at frame 3, so frame 5 (= 3 + k) no longer sees it.
        assert_eq!(masks[5], [o, o, o, o]);
        assert_eq!(h.len(), 2);
        assert_eq!(fraction(&masks[3]), 0.5);
        assert_eq!(fraction(&masks[5]), 0.0);
        assert_eq!(fraction(&[]), 0.0);
        // k = 3 still sees frame 3's change at frame 5, not at 6.
        let mut h = IdHistory::new(3);
        let masks: Vec<Vec<bool>> = seq.iter().map(|ids| h.next(ids.clone())).collect();
        assert_eq!(masks[5], [o, o, t, o]);
        assert_eq!(masks[6], [o, o, o, o]);
        assert_eq!(h.len(), 3);
    }

    fn image(v: [f32; 4]) -> InputImage {
        let rgb: Vec<f32> = v.iter().flat_map(|x| [*x; 3]).collect();
        InputImage {
            path: "x".into(),
            layer: String::new(),
            channels: vec![],
            rgb: Rgb::from_interleaved(4, 1, &rgb),
            encoding: cbr_metrics::Encoding::Srgb,
        }
    }

    #[test]
    fn flicker_and_change_have_the_known_answers() {
        // Display values as stored (sRGB inputs). The reference moves by 0.2 at pixel 0; the
        // test follows it there, but also toggles pixel 3 by 0.4 (flicker the reference lacks).
        let o = CompareOptions::default();
        let mut s = Stability::default();
        let r0 = image([0.2, 0.5, 0.5, 0.5]);
        let r1 = image([0.4, 0.5, 0.5, 0.5]);
        let x0 = image([0.2, 0.5, 0.5, 0.3]);
        let x1 = image([0.4, 0.5, 0.5, 0.7]);
        assert_eq!(s.next(&r0, &x0, &o).expect("same size"), None);
        let c = s
            .next(&r1, &x1, &o)
            .expect("same size")
            .expect("second frame");
        let close = |a: f64, b: f64| (a - b).abs() < 1e-6;
        assert!(close(c.ref_change, 0.2 / 4.0), "{c:?}");
        assert!(close(c.change, (0.2 + 0.4) / 4.0), "{c:?}");
        // e goes -0.2 -> +0.2 at pixel 3 only.
        assert!(close(c.flicker, 0.4 / 4.0), "{c:?}");
        // A test that tracks the reference exactly does not flicker.
        let mut s = Stability::default();
        s.next(&r0, &r0, &o).expect("same size");
        let c = s.next(&r1, &r1, &o).expect("same size").expect("second");
        assert_eq!(c.flicker, 0.0);
        assert_eq!(c.change, c.ref_change);
    }
}
