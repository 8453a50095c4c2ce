//! The texture decoder (PNG, JPEG, TGA, BMP) and the mip chain. The first byte picks the file
//! name's extension (the decoder's hint when the contents name no format: TGA has no magic
//! number) and the colour space; the rest is the file. Images declaring more than
//! `cbr_fuzz::TEXEL_BUDGET` pixels are skipped (see src/lib.rs).
#![no_main]

use std::path::Path;

use cbr_scene::Texture;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&first, bytes)) = data.split_first() else {
        return;
    };
    let name = ["t.png", "t.jpg", "t.tga", "t.bmp"][usize::from(first & 3)];
    let srgb = first & 4 != 0;
    if !cbr_fuzz::within_budget(name, bytes) {
        return;
    }
    let _ = Texture::decode(Path::new(name), bytes, srgb);
});
