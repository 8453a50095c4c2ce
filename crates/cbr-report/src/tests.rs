//! Rendering tests on bench.json files built here (old form and the form with reference
//! fields), with small stand-in image files.

use crate::{BenchDir, Options, render};

/// A bench.json like `cbr bench` writes; `new_form` adds the reference fields.
pub(crate) fn fixture_json(new_form: bool, reference: &str) -> serde_json::Value {
    use serde_json::json;
    let mut rows = Vec::new();
    for (w, h) in [(8u64, 6u64), (16, 12)] {
        for (i, config) in ["native", "checkerboard:rotated:ours", "upscale:bilinear"]
            .iter()
            .enumerate()
        {
            let is_native = *config == "native";
            let has_error = !is_native || new_form && reference != "native";
            let name = config.replace(':', "_");
            let per_frame: Vec<_> = (4..7)
                .map(|f| {
                    let mut e = json!({"frame": f, "psnr": 30.0 + i as f64, "ssim": 0.9,
                        "flip_mean": 0.01 * (i + 1) as f64 + 0.001 * f as f64,
                        "flip_median": 0.005, "relmse": 0.02});
                    if new_form {
                        e["flip_edge"] = json!(0.05 * (i + 1) as f64);
                    }
                    e
                })
                .collect();
            let mut error = json!({
                "psnr_mean": 30.0 + i as f64,
                "ssim_mean": 0.9 + 0.01 * i as f64,
                "flip_mean": 0.03 + 0.011 * i as f64,
                "flip_median_mean": 0.004 * (i + 1) as f64,
                "relmse_mean": 0.02 * (i + 1) as f64,
                "per_frame": per_frame,
            });
            if new_form {
                error["flip_edge_mean"] = if i == 2 {
                    json!(null)
                } else {
                    json!(0.1 + 0.05 * i as f64)
                };
            }
            let mut row = json!({
                "scene": "demo",
                "config": config,
                "width": w,
                "height": h,
                "frame_ms": {"median": 1.5 + 0.7 * i as f64, "p5": 1.4, "p95": 2.0 + i as f64},
                "passes": {
                    "native.raster": {"median": 1.0},
                    "resolve": {"median": 0.3 * i as f64},
                    "readback": {"median": 0.2}
                },
                "images": {
                    "frame": 6,
                    "image": format!("images/{w}x{h}/{name}.png"),
                    "flip": if has_error { json!(format!("images/{w}x{h}/{name}.flip.png")) } else { json!(null) },
                    "exr": format!("frames/{w}x{h}/{name}.exr"),
                },
                "crops": [[0, 0, 2, 2], [4, 2, 2, 2]],
                "error": if has_error { error } else { json!(null) },
                "pareto": i == 1,
            });
            if new_form {
                row["reference"] = json!(reference);
            }
            rows.push(row);
        }
    }
    let mut j = json!({
        "schema": "cbr.bench/1",
        "cbr_version": "0.1.0",
        "git_commit": "abc123",
        "command": ["cbr", "bench", "builtin:demo"],
        "device": {"name": "llvmpipe", "driver_info": "Mesa"},
        "scene": {"name": "demo", "source": "builtin", "triangles": 12},
        "protocol": {"warmup_frames": 4, "measured_frames": 3, "timing": "GPU timestamps",
            "frame_ms": "sum", "reference": "native at the same resolution and frame",
            "display": "sRGB", "metrics": "PSNR, SSIM, FLIP"},
        "rows": rows,
    });
    if new_form {
        j["reference"] = json!(reference);
        if reference != "native" {
            j["reference_images"] = json!({
                "8x6": {"image": "images/8x6/ref.png", "exr": "frames/8x6/ref.exr"},
                "16x12": {"image": "images/16x12/ref.png", "exr": "frames/16x12/ref.exr"},
            });
        }
    }
    j
}

/// Writes `json` and a small file for every image it names into `dir`.
pub(crate) fn write_fixture(dir: &std::path::Path, json: &serde_json::Value) -> BenchDir {
    let mut files: Vec<String> = Vec::new();
    for r in json["rows"].as_array().unwrap() {
        for k in ["image", "flip"] {
            if let Some(p) = r["images"][k].as_str() {
                files.push(p.into());
            }
        }
    }
    if let Some(m) = json["reference_images"].as_object() {
        files.extend(
            m.values()
                .filter_map(|v| v["image"].as_str().map(String::from)),
        );
    }
    for f in files {
        let p = dir.join(&f);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, f.as_bytes()).unwrap();
    }
    std::fs::write(dir.join("bench.json"), serde_json::to_string(json).unwrap()).unwrap();
    BenchDir::load(dir).unwrap()
}

fn options(out: &std::path::Path, assets_dir: Option<std::path::PathBuf>) -> Options {
    Options {
        out: out.to_path_buf(),
        assets_dir,
        colormap: vec![[0, 0, 0], [255, 255, 255]],
        created: "2026-01-01 00:00:00 UTC".into(),
    }
}

#[test]
fn old_form_renders_every_section() {
    let d = tempfile::tempdir().unwrap();
    let b = write_fixture(d.path(), &fixture_json(false, "native"));
    let html = render(&[b], &options(&d.path().join("report.html"), None)).unwrap();
    for s in [
        "<h2 id=\"provenance\">",
        "<table class=\"sortable\" id=\"summary-table\">",
        "<h2 id=\"scene-0\">demo at 8x6</h2>",
        "<h2 id=\"scene-1\">demo at 16x12</h2>",
        "<svg class=\"chart\"",
        "data-name=\"native (reference)\"",
        "class=\"crop-outline\"",
        "GPU time per pass",
        "aria-label=\"FLIP per frame\"",
        "<a href=\"bench.json\">bench.json</a>",
    ] {
        assert!(html.contains(s), "{s}");
    }
    // Every image once: 2 resolutions x (3 images + 2 FLIP maps).
    assert_eq!(html.matches("data:image/png;base64,").count(), 10);
}

#[test]
fn assets_are_copied_and_linked() {
    let d = tempfile::tempdir().unwrap();
    let bench = d.path().join("bench");
    std::fs::create_dir_all(&bench).unwrap();
    let b = write_fixture(&bench, &fixture_json(false, "native"));
    let out = d.path().join("r/report.html");
    let assets = d.path().join("r/assets");
    let html = render(&[b], &options(&out, Some(assets.clone()))).unwrap();
    assert!(!html.contains("data:image/png"));
    assert!(assets.join("b0/images/8x6/native.png").is_file());
    assert!(html.contains("\"assets/b0/images/8x6/native.png\""));
    assert!(html.contains("href=\"../bench/bench.json\""));
}

/// The speed-vs-error chart SVGs of a report.
fn charts(html: &str) -> Vec<&str> {
    html.split("<svg class=\"chart\"")
        .skip(1)
        .map(|s| &s[..s.find("</svg>").unwrap()])
        .collect()
}

#[test]
fn chart_axes_have_three_labelled_ticks() {
    // Times 2.2 and 2.9 ms, FLIP 0.041 and 0.052: under a decade on both axes.
    let d = tempfile::tempdir().unwrap();
    let b = write_fixture(d.path(), &fixture_json(false, "native"));
    let html = render(&[b], &options(&d.path().join("report.html"), None)).unwrap();
    let c = charts(&html);
    assert_eq!(c.len(), 2);
    for svg in c {
        let x: Vec<&str> = svg
            .split("<text class=\"xtick\"")
            .skip(1)
            .map(|s| &s[s.find('>').unwrap() + 1..s.find("</text>").unwrap()])
            .collect();
        let y: Vec<&str> = svg
            .split("<text class=\"ytick\"")
            .skip(1)
            .map(|s| &s[s.find('>').unwrap() + 1..s.find("</text>").unwrap()])
            .collect();
        assert_eq!(x, ["2", "2.5", "3", "3.5"]);
        assert_eq!(y, ["0.04", "0.05", "0.06"]);
        assert!(svg.contains(">GPU ms per frame (median, log scale)</text>"));
    }
}
