//! What the fuzz targets share.
//!
//! A few hundred bytes of PNG, JPEG or EXR can declare an image of hundreds of millions of
//! pixels, which the decoders then fill: valid work, linear in the size, and slow under the
//! sanitizer (a 364-byte JPEG of 8964x4355 takes > 10 s). The image targets therefore skip inputs
//! whose header declares more than [`TEXEL_BUDGET`] pixels (EXR: samples over all layers and
//! channels): the sides themselves stay free, so cbr's own limits (textures and EXR layers over
//! 16384 per side are refused from the header) are still exercised.

use std::io::Cursor;
use std::path::Path;

/// The most pixels an image input may declare (e.g. 512 x 512, or 65536 x 4), and the most samples
/// an EXR may.
pub const TEXEL_BUDGET: u64 = 1 << 18;

/// Whether the image `bytes` (named `name`, whose extension is the hint when the contents name no
/// format) declares at most [`TEXEL_BUDGET`] pixels; true when the header cannot be read (the
/// decoder then fails fast).
pub fn within_budget(name: &str, bytes: &[u8]) -> bool {
    let mut r = image::ImageReader::new(Cursor::new(bytes));
    if let Ok(format) = image::ImageFormat::from_path(Path::new(name)) {
        r.set_format(format);
    }
    let Ok(r) = r.with_guessed_format() else {
        return true;
    };
    match r.into_dimensions() {
        Ok((w, h)) => u64::from(w) * u64::from(h) <= TEXEL_BUDGET,
        Err(_) => true,
    }
}

/// Whether the EXR `bytes` declares at most [`TEXEL_BUDGET`] samples over all its layers and
/// channels, counting a layer over 16384 per side as within it (cbr refuses those from the header,
/// which is worth fuzzing); true when the headers cannot be read (the reader then fails fast).
pub fn exr_within_budget(bytes: &[u8]) -> bool {
    let Ok(meta) = exr::meta::MetaData::read_from_buffered(bytes, false) else {
        return true;
    };
    let mut samples = 0u64;
    for h in &meta.headers {
        let (w, hgt) = (h.layer_size.0 as u64, h.layer_size.1 as u64);
        if w > 16384 || hgt > 16384 {
            return true;
        }
        samples += w * hgt * h.channels.list.len().max(1) as u64;
    }
    samples <= TEXEL_BUDGET
}
