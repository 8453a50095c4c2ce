//! RGBA8 textures with full mip chains. Colour textures are sRGB-encoded and filtered in linear
//! space; masks and height maps are linear.

use std::path::Path;

use rayon::prelude::*;

use crate::error::{Result, SceneError};
use crate::scene::MAX_RESOLUTION;

#[derive(Clone, Debug)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    /// RGBA8, rows top to bottom.
    pub rgba: Vec<u8>,
}

#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    /// Colour data in sRGB encoding (sampled through an `_SRGB` format).
    pub srgb: bool,
    /// Whether the source image had an alpha channel with any texel below 1.
    pub has_alpha: bool,
    /// Whether the source image had colour channels (false for grey images, whose value is in RGB).
    pub levels: Vec<Level>,
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn downsample(src: &Level, srgb: bool, lut: &[f32; 256]) -> Level {
    let w = (src.width / 2).max(1);
    let h = (src.height / 2).max(1);
    let mut rgba = vec![0u8; (w * h * 4) as usize];
    rgba.par_chunks_mut((w * 4) as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for x in 0..w as usize {
                let mut acc = [0f32; 4];
                // Box filter over the (up to) 2x2 source texels; odd sizes clamp at the edge.
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let sx = (2 * x + dx).min(src.width as usize - 1);
                    let sy = (2 * y + dy).min(src.height as usize - 1);
                    let i = (sy * src.width as usize + sx) * 4;
                    for (c, a) in acc.iter_mut().enumerate() {
                        let v = src.rgba[i + c];
                        *a += if srgb && c < 3 {
                            lut[v as usize]
                        } else {
                            f32::from(v) / 255.0
                        };
                    }
                }
                for (c, a) in acc.iter().enumerate() {
                    let v = a * 0.25;
                    let v = if srgb && c < 3 { linear_to_srgb(v) } else { v };
                    row[x * 4 + c] = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                }
            }
        });
    Level {
        width: w,
        height: h,
        rgba,
    }
}

/// A texture file that cannot be read: "is a directory" rather than the OS's wording.
pub(crate) fn read_error(path: &Path, e: &std::io::Error) -> SceneError {
    if e.kind() == std::io::ErrorKind::IsADirectory || path.is_dir() {
        SceneError::file(path, "cannot read texture: is a directory")
    } else {
        SceneError::file(path, format!("cannot read texture: {e}"))
    }
}

impl Texture {
    /// A texture from level-0 RGBA8 texels; builds the full mip chain down to 1x1.
    pub fn from_rgba8(name: &str, width: u32, height: u32, rgba: Vec<u8>, srgb: bool) -> Texture {
        assert_eq!(
            rgba.len(),
            (width * height * 4) as usize,
            "texture {name}: size mismatch"
        );
        let has_alpha = rgba.chunks_exact(4).any(|p| p[3] < 255);
        let lut: [f32; 256] = std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0));
        let mut levels = vec![Level {
            width,
            height,
            rgba,
        }];
        while let Some(last) = levels.last() {
            if last.width == 1 && last.height == 1 {
                break;
            }
            let next = downsample(last, srgb, &lut);
            levels.push(next);
        }
        Texture {
            name: name.to_string(),
            srgb,
            has_alpha,
            levels,
        }
    }

    /// Decodes an image file (PNG, JPEG, TGA, BMP). Errors name the file once.
    pub fn load(path: &Path, srgb: bool) -> Result<Texture> {
        let bytes = std::fs::read(path).map_err(|e| read_error(path, &e))?;
        Texture::decode(path, &bytes, srgb)
    }

    /// Decodes an image held in memory; `path` names it in errors and in [`Texture::name`]. The
    /// format is found from the contents (the extension when they say nothing). Images over
    /// [`MAX_RESOLUTION`] per side are refused from their header, before any texel is decoded.
    pub fn decode(path: &Path, bytes: &[u8], srgb: bool) -> Result<Texture> {
        let reader = || -> Result<image::ImageReader<std::io::Cursor<&[u8]>>> {
            let mut r = image::ImageReader::new(std::io::Cursor::new(bytes));
            if let Ok(format) = image::ImageFormat::from_path(path) {
                r.set_format(format);
            }
            r.with_guessed_format().map_err(|e| read_error(path, &e))
        };
        let decode_err = |e| SceneError::file(path, format!("cannot decode texture: {e}"));
        let (w, h) = reader()?.into_dimensions().map_err(decode_err)?;
        if w > MAX_RESOLUTION || h > MAX_RESOLUTION {
            return Err(SceneError::file(
                path,
                format!("texture is {w}x{h} texels; at most {MAX_RESOLUTION} per side"),
            ));
        }
        let img = reader()?.decode().map_err(decode_err)?;
        let rgba = img.to_rgba8();
        let (w, h) = rgba.dimensions();
        if w == 0 || h == 0 {
            return Err(SceneError::file(path, "texture has zero size"));
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        Ok(Texture::from_rgba8(&name, w, h, rgba.into_raw(), srgb))
    }

    /// The coverage texture of an alpha-tested material, for averages over the part of a
    /// footprint where the alpha test passes (`analytic`). Level 0, at the albedo's size (the
    /// mask's without an albedo texture), holds the albedo (white without one) where the mask's
    /// channel `channel`, taken at the nearest texel, is at least one half, 0 elsewhere, and the
    /// pass (0 or 1) in alpha. Its mips average both in linear space, so a filtered texel holds
    /// (mean of albedo x pass, mean of pass) over the filter: their quotient is the albedo's mean
    /// over the passing texels alone, and the alpha the passing share. The albedo's own mips
    /// average in the colour of texels that fail the test, which no one sees.
    pub fn alpha_coverage(albedo: Option<&Texture>, mask: &Texture, channel: usize) -> Texture {
        let channel = channel.min(3);
        let base = albedo.unwrap_or(mask);
        let (w, h) = (base.width(), base.height());
        let (mw, mh) = (mask.width(), mask.height());
        let m0 = &mask.levels[0].rgba;
        let mut rgba = vec![0u8; (w * h * 4) as usize];
        rgba.par_chunks_mut((w * 4) as usize)
            .enumerate()
            .for_each(|(y, row)| {
                let my = ((y as u64 * u64::from(mh)) / u64::from(h)) as usize;
                for x in 0..w as usize {
                    let mx = ((x as u64 * u64::from(mw)) / u64::from(w)) as usize;
                    let pass = m0[(my * mw as usize + mx) * 4 + channel] >= 128;
                    if !pass {
                        continue;
                    }
                    let texel = &mut row[x * 4..x * 4 + 4];
                    match albedo {
                        Some(a) => {
                            let i = (y * w as usize + x) * 4;
                            texel[..3].copy_from_slice(&a.levels[0].rgba[i..i + 3]);
                        }
                        None => texel[..3].fill(255),
                    }
                    texel[3] = 255;
                }
            });
        let name = Texture::alpha_coverage_name(albedo, mask);
        let srgb = albedo.is_some_and(|a| a.srgb);
        Texture::from_rgba8(&name, w, h, rgba, srgb)
    }

    /// The name [`Texture::alpha_coverage`] gives its texture.
    pub fn alpha_coverage_name(albedo: Option<&Texture>, mask: &Texture) -> String {
        format!(
            "{} (alpha coverage of {})",
            albedo.unwrap_or(mask).name,
            mask.name
        )
    }

    /// A loud magenta/black checker used in place of a missing texture when the user asks for it.
    pub fn fallback(name: &str) -> Texture {
        let n = 16u32;
        let rgba = (0..n * n)
            .flat_map(|i| {
                let (x, y) = (i % n, i / n);
                if ((x / 4) + (y / 4)) % 2 == 0 {
                    [255, 0, 255, 255]
                } else {
                    [0, 0, 0, 255]
                }
            })
            .collect();
        Texture::from_rgba8(name, n, n, rgba, true)
    }

    /// Bytes of the whole mip chain (RGBA8).
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.rgba.len() as u64).sum()
    }

    pub fn width(&self) -> u32 {
        self.levels[0].width
    }
    pub fn height(&self) -> u32 {
        self.levels[0].height
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_chain_goes_to_one_by_one() {
        let t = Texture::from_rgba8("t", 5, 3, vec![255; 5 * 3 * 4], false);
        let sizes: Vec<(u32, u32)> = t.levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, vec![(5, 3), (2, 1), (1, 1)]);
        assert!(!t.has_alpha);
    }

    #[test]
    fn srgb_mips_average_in_linear_space() {
        // Black and white texels average to linear 0.5, which is sRGB 188, not 128.
        let rgba = vec![
            0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255,
        ];
        let t = Texture::from_rgba8("t", 2, 2, rgba.clone(), true);
        assert_eq!(t.levels[1].rgba[0], 188);
        let lin = Texture::from_rgba8("t", 2, 2, rgba, false);
        assert_eq!(lin.levels[1].rgba[0], 128);
    }

    #[test]
    fn alpha_coverage_mips_hold_the_passing_texels_colour_premultiplied() {
        // 4x2 albedo: red texels that pass, blue ones (alpha 0) that fail, in columns; the mask is
        // the albedo's own alpha at half the resolution (2x1), so each mask texel covers two
        // albedo columns: pass, fail.
        let red_blue = [[255, 0, 0, 255], [0, 0, 255, 0]];
        let albedo: Vec<u8> = (0..8).flat_map(|i| red_blue[(i % 4) / 2]).collect();
        let albedo = Texture::from_rgba8("albedo", 4, 2, albedo, true);
        let mask = Texture::from_rgba8("mask", 2, 1, vec![0, 0, 0, 200, 0, 0, 0, 100], false);
        let c = Texture::alpha_coverage(Some(&albedo), &mask, 3);
        assert!(c.srgb);
        assert_eq!((c.width(), c.height()), (4, 2));
        // Level 0: the albedo where the mask passes (200 >= 128), 0 where it fails (100).
        assert_eq!(&c.levels[0].rgba[..8], &[255, 0, 0, 255, 255, 0, 0, 255]);
        assert_eq!(&c.levels[0].rgba[8..16], &[0, 0, 0, 0, 0, 0, 0, 0]);
        // Level 1 (2x1): left texel all passing red; right all failing: no blue anywhere.
        assert_eq!(&c.levels[1].rgba[..8], &[255, 0, 0, 255, 0, 0, 0, 0]);
        // Level 2 (1x1): half passing; red premultiplied by 1/2 in linear space (sRGB 188),
        // so red / alpha is the passing texels' red, 1.
        assert_eq!(c.levels[2].rgba, vec![188, 0, 0, 128]);
        // The albedo's own level 2 mixes in the failing blue.
        assert!(albedo.levels[2].rgba[2] > 100);
        // Without an albedo texture: white where the mask passes, at the mask's size.
        let w = Texture::alpha_coverage(None, &mask, 3);
        assert_eq!(w.levels[0].rgba, vec![255, 255, 255, 255, 0, 0, 0, 0]);
        assert!(!w.srgb);
    }
}
