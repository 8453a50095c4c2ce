//! Inputs the fuzzer (fuzz/, docs/fuzzing.md) found crashing or hanging the scene loaders, in
//! `tests/fuzz_regressions/TARGET/`, replayed exactly as the fuzz target TARGET reads them. Each
//! must give a clean `Ok` or `Err` (a panic fails the test), and the outcome listed for it.

use std::path::Path;

use cbr_scene::obj::{ObjOptions, load_obj_from};
use cbr_scene::{LoadOptions, MemoryFiles, MissingTextures, Texture, Up, load_from};

/// Each regression file (TARGET/NAME) and what replaying it must give: `Ok(())`, or an error
/// containing the text (the `obj` target loads twice: both must match).
const EXPECTED: &[(&str, Result<(), &str>)] = &[
    // A 364-byte JPEG declaring 8964x4355: the decoder fills 39 Mpx from it, > 10 s under the
    // fuzzer's sanitizer (seconds here): linear work, not a hang; the fuzz targets now skip
    // images declaring over 2^18 pixels (fuzz/src/lib.rs).
    ("texture/jpeg-8964x4355-timeout.bin", Ok(())),
    // A 54-byte BMP declaring 20000x20000: refused from its header, before 1.6 GB are decoded.
    (
        "texture/bmp-20000x20000.bin",
        Err("texture is 20000x20000 texels; at most 16384 per side"),
    ),
];

/// The `texture` target: the first byte picks the extension and the colour space.
fn texture(data: &[u8]) -> Result<(), String> {
    let (&first, bytes) = data.split_first().ok_or("empty input")?;
    let name = ["t.png", "t.jpg", "t.tga", "t.bmp"][usize::from(first & 3)];
    Texture::decode(Path::new(name), bytes, first & 4 != 0)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// The `obj` target: `OBJ \0 MTL \0 TEXTURE`, loaded with the default options and again with
/// the fallback for missing textures, Z up and a default material.
fn obj(data: &[u8]) -> Result<(), String> {
    let mut parts = data.splitn(3, |&b| b == 0);
    let mut files = MemoryFiles::new();
    files.insert("s/in.obj", parts.next().unwrap_or_default());
    if let Some(mtl) = parts.next() {
        files.insert("s/in.mtl", mtl);
    }
    if let Some(tex) = parts.next() {
        files.insert("s/tex.png", tex);
    }
    let path = Path::new("s/in.obj");
    let first = load_obj_from(&files, path, &ObjOptions::default()).map(|_| ());
    let opts = ObjOptions {
        mtl_override: None,
        default_material: Some("m".into()),
        missing_textures: MissingTextures::Fallback,
        up: Up::Z,
    };
    let second = load_obj_from(&files, path, &opts).map(|_| ());
    first.and(second).map_err(|e| e.to_string())
}

/// The `scene_toml` target: the TOML as `s/scene.toml` beside a two-object OBJ `s/t.obj`.
fn scene_toml(data: &[u8]) -> Result<(), String> {
    let mut files = MemoryFiles::new();
    files.insert("s/scene.toml", data);
    files.insert(
        "s/t.obj",
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n\
         o A\nusemtl m\nf 1/1/1 2/1/1 3/1/1\no B\nf 1 2 4\n",
    );
    files.insert("s/t.mtl", "newmtl m\nKd 0.5 0.5 0.5\nKe 0 0 0\n");
    load_from(&files, "s/scene.toml", &LoadOptions::default())
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn fuzz_regressions_load_cleanly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut seen = 0;
    for target in std::fs::read_dir(&root).expect("regression folder") {
        let target = target.expect("entry").path();
        let tname = target
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        for entry in std::fs::read_dir(&target).expect("target folder") {
            let path = entry.expect("entry").path();
            let name = format!(
                "{tname}/{}",
                path.file_name().expect("name").to_string_lossy()
            );
            let expected = EXPECTED
                .iter()
                .find(|(n, _)| *n == name)
                .unwrap_or_else(|| panic!("{name}: add its expected outcome to EXPECTED"))
                .1;
            let data = std::fs::read(&path).expect("read");
            let got = match tname.as_str() {
                "texture" => texture(&data),
                "obj" => obj(&data),
                "scene_toml" => scene_toml(&data),
                other => panic!("no fuzz target `{other}`"),
            };
            match (expected, &got) {
                (Ok(()), Ok(())) => {}
                (Err(want), Err(e)) if e.contains(want) => {}
                _ => panic!("{name}: expected {expected:?}, got {got:?}"),
            }
            seen += 1;
        }
    }
    assert_eq!(seen, EXPECTED.len(), "every listed file is present");
}
