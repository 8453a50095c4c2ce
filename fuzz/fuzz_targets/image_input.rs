//! The image reader behind `cbr compare`: EXR (any layer and channels) and PNG/JPEG/TGA/BMP. The
//! first byte picks the file name's extension and which layer and channels are asked for; the
//! rest is the file. Images declaring more than `cbr_fuzz::TEXEL_BUDGET` pixels (EXR: samples)
//! are skipped (see src/lib.rs).
#![no_main]

use std::io::Cursor;
use std::path::Path;

use cbr_metrics::input::read;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&first, bytes)) = data.split_first() else {
        return;
    };
    let name = ["in.exr", "in.png", "in.jpg", "in.tga"][usize::from(first & 3)];
    let exr = bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) || name.ends_with(".exr");
    let small = if exr {
        cbr_fuzz::exr_within_budget(bytes)
    } else {
        cbr_fuzz::within_budget(name, bytes)
    };
    if !small {
        return;
    }
    let one = ["Z".to_string()];
    let rgb = ["R".to_string(), "G".to_string(), "B".to_string()];
    let (layer, channels): (Option<&str>, Option<&[String]>) = match (first >> 2) & 3 {
        0 => (None, None),
        1 => (Some("depth"), Some(&one)),
        2 => (Some("color"), Some(&rgb)),
        _ => (None, Some(&one)),
    };
    let _ = read(Path::new(name), Cursor::new(bytes), layer, channels);
});
