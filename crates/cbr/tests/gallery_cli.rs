//! The hard-case gallery from the command line: `cbr info` lists every built-in scene, a bad
//! `builtin:` name is one clear error, `builtin:nan` reports its non-finite fragments per frame,
//! and `cbr montage` (the gallery's strips) places, crops and enlarges exactly, and refuses bad
//! input without writing anything.

mod common;
use common::{cbr, s, stderr};

use std::path::Path;

#[test]
fn info_lists_every_built_in_scene() {
    let o = cbr(&["info"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for name in cbr_scene::BUILTINS {
        assert!(
            out.lines().any(|l| l.trim_start().starts_with(name)),
            "`cbr info` does not list builtin:{name}"
        );
    }
    let o = cbr(&["info", "--json"], &[]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let listed: Vec<&str> = v["scenes"]
        .as_array()
        .expect("scenes")
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(listed, cbr_scene::BUILTINS);
}

#[test]
fn bad_builtin_names_are_one_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    for (scene, expect) in [
        ("builtin:nope", "no built-in scene `nope`"),
        ("builtin:far:x", "builtin:far:x"),
        ("builtin:far:1e12", "at most 1e9"),
        ("builtin:wires:2", "no built-in scene `wires:2`"),
    ] {
        let o = cbr(&["render", scene, "--frames", "1", "-o", s(&out)], &[]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{scene}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(expect),
            "{scene}: {err}"
        );
        assert!(!err.contains("panicked"), "{scene}: {err}");
        assert!(!out.exists(), "{scene}: wrote {}", out.display());
    }
}

#[test]
fn nan_case_counts_and_warns_per_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("nan");
    let o = cbr(
        &[
            "render",
            "builtin:nan",
            "--width",
            "64",
            "--height",
            "36",
            "--frames",
            "2",
            "-o",
            s(&out),
        ],
        &[],
    );
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("frame 0:") && err.contains("NaN or infinity"),
        "no warning: {err}"
    );
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    for f in run["frames"].as_array().expect("frames") {
        assert!(f["nonfinite_fragments"].as_u64().unwrap() > 0, "{f}");
    }
}

fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) {
    let mut img = image::RgbaImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgba(f(x, y));
    }
    img.save(path).unwrap();
}

#[test]
fn montage_places_crops_and_enlarges_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    png(&a, 8, 6, |x, y| [x as u8, y as u8, 1, 255]);
    png(&b, 8, 6, |x, y| [x as u8, y as u8, 2, 255]);
    let strip = dir.path().join("strip.png");
    let o = cbr(
        &[
            "montage",
            s(&a),
            s(&b),
            "-",
            s(&a),
            "--columns",
            "2",
            "--crop",
            "2,1,4,3",
            "--scale",
            "2",
            "--gap",
            "1",
            "-o",
            s(&strip),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&strip).unwrap().to_rgba8();
    // Two columns of 8x6 tiles (4x3 crops enlarged twice), two rows, 1 px gaps.
    assert_eq!(img.dimensions(), (17, 13));
    // Tile 0 (a) at (0, 0): pixel (5, 3) is crop texel (2, 1) = source (4, 2).
    assert_eq!(img.get_pixel(5, 3).0, [4, 2, 1, 255]);
    // Tile 1 (b) starts at x = 9.
    assert_eq!(img.get_pixel(9, 0).0, [2, 1, 2, 255]);
    // Tile 2 is blank, tile 3 (a) starts at (9, 7); the gaps are white.
    assert_eq!(img.get_pixel(3, 9).0, [255; 4]);
    assert_eq!(img.get_pixel(16, 12).0, [5, 3, 1, 255]);
    assert_eq!(img.get_pixel(8, 0).0, [255; 4]);
}

#[test]
fn montage_refuses_bad_input_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (a, small) = (dir.path().join("a.png"), dir.path().join("small.png"));
    png(&a, 8, 6, |_, _| [9, 9, 9, 255]);
    png(&small, 4, 4, |_, _| [9, 9, 9, 255]);
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not a png").unwrap();
    let strip = dir.path().join("strip.png");
    let missing = dir.path().join("missing.png");
    for (args, expect) in [
        (vec![s(&a), s(&missing)], "missing.png"),
        (vec![s(&a), s(&junk)], "junk.png"),
        (vec![s(&a), s(&small)], "small.png: 4x4"),
        (vec![s(&a), "--crop", "6,0,4,4"], "does not fit"),
        (vec![s(&a), "--crop", "1,2,3"], "--crop 1,2,3"),
        (vec![s(&a), "--scale", "0"], "--scale 0"),
        (vec!["-", "-"], "nothing to place"),
    ] {
        let mut full = vec!["montage"];
        full.extend(&args);
        full.extend(["-o", s(&strip)]);
        let o = cbr(&full, &[]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(expect),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!strip.exists(), "{args:?}: wrote the strip");
    }
}
