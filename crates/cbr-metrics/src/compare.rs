//! Comparing two images or two sequences of frames: which metrics, on which values, pooled how.
//!
//! Values: MSE, relMSE and HDR-FLIP on linear values (EXR as stored; LDR files sRGB-decoded);
//! PSNR, SSIM and LDR-FLIP on display values (EXR through the display transform; LDR files as
//! stored). Pixels where either image has a non-finite channel are counted, read as 0 by the
//! filters, and left out of every average and percentile.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::display::DisplayTransform;
use crate::error::MetricsError;
use crate::flip::{Flip, HdrExposures, default_ppd, srgb_to_linear_fast};
use crate::input::{Encoding, InputImage};
use crate::planes::{Plane, Rgb};
use crate::ssim;
use crate::stats::{Pooled, pool};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Metric {
    Psnr,
    Ssim,
    Flip,
    HdrFlip,
    Mse,
    RelMse,
}

impl Metric {
    pub const ALL: [Metric; 6] = [
        Metric::Psnr,
        Metric::Ssim,
        Metric::Flip,
        Metric::HdrFlip,
        Metric::Mse,
        Metric::RelMse,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "psnr",
            Metric::Ssim => "ssim",
            Metric::Flip => "flip",
            Metric::HdrFlip => "hdrflip",
            Metric::Mse => "mse",
            Metric::RelMse => "relmse",
        }
    }

    pub fn parse(s: &str) -> Option<Metric> {
        Metric::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
    }

    /// PSNR and SSIM grow with quality; the others are errors.
    pub fn higher_is_better(self) -> bool {
        matches!(self, Metric::Psnr | Metric::Ssim)
    }
}

#[derive(Clone, Debug)]
pub struct CompareOptions {
    pub metrics: Vec<Metric>,
    /// (x, y, w, h) applied to both images first.
    pub crop: Option<[usize; 4]>,
    pub display: DisplayTransform,
    pub ppd: f32,
    pub relmse_eps: f32,
    /// Keep the FLIP (or HDR-FLIP) and absolute-difference maps in the result.
    pub keep_maps: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            metrics: Metric::ALL.to_vec(),
            crop: None,
            display: DisplayTransform::default(),
            ppd: default_ppd(),
            relmse_eps: 0.01,
            keep_maps: false,
        }
    }
}

/// A PSNR in dB; identical images give +inf, written as the string "inf" in JSON.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Db(pub f64);

impl Serialize for Db {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.is_finite() {
            s.serialize_f64(self.0)
        } else {
            s.serialize_str("inf")
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Source {
    pub path: PathBuf,
    pub encoding: Encoding,
    #[serde(skip_serializing_if = "String::is_empty")]
    pub layer: String,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<String>,
    pub nonfinite_pixels: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct HdrFlipResult {
    #[serde(flatten)]
    pub pooled: Pooled,
    pub exposures: HdrExposures,
}

/// Everything measured for one pair.
#[derive(Clone, Debug, Serialize)]
pub struct PairResult {
    pub reference: Source,
    pub test: Source,
    pub width: usize,
    pub height: usize,
    /// Pixels left out of every average (non-finite in either image).
    pub excluded_pixels: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub psnr: Option<Db>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ssim: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip: Option<Pooled>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hdrflip: Option<HdrFlipResult>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mse: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relmse: Option<f64>,
    #[serde(skip)]
    pub flip_map: Option<Plane>,
    #[serde(skip)]
    pub diff_map: Option<Plane>,
}

impl PairResult {
    /// The headline value of a metric (FLIP: the mean).
    pub fn value(&self, m: Metric) -> Option<f64> {
        match m {
            Metric::Psnr => self.psnr.map(|d| d.0),
            Metric::Ssim => self.ssim,
            Metric::Flip => self.flip.map(|p| p.mean),
            Metric::HdrFlip => self.hdrflip.as_ref().map(|h| h.pooled.mean),
            Metric::Mse => self.mse,
            Metric::RelMse => self.relmse,
        }
    }
}

fn finite(p: [f32; 3]) -> bool {
    p.iter().all(|v| v.is_finite())
}

fn zero_nonfinite(p: [f32; 3]) -> [f32; 3] {
    p.map(|v| if v.is_finite() { v } else { 0.0 })
}

pub fn compare_images(
    reference: &InputImage,
    test: &InputImage,
    o: &CompareOptions,
) -> Result<PairResult, MetricsError> {
    let (r0, t0) = (&reference.rgb, &test.rgb);
    if (r0.width, r0.height) != (t0.width, t0.height) {
        return Err(MetricsError::Mismatch(format!(
            "size mismatch: {} is {}x{}, {} is {}x{}",
            reference.path.display(),
            r0.width,
            r0.height,
            test.path.display(),
            t0.width,
            t0.height
        )));
    }
    let cropped;
    let (r, t) = match o.crop {
        Some([x, y, w, h]) => {
            if w == 0 || h == 0 || x + w > r0.width || y + h > r0.height {
                return Err(MetricsError::Mismatch(format!(
                    "crop {x},{y},{w},{h} does not fit in {}x{}",
                    r0.width, r0.height
                )));
            }
            cropped = (r0.crop(x, y, w, h), t0.crop(x, y, w, h));
            (&cropped.0, &cropped.1)
        }
        None => (r0, t0),
    };
    let n = r.width * r.height;
    let count_nonfinite = |img: &Rgb| {
        (0..n)
            .into_par_iter()
            .filter(|&i| !finite(img.pixel(i)))
            .count()
    };
    let (rn, tn) = (count_nonfinite(r), count_nonfinite(t));
    let valid: Option<Vec<bool>> = (rn + tn > 0).then(|| {
        (0..n)
            .into_par_iter()
            .map(|i| finite(r.pixel(i)) && finite(t.pixel(i)))
            .collect()
    });
    let excluded = valid
        .as_ref()
        .map(|v| v.iter().filter(|ok| !**ok).count())
        .unwrap_or(0);
    let display = o.display;
    let to_display = |enc: Encoding| {
        move |p: [f32; 3]| match enc {
            Encoding::Linear => zero_nonfinite(p).map(|v| display.apply(v)),
            Encoding::Srgb => zero_nonfinite(p).map(|v| v.clamp(0.0, 1.0)),
        }
    };
    let to_linear = |enc: Encoding| {
        move |p: [f32; 3]| match enc {
            Encoding::Linear => zero_nonfinite(p),
            Encoding::Srgb => zero_nonfinite(p).map(srgb_to_linear_fast),
        }
    };
    let (rd, td) = (to_display(reference.encoding), to_display(test.encoding));
    let (rl, tl) = (to_linear(reference.encoding), to_linear(test.encoding));
    let wants = |m: Metric| o.metrics.contains(&m);
    let ok = |i: usize| valid.as_ref().is_none_or(|v| v[i]);

    // Pointwise sums in one pass: display squared error, linear squared and relative error.
    // Added in fixed chunks, in order: the same sums whatever the threads (deterministic).
    let (sd, sl, srel, count) = ordered_sum(n, (0.0f64, 0.0f64, 0.0f64, 0usize), |acc, i| {
        if !ok(i) {
            return;
        }
        let (a, b) = (rd(r.pixel(i)), td(t.pixel(i)));
        let (la, lb) = (rl(r.pixel(i)), tl(t.pixel(i)));
        for c in 0..3 {
            acc.0 += f64::from(b[c] - a[c]).powi(2);
            let d2 = f64::from(lb[c] - la[c]).powi(2);
            acc.1 += d2;
            acc.2 += d2 / (f64::from(la[c]).powi(2) + f64::from(o.relmse_eps));
        }
        acc.3 += 3;
    });
    let mean = |s: f64| (count > 0).then(|| s / count as f64);
    let psnr = wants(Metric::Psnr)
        .then(|| {
            mean(sd).map(|m| {
                Db(if m > 0.0 {
                    -10.0 * m.log10()
                } else {
                    f64::INFINITY
                })
            })
        })
        .flatten();

    let mask = valid.as_deref();
    let ssim = if wants(Metric::Ssim) {
        ssim::mean_interior(&ssim::ssim_map(r, rd, t, td), mask)
    } else {
        None
    };
    let flip = Flip::new(o.ppd);
    let mut flip_map = None;
    let ldr = if wants(Metric::Flip) {
        // LDR-FLIP of the display images (their sRGB decode is FLIP's linear input).
        let m = flip.error_map(
            r,
            |p| rd(p).map(srgb_to_linear_fast),
            t,
            |p| td(p).map(srgb_to_linear_fast),
        );
        let p = pool(&m.data, mask);
        flip_map = Some(m);
        p
    } else {
        None
    };
    let hdrflip = if wants(Metric::HdrFlip) {
        let (m, exposures) = flip.hdr(r, rl, t, tl, None);
        let p = pool(&m.data, mask).map(|pooled| HdrFlipResult { pooled, exposures });
        if flip_map.is_none() {
            flip_map = Some(m);
        }
        p
    } else {
        None
    };
    let diff_map = o.keep_maps.then(|| {
        Plane::from_fn(r.width, r.height, |i| {
            let (a, b) = (rd(r.pixel(i)), td(t.pixel(i)));
            ((a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs()) / 3.0
        })
    });
    let source = |img: &InputImage, nonfinite| Source {
        path: img.path.clone(),
        encoding: img.encoding,
        layer: img.layer.clone(),
        channels: img.channels.clone(),
        nonfinite_pixels: nonfinite,
    };
    Ok(PairResult {
        reference: source(reference, rn),
        test: source(test, tn),
        width: r.width,
        height: r.height,
        excluded_pixels: excluded,
        psnr,
        ssim,
        flip: ldr,
        hdrflip,
        mse: if wants(Metric::Mse) { mean(sl) } else { None },
        relmse: if wants(Metric::RelMse) {
            mean(srel)
        } else {
            None
        },
        flip_map: if o.keep_maps { flip_map } else { None },
        diff_map,
    })
}

/// Display values of an image, cropped as `o` says: linear inputs (EXR) through the display
/// transform, LDR inputs as stored (clamped to [0, 1]); non-finite channels read as 0. What PSNR,
/// SSIM and LDR-FLIP see, and what flicker is measured on.
pub fn display_values(img: &InputImage, o: &CompareOptions) -> Rgb {
    let d = o.display;
    let enc = img.encoding;
    let disp = move |p: [f32; 3]| match enc {
        Encoding::Linear => zero_nonfinite(p).map(|v| d.apply(v)),
        Encoding::Srgb => zero_nonfinite(p).map(|v| v.clamp(0.0, 1.0)),
    };
    // Borrow the image unless a crop needs a copy.
    let rgb: Cow<Rgb> = match o.crop {
        Some([x, y, w, h]) => Cow::Owned(img.rgb.crop(x, y, w, h)),
        None => Cow::Borrowed(&img.rgb),
    };
    rgb.map(disp)
}

/// The signed error test - reference per pixel and channel, of two images of display values
/// (`display_values`) of the same size.
pub fn signed_error(reference: &Rgb, test: &Rgb) -> Rgb {
    let channel = |k: usize| {
        Plane::from_fn(test.width, test.height, |i| {
            test.c[k].data[i] - reference.c[k].data[i]
        })
    };
    Rgb {
        width: test.width,
        height: test.height,
        c: [channel(0), channel(1), channel(2)],
    }
}

/// The signed display-space error e = test - reference, per channel (non-finite read as 0).
pub fn display_error(reference: &InputImage, test: &InputImage, o: &CompareOptions) -> Rgb {
    signed_error(&display_values(reference, o), &display_values(test, o))
}

/// The mean over pixels and channels of |now - before|. On two consecutive display errors
/// (`display_error`) it is a frame's **flicker**; on two consecutive display images, how much
/// the image itself changed. Images of different sizes are an error.
pub fn mean_abs_change(now: &Rgb, before: &Rgb) -> Result<f64, MetricsError> {
    if (now.width, now.height) != (before.width, before.height) {
        return Err(MetricsError::Mismatch(format!(
            "size mismatch: {}x{} after {}x{}",
            now.width, now.height, before.width, before.height
        )));
    }
    let n = now.width * now.height;
    let (sum, ..) = ordered_sum(n, (0.0f64, 0.0, 0.0, 0), |acc, i| {
        let (a, b) = (now.pixel(i), before.pixel(i));
        acc.0 += f64::from((a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs());
    });
    Ok(sum / (3 * n) as f64)
}

/// Sums over pixels 0..n: `add` accumulates one pixel into a chunk's sums; chunks of a fixed
/// size run in parallel and are added in order, so the result does not depend on how rayon
/// splits the work (a parallel `sum`/`reduce` of floats does: its last bits change from run to
/// run, and bench rows would not be bit for bit the same).
fn ordered_sum(
    n: usize,
    zero: (f64, f64, f64, usize),
    add: impl Fn(&mut (f64, f64, f64, usize), usize) + Sync,
) -> (f64, f64, f64, usize) {
    const CHUNK: usize = 4096;
    let parts: Vec<(f64, f64, f64, usize)> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut acc = zero;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                add(&mut acc, i);
            }
            acc
        })
        .collect();
    parts
        .into_iter()
        .fold(zero, |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2, a.3 + b.3))
}

/// One frame of a sequence comparison.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    pub frame: String,
    pub warmup: bool,
    #[serde(flatten)]
    pub result: PairResult,
    /// Mean |e_t - e_(t-1)| of the signed display error e = test - reference (not for the first
    /// measured frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flicker: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SequenceResult {
    pub frames: Vec<FrameRow>,
    pub warmup: usize,
    /// Mean over the measured (post-warm-up) frames of each metric's headline value.
    pub mean: std::collections::BTreeMap<&'static str, Db>,
    /// Mean flicker over the measured frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flicker: Option<f64>,
}

/// Image files of a frame folder (EXR, PNG, JPEG), sorted by name.
pub fn frame_files(dir: &Path) -> Result<Vec<String>, MetricsError> {
    let rd = std::fs::read_dir(dir).map_err(|e| MetricsError::Input {
        path: dir.to_path_buf(),
        msg: format!("cannot list: {e}"),
    })?;
    let mut names: Vec<String> = rd
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            let l = n.to_ascii_lowercase();
            !n.starts_with('.')
                && (l.ends_with(".exr")
                    || l.ends_with(".png")
                    || l.ends_with(".jpg")
                    || l.ends_with(".jpeg"))
        })
        .collect();
    names.sort();
    // Prefer EXR frames when a folder holds both EXR and PNG of each frame (cbr render writes both).
    if names
        .iter()
        .any(|n| n.to_ascii_lowercase().ends_with(".exr"))
    {
        names.retain(|n| n.to_ascii_lowercase().ends_with(".exr"));
    }
    if names.is_empty() {
        return Err(MetricsError::Input {
            path: dir.to_path_buf(),
            msg: "no EXR, PNG or JPEG frames".into(),
        });
    }
    Ok(names)
}

/// Compares the frames of two folders by name, skipping `warmup` frames in the means.
pub fn compare_sequences(
    reference_dir: &Path,
    test_dir: &Path,
    load: impl Fn(&Path) -> Result<InputImage, MetricsError>,
    o: &CompareOptions,
    warmup: usize,
) -> Result<SequenceResult, MetricsError> {
    let names = frame_files(reference_dir)?;
    let mut frames = Vec::with_capacity(names.len());
    let mut previous: Option<Rgb> = None;
    for (k, name) in names.iter().enumerate() {
        let tp = test_dir.join(name);
        if !tp.is_file() {
            return Err(MetricsError::Input {
                path: tp,
                msg: format!("missing: the reference folder has {name}"),
            });
        }
        let (r, t) = (load(&reference_dir.join(name))?, load(&tp)?);
        let result = compare_images(&r, &t, o)?;
        let measured = k >= warmup;
        let err = measured.then(|| display_error(&r, &t, o));
        let flicker = match (&err, &previous) {
            (Some(e), Some(p)) => Some(mean_abs_change(e, p)?),
            _ => None,
        };
        if err.is_some() {
            previous = err;
        }
        frames.push(FrameRow {
            frame: name.clone(),
            warmup: !measured,
            result,
            flicker,
        });
    }
    let measured: Vec<&FrameRow> = frames.iter().filter(|f| !f.warmup).collect();
    if measured.is_empty() {
        return Err(MetricsError::Mismatch(format!(
            "--warmup {warmup} skips all {} frames",
            frames.len()
        )));
    }
    let mut mean = std::collections::BTreeMap::new();
    for m in &o.metrics {
        let v: Vec<f64> = measured.iter().filter_map(|f| f.result.value(*m)).collect();
        if v.len() == measured.len() {
            mean.insert(m.name(), Db(v.iter().sum::<f64>() / v.len() as f64));
        }
    }
    let fl: Vec<f64> = measured.iter().filter_map(|f| f.flicker).collect();
    let flicker = (!fl.is_empty()).then(|| fl.iter().sum::<f64>() / fl.len() as f64);
    Ok(SequenceResult {
        frames,
        warmup,
        mean,
        flicker,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 56 (merged shards equal the unsharded run bit for bit): the pixel sums are the
    /// same bits whatever the number of threads.
    #[test]
    fn pixel_sums_do_not_depend_on_the_threads() {
        let sum = || {
            ordered_sum(300_000, (0.0, 0.0, 0.0, 0), |acc, i| {
                acc.0 += (i as f64 * 0.37).sin() * 1e6 + 1e-3;
                acc.3 += 1;
            })
        };
        let with = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(sum)
        };
        let one = with(1);
        assert_eq!(one.3, 300_000);
        for t in [2, 3, 8] {
            for _ in 0..4 {
                assert_eq!(with(t).0.to_bits(), one.0.to_bits(), "{t} threads");
            }
        }
    }
    use crate::planes::Rgb;

    fn img(w: usize, h: usize, f: impl Fn(usize) -> f32, enc: Encoding) -> InputImage {
        let v: Vec<f32> = (0..w * h * 3).map(f).collect();
        InputImage {
            path: "x".into(),
            layer: String::new(),
            channels: vec![],
            rgb: Rgb::from_interleaved(w, h, &v),
            encoding: enc,
        }
    }

    #[test]
    fn identical_images_are_perfect() {
        let a = img(32, 20, |i| ((i * 13) % 29) as f32 / 7.0, Encoding::Linear);
        let r = compare_images(&a, &a, &CompareOptions::default()).expect("compare");
        assert_eq!(r.psnr, Some(Db(f64::INFINITY)));
        assert_eq!(
            serde_json::to_value(r.psnr).expect("json"),
            serde_json::json!("inf")
        );
        assert!((r.ssim.expect("ssim") - 1.0).abs() < 1e-6);
        assert_eq!(r.flip.expect("flip").max, 0.0);
        assert_eq!(r.hdrflip.expect("hdrflip").pooled.max, 0.0);
        assert_eq!((r.mse, r.relmse), (Some(0.0), Some(0.0)));
    }

    #[test]
    fn psnr_falls_as_noise_grows_and_flip_stays_in_range() {
        let a = img(48, 32, |i| ((i * 7) % 23) as f32 / 22.0, Encoding::Srgb);
        let mut last = f64::INFINITY;
        for k in 1..5 {
            let b = img(
                48,
                32,
                |i| {
                    (((i * 7) % 23) as f32 / 22.0
                        + 0.02 * k as f32 * if (i * 31) % 3 == 0 { 1.0 } else { -1.0 })
                    .clamp(0.0, 1.0)
                },
                Encoding::Srgb,
            );
            let r = compare_images(&a, &b, &CompareOptions::default()).expect("compare");
            let p = r.psnr.expect("psnr").0;
            assert!(p < last, "{p} >= {last}");
            last = p;
            let f = r.flip.expect("flip");
            assert!(f.min >= 0.0 && f.max <= 1.0);
        }
    }

    #[test]
    fn nonfinite_pixels_are_counted_and_excluded() {
        let a = img(16, 16, |i| (i % 5) as f32, Encoding::Linear);
        let mut b = img(16, 16, |i| (i % 5) as f32, Encoding::Linear);
        b.rgb.c[1].data[7] = f32::NAN;
        b.rgb.c[0].data[9] = f32::INFINITY;
        let r = compare_images(&a, &b, &CompareOptions::default()).expect("compare");
        assert_eq!(
            (
                r.test.nonfinite_pixels,
                r.reference.nonfinite_pixels,
                r.excluded_pixels
            ),
            (2, 0, 2)
        );
        assert!(r.mse.expect("mse").is_finite());
        assert!(r.flip.expect("flip").mean.is_finite());
    }

    #[test]
    fn size_mismatch_and_bad_crops_are_errors() {
        let a = img(8, 8, |_| 0.5, Encoding::Srgb);
        let b = img(8, 9, |_| 0.5, Encoding::Srgb);
        assert!(
            compare_images(&a, &b, &CompareOptions::default())
                .unwrap_err()
                .to_string()
                .contains("size mismatch")
        );
        let o = CompareOptions {
            crop: Some([4, 4, 8, 2]),
            ..Default::default()
        };
        assert!(
            compare_images(&a, &a, &o)
                .unwrap_err()
                .to_string()
                .contains("does not fit")
        );
    }

    #[test]
    fn flicker_is_the_mean_change_of_the_signed_display_error() {
        // LDR inputs are display values as stored: the error is test - reference exactly.
        let reference = img(4, 2, |_| 0.5, Encoding::Srgb);
        let up = img(4, 2, |i| if i % 3 == 0 { 0.6 } else { 0.5 }, Encoding::Srgb);
        let down = img(4, 2, |i| if i % 3 == 0 { 0.4 } else { 0.5 }, Encoding::Srgb);
        let o = CompareOptions::default();
        let (e1, e2) = (
            display_error(&reference, &up, &o),
            display_error(&reference, &down, &o),
        );
        // The error goes +0.1 -> -0.1 on the 8 of 24 channels with i % 3 == 0: mean |0.2| * 8/24.
        let f = mean_abs_change(&e2, &e1).expect("same size");
        assert!((f - 0.2 / 3.0).abs() < 1e-6, "{f}");
        // A static bias does not flicker.
        assert_eq!(mean_abs_change(&e1, &e1).expect("same size"), 0.0);
        assert!(
            (e1.c[0].data[0] - 0.1).abs() < 1e-6,
            "test - reference, not the reverse"
        );
        // Linear inputs go through the display transform first, non-finite read as 0.
        let lin = img(2, 1, |i| [0.18, f32::NAN][i / 3], Encoding::Linear);
        let d = display_values(&lin, &o);
        assert_eq!(d.pixel(0), [o.display.apply(0.18); 3]);
        assert_eq!(d.pixel(1), [0.0; 3]);
        assert!(mean_abs_change(&d, &e1).is_err(), "size mismatch");
    }
}
