//! The `cbr` binary end to end: outputs, and every kind of bad input (one clear error naming the
//! file and line or the feature, exit status 1, no panic, no output written).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{cbr, stderr};

/// Runs `cbr render` on `scene` into a fresh folder and asserts a clean failure whose message
/// contains every string in `expect`.
fn expect_failure(scene: &Path, extra: &[&str], env: &[(&str, &str)], expect: &[&str]) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let mut args = vec![
        "render",
        scene.to_str().expect("utf8"),
        "-o",
        out.to_str().expect("utf8"),
    ];
    args.extend_from_slice(extra);
    let o = cbr(&args, env);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "exit status; stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    assert!(err.starts_with("error: "), "one clear error:\n{err}");
    for e in expect {
        assert!(err.contains(e), "expected `{e}` in:\n{err}");
    }
    assert!(!out.exists(), "no output folder may be written on failure");
}

/// The bench.json a `cbr bench` run wrote into `out`.
fn read_bench_json(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("bench.json")).expect("bench.json"))
        .expect("json")
}

fn write(dir: &Path, name: &str, text: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";

#[test]
fn malformed_obj_inputs_name_the_file_and_line() {
    let d = tempfile::tempdir().expect("tempdir");
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "nan.obj",
            "v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n",
            &["nan.obj:2:", "not a finite number"],
        ),
        (
            "inf.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n",
            &["inf.obj:3:", "not a finite number"],
        ),
        (
            "overflow.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 -1e400\nf 1 2 3\n",
            &["overflow.obj:3: vertex z:", "not a finite number"],
        ),
        (
            "toofar.obj",
            "v 0 0 0\nv 9e12 0 0\nv 0 1 0\nf 1 2 3\n",
            &[
                "toofar.obj:2: vertex x:",
                "beyond what f64 holds at 1 mm precision",
            ],
        ),
        (
            "garbage.obj",
            "v 0 0 0\nv 1 zero 0\n",
            &["garbage.obj:2:", "`zero` is not a number"],
        ),
        (
            "range.obj",
            "v 0 0 0\nv 1 0 0\nf 1 2 9\n",
            &["range.obj:3:", "face refers to vertex 9"],
        ),
        (
            "neg.obj",
            "v 0 0 0\nf -1 -2 -3\n",
            &["neg.obj:2:", "vertex -2"],
        ),
        (
            "degenerate.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 1 2\n",
            &["degenerate.obj", "no drawable triangles"],
        ),
        (
            "empty.obj",
            "# nothing\n",
            &["empty.obj", "no drawable triangles"],
        ),
    ];
    for (name, text, expect) in cases {
        let p = write(d.path(), name, text.as_bytes());
        expect_failure(&p, &[], &[], expect);
    }
    expect_failure(
        &d.path().join("absent.obj"),
        &[],
        &[],
        &["absent.obj", "cannot read"],
    );
}

#[test]
fn malformed_mtl_and_textures_name_the_file() {
    let d = tempfile::tempdir().expect("tempdir");
    let obj = |mtl: &str| format!("mtllib {mtl}\n{TRI}usemtl m\nf 1/1 2/1 3/1\n");
    write(d.path(), "short.mtl", b"newmtl m\nKd 0.5 0.5\n");
    let p = write(d.path(), "short.obj", obj("short.mtl").as_bytes());
    expect_failure(&p, &[], &[], &["short.mtl:2:", "Kd needs 3 numbers"]);

    write(d.path(), "missing.mtl", b"newmtl m\nmap_Kd nothere.png\n");
    let p = write(d.path(), "missing.obj", obj("missing.mtl").as_bytes());
    expect_failure(
        &p,
        &[],
        &[],
        &["nothere.png", "missing.mtl", "--missing-textures fallback"],
    );

    write(
        d.path(),
        "corrupt.png",
        b"\x89PNG\r\n\x1a\nthis is not a png",
    );
    write(d.path(), "corrupt.mtl", b"newmtl m\nmap_Kd corrupt.png\n");
    let p = write(d.path(), "corrupt.obj", obj("corrupt.mtl").as_bytes());
    expect_failure(&p, &[], &[], &["corrupt.png", "cannot decode texture"]);

    // The fallback renders, flagged in run.json.
    let out = d.path().join("fallback-out");
    let p = d.path().join("missing.obj");
    let o = cbr(
        &[
            "render",
            p.to_str().expect("utf8"),
            "-o",
            out.to_str().expect("utf8"),
            "--width",
            "32",
            "--height",
            "32",
            "--missing-textures",
            "fallback",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("run.json"))
            .expect("json");
    assert_eq!(run["scene"]["load"]["fallback_textures"], 1);
    assert!(
        run["scene"]["load"]["warnings"][0]
            .as_str()
            .unwrap_or("")
            .contains("nothere.png")
    );
}

#[test]
fn malformed_scene_toml_names_the_file_line_and_key() {
    let d = tempfile::tempdir().expect("tempdir");
    write(d.path(), "t.obj", format!("{TRI}f 1 2 3\n").as_bytes());
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "syntax.toml",
            "obj = \"t.obj\"\nwidth = = 3\n",
            &["syntax.toml:2:"],
        ),
        (
            "unknown.toml",
            "obj = \"t.obj\"\n[camera]\nfov = 3\n",
            &["unknown.toml:3:", "camera.fov", "unknown field"],
        ),
        (
            "type.toml",
            "obj = \"t.obj\"\nframes = \"many\"\n",
            &["type.toml:2:", "`frames`"],
        ),
        (
            "both.toml",
            "obj = \"t.obj\"\nprocedural = \"demo\"\n",
            &["both.toml", "exactly one of `obj` and `procedural`"],
        ),
        (
            "res.toml",
            "obj = \"t.obj\"\nwidth = 100000\n",
            &["res.toml", "100000x720", "outside"],
        ),
        (
            "anim.toml",
            "obj = \"t.obj\"\n[[animate]]\nobject = \"ghost\"\n",
            &["anim.toml", "`ghost` matches no object"],
        ),
        (
            "objmissing.toml",
            "obj = \"nope.obj\"\n",
            &["nope.obj", "cannot read"],
        ),
    ];
    for (name, text, expect) in cases {
        let p = write(d.path(), name, text.as_bytes());
        expect_failure(&p, &[], &[], expect);
    }
}

#[test]
fn absurd_arguments_and_unknown_scenes_fail_cleanly() {
    let d = tempfile::tempdir().expect("tempdir");
    let p = write(d.path(), "t.obj", format!("{TRI}f 1 2 3\n").as_bytes());
    expect_failure(&p, &["--width", "0"], &[], &["resolution 0x720"]);
    expect_failure(&p, &["--height", "999999"], &[], &["outside 1..=16384"]);
    expect_failure(
        &p,
        &["--frames", "0"],
        &[],
        &["--frames must be at least 1"],
    );
    expect_failure(
        Path::new("builtin:nope"),
        &[],
        &[],
        &["no built-in scene `nope`"],
    );
    let txt = write(d.path(), "scene.txt", b"hello");
    expect_failure(&txt, &[], &[], &["scene.txt", "expected a .toml scene"]);
}

#[test]
fn no_vulkan_device_is_a_clear_error() {
    let d = tempfile::tempdir().expect("tempdir");
    let p = write(d.path(), "t.obj", format!("{TRI}f 1 2 3\n").as_bytes());
    let env = [
        ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
    ];
    expect_failure(
        &p,
        &[],
        &env,
        &["no Vulkan device found", "/nonexistent/icd.json"],
    );
    expect_failure(
        &p,
        &["--device", "no-such-gpu"],
        &[],
        &[
            "no usable Vulkan device",
            "does not match --device \"no-such-gpu\"",
        ],
    );
}

#[test]
fn shader_errors_name_the_file_and_line() {
    let d = tempfile::tempdir().expect("tempdir");
    let p = write(d.path(), "t.obj", format!("{TRI}f 1 2 3\n").as_bytes());
    let shaders = d.path().join("shaders");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    for sub in ["inc", "scene"] {
        std::fs::create_dir_all(shaders.join(sub)).expect("mkdir");
        for e in std::fs::read_dir(src.join(sub)).expect("read shaders") {
            let e = e.expect("entry");
            std::fs::copy(e.path(), shaders.join(sub).join(e.file_name())).expect("copy");
        }
    }
    let frag = shaders.join("scene/forward.frag");
    let text = std::fs::read_to_string(&frag).expect("frag");
    std::fs::write(
        &frag,
        text.replacen(
            "void main() {",
            "void main() {\n    undefined_symbol = 1;",
            1,
        ),
    )
    .expect("write");
    let line = std::fs::read_to_string(&frag)
        .expect("frag")
        .lines()
        .position(|l| l.contains("undefined_symbol"))
        .expect("line")
        + 1;
    expect_failure(
        &p,
        &[],
        &[("CBR_SHADER_DIR", shaders.to_str().expect("utf8"))],
        &[&format!("scene/forward.frag:{line}"), "undefined_symbol"],
    );
}

#[test]
fn demo_renders_readable_outputs_with_zero_validation_messages() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("demo");
    let o = cbr(
        &[
            "render",
            "builtin:demo",
            "-o",
            out.to_str().expect("utf8"),
            "--width",
            "96",
            "--height",
            "54",
            "--frames",
            "2",
            "--validation",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("run.json"))
            .expect("json");
    assert_eq!(run["validation"]["enabled"], true);
    assert_eq!(
        run["validation"]["messages"], 0,
        "{}",
        run["validation"]["list"]
    );
    assert_eq!(run["frames"].as_array().map(Vec::len), Some(2));
    assert!(
        run["passes"][0]["gpu_ms"]["median"].as_f64().unwrap_or(0.0) > 0.0,
        "{}",
        run["passes"]
    );
    assert!(
        run["device"]["name"]
            .as_str()
            .is_some_and(|n| !n.is_empty())
    );
    for f in [
        "frame_0000.exr",
        "frame_0001.exr",
        "frame_0000.png",
        "frame_0001.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .expect("dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    // Our own reader, and OpenEXR's exrheader when installed.
    let ids = cbr_metrics::input::load(
        &out.join("frame_0001.exr"),
        Some("object_id"),
        Some(&["id".to_string()]),
    )
    .expect("object_id layer");
    assert_eq!((ids.rgb.width, ids.rgb.height), (96, 54));
    assert!(ids.rgb.c[0].data.iter().any(|&i| i > 0.0));
    match Command::new("exrheader")
        .arg(out.join("frame_0000.exr"))
        .output()
    {
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(o.status.success(), "exrheader failed: {}", stderr(&o));
            for part in ["color", "depth", "velocity", "object_id", "primitive_id"] {
                assert!(
                    text.contains(&format!("\"{part}\"")),
                    "exrheader does not list part {part}:\n{text}"
                );
            }
        }
        Err(_) => eprintln!(
            "SKIPPED exrheader check: exrheader is not installed (apt-get install openexr)"
        ),
    }
}

#[test]
fn resolve_and_upscale_write_their_layers_and_debug_views() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("cb");
    let run = common::render_demo(
        &out,
        (64, 36),
        2,
        &[
            "--validation",
            "--technique",
            "checkerboard",
            "--layout",
            "split",
            "--resolve",
            "pq4k",
            "--resolve-mapping",
            "pixel",
            "--resolve-group",
            "16",
            "--resolve-debug",
            "--resolve-without",
            "clamp,prepass",
        ],
    )
    .expect("render");
    assert_eq!(run["validation"]["messages"], 0, "{}", run["validation"]);
    // The shorthand flags become one spec, recorded whole (more cases: shorthand_flags_edit_the_spec).
    assert_eq!(
        run["settings"]["technique"],
        "checkerboard:split:pq4k:pixel:16:debug:without-clamp:without-prepass"
    );
    let cb = &run["settings"]["checkerboard"];
    assert_eq!(cb["resolve"]["mode"], "pq4k");
    assert_eq!(cb["resolve"]["ablation"]["clamp"], false);
    assert_eq!(run["frames"][0]["resolve_reset"], true);
    assert_eq!(run["frames"][1]["resolve_reset"], false);
    // The resolved frame has no holes; the debug layers say which pixels were missing.
    let color = cbr_metrics::input::load(&out.join("frame_0001.exr"), None, None).expect("color");
    assert!(color.rgb.c[1].data.iter().all(|&v| v > 0.0));
    let missing = cbr_metrics::input::load(
        &out.join("frame_0001.exr"),
        Some("resolve_missing"),
        Some(&["Y".to_string()]),
    )
    .expect("resolve_missing layer");
    let n = missing.rgb.c[0].data.iter().filter(|&&v| v > 0.5).count();
    assert_eq!(n, 64 * 36 / 2, "half the pixels are missing each frame");
    for view in ["parity", "reprojected", "spatial", "velocity", "ids"] {
        let f = out.join(format!("debug/frame_0001_{view}.png"));
        assert!(f.is_file(), "{}", f.display());
    }
    // The upscale baseline, and a bad group size.
    let up = d.path().join("up");
    let o = cbr(
        &[
            "render",
            "builtin:demo",
            "-o",
            up.to_str().expect("utf8"),
            "--width",
            "64",
            "--height",
            "36",
            "--frames",
            "1",
            "--technique",
            "upscale",
            "--filter",
            "bicubic",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(up.join("frame_0000.exr").is_file());
    let o = cbr(&["render", "builtin:demo", "--resolve-group", "12"], &[]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("8 or 16"), "{}", stderr(&o));
}

/// `taau:debug` from the command line: validation clean, the frame complete, the `taau` layer in
/// the EXR (disocclusion, lock, sample and history weight) and its four PNGs under debug/; a bad
/// `taau` parameter is one line naming it, with nothing written.
#[test]
fn taau_writes_its_debug_layer_and_refuses_bad_parameters() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("taau");
    let run = common::render_demo(
        &out,
        (64, 36),
        3,
        &["--validation", "--technique", "taau:0.77:debug"],
    )
    .expect("render");
    assert_eq!(run["validation"]["messages"], 0, "{}", run["validation"]);
    assert_eq!(run["settings"]["technique"], "taau:0.77:debug");
    let exr = out.join("frame_0002.exr");
    let color = cbr_metrics::input::load(&exr, None, None).expect("color");
    assert!(color.rgb.c[1].data.iter().all(|v| v.is_finite()));
    let hw = cbr_metrics::input::load(&exr, Some("taau"), Some(&["history_weight".to_string()]))
        .expect("taau layer");
    assert!(
        hw.rgb.c[0].data.iter().any(|&v| v > 1.0),
        "frame 2 accumulated no history"
    );
    for c in ["disocclusion", "lock", "sample_weight", "history_weight"] {
        let f = out.join(format!("debug/frame_0002_taau_{c}.png"));
        assert!(f.is_file(), "{}", f.display());
    }
    let bad = d.path().join("bad");
    let o = cbr(
        &[
            "render",
            "builtin:demo",
            "-o",
            bad.to_str().expect("utf8"),
            "--technique",
            "taau:without-clip",
        ],
        &[],
    );
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("taau can go without"), "{e}");
    assert!(
        !bad.join("frame_0000.exr").exists(),
        "a refused spec wrote a frame"
    );
}

/// bench.json's schema: the keys and types every consumer (the report, scripts) relies on.
fn check_bench_schema(b: &serde_json::Value) {
    assert_eq!(b["schema"], "cbr.bench/1");
    for k in [
        "cbr_version",
        "git_commit",
        "command",
        "device",
        "scene",
        "protocol",
        "rows",
    ] {
        assert!(!b[k].is_null(), "bench.json lacks `{k}`");
    }
    assert!(b["device"]["name"].is_string() && b["device"]["driver_info"].is_string());
    // The machine (on lavapipe, the device): its logical CPUs always; on Linux its CPU and the
    // load average at the start and end.
    let m = &b["machine"];
    assert!(m["logical_cpus"].as_u64().is_some_and(|n| n >= 1), "{m}");
    if std::path::Path::new("/proc/loadavg").exists() {
        for k in ["start", "end"] {
            let l = m["load_average"][k].as_array().expect("load average");
            assert!(
                l.len() == 3 && l.iter().all(|v| v.as_f64().is_some_and(|v| v >= 0.0)),
                "{m}"
            );
        }
        assert!(m["cpu"].is_string() && m["simd"].is_array(), "{m}");
    }
    let rows = b["rows"].as_array().expect("rows");
    assert!(!rows.is_empty());
    let reference = b["reference"].as_str().expect("reference named at the top");
    for r in rows {
        assert_eq!(r["reference"], reference, "every row names its reference");
        for k in ["scene", "config", "technique", "device", "driver"] {
            assert!(r[k].is_string(), "row lacks string `{k}`: {r}");
        }
        for k in ["width", "height", "warmup", "frames"] {
            assert!(r[k].is_u64(), "row lacks integer `{k}`: {r}");
        }
        assert!(r["lod_bias"].is_f64() && r["pareto"].is_boolean() && r["id_prepass"].is_boolean());
        let cached = r["cached_frames"].as_u64().expect("cached_frames");
        if cached < r["frames"].as_u64().expect("frames") {
            for k in ["median", "p5", "p95"] {
                assert!(r["frame_ms"][k].is_f64(), "frame_ms.{k}: {r}");
            }
            assert!(r["frame_ms"]["p5"].as_f64() <= r["frame_ms"]["median"].as_f64());
            assert!(r["frame_ms"]["median"].as_f64() <= r["frame_ms"]["p95"].as_f64());
            assert!(r["passes"].as_object().is_some_and(|p| !p.is_empty()));
        } else {
            assert!(r["frame_ms"].is_null(), "cached frames are not timed: {r}");
        }
        if r["config"] == reference {
            assert!(r["error"].is_null());
        } else {
            let e = &r["error"];
            for k in [
                "ssim_mean",
                "flip_mean",
                "flip_edge_mean",
                "flip_interior_mean",
                "relmse_mean",
            ] {
                assert!(e[k].is_f64(), "error.{k}: {r}");
            }
            let frames = r["frames"].as_u64().expect("frames") as usize;
            assert_eq!(e["per_frame"].as_array().map(Vec::len), Some(frames));
            // Temporal: the disocclusion FLIP is null only when no frame has a disoccluded
            // pixel; flicker and the changes need two measured frames.
            assert!(e["disocc_fraction_mean"].is_f64(), "{r}");
            let k = "flip_disocc_mean";
            assert!(e[k].is_f64() || e[k].is_null() && e["disocc_fraction_mean"] == 0.0);
            for k in ["flicker_mean", "change_mean", "ref_change_mean"] {
                assert_eq!(e[k].is_f64(), frames > 1, "error.{k}: {r}");
            }
        }
        assert_eq!(
            r["disocclusion_frames"],
            b["protocol"]["disocclusion_frames"]
        );
        if r["resolve"].is_string() {
            assert!(r["copy_floor_ms"]["median"].is_f64(), "copy floor: {r}");
            assert!(r["passes"]["resolve"]["median"].is_f64());
        }
    }
}

#[test]
fn bench_writes_json_and_csv_with_the_protocol_and_sweeps() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("bench");
    let sweep = write(
        d.path(),
        "sweep.toml",
        b"techniques = [\"checkerboard:rotated:ours\", \"upscale:bilinear\"]\nmappings = [\"pixel\", \"quad\"]\nresolutions = [\"64x36\"]\nwarmup = 1\nframes = 2\n",
    );
    let o = cbr(
        &[
            "bench",
            "builtin:demo",
            "--sweep",
            sweep.to_str().expect("utf8"),
            "--validation",
            "-o",
            out.to_str().expect("utf8"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let b = read_bench_json(&out);
    check_bench_schema(&b);
    assert_eq!(b["validation"]["messages"], 0);
    let configs: Vec<&str> = b["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r["config"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(
        configs,
        [
            "native",
            "checkerboard:rotated:ours:pixel",
            "checkerboard:rotated:ours:quad",
            "upscale:bilinear"
        ]
    );
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5, "{csv}");
    assert!(lines[0].starts_with("scene,config,technique,"));
    assert!(lines[1..].iter().all(|l| l.contains(",64,36,")), "{csv}");
    // Bad input: an unknown key in the sweep, an unknown configuration.
    let bad = write(
        d.path(),
        "bad.toml",
        b"frames = 2\nresolution = [\"64x36\"]\n",
    );
    let o = cbr(
        &[
            "bench",
            "builtin:demo",
            "--sweep",
            bad.to_str().expect("utf8"),
        ],
        &[],
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("bad.toml") && stderr(&o).contains("resolution"),
        "{}",
        stderr(&o)
    );
    let o = cbr(
        &[
            "bench",
            "builtin:demo",
            "--techniques",
            "checkerboard:hexagon",
        ],
        &[],
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("hexagon"), "{}", stderr(&o));
}

#[test]
fn bench_timing_only_times_every_row_and_measures_no_error() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("bench");
    // ssaa is cacheable: timing only neither reads nor writes the frame cache.
    let cache = d.path().join("cache");
    let o = cbr(
        &[
            "bench",
            "builtin:demo",
            "--width",
            "64",
            "--height",
            "36",
            "--warmup",
            "1",
            "--frames",
            "2",
            "--techniques",
            "checkerboard:rotated:ours,checkerboard:split:pq4k:fp16,ssaa:2",
            "--groups",
            "8,16",
            "--timing-only",
            "--validation",
            "-o",
            out.to_str().expect("utf8"),
        ],
        &[("CBR_CACHE_DIR", cache.to_str().expect("utf8"))],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let b = read_bench_json(&out);
    assert_eq!(b["validation"]["messages"], 0);
    assert_eq!(b["protocol"]["timing_only"], true);
    assert_eq!(b["protocol"]["metrics"], "not measured (--timing-only)");
    assert!(
        !cache.exists() || std::fs::read_dir(&cache).expect("cache").next().is_none(),
        "no frame may be cached"
    );
    let rows = b["rows"].as_array().expect("rows");
    let configs: Vec<&str> = rows
        .iter()
        .map(|r| r["config"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(
        configs,
        [
            "native",
            "checkerboard:rotated:ours:8",
            "checkerboard:rotated:ours:16",
            "checkerboard:split:pq4k:fp16:8",
            "checkerboard:split:pq4k:fp16:16",
            "ssaa:2"
        ]
    );
    for r in rows {
        let c = r["config"].as_str().unwrap_or("");
        assert!(r["error"].is_null(), "{c}: {}", r["error"]);
        assert!(r["images"].is_null(), "{c}: no image is written");
        assert_eq!(r["frame_ms"]["n"], 2, "{c}");
        assert!(
            r["frame_ms"]["median"].as_f64().is_some_and(|t| t > 0.0),
            "{c}"
        );
        // Where the run's wall-clock time went: the set-up and the frames.
        for k in ["setup_s", "frames_wall_s"] {
            assert!(r[k].as_f64().is_some_and(|t| t > 0.0), "{c}: {k}");
        }
        if c.starts_with("checkerboard") {
            assert_eq!(r["passes"]["resolve"]["n"], 2, "{c}");
            assert_eq!(r["copy_floor_ms"]["n"], 2, "{c}");
        }
    }
    let written: Vec<String> = std::fs::read_dir(&out)
        .expect("out")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        written
            .iter()
            .all(|f| f == "bench.json" || f == "bench.csv"),
        "{written:?}"
    );
    let report = d.path().join("report.html");
    let o = cbr(
        &[
            "report",
            out.to_str().expect("utf8"),
            "-o",
            report.to_str().expect("utf8"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // No error is measured, so no reference is taken.
    let refused = d.path().join("refused");
    let o = cbr(
        &[
            "bench",
            "builtin:demo",
            "--width",
            "64",
            "--height",
            "36",
            "--timing-only",
            "--reference",
            "ssaa:4",
            "-o",
            refused.to_str().expect("utf8"),
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--timing-only"), "{}", stderr(&o));
    assert!(!refused.exists());
}

#[test]
fn bench_against_a_supersampled_reference_names_it_everywhere_and_caches_it() {
    let d = tempfile::tempdir().expect("tempdir");
    let cache = d.path().join("cache");
    let cache_env = [("CBR_CACHE_DIR", cache.to_str().expect("utf8"))];
    let run = |out: &Path| {
        let o = cbr(
            &[
                "bench",
                "builtin:demo",
                "--width",
                "48",
                "--height",
                "27",
                "--warmup",
                "1",
                "--frames",
                "2",
                "--reference",
                "ssaa:2",
                "--techniques",
                "msaa:4,checkerboard:rotated:ours+sharpen,analytic",
                "--validation",
                "-o",
                out.to_str().expect("utf8"),
            ],
            &cache_env,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let b = read_bench_json(out);
        check_bench_schema(&b);
        assert_eq!(b["validation"]["messages"], 0);
        b
    };
    let b = run(&d.path().join("first"));
    assert_eq!(b["reference"], "ssaa:2");
    let configs: Vec<&str> = b["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r["config"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(
        configs,
        [
            "ssaa:2",
            "native",
            "msaa:4",
            "checkerboard:rotated:ours+sharpen",
            "analytic"
        ]
    );
    // analytic's error by what its resolve composited: shares of all and of edge pixels.
    let a = &b["rows"][4]["error"]["analytic_attribution"];
    for set in ["all", "edge"] {
        let sum = |k: &str| -> f64 {
            cbr_bench::analytic_attribution::CLASSES
                .iter()
                .map(|c| a[set][c][k].as_f64().expect("share"))
                .sum()
        };
        assert!((sum("pixels") - 1.0).abs() < 1e-9, "{set}: {a}");
        assert!((sum("error") - 1.0).abs() < 1e-9, "{set}: {a}");
    }
    assert!(b["rows"][2]["error"]["analytic_attribution"].is_null());
    let native = &b["rows"][1];
    assert!(
        native["error"]["flip_edge_mean"]
            .as_f64()
            .is_some_and(|v| v > 0.0)
    );
    assert!(native["error"]["per_frame"][0]["flip_edge"].is_f64());
    // The frame's FLIP mean is the pixel-weighted mix of its edge and interior means.
    let f0 = &native["error"]["per_frame"][0];
    let (mean, edge, interior) = (
        f0["flip_mean"].as_f64().expect("flip"),
        f0["flip_edge"].as_f64().expect("edge"),
        f0["flip_interior"].as_f64().expect("interior"),
    );
    assert!(
        edge.min(interior) - 1e-6 <= mean && mean <= edge.max(interior) + 1e-6 && edge != interior,
        "mean {mean}, edge {edge}, interior {interior}"
    );
    assert!(b["reference_images"]["48x27"]["image"].is_string());
    assert!(
        b["protocol"]["reference"]
            .as_str()
            .unwrap_or("")
            .starts_with("ssaa:2")
    );
    assert_eq!(b["rows"][0]["cached_frames"], 0);
    // The second run reads the reference from the cache: same errors, untimed reference.
    let again = run(&d.path().join("second"));
    assert_eq!(again["rows"][0]["cached_frames"], 2);
    assert_eq!(
        again["rows"][1]["error"]["flip_mean"],
        b["rows"][1]["error"]["flip_mean"]
    );
    let csv = std::fs::read_to_string(d.path().join("first/bench.csv")).expect("csv");
    assert!(csv.lines().next().unwrap_or("").contains("flip_edge_mean"));
    assert!(
        csv.lines().nth(2).unwrap_or("").contains(",ssaa:2,"),
        "{csv}"
    );
    // A reference that is no spec is refused by name (device refusals: tests/msaa.rs).
    for (bad, says) in [("ssaa:0", "ssaa N `0`"), ("hexagonal", "`hexagonal`")] {
        let o = cbr(
            &[
                "bench",
                "builtin:demo",
                "--width",
                "16",
                "--height",
                "9",
                "--reference",
                bad,
                "-o",
                d.path().join("bad").to_str().expect("utf8"),
            ],
            &cache_env,
        );
        assert!(!o.status.success());
        assert!(stderr(&o).contains(says), "{bad}: {}", stderr(&o));
    }
}

#[test]
fn bench_writes_the_temporal_metrics_with_finite_values() {
    let d = tempfile::tempdir().expect("tempdir");
    let cache = d.path().join("cache");
    let cache_env = [("CBR_CACHE_DIR", cache.to_str().expect("utf8"))];
    let run = |reference: &str, k: Option<&str>, out: &Path| {
        let mut args = vec![
            "bench",
            "builtin:demo",
            "--width",
            "48",
            "--height",
            "27",
            "--warmup",
            "3",
            "--frames",
            "3",
            "--reference",
            reference,
            "--techniques",
            "native,upscale:bilinear",
            "-o",
            out.to_str().expect("utf8"),
        ];
        if let Some(k) = k {
            args.extend(["--disocclusion-frames", k]);
        }
        let o = cbr(&args, &cache_env);
        assert!(o.status.success(), "{}", stderr(&o));
        let b = read_bench_json(out);
        check_bench_schema(&b);
        b
    };
    let per_frame = |r: &serde_json::Value, key: &str| -> Vec<Option<f64>> {
        r["error"]["per_frame"]
            .as_array()
            .expect("per_frame")
            .iter()
            .map(|f| f[key].as_f64())
            .collect()
    };
    // ssaa:2 skips its warm-up frames: a native raster gives their IDs, checked on frame 3.
    let b = run("ssaa:2", None, &d.path().join("k4"));
    assert_eq!(b["protocol"]["disocclusion_frames"], 4);
    let ids = &b["protocol"]["disocclusion_ids"][0];
    assert_eq!(ids["native"]["native_frames"], serde_json::json!([0, 3]));
    assert_eq!(ids["native"]["mismatched_pixels"], 0, "{ids}");
    let rows = b["rows"].as_array().expect("rows");
    let ref_change = per_frame(&rows[1], "ref_change");
    assert_eq!(
        ref_change[0], None,
        "no change before the first measured frame"
    );
    for r in &rows[1..] {
        let e = &r["error"];
        for k in [
            "flip_disocc_mean",
            "flicker_mean",
            "change_mean",
            "ref_change_mean",
        ] {
            assert!(e[k].as_f64().is_some_and(f64::is_finite), "{k}: {r}");
        }
        let fraction = per_frame(r, "disocc_fraction");
        assert!(
            fraction
                .iter()
                .all(|f| f.is_some_and(|f| f > 0.0 && f < 0.5)),
            "{fraction:?}"
        );
        assert!(per_frame(r, "flip_disocc").iter().all(Option::is_some));
        // The reference's change is the reference's: the same on every row.
        assert_eq!(per_frame(r, "ref_change"), ref_change);
        // |change - ref_change| <= flicker, frame by frame (the triangle inequality).
        let (x, f) = (per_frame(r, "change"), per_frame(r, "flicker"));
        for t in 1..3 {
            let (x, rc, f) = (
                x[t].expect("x"),
                ref_change[t].expect("r"),
                f[t].expect("f"),
            );
            assert!((x - rc).abs() <= f + 1e-9 && f > 0.0, "{x} {rc} {f}");
        }
    }
    // Where the ID changed, the error is higher than over the whole frame (edges move there).
    let native = &rows[1]["error"];
    assert!(
        native["flip_disocc_mean"].as_f64() > native["flip_mean"].as_f64(),
        "{native}"
    );
    let csv = std::fs::read_to_string(d.path().join("k4/bench.csv")).expect("csv");
    let head: Vec<&str> = csv.lines().next().unwrap_or("").split(',').collect();
    // The native row; counted from the end (the device name holds a quoted comma).
    let cells: Vec<&str> = csv.lines().nth(2).unwrap_or("").split(',').collect();
    for c in [
        "disocclusion_frames",
        "flip_disocc_mean",
        "flicker_mean",
        "ref_change_mean",
    ] {
        let from_end = head.len() - head.iter().position(|h| *h == c).expect(c);
        let cell = cells[cells.len() - from_end];
        assert!(cell.parse::<f64>().is_ok(), "{c}: {csv}");
    }
    // A shorter window marks a subset of the pixels; the reference's own frames give the IDs
    // when it renders its warm-up frames (native).
    let b1 = run("ssaa:2", Some("1"), &d.path().join("k1"));
    assert_eq!(b1["rows"][1]["disocclusion_frames"], 1);
    let (f1, f4) = (
        per_frame(&b1["rows"][1], "disocc_fraction"),
        per_frame(&rows[1], "disocc_fraction"),
    );
    assert!(f1.iter().zip(&f4).all(|(a, b)| a < b), "{f1:?} {f4:?}");
    let n = run("native", Some("2"), &d.path().join("native"));
    assert_eq!(n["protocol"]["disocclusion_ids"][0]["source"], "reference");
    assert!(n["protocol"]["disocclusion_ids"][0]["native"].is_null());
    assert!(n["rows"][1]["error"]["flip_disocc_mean"].is_f64());
    let o = cbr(
        &["bench", "builtin:demo", "--disocclusion-frames", "0"],
        &cache_env,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--disocclusion-frames must be at least 1"));
}

#[test]
fn shorthand_flags_edit_the_spec_and_contradictions_are_refused() {
    let d = tempfile::tempdir().expect("tempdir");
    let spec_of = |args: &[&str]| -> Result<String, String> {
        let out = d
            .path()
            .join(format!("o{}", args.join("_").replace([':', '+', '-'], "")));
        let run = common::render_demo(&out, (32, 18), 1, args)?;
        Ok(run["settings"]["technique"]
            .as_str()
            .unwrap_or("")
            .to_string())
    };
    let ok = |args: &[&str], want: &str| {
        assert_eq!(spec_of(args).as_deref(), Ok(want), "{args:?}");
    };
    ok(
        &["--technique", "checkerboard"],
        "checkerboard:rotated:ours",
    );
    ok(
        &[
            "--technique",
            "checkerboard",
            "--layout",
            "split",
            "--id-prepass",
        ],
        "checkerboard:split:ours:prepass",
    );
    ok(
        &["--technique", "upscale", "--filter", "bicubic"],
        "upscale:bicubic",
    );
    ok(
        &["--technique", "msaa:4", "--sample-shading"],
        "msaa:4:sample",
    );
    ok(
        &["--technique", "native+sharpen:0.25"],
        "native+sharpen:0.25",
    );
    ok(
        &[
            "--technique",
            "checkerboard:rotated:ours+taa:16",
            "--taa-without",
            "clip,catmull",
        ],
        "checkerboard:rotated:ours+taa:16:without-clip:without-catmull",
    );
    for (args, says) in [
        (
            &["--technique", "native", "--taa-without", "ids"][..],
            "needs `+taa`",
        ),
        (
            &["--technique", "native+taa:inside", "--taa-without", "ids"],
            "INSIDE",
        ),
        (&["--technique", "ssaa:2+taa"], "geometry"),
        (
            &["--technique", "checkerboard:split", "--layout", "rotated"][..],
            "contradicts",
        ),
        (
            &["--technique", "native", "--layout", "split"],
            "--layout applies to",
        ),
        (
            &["--technique", "native", "--sample-shading"],
            "--sample-shading applies to",
        ),
        (
            &["--technique", "ssaa:4", "--filter", "bicubic"],
            "--filter applies to",
        ),
        (
            &["--technique", "checkerboard:split:none+sharpen"],
            "full frame",
        ),
        (&["--technique", "native+blur"], "+sharpen"),
    ] {
        let e = spec_of(args).expect_err("refused");
        assert!(e.contains(says) && !e.contains("panicked"), "{args:?}: {e}");
    }
}

#[test]
fn interlaced_writes_its_mask_and_debug_views() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("il");
    let run = common::render_demo(
        &out,
        (64, 36),
        3,
        &["--validation", "--technique", "interlaced:debug"],
    )
    .expect("render");
    assert_eq!(run["validation"]["messages"], 0, "{}", run["validation"]);
    assert_eq!(run["settings"]["technique"], "interlaced:debug");
    for (f, parity, reset) in [(0, 0, true), (1, 1, false), (2, 0, false)] {
        assert_eq!(run["frames"][f]["parity"], parity);
        assert_eq!(run["frames"][f]["resolve_reset"], reset);
    }
    // Frame 1 rendered the odd rows: `mask` says so, and the missing view is its complement.
    let layer = |name: &str| {
        cbr_metrics::input::load(
            &out.join("frame_0001.exr"),
            Some(name),
            Some(&["Y".to_string()]),
        )
        .unwrap_or_else(|e| panic!("layer {name}: {e}"))
        .rgb
        .c[0]
            .data
            .clone()
    };
    let (mask, missing) = (layer("mask"), layer("resolve_missing"));
    for (i, (m, g)) in mask.iter().zip(&missing).enumerate() {
        let odd = (i / 64) % 2 == 1;
        assert_eq!(
            (*m, *g),
            if odd { (1.0, 0.0) } else { (0.0, 1.0) },
            "pixel {i}"
        );
    }
    for view in ["parity", "reprojected", "spatial", "still", "ids"] {
        let f = out.join(format!("debug/frame_0001_{view}.png"));
        assert!(f.is_file(), "{}", f.display());
    }
    // A parameter it does not read: one error naming it and what it reads.
    let o = cbr(
        &["render", "builtin:demo", "--technique", "interlaced:fields"],
        &[],
    );
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("`fields`") && err.contains("without-clamp"),
        "{err}"
    );
}

/// Renders frame 0 of the demo with `technique` at `w` x `h`; returns the folder (kept alive by
/// the TempDir), the output directory and run.json.
fn render_demo_frame(
    technique: &str,
    w: u32,
    h: u32,
) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let run = common::render_demo(&out, (w, h), 1, &["--technique", technique])
        .unwrap_or_else(|e| panic!("{technique}: {e}"));
    (dir, out, run)
}

#[test]
fn analytic_seed_counts_its_errors_in_run_json_and_draws_them() {
    let (_dir, out, run) = render_demo_frame("analytic:seed", 96, 54);
    let a = &run["frames"][0]["analytic"];
    let edge = a["edge_pixels"].as_u64().expect("edge pixels");
    let off = a["seed_differs_pixels"].as_u64().expect("seed pixels");
    let share = a["seed_differs_edge_fraction"].as_f64().expect("share");
    assert!(edge > 100 && off > 0 && share > 0.0 && share <= 1.0, "{a}");
    assert_eq!(a["kept_per_pixel"], 32, "{a}");
    assert!(a["tail_fragments"].as_u64().is_some(), "{a}");
    assert_eq!(a["nonfinite_pixels"], 0, "{a}");
    assert!(out.join("debug/frame_0000_seed_differs.png").is_file());
}

/// `interleaved:...:debug` writes its debug views: the EXR layer `interleaved` (subset, edge,
/// fallback, read back by our reader: the subset layer is (x mod M) + M (y mod N) where something
/// was drawn), the four PNGs, and its counts in run.json (no round-trip mismatch).
#[test]
fn interleaved_debug_views_reach_the_exr_the_pngs_and_run_json() {
    let (_dir, out, run) = render_demo_frame("interleaved:3x2:vpls=48:debug", 64, 36);
    let i = &run["frames"][0]["interleaved"];
    assert_eq!(i["tile"], serde_json::json!([3, 2]), "{i}");
    assert_eq!(i["roundtrip_mismatches"], 0, "{i}");
    let visible = i["visible_pixels"].as_u64().expect("visible");
    let edges = i["edge_pixels"].as_u64().expect("edges");
    let fallback = i["fallback_pixels"].as_u64().expect("fallback");
    assert!(visible > 500 && edges > 0 && edges < visible, "{i}");
    assert!(fallback > 0 && fallback <= visible, "{i}");
    for view in ["mosaic", "subset", "edges", "fallback"] {
        let png = out.join(format!("debug/frame_0000_interleaved_{view}.png"));
        assert!(png.is_file(), "{}", png.display());
    }
    let exr = out.join("frame_0000.exr");
    let subset = cbr_metrics::input::load(&exr, Some("interleaved"), Some(&["subset".into()]))
        .expect("interleaved layer");
    let ids = cbr_metrics::input::load(&exr, Some("object_id"), Some(&["id".into()]))
        .expect("object_id layer");
    let (w, h) = (subset.rgb.width, subset.rgb.height);
    assert_eq!((w, h), (64, 36));
    for y in 0..h {
        for x in 0..w {
            if ids.rgb.c[0].data[y * w + x] > 0.0 {
                let want = (x % 3 + 3 * (y % 2)) as f32;
                assert_eq!(subset.rgb.c[0].data[y * w + x], want, "({x}, {y})");
            }
        }
    }
}
