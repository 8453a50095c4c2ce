//! The image reader behind `cbr compare`: EXR (any layer and channels) and PNG/JPEG/TGA/BMP. The
//! first byte picks the file name's extension and which layer and channels are asked for; the
//! rest is the file.
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
