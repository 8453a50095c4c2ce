//! What the fuzz targets share.
//!
//! A few hundred bytes of PNG or JPEG can declare an image of hundreds of millions of pixels,
//! which the decoders then fill: valid work, linear in the size, and slow under the sanitizer
//! (a 364-byte JPEG of 8964x4355 takes > 10 s). The image targets therefore skip inputs whose
//! header declares more than [`TEXEL_BUDGET`] pixels: the sides themselves stay free, so limits on
//! a side (cbr refuses textures over 16384 per side) are still exercised.

use std::io::Cursor;
use std::path::Path;

/// The most pixels an image input may declare (e.g. 512 x 512, or 65536 x 4).
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
