//! `cbr compare` end to end: exit status 0 (thresholds hold), 1 (one fails), 2 (errors); JSON;
//! error maps; sequences.

mod common;
use common::{cbr, s};

use std::path::Path;
use std::process::Output;

fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
    let mut img = image::RgbImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb(f(x, y));
    }
    img.save(path).expect("png");
}

/// Asserts the exit status (showing stderr if it differs) and parses the JSON on stdout.
fn json(o: &Output, status: i32) -> serde_json::Value {
    assert_eq!(
        o.status.code(),
        Some(status),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("json on stdout")
}

/// Asserts a clean error: exit status 2 and `message` on stderr.
fn fails(o: &Output, message: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(message), "expected `{message}` in: {err}");
}

#[test]
fn pairs_thresholds_json_and_maps() {
    let d = tempfile::tempdir().expect("tempdir");
    let (a, b, c) = (
        d.path().join("a.png"),
        d.path().join("b.png"),
        d.path().join("c.png"),
    );
    png(&a, 48, 32, |x, y| [(x * 5) as u8, (y * 7) as u8, 128]);
    png(&b, 48, 32, |x, y| {
        [
            (x * 5) as u8,
            (y * 7) as u8,
            if (x + y) % 5 == 0 { 200 } else { 128 },
        ]
    });
    png(&c, 40, 32, |_, _| [0, 0, 0]);

    let o = cbr(
        &[
            "compare",
            s(&a),
            s(&a),
            "--fail-above",
            "flip=0",
            "--fail-above",
            "psnr=100",
        ],
        &[],
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "identical: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("PSNR      inf dB"));

    let heat = d.path().join("heat.png");
    let o = cbr(
        &[
            "compare",
            s(&a),
            s(&b),
            "--json",
            "--heatmap",
            s(&heat),
            "--fail-above",
            "flip=0.0001",
        ],
        &[],
    );
    let j = json(&o, 1);
    let mean = j["flip"]["mean"].as_f64().expect("flip mean");
    assert!(mean > 0.0 && mean < 1.0, "{j}");
    assert!(j["psnr"].as_f64().expect("psnr") > 10.0);
    assert!(
        j["thresholds_failed"][0]
            .as_str()
            .expect("failure")
            .contains("flip")
    );
    let (w, h) = image::image_dimensions(&heat).expect("heatmap written");
    assert_eq!((w, h), (48 + 4 + 24, 32), "map plus the colour bar");

    let o = cbr(&["compare", s(&a), s(&c)], &[]);
    fails(&o, "size mismatch");
    let o = cbr(&["compare", s(&a), s(&d.path().join("missing.png"))], &[]);
    fails(&o, "missing.png: no such file");
    let o = cbr(
        &["compare", s(&a), s(&b), "--fail-above", "sharpness=3"],
        &[],
    );
    fails(&o, "unknown metric `sharpness`");
    let o = cbr(&["compare", s(&a), s(&b), "--crop", "40,0,20,10"], &[]);
    fails(&o, "does not fit");
}

#[test]
fn exr_layers_and_sequences() {
    let d = tempfile::tempdir().expect("tempdir");
    let (r, t) = (d.path().join("ref"), d.path().join("test"));
    // Two short renders of the demo: the reference, and the same frames at another LOD bias.
    for (dir, bias) in [(&r, "0"), (&t, "2")] {
        common::render_demo(dir, (64, 36), 3, &["--lod-bias", bias]).expect("render");
    }
    let o = cbr(
        &[
            "compare",
            s(&r.join("frame_0001.exr")),
            s(&r.join("frame_0001.exr")),
            "--layer",
            "depth",
            "--metrics",
            "mse",
            "--json",
        ],
        &[],
    );
    let j = json(&o, 0);
    assert_eq!(j["reference"]["layer"], "depth");
    assert_eq!(j["reference"]["channels"][0], "Z");
    assert!(
        j["reference"]["nonfinite_pixels"].as_u64().expect("count") > 0,
        "the sky's depth is +inf: counted, not averaged"
    );
    assert_eq!(j["mse"], 0.0);
    assert_eq!(j["excluded_pixels"], j["reference"]["nonfinite_pixels"]);
    let o = cbr(
        &[
            "compare",
            s(&r.join("frame_0001.exr")),
            s(&t.join("frame_0001.exr")),
            "--layer",
            "nope",
        ],
        &[],
    );
    fails(&o, "no layer `nope`");

    let o = cbr(
        &[
            "compare",
            s(&r),
            s(&t),
            "--warmup",
            "1",
            "--metrics",
            "psnr,flip",
            "--json",
        ],
        &[],
    );
    let j = json(&o, 0);
    assert_eq!(j["frames"].as_array().map(Vec::len), Some(3));
    assert_eq!(j["frames"][0]["warmup"], true);
    assert!(
        j["mean"]["flip"].as_f64().expect("mean flip") > 0.0,
        "blurrier textures differ"
    );
    assert!(
        j["flicker"].as_f64().is_some(),
        "flicker from the measured frames"
    );
    let o = cbr(&["compare", s(&r), s(&t), "--warmup", "3"], &[]);
    fails(&o, "--warmup 3 skips all 3 frames");
}
