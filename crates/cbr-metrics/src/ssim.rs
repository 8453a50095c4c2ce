//! SSIM exactly as Wang et al. 2004 and scikit-image's `structural_similarity(gaussian_weights=True,
//! sigma=1.5, use_sample_covariance=False, data_range=1)`: 11x11 Gaussian window (sigma 1.5,
//! truncated at 3.5 sigma), K1 = 0.01, K2 = 0.03, computed per RGB channel of the display image and
//! averaged over the channels; the map's mean excludes the 5-pixel border (as scikit-image crops it).

use rayon::prelude::*;

use crate::planes::{PixelFn, Plane, Rgb, banded};

pub const RADIUS: usize = 5;
const SIGMA: f32 = 1.5;
const C1: f32 = 0.01 * 0.01;
const C2: f32 = 0.03 * 0.03;

fn window() -> Vec<f32> {
    let mut w: Vec<f32> = (-(RADIUS as i32)..=RADIUS as i32)
        .map(|x| (-(x * x) as f32 / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    let s: f32 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= s);
    w
}

/// The SSIM map averaged over the channels, for images whose pixels `to_r` and `to_t` map to
/// display values in [0, 1]. Border pixels use clamped windows; `mean_interior` excludes them.
pub fn ssim_map(reference: &Rgb, to_r: impl PixelFn, test: &Rgb, to_t: impl PixelFn) -> Plane {
    let g = window();
    banded(reference.width, reference.height, RADIUS, |y0, y1| {
        let (r, t) = (
            reference.rows_mapped(y0, y1, &to_r),
            test.rows_mapped(y0, y1, &to_t),
        );
        let w = r.width;
        let mut acc = Plane::new(w, y1 - y0);
        for c in 0..3 {
            let (x, y) = (&r.c[c], &t.c[c]);
            let prod =
                |a: &Plane, b: &Plane| Plane::from_fn(w, a.height, |i| a.data[i] * b.data[i]);
            let (ux, uy) = (x.separable(&g, &g), y.separable(&g, &g));
            let (uxx, uyy, uxy) = (
                prod(x, x).separable(&g, &g),
                prod(y, y).separable(&g, &g),
                prod(x, y).separable(&g, &g),
            );
            acc.data.par_iter_mut().enumerate().for_each(|(i, a)| {
                let (mx, my) = (ux.data[i], uy.data[i]);
                let (vx, vy, vxy) = (
                    uxx.data[i] - mx * mx,
                    uyy.data[i] - my * my,
                    uxy.data[i] - mx * my,
                );
                *a += ((2.0 * mx * my + C1) * (2.0 * vxy + C2))
                    / ((mx * mx + my * my + C1) * (vx + vy + C2))
                    / 3.0;
            });
        }
        acc
    })
}

/// Mean of an SSIM map over the interior (the border of `RADIUS` pixels excluded) and valid pixels.
/// `None` when the image is too small to have an interior.
pub fn mean_interior(map: &Plane, valid: Option<&[bool]>) -> Option<f64> {
    let (w, h) = (map.width, map.height);
    if w <= 2 * RADIUS || h <= 2 * RADIUS {
        return None;
    }
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in RADIUS..h - RADIUS {
        for x in RADIUS..w - RADIUS {
            let i = y * w + x;
            if valid.is_none_or(|v| v[i]) {
                sum += f64::from(map.data[i]);
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_score_one_and_noise_lowers_it() {
        let (w, h) = (32, 24);
        let a = Rgb::from_interleaved(
            w,
            h,
            &(0..w * h * 3)
                .map(|i| ((i * 31) % 17) as f32 / 16.0)
                .collect::<Vec<_>>(),
        );
        let id = |p: [f32; 3]| p;
        let s = mean_interior(&ssim_map(&a, id, &a, id), None).expect("ssim");
        assert!((s - 1.0).abs() < 1e-6, "{s}");
        let b = a.map(|p| p.map(|v| (v * 0.8 + 0.1).min(1.0)));
        let s2 = mean_interior(&ssim_map(&a, id, &b, id), None).expect("ssim");
        assert!(s2 < 0.999, "{s2}");
        assert!(mean_interior(&Plane::new(10, 10), None).is_none());
    }
}
