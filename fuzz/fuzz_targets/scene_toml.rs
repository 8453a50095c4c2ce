//! The scene TOML: `SceneDesc::parse`, then the whole scene load (settings, camera path, lights,
//! animation) over a small in-memory OBJ, `s/t.obj` with objects `A` and `B` and its MTL.
#![no_main]

use std::path::Path;

use cbr_scene::desc::SceneDesc;
use cbr_scene::{LoadOptions, MemoryFiles, load_from};
use libfuzzer_sys::fuzz_target;

const OBJ: &str = "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n\
o A\nusemtl m\nf 1/1/1 2/1/1 3/1/1\no B\nf 1 2 4\n";
const MTL: &str = "newmtl m\nKd 0.5 0.5 0.5\nKe 0 0 0\n";

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let toml = Path::new("s/scene.toml");
    if SceneDesc::parse(text, toml).is_err() {
        return;
    }
    let mut files = MemoryFiles::new();
    files.insert(toml, data);
    files.insert("s/t.obj", OBJ);
    files.insert("s/t.mtl", MTL);
    let _ = load_from(&files, "s/scene.toml", &LoadOptions::default());
});
