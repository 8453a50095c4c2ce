//! The OBJ + MTL loader (and the textures an MTL names), entirely in memory.
//!
//! Input: `OBJ \0 MTL \0 TEXTURE` (the parts after the first NUL are optional). They become
//! `s/in.obj`, `s/in.mtl` (found through the OBJ's `mtllib`, or as the OBJ's sibling when the
//! named one is missing) and `s/tex.png` (what the seeds' MTLs name). Loaded twice: with the
//! default options, and with the fallback for missing textures, Z up and a default material.
//! Textures declaring more than `cbr_fuzz::TEXEL_BUDGET` pixels are skipped (see src/lib.rs).
#![no_main]

use std::path::Path;

use cbr_scene::obj::{ObjOptions, load_obj_from};
use cbr_scene::{MemoryFiles, MissingTextures, Up};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0);
    let mut files = MemoryFiles::new();
    files.insert("s/in.obj", parts.next().unwrap_or_default());
    if let Some(mtl) = parts.next() {
        files.insert("s/in.mtl", mtl);
    }
    if let Some(tex) = parts.next() {
        if !cbr_fuzz::within_budget("tex.png", tex) {
            return;
        }
        files.insert("s/tex.png", tex);
    }
    let obj = Path::new("s/in.obj");
    let _ = load_obj_from(&files, obj, &ObjOptions::default());
    let opts = ObjOptions {
        mtl_override: None,
        default_material: Some("m".into()),
        missing_textures: MissingTextures::Fallback,
        up: Up::Z,
    };
    let _ = load_obj_from(&files, obj, &opts);
});
