//! FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images") and HDR-FLIP
//! (Andersson et al. 2021), written here from the papers' algorithm and constants and checked
//! against NVIDIA's implementation (flip-evaluator) in tests/oracles.rs.
//!
//! LDR-FLIP per pixel, on linear RGB in [0, 1]:
//! 1. colour: to YCxCz; each channel filtered by its contrast sensitivity function (a sum of
//!    Gaussians, in degrees of visual angle); back to linear RGB, clamped; to CIELAB; Hunt-adjusted
//!    (a, b scaled by L/100); HyAB distance; raised to 0.7 and compressed against the distance between
//!    green and blue (80% of the range below 40% of it, 0.95 at 40%).
//! 2. features: on luminance, edges (first derivative of a Gaussian) and points (second derivative),
//!    sigma = 0.5 * 0.082 degrees; difference = max(edge, point) / sqrt(2), raised to 0.5.
//! 3. error = colour ^ (1 - features).
//!
//! All filters are separable here (the CSFs are sums of Gaussians, the feature filters products of
//! 1D derivatives and Gaussians), normalised exactly as their 2D forms; borders clamp.

use rayon::prelude::*;

use crate::planes::{PixelFn, Plane, Rgb, banded};

/// Pixels per degree of the default viewing condition: a 0.7 m wide, 3840-pixel display seen from
/// 0.7 m (the FLIP papers' "67 PPD").
pub fn default_ppd() -> f32 {
    (0.7 * (3840.0 / 0.7) * std::f64::consts::PI / 180.0) as f32
}

const WHITE: [f32; 3] = [0.950_428_55, 1.0, 1.088_900_4];
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
const FEATURE_SPACING_DEG: f32 = 0.082;

/// (a1, b1, a2, b2) of the achromatic, red-green and blue-yellow CSFs.
const CSF: [(f32, f32, f32, f32); 3] = [
    (1.0, 0.0047, 0.0, 1e-5),
    (1.0, 0.0053, 0.0, 1e-5),
    (34.1, 0.04, 13.5, 0.025),
];

fn mul(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [0.412_456_4, 0.357_576_1, 0.180_437_5],
    [0.212_672_9, 0.715_152_2, 0.072_175],
    [0.019_333_9, 0.119_192, 0.950_304_1],
];
const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266, 1.876_010_8, 0.041_556],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

const SRGB_LUT_SIZE: usize = 4096;

fn srgb_lut() -> &'static [f32] {
    static LUT: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        (0..=SRGB_LUT_SIZE)
            .map(|i| srgb_to_linear(i as f32 / SRGB_LUT_SIZE as f32))
            .collect()
    })
}

/// `srgb_to_linear` through a linearly interpolated table on [0, 1] (error < 3e-8; the exact
/// function outside): the decode otherwise costs three `powf` per pixel.
pub fn srgb_to_linear_fast(c: f32) -> f32 {
    if !(0.0..=1.0).contains(&c) {
        return srgb_to_linear(c);
    }
    let lut = srgb_lut();
    let x = c * SRGB_LUT_SIZE as f32;
    let i = (x as usize).min(SRGB_LUT_SIZE - 1);
    let f = x - i as f32;
    lut[i] + (lut[i + 1] - lut[i]) * f
}

fn xyz_to_ycxcz(x: [f32; 3]) -> [f32; 3] {
    let (xn, yn, zn) = (x[0] / WHITE[0], x[1] / WHITE[1], x[2] / WHITE[2]);
    [116.0 * yn - 16.0, 500.0 * (xn - yn), 200.0 * (yn - zn)]
}

fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let yy = (c[0] + 16.0) / 116.0;
    [
        WHITE[0] * (c[1] / 500.0 + yy),
        WHITE[1] * yy,
        WHITE[2] * (yy - c[2] / 200.0),
    ]
}

/// Cube root of a positive number: an exponent-dividing bit trick (~5% off) refined by two Halley
/// steps (cubic convergence), accurate to f32 rounding and ~4x faster than `f32::cbrt` here.
#[inline(always)]
fn cbrt_pos(x: f32) -> f32 {
    let mut y = f32::from_bits(x.to_bits() / 3 + 709_921_077);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

#[inline(always)]
fn lab_f(t: f32) -> f32 {
    const D: f32 = 6.0 / 29.0;
    // Branch-free so loops over planes vectorise; the cube root of a non-positive t is unused.
    let c = cbrt_pos(t.max(1e-30));
    let lin = t / (3.0 * D * D) + 4.0 / 29.0;
    if t > D * D * D { c } else { lin }
}

/// Hunt-adjusted CIELAB of a linear RGB colour.
#[inline(always)]
fn hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    let x = mul(&RGB_TO_XYZ, rgb);
    let (fx, fy, fz) = (
        lab_f(x[0] / WHITE[0]),
        lab_f(x[1] / WHITE[1]),
        lab_f(x[2] / WHITE[2]),
    );
    let l = 116.0 * fy - 16.0;
    let (a, b) = (500.0 * (fx - fy), 200.0 * (fy - fz));
    [l, 0.01 * l * a, 0.01 * l * b]
}

fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn normalise(v: &mut [f32]) {
    let s: f32 = v.iter().sum();
    v.iter_mut().for_each(|x| *x /= s);
}

/// Scales positive weights to sum to 1 and negative ones to sum to -1.
fn normalise_signed(v: &mut [f32]) {
    let p: f32 = v.iter().filter(|x| **x > 0.0).sum();
    let n: f32 = -v.iter().filter(|x| **x < 0.0).sum::<f32>();
    v.iter_mut()
        .for_each(|x| *x /= if *x > 0.0 { p } else { n });
}

/// The CSF filters: per channel, a list of (weight, 1D kernel) whose separable sum is the 2D kernel
/// normalised to 1.
fn csf_filters(ppd: f32) -> Vec<Vec<(f32, Vec<f32>)>> {
    let b_max = CSF.iter().map(|c| c.1.max(c.3)).fold(0.0, f32::max);
    let sigma_px = (b_max / (2.0 * std::f32::consts::PI.powi(2))).sqrt() * ppd;
    let r = (3.0 * sigma_px).ceil() as i32;
    let pi2 = std::f32::consts::PI.powi(2);
    CSF.iter()
        .map(|&(a1, b1, a2, b2)| {
            let terms: Vec<(f32, Vec<f32>)> = [(a1, b1), (a2, b2)]
                .into_iter()
                .filter(|&(a, _)| a > 0.0)
                .map(|(a, b)| {
                    let g: Vec<f32> = (-r..=r)
                        .map(|x| (-pi2 * (x as f32 / ppd).powi(2) / b).exp())
                        .collect();
                    (a * (std::f32::consts::PI / b).sqrt(), g)
                })
                .collect();
            let total: f32 = terms
                .iter()
                .map(|(a, g)| a * g.iter().sum::<f32>().powi(2))
                .sum();
            terms.into_iter().map(|(a, g)| (a / total, g)).collect()
        })
        .collect()
}

struct FeatureKernels {
    g: Vec<f32>,
    dg: Vec<f32>,
    ddg: Vec<f32>,
}

fn feature_kernels(ppd: f32) -> FeatureKernels {
    let sigma = 0.5 * FEATURE_SPACING_DEG * ppd;
    let r = (3.0 * sigma).ceil() as i32;
    let xs: Vec<f32> = (-r..=r).map(|x| x as f32).collect();
    let mut g: Vec<f32> = xs
        .iter()
        .map(|x| (-x * x / (2.0 * sigma * sigma)).exp())
        .collect();
    let mut dg: Vec<f32> = xs.iter().zip(&g).map(|(x, g)| -x * g).collect();
    let mut ddg: Vec<f32> = xs
        .iter()
        .zip(&g)
        .map(|(x, g)| (x * x / (sigma * sigma) - 1.0) * g)
        .collect();
    normalise(&mut g);
    normalise_signed(&mut dg);
    normalise_signed(&mut ddg);
    FeatureKernels { g, dg, ddg }
}

/// Precomputed filters for one viewing condition.
pub struct Flip {
    csf: Vec<Vec<(f32, Vec<f32>)>>,
    features: FeatureKernels,
    cmax: f32,
}

/// Per image: Hunt-adjusted Lab after CSF filtering, and edge and point feature magnitudes.
struct Prepared {
    lab: [Plane; 3],
    edge: Plane,
    point: Plane,
}

type RowSlices<'a> = (&'a [f32], &'a [f32], &'a [f32], &'a [f32], &'a [f32]);

impl Prepared {
    /// Row `y` of L, a, b, edge and point.
    fn row(&self, y: usize, w: usize) -> RowSlices<'_> {
        let s = y * w..(y + 1) * w;
        (
            &self.lab[0].data[s.clone()],
            &self.lab[1].data[s.clone()],
            &self.lab[2].data[s.clone()],
            &self.edge.data[s.clone()],
            &self.point.data[s],
        )
    }
}

impl Flip {
    pub fn new(ppd: f32) -> Flip {
        let cmax = hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(QC);
        Flip {
            csf: csf_filters(ppd),
            features: feature_kernels(ppd),
            cmax,
        }
    }

    fn prepare(&self, linear: &Rgb) -> Prepared {
        let ycc = linear.map(|p| xyz_to_ycxcz(mul(&RGB_TO_XYZ, p)));
        // Colour: CSF per channel, back to linear RGB, clamp, Hunt-adjusted Lab.
        let filtered: Vec<Plane> = ycc
            .c
            .par_iter()
            .zip(&self.csf)
            .map(|(plane, terms)| {
                let mut acc = Plane::new(plane.width, plane.height);
                for (w, k) in terms {
                    let f = plane.separable(k, k);
                    acc.data
                        .iter_mut()
                        .zip(&f.data)
                        .for_each(|(a, v)| *a += w * v);
                }
                acc
            })
            .collect();
        let mut lab = [
            filtered[0].clone(),
            filtered[1].clone(),
            filtered[2].clone(),
        ];
        {
            let [l, a, b] = &mut lab;
            l.data
                .par_chunks_mut(linear.width)
                .zip(a.data.par_chunks_mut(linear.width))
                .zip(b.data.par_chunks_mut(linear.width))
                .for_each(|((l, a), b)| {
                    for ((l, a), b) in l.iter_mut().zip(a.iter_mut()).zip(b.iter_mut()) {
                        let rgb =
                            mul(&XYZ_TO_RGB, ycxcz_to_xyz([*l, *a, *b])).map(|v| v.clamp(0.0, 1.0));
                        [*l, *a, *b] = hunt_lab(rgb);
                    }
                });
        }
        // Features on the unfiltered luminance, (Y' + 16) / 116 = Y / Yw.
        let lum = Plane::from_fn(linear.width, linear.height, |i| {
            (ycc.c[0].data[i] + 16.0) / 116.0
        });
        let k = &self.features;
        // Three row passes serve the four filters: rows(g) feeds both y-derivatives.
        let (rows_g, (rows_dg, rows_ddg)) = rayon::join(
            || lum.convolve_rows(&k.g),
            || rayon::join(|| lum.convolve_rows(&k.dg), || lum.convolve_rows(&k.ddg)),
        );
        let ((ex, ey), (px, py)) = rayon::join(
            || {
                rayon::join(
                    || rows_dg.convolve_cols(&k.g),
                    || rows_g.convolve_cols(&k.dg),
                )
            },
            || {
                rayon::join(
                    || rows_ddg.convolve_cols(&k.g),
                    || rows_g.convolve_cols(&k.ddg),
                )
            },
        );
        let mag = |a: &Plane, b: &Plane| {
            Plane::from_fn(a.width, a.height, |i| {
                (a.data[i] * a.data[i] + b.data[i] * b.data[i]).sqrt()
            })
        };
        Prepared {
            lab,
            edge: mag(&ex, &ey),
            point: mag(&px, &py),
        }
    }

    /// The largest filter radius: the halo a band needs.
    fn halo(&self) -> usize {
        self.csf[0][0].1.len().max(self.features.g.len()) / 2
    }

    /// LDR-FLIP of two images whose pixels `to_r` and `to_t` map to linear RGB in [0, 1], in bands.
    pub fn error_map(
        &self,
        reference: &Rgb,
        to_r: impl PixelFn,
        test: &Rgb,
        to_t: impl PixelFn,
    ) -> Plane {
        let (w, h) = (reference.width, reference.height);
        banded(w, h, self.halo(), |y0, y1| {
            let (r, t) = (
                reference.rows_mapped(y0, y1, &to_r),
                test.rows_mapped(y0, y1, &to_t),
            );
            self.band_error(&r, &t)
        })
    }

    fn band_error(&self, reference: &Rgb, test: &Rgb) -> Plane {
        let (r, t) = rayon::join(|| self.prepare(reference), || self.prepare(test));
        let cmax = self.cmax;
        let (w, h) = (reference.width, reference.height);
        let mut out = Plane::new(w, h);
        out.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            let (rl, ra, rb, re, rp) = r.row(y, w);
            let (tl, ta, tb, te, tp) = t.row(y, w);
            for (x, o) in row.iter_mut().enumerate() {
                let de = hyab([rl[x], ra[x], rb[x]], [tl[x], ta[x], tb[x]]);
                let de = if de > 0.0 { de.powf(QC) } else { 0.0 };
                let colour = if de < PC * cmax {
                    PT / (PC * cmax) * de
                } else {
                    PT + (de - PC * cmax) / (cmax - PC * cmax) * (1.0 - PT)
                };
                let fe = (re[x] - te[x]).abs().max((rp[x] - tp[x]).abs());
                // The feature exponent is 0.5: a square root.
                let feature = (fe / std::f32::consts::SQRT_2).sqrt();
                *o = if colour == 0.0 || feature == 0.0 {
                    colour
                } else {
                    colour.powf(1.0 - feature)
                };
            }
        });
        out
    }

    /// LDR-FLIP of two sRGB-encoded images with values in [0, 1].
    pub fn ldr(&self, reference: &Rgb, test: &Rgb) -> Plane {
        let decode = |p: [f32; 3]| p.map(srgb_to_linear_fast);
        self.error_map(reference, decode, test, decode)
    }
}

/// The exposure range HDR-FLIP evaluates.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HdrExposures {
    pub start: f32,
    pub stop: f32,
    pub count: u32,
}

/// FLIP's ACES tone curve (Narkowicz's fit with the input pre-scaled by 0.6), clamped to [0, 1].
fn aces(x: f32) -> f32 {
    const A: f32 = 0.6 * 0.6 * 2.51;
    const B: f32 = 0.6 * 0.03;
    const D: f32 = 0.6 * 0.6 * 2.43;
    const E: f32 = 0.6 * 0.59;
    const F: f32 = 0.14;
    ((A * x * x + B * x) / (D * x * x + E * x + F)).clamp(0.0, 1.0)
}

/// The input that the tone curve maps to `y` (positive root of the quadratic).
fn aces_inverse(y: f32) -> f32 {
    let (a, b, d, e, f) = (
        0.6f64 * 0.6 * 2.51,
        0.6f64 * 0.03,
        0.6f64 * 0.6 * 2.43,
        0.6f64 * 0.59,
        0.14f64,
    );
    let y = f64::from(y);
    let (qa, qb, qc) = (a - y * d, b - y * e, -y * f);
    ((-qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa)) as f32
}

impl HdrExposures {
    /// From the reference: the start exposure maps its brightest luminance, the stop exposure its
    /// median luminance (the upper one for even counts), to 0.85 after tone mapping; one exposure
    /// per stop, at least two. A median of 0 is raised to the smallest positive luminance.
    pub fn for_reference(reference: &Rgb, to_linear: impl PixelFn) -> HdrExposures {
        let mut lum: Vec<f32> = (0..reference.width * reference.height)
            .into_par_iter()
            .map(|i| {
                let p = to_linear(reference.pixel(i));
                0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
            })
            .collect();
        let n = lum.len();
        let max = lum.iter().copied().fold(0.0f32, f32::max);
        lum.select_nth_unstable_by(n / 2, f32::total_cmp);
        let mut median = lum[n / 2];
        if median <= 0.0 {
            median = lum
                .iter()
                .copied()
                .filter(|&v| v > 0.0)
                .fold(f32::INFINITY, f32::min);
        }
        let x = aces_inverse(0.85);
        if !(max > 0.0 && median.is_finite()) {
            return HdrExposures {
                start: 0.0,
                stop: 0.0,
                count: 2,
            };
        }
        let (start, stop) = ((x / max).log2(), (x / median).log2());
        HdrExposures {
            start,
            stop,
            count: ((stop - start).ceil() as u32).max(2),
        }
    }
}

impl Flip {
    /// HDR-FLIP of two linear HDR images (negative values clamped to 0): the maximum over the
    /// exposure range of LDR-FLIP of the ACES-tone-mapped images.
    pub fn hdr(
        &self,
        reference: &Rgb,
        to_r: impl PixelFn,
        test: &Rgb,
        to_t: impl PixelFn,
        exposures: Option<HdrExposures>,
    ) -> (Plane, HdrExposures) {
        let ex = exposures.unwrap_or_else(|| HdrExposures::for_reference(reference, &to_r));
        let map = banded(reference.width, reference.height, self.halo(), |y0, y1| {
            let mut worst = Plane::new(reference.width, y1 - y0);
            for i in 0..ex.count {
                let c = ex.start + i as f32 * (ex.stop - ex.start) / (ex.count - 1) as f32;
                let scale = c.exp2();
                let tone = |p: [f32; 3]| p.map(|v| aces(v.max(0.0) * scale));
                let e = self.band_error(
                    &reference.rows_mapped(y0, y1, |p| tone(to_r(p))),
                    &test.rows_mapped(y0, y1, |p| tone(to_t(p))),
                );
                worst
                    .data
                    .iter_mut()
                    .zip(&e.data)
                    .for_each(|(w, v)| *w = w.max(*v));
            }
            worst
        });
        (map, ex)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ppd_and_kernel_sizes_follow_the_viewing_condition() {
        assert!((default_ppd() - 67.0206).abs() < 1e-3);
        let f = csf_filters(default_ppd());
        assert_eq!(
            f[0][0].1.len(),
            21,
            "CSF radius ceil(3 sigma) = 10 at 67 ppd"
        );
        assert_eq!(f[2].len(), 2, "blue-yellow is a sum of two Gaussians");
        let k = feature_kernels(default_ppd());
        assert_eq!(k.g.len(), 19);
        assert!((k.dg.iter().filter(|x| **x > 0.0).sum::<f32>() - 1.0).abs() < 1e-6);
        assert!((k.ddg.iter().filter(|x| **x < 0.0).sum::<f32>() + 1.0).abs() < 1e-6);
    }

    #[test]
    fn fast_cube_root_is_exact_to_rounding() {
        for i in 1..100_000 {
            let x = i as f32 * 1e-5 + (i as f32).powi(2) * 1e-3;
            let (a, b) = (cbrt_pos(x), x.cbrt());
            assert!((a - b).abs() <= 2.0 * f32::EPSILON * b, "{x}: {a} vs {b}");
        }
    }

    #[test]
    fn srgb_table_matches_the_function() {
        let worst = (0..=100_000)
            .map(|i| i as f32 / 100_000.0)
            .map(|c| (srgb_to_linear_fast(c) - srgb_to_linear(c)).abs())
            .fold(0.0, f32::max);
        assert!(worst < 5e-7, "{worst}");
        assert_eq!(srgb_to_linear_fast(2.0), srgb_to_linear(2.0));
    }

    #[test]
    fn aces_inverse_inverts() {
        let x = aces_inverse(0.85);
        assert!((aces(x) - 0.85).abs() < 1e-5, "{x}");
    }

    #[test]
    fn identical_images_have_zero_error_and_errors_are_in_unit_range() {
        let (w, h) = (24, 16);
        let a = Rgb::from_interleaved(
            w,
            h,
            &(0..w * h * 3)
                .map(|i| ((i * 7919) % 101) as f32 / 100.0)
                .collect::<Vec<_>>(),
        );
        let b = Rgb::from_interleaved(
            w,
            h,
            &(0..w * h * 3)
                .map(|i| ((i * 104_729) % 97) as f32 / 96.0)
                .collect::<Vec<_>>(),
        );
        let flip = Flip::new(default_ppd());
        assert!(flip.ldr(&a, &a).data.iter().all(|&e| e == 0.0));
        let e = flip.ldr(&a, &b);
        assert!(e.data.iter().all(|&e| (0.0..=1.0).contains(&e)));
        assert!(e.data.iter().any(|&e| e > 0.1));
    }
}
