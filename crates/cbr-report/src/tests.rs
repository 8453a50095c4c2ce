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

fn report(dirs: &[(&str, serde_json::Value)]) -> String {
    let d = tempfile::tempdir().unwrap();
    let benches: Vec<BenchDir> = dirs
        .iter()
        .map(|(name, json)| {
            let dir = d.path().join(name);
            std::fs::create_dir_all(&dir).unwrap();
            write_fixture(&dir, json)
        })
        .collect();
    render(&benches, &options(&d.path().join("report.html"), None)).unwrap()
}

/// The header cells (data-key, inner HTML) of every summary table.
fn summary_headers(html: &str) -> Vec<Vec<(String, String)>> {
    html.split("<table class=\"sortable\"")
        .skip(1)
        .map(|t| {
            let head = &t[..t.find("</thead>").unwrap()];
            head.split("<th ")
                .skip(1)
                .map(|th| {
                    let k = th.find("data-key=\"").unwrap() + 10;
                    let key = &th[k..k + th[k..].find('"').unwrap()];
                    let body = &th[th.find('>').unwrap() + 1..th.find("</th>").unwrap()];
                    (key.to_string(), body.to_string())
                })
                .collect()
        })
        .collect()
}

/// The rows of summary table `t`: (configuration at resolution, column key -> cell text).
fn summary_rows(html: &str, t: usize) -> Vec<(String, Vec<(String, String)>)> {
    let keys: Vec<String> = summary_headers(html)[t]
        .iter()
        .map(|h| h.0.clone())
        .collect();
    let table = html.split("<table class=\"sortable\"").nth(t + 1).unwrap();
    let body = &table[table.find("<tbody>").unwrap()..table.find("</tbody>").unwrap()];
    body.split("<tr>")
        .skip(1)
        .map(|tr| {
            let cells: Vec<String> = tr
                .split("<td")
                .skip(1)
                .map(|td| td[td.find('>').unwrap() + 1..td.find("</td>").unwrap()].to_string())
                .collect();
            assert_eq!(cells.len(), keys.len());
            let name = format!("{}@{}", cells[2], cells[1]);
            (name, keys.iter().cloned().zip(cells).collect())
        })
        .collect()
}

fn cell<'a>(rows: &'a [(String, Vec<(String, String)>)], row: &str, key: &str) -> &'a str {
    let r = &rows.iter().find(|r| r.0 == row).unwrap().1;
    &r.iter().find(|c| c.0 == key).unwrap().1
}

const ERROR_KEYS: [&str; 8] = [
    "psnr",
    "ssim",
    "flip_mean",
    "flip_median",
    "flip_edge",
    "flip_disocc",
    "flicker",
    "relmse",
];

/// Every error column of `table` (and the Pareto column) says `vs reference`; `edge`: whether
/// the edge FLIP column is there; `temporal`: whether the disocclusion FLIP, flicker, change and
/// reference change columns are.
fn assert_headers(table: &[(String, String)], reference: &str, edge: bool) {
    assert_headers_with(table, reference, edge, false);
}

fn assert_headers_with(table: &[(String, String)], reference: &str, edge: bool, temporal: bool) {
    let vs = format!("<br><span class=\"vs\">vs {reference}</span>");
    let shown = |key: &str| match key {
        "flip_edge" => edge,
        "flip_disocc" | "flicker" | "change" | "ref_change" => temporal,
        _ => true,
    };
    for key in ERROR_KEYS.iter().chain(&["pareto"]) {
        match table.iter().find(|(k, _)| k == key) {
            Some((_, body)) => assert!(body.ends_with(&vs), "{key}: {body}"),
            None => assert!(!shown(key), "no {key} column"),
        }
    }
    for key in [
        "flip_edge",
        "flip_disocc",
        "flicker",
        "change",
        "ref_change",
    ] {
        assert_eq!(table.iter().any(|(k, _)| k == key), shown(key), "{key}");
    }
    for (k, body) in table {
        if !ERROR_KEYS.contains(&k.as_str()) && k != "pareto" {
            assert!(!body.contains("vs "), "{k}: {body}");
        }
    }
}

/// Adds what `cbr bench` writes since the temporal metrics: k on every row, the disocclusion
/// FLIP (null for upscale:bilinear at 8x6: no disoccluded pixel in any frame), flicker, change
/// and the reference's change.
fn with_temporal(mut json: serde_json::Value, k: u64) -> serde_json::Value {
    use serde_json::json;
    for (n, r) in json["rows"].as_array_mut().unwrap().iter_mut().enumerate() {
        r["disocclusion_frames"] = json!(k);
        let i = (n % 3) as f64;
        let e = &mut r["error"];
        if e.is_null() {
            continue;
        }
        e["flip_disocc_mean"] = if n == 2 {
            json!(null)
        } else {
            json!(0.2 + 0.1 * i)
        };
        e["disocc_fraction_mean"] = json!(0.05);
        e["flicker_mean"] = json!(0.01 + 0.002 * i);
        e["change_mean"] = json!(0.03 + 0.001 * i);
        e["ref_change_mean"] = json!(0.025);
    }
    json
}

#[test]
fn old_form_renders_every_section() {
    let html = report(&[("a", fixture_json(false, "native"))]);
    for s in [
        "<h2 id=\"provenance\">",
        "<table class=\"sortable\" id=\"summary-table\">",
        "<h2 id=\"scene-0\">demo at 8x6, errors vs native</h2>",
        "<h2 id=\"scene-1\">demo at 16x12, errors vs native</h2>",
        "<svg class=\"chart\"",
        "data-name=\"native (reference)\"",
        "class=\"crop-outline\"",
        "GPU time per pass",
        "aria-label=\"FLIP per frame vs native\"",
        "<a href=\"a/bench.json\">bench.json</a>",
    ] {
        assert!(html.contains(s), "{s}");
    }
    // Every image once: 2 resolutions x (3 images + 2 FLIP maps).
    assert_eq!(html.matches("data:image/png;base64,").count(), 10);
}

#[test]
fn old_form_errors_say_vs_native() {
    let html = report(&[("a", fixture_json(false, "native"))]);
    let tables = summary_headers(&html);
    assert_eq!(tables.len(), 1);
    assert_headers(&tables[0], "native", false);
    for s in [
        "each against native at the same resolution",
        "native (bench.json from before the reference field)",
        ">FLIP mean vs native (log scale)</text>",
        "<h3>Viewer (frame 6, reference: native)</h3>",
        "data-name=\"FLIP upscale:bilinear vs native\"",
        "the highest FLIP vs native (outlined in the reference)",
        "<h3>FLIP per frame vs native</h3>",
        ">FLIP mean vs native:</text>",
    ] {
        assert!(html.contains(s), "{s}");
    }
    assert!(!html.contains("ssaa"));
    assert!(!html.contains("FLIP native"), "native is the reference");
    assert!(!html.contains("vs reference"));
}

#[test]
fn new_form_names_its_reference_and_adds_edge_flip() {
    let html = report(&[("a", fixture_json(true, "ssaa:16"))]);
    assert!(html.contains("vs ssaa:16"));
    assert!(!html.contains("vs native"), "no error is against native");
    let tables = summary_headers(&html);
    assert_eq!(tables.len(), 1);
    assert_headers(&tables[0], "ssaa:16", true);
    // The edge column: two rows with a value, upscale's is null; native is measured too.
    let rows = summary_rows(&html, 0);
    assert_eq!(rows.len(), 6);
    assert_eq!(cell(&rows, "native@8x6", "flip_edge"), "0.1000");
    assert_eq!(
        cell(&rows, "checkerboard:rotated:ours@8x6", "flip_edge"),
        "0.1500"
    );
    assert_eq!(cell(&rows, "upscale:bilinear@8x6", "flip_edge"), "–");
    assert_eq!(cell(&rows, "native@8x6", "flip_mean"), "0.0300");
    assert_eq!(cell(&rows, "native@16x12", "psnr"), "30.00");
    // ... a point, a technique panel and a FLIP map.
    assert!(html.contains("<title>native: 1.500 ms, FLIP vs ssaa:16 0.0300</title>"));
    assert!(html.contains("data-name=\"native\""));
    assert!(html.contains("{&quot;im&quot;:&quot;im1&quot;,&quot;name&quot;:&quot;native&quot;}"));
    assert!(html.contains("data-name=\"FLIP native vs ssaa:16\""));
    // The reference panel and the wipe's reference are the reference's own snapshot.
    assert!(html.contains("<img alt=\"ssaa:16 (reference)\" data-im=\"im0\""));
    assert!(html.contains("<img alt=\"reference\" data-im=\"im0\""));
    assert!(html.contains(&format!(
        "\"im0\":\"data:image/png;base64,{}\"",
        base64::Engine::encode(
            &base64::engine::general_purpose::STANDARD,
            "images/8x6/ref.png"
        )
    )));
    assert!(!html.contains("native (reference)"));
    assert!(html.contains("<a href=\"a/frames/8x6/ref.exr\">ssaa:16 (reference)</a>"));
    for s in [
        "each against ssaa:16 at the same resolution",
        "<h2 id=\"scene-0\">demo at 8x6, errors vs ssaa:16</h2>",
        "<tr><th class=\"t\">reference (every error is against it)</th><td>ssaa:16</td></tr>",
        ">FLIP mean vs ssaa:16 (log scale)</text>",
        "<h3>Viewer (frame 6, reference: ssaa:16)</h3>",
        "the highest FLIP vs ssaa:16 (outlined in the reference)",
        "<h3>FLIP per frame vs ssaa:16</h3>",
        ">FLIP mean vs ssaa:16:</text>",
    ] {
        assert!(html.contains(s), "{s}");
    }
    // 2 resolutions x (reference + 3 images + 3 FLIP maps).
    assert_eq!(html.matches("data:image/png;base64,").count(), 14);
}

#[test]
fn new_form_against_native() {
    let html = report(&[("a", fixture_json(true, "native"))]);
    let tables = summary_headers(&html);
    assert_headers(&tables[0], "native", true);
    assert!(html.contains("data-name=\"native (reference)\""));
    assert!(html.contains(
        "<tr><th class=\"t\">reference (every error is against it)</th><td>native</td></tr>"
    ));
}

#[test]
fn reference_from_the_top_level_or_the_rows() {
    let mut only_top = fixture_json(true, "ssaa:16");
    for r in only_top["rows"].as_array_mut().unwrap() {
        r.as_object_mut().unwrap().remove("reference");
    }
    let mut only_rows = fixture_json(true, "ssaa:16");
    only_rows.as_object_mut().unwrap().remove("reference");
    for json in [only_top, only_rows] {
        let html = report(&[("a", json)]);
        assert_headers(&summary_headers(&html)[0], "ssaa:16", true);
        assert!(!html.contains("vs native"));
        assert!(html.contains("<td>ssaa:16</td>"), "provenance");
        assert!(html.contains("data-name=\"ssaa:16 (reference)\""));
    }
}

#[test]
fn mixed_references_are_labelled_per_folder() {
    let html = report(&[
        ("old", fixture_json(false, "native")),
        ("new", fixture_json(true, "ssaa:16")),
    ]);
    let tables = summary_headers(&html);
    assert_eq!(tables.len(), 2, "one table per reference");
    assert_headers(&tables[0], "native", false);
    assert_headers(&tables[1], "ssaa:16", true);
    let native = html.find("<h3>Errors against native</h3>").unwrap();
    let ssaa = html.find("<h3>Errors against ssaa:16</h3>").unwrap();
    assert!(native < ssaa);
    assert!(html.contains("each against native or ssaa:16 (per bench folder) at the same"));
    for (id, reference) in [(0, "native"), (1, "native"), (2, "ssaa:16"), (3, "ssaa:16")] {
        let i = html.find(&format!("<h2 id=\"scene-{id}\">")).unwrap();
        let end = html[i + 1..]
            .find("<h2 ")
            .map(|e| i + 1 + e)
            .unwrap_or(html.len());
        let section = &html[i..end];
        let other = if reference == "native" {
            "ssaa:16"
        } else {
            "native"
        };
        assert!(
            section.contains(&format!("errors vs {reference}</h2>")),
            "{id}"
        );
        assert!(
            section.contains(&format!("FLIP mean vs {reference} (log scale)")),
            "{id}"
        );
        assert!(
            section.contains(&format!("FLIP per frame vs {reference}")),
            "{id}"
        );
        assert!(!section.contains(&format!("vs {other}")), "{id}");
    }
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

#[test]
fn temporal_columns_appear_with_their_window_and_values() {
    // Without the fields (bench.json from before them) the columns are hidden.
    let html = report(&[("a", fixture_json(true, "ssaa:16"))]);
    assert_headers_with(&summary_headers(&html)[0], "ssaa:16", true, false);
    assert!(!html.contains("disocclusion FLIP"));

    let html = report(&[("a", with_temporal(fixture_json(true, "ssaa:16"), 4))]);
    let tables = summary_headers(&html);
    assert_headers_with(&tables[0], "ssaa:16", true, true);
    let head = |key: &str| {
        tables[0]
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, b)| b.clone())
            .unwrap()
    };
    assert!(head("flip_disocc").starts_with("disocclusion FLIP (k = 4)<br>"));
    assert_eq!(head("ref_change"), "reference change");
    assert!(html.contains(
        "title=\"FLIP mean over the pixels whose reference object ID changed within the last k frames"
    ));
    assert!(html.contains("frames with no such pixel are left out (k = 4)\">"));
    // Values, a null as a dash, and the lowest flicker and disocclusion FLIP marked best.
    let rows = summary_rows(&html, 0);
    assert_eq!(cell(&rows, "native@8x6", "flip_disocc"), "0.2000");
    assert_eq!(
        cell(&rows, "checkerboard:rotated:ours@8x6", "flip_disocc"),
        "0.3000"
    );
    assert_eq!(cell(&rows, "upscale:bilinear@8x6", "flip_disocc"), "–");
    assert_eq!(
        cell(&rows, "checkerboard:rotated:ours@16x12", "flicker"),
        "0.0120"
    );
    assert_eq!(cell(&rows, "upscale:bilinear@16x12", "change"), "0.0320");
    assert_eq!(cell(&rows, "native@16x12", "ref_change"), "0.0250");
    assert!(html.contains("<td class=\"best\" data-v=\"0.01\">0.0100</td>"));
    assert!(html.contains("<td class=\"best\" data-v=\"0.2\">0.2000</td>"));
    assert!(
        !html.contains("<td class=\"best\" data-v=\"0.025\">"),
        "the reference's change is not ranked"
    );

    // Two bench folders with different windows: the header names both.
    let html = report(&[
        ("a", with_temporal(fixture_json(true, "ssaa:16"), 4)),
        ("b", with_temporal(fixture_json(true, "ssaa:16"), 2)),
    ]);
    assert!(html.contains(">disocclusion FLIP (k = 2, 4)<br>"));
}

#[test]
fn attribution_panel_appears_with_its_shares() {
    let plain = report(&[("a", fixture_json(true, "ssaa:16"))]);
    assert!(!plain.contains("Error by pixel class"));
    let mut json = fixture_json(true, "ssaa:16");
    let class = |p: f64, e: f64| serde_json::json!({"pixels": p, "error": e, "error_mean": 0.02, "flip_mean": 0.1});
    for r in json["rows"].as_array_mut().unwrap() {
        if r["config"] == "checkerboard:rotated:ours" {
            r["error"]["attribution"] = serde_json::json!({
                "rendered": class(0.5, 0.25), "history": class(0.4, 0.5),
                "clamped_history": class(0.05, 0.125), "rejected_id": class(0.05, 0.125),
                "rejected_depth": class(0.0, 0.0), "spatial": class(0.0, 0.0),
                "disoccluded": class(0.1, 0.3),
            });
        }
    }
    let html = report(&[("a", json)]);
    assert!(html.contains("Error by pixel class vs ssaa:16"), "no panel");
    assert!(
        html.contains("history: 50.0% of the error"),
        "no bar for history's error share"
    );
    assert!(
        html.contains("<td>40.0% / 50.0% / 0.0200</td>"),
        "no table cell"
    );
    assert!(
        html.contains("<td>10.0% / 30.0% / 0.0200</td>"),
        "no disoccluded cell"
    );
}

#[test]
fn rows_placed_on_a_supersampling_ladder_show_its_n_and_the_speedup() {
    let mut json = fixture_json(true, "ssaa:32");
    // The checkerboard row at 8x6 placed between two rungs; native there worse than the ladder.
    let rows = json["rows"].as_array_mut().unwrap();
    rows[1]["equal_error_ssaa"] = serde_json::json!({
        "flip_edge": {"n": 9.76, "samples_per_pixel": 95.3, "between": [8.0, 10.0],
                      "frame_ms": 3000.0, "speedup": 9.04},
        "ladder": [8.0, 10.0],
    });
    rows[0]["equal_error_ssaa"] = serde_json::json!({"flip_edge": {"worse_than": 8.0}});
    let html = report(&[("a", json)]);
    let table = &summary_headers(&html)[0];
    let header = |key: &str| &table.iter().find(|(k, _)| k == key).unwrap().1;
    assert!(header("equal_ssaa").ends_with("vs ssaa:32</span>"));
    assert!(!header("equal_ssaa_speedup").contains("vs "));
    let rows = summary_rows(&html, 0);
    for (row, key, text) in [
        ("checkerboard:rotated:ours@8x6", "equal_ssaa", "9.8"),
        ("checkerboard:rotated:ours@8x6", "equal_ssaa_speedup", "9.0"),
        ("native@8x6", "equal_ssaa", "–"),
        ("upscale:bilinear@16x12", "equal_ssaa_speedup", "–"),
    ] {
        assert_eq!(cell(&rows, row, key), text, "{row} {key}");
    }
    // Without any placed row the columns are not shown.
    let html = report(&[("a", fixture_json(true, "ssaa:32"))]);
    assert!(
        summary_headers(&html)[0]
            .iter()
            .all(|(k, _)| !k.starts_with("equal_ssaa"))
    );
}

#[test]
fn a_gpu_stats_file_beside_bench_json_adds_the_model_beside_lavapipe() {
    use serde_json::json;
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("a");
    std::fs::create_dir_all(&dir).unwrap();
    let b = write_fixture(&dir, &fixture_json(true, "native"));
    let frame = |family: &str, gpu: &str, us: f64| {
        json!({"family": family, "spec": "checkerboard:rotated:ours", "wave": 64, "gpu": gpu,
               "width": 16, "height": 12, "alu_us": us, "memory_us": 1.0, "predicted_us": us + 2.0,
               "passes": [
                   {"pass": "native.raster", "alu_us": 2.0, "memory_us": 1.0, "predicted_us": 2.0, "bound": "alu"},
                   {"pass": "resolve", "alu_us": 0.5, "memory_us": us, "predicted_us": us, "bound": "memory"}],
               "unmodelled": [], "excluded": []})
    };
    let study = json!({
        "version": 1, "width": 16, "height": 12,
        "families": [{"family": "vega10", "gpu": "Radeon RX Vega 56"},
                     {"family": "navi21", "gpu": "Radeon RX 6800 XT"}],
        "frames": [frame("vega10", "Radeon RX Vega 56", 12.25), frame("navi21", "Radeon RX 6800 XT", 7.5)],
    });
    std::fs::write(dir.join("gpu-stats.json"), study.to_string()).unwrap();
    let html = render(&[b], &options(&d.path().join("report.html"), None)).unwrap();
    assert_eq!(
        html.matches("Static GPU cost model").count(),
        2,
        "both groups"
    );
    // The 8x6 group: the file models another size.
    assert!(
        html.contains("gpu-stats.json models 16x12, not this group's 8x6"),
        "{html}"
    );
    // The 16x12 group: ours' resolve, lavapipe median 0.3 ms, beside both GPUs.
    for s in [
        "<th>Radeon RX Vega 56 (vega10) us</th>",
        "<td>checkerboard:rotated:ours</td><td>resolve</td><td>0.300</td><td>12.2 m</td><td>7.5 m</td>",
        "<td>frame (these passes)</td><td>1.300</td><td>14.2</td><td>9.5</td>",
    ] {
        assert!(html.contains(s), "{s}");
    }
    // Configurations the file does not model get no row.
    assert!(!html.contains("<td>upscale:bilinear</td><td>resolve</td>"));
    // A broken file is an error naming it.
    std::fs::write(dir.join("gpu-stats.json"), "{").unwrap();
    let b = BenchDir::load(&dir).unwrap();
    let err = render(&[b], &options(&d.path().join("report.html"), None)).unwrap_err();
    assert!(err.to_string().contains("gpu-stats.json"), "{err}");
}
