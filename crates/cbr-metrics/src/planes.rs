//! Planar float images and the separable convolution every metric here is built from.

use rayon::prelude::*;

/// A single-channel float image, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane {
    pub fn new(width: usize, height: usize) -> Plane {
        Plane {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize) -> f32 + Sync + Send) -> Plane {
        let data = (0..width * height).into_par_iter().map(f).collect();
        Plane {
            width,
            height,
            data,
        }
    }

    /// Convolves rows with `kx` then columns with `ky` (both odd length, centred), clamping
    /// coordinates at the borders (edge replication).
    pub fn separable(&self, kx: &[f32], ky: &[f32]) -> Plane {
        let tmp = self.convolve_rows(kx);
        tmp.convolve_cols(ky)
    }

    pub fn convolve_rows(&self, k: &[f32]) -> Plane {
        let (w, r) = (self.width, k.len() / 2);
        let mut out = Plane::new(self.width, self.height);
        out.data
            .par_chunks_mut(w)
            .zip(self.data.par_chunks(w))
            .for_each(|(dst, src)| {
                if w > 2 * r {
                    // Interior: tap-outer, pixel-inner, so the inner loop vectorises across pixels.
                    let n = w - 2 * r;
                    let d = &mut dst[r..r + n];
                    for (i, kv) in k.iter().enumerate() {
                        for (o, s) in d.iter_mut().zip(&src[i..i + n]) {
                            *o += kv * s;
                        }
                    }
                }
                // Borders (and rows narrower than the kernel) with clamped coordinates.
                for x in (0..w).filter(|&x| x < r || x + r >= w) {
                    dst[x] = k
                        .iter()
                        .enumerate()
                        .map(|(i, kv)| {
                            src[(x as isize + i as isize - r as isize).clamp(0, w as isize - 1)
                                as usize]
                                * kv
                        })
                        .sum();
                }
            });
        out
    }

    pub fn convolve_cols(&self, k: &[f32]) -> Plane {
        let (w, h, r) = (self.width, self.height, k.len() / 2);
        let mut out = Plane::new(w, h);
        out.data.par_chunks_mut(w).enumerate().for_each(|(y, dst)| {
            for (i, kv) in k.iter().enumerate() {
                let sy = (y as isize + i as isize - r as isize).clamp(0, h as isize - 1) as usize;
                let src = &self.data[sy * w..(sy + 1) * w];
                for (d, s) in dst.iter_mut().zip(src) {
                    *d += s * kv;
                }
            }
        });
        out
    }
}

/// A per-pixel transform applied while reading an image (decoding, tone mapping, ...).
pub trait PixelFn: Fn([f32; 3]) -> [f32; 3] + Sync + Send {}
impl<F: Fn([f32; 3]) -> [f32; 3] + Sync + Send> PixelFn for F {}

/// An RGB image as three planes.
#[derive(Clone, Debug)]
pub struct Rgb {
    pub width: usize,
    pub height: usize,
    pub c: [Plane; 3],
}

impl Rgb {
    pub fn from_interleaved(width: usize, height: usize, rgb: &[f32]) -> Rgb {
        let plane = |k: usize| Plane::from_fn(width, height, |i| rgb[3 * i + k]);
        Rgb {
            width,
            height,
            c: [plane(0), plane(1), plane(2)],
        }
    }

    pub fn map(&self, f: impl PixelFn) -> Rgb {
        let n = self.width * self.height;
        let px: Vec<[f32; 3]> = (0..n)
            .into_par_iter()
            .map(|i| f([self.c[0].data[i], self.c[1].data[i], self.c[2].data[i]]))
            .collect();
        let plane = |k: usize| Plane {
            width: self.width,
            height: self.height,
            data: px.iter().map(|p| p[k]).collect(),
        };
        Rgb {
            width: self.width,
            height: self.height,
            c: [plane(0), plane(1), plane(2)],
        }
    }

    pub fn pixel(&self, i: usize) -> [f32; 3] {
        [self.c[0].data[i], self.c[1].data[i], self.c[2].data[i]]
    }

    /// Rows `y0..y1`, with `f` applied to every pixel.
    pub fn rows_mapped(&self, y0: usize, y1: usize, f: impl PixelFn) -> Rgb {
        let w = self.width;
        let n = (y1 - y0) * w;
        let px: Vec<[f32; 3]> = (0..n)
            .into_par_iter()
            .map(|i| f(self.pixel(y0 * w + i)))
            .collect();
        let plane = |k: usize| Plane {
            width: w,
            height: y1 - y0,
            data: px.iter().map(|p| p[k]).collect(),
        };
        Rgb {
            width: w,
            height: y1 - y0,
            c: [plane(0), plane(1), plane(2)],
        }
    }

    /// The sub-rectangle (x, y, w, h).
    pub fn crop(&self, x: usize, y: usize, w: usize, h: usize) -> Rgb {
        let plane = |p: &Plane| Plane::from_fn(w, h, |i| p.data[(y + i / w) * p.width + x + i % w]);
        Rgb {
            width: w,
            height: h,
            c: [plane(&self.c[0]), plane(&self.c[1]), plane(&self.c[2])],
        }
    }
}

/// Output rows per band, and the driver: `f(band, y0)` gets the rows `y0..` of the band with `halo`
/// extra rows on each side (clamped to the image) and returns a plane of the same rows; the core
/// rows are copied into the result. With `halo` >= every filter radius the result equals the
/// whole-image computation, while memory stays proportional to the band.
pub const BAND_ROWS: usize = 128;

pub fn banded(
    width: usize,
    height: usize,
    halo: usize,
    f: impl Fn(usize, usize) -> Plane + Sync + Send,
) -> Plane {
    let mut out = Plane::new(width, height);
    out.data
        .par_chunks_mut(BAND_ROWS * width)
        .enumerate()
        .for_each(|(b, chunk)| {
            let core0 = b * BAND_ROWS;
            let core1 = (core0 + BAND_ROWS).min(height);
            let (y0, y1) = (core0.saturating_sub(halo), (core1 + halo).min(height));
            let band = f(y0, y1);
            chunk.copy_from_slice(&band.data[(core0 - y0) * width..(core1 - y0) * width]);
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separable_convolution_matches_direct_2d_with_clamped_borders() {
        let (w, h) = (7, 5);
        let p = Plane::from_fn(w, h, |i| ((i * 37) % 11) as f32);
        let kx = [0.2, 0.5, 0.3];
        let ky = [0.1, 0.2, 0.4, 0.2, 0.1];
        let fast = p.separable(&kx, &ky);
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for (j, b) in ky.iter().enumerate() {
                    for (i, a) in kx.iter().enumerate() {
                        let sx = (x as isize + i as isize - 1).clamp(0, w as isize - 1) as usize;
                        let sy = (y as isize + j as isize - 2).clamp(0, h as isize - 1) as usize;
                        acc += a * b * p.data[sy * w + sx];
                    }
                }
                assert!((fast.data[y * w + x] - acc).abs() < 1e-5, "({x},{y})");
            }
        }
    }
}
