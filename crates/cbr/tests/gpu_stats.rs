//! `cbr gpu-stats` as a user runs it: every pipeline of the specs compiled for vega10 and navi21
//! (navi21's compute as wave64 and wave32), the statistics by the driver's names, the model's
//! figures recomputed here from the row's own inputs and the published GPU figures in the file,
//! byte-identical reruns, `--model-only` without the scene raster, and the errors (an unknown
//! family, a missing RADV ICD). Skips with a message where RADV's ICD is not installed.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

const SPECS: &str =
    "checkerboard:rotated:pq4k:pixel:16,checkerboard:rotated:ours:quad:8+taa,native";

fn cbr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cbr"))
        .args(args)
        .output()
        .expect("run cbr")
}

fn no_radv() -> bool {
    if cbr_gpu::null_device::radeon_icd().is_none() {
        eprintln!(
            "skipped: RADV's ICD {} is not installed",
            cbr_gpu::null_device::radeon_icd_path().display()
        );
        return true;
    }
    false
}

fn study(dir: &Path, extra: &[&str]) -> (Value, String) {
    let mut args = vec![
        "gpu-stats",
        "--techniques",
        SPECS,
        "--families",
        "vega10,navi21",
        "--width",
        "96",
        "--height",
        "54",
        "-o",
        dir.to_str().expect("utf-8 path"),
    ];
    args.extend_from_slice(extra);
    let out = cbr(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{:?}\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let json = std::fs::read_to_string(dir.join("gpu-stats.json")).expect("gpu-stats.json");
    (serde_json::from_str(&json).expect("json"), stdout)
}

fn f(v: &Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or_else(|| panic!("{k} in {v}"))
}

#[test]
fn gpu_stats_compiles_every_pass_per_family_and_models_it() {
    if no_radv() {
        return;
    }
    let tmp = tempfile::tempdir().expect("tmp");
    let (j, stdout) = study(&tmp.path().join("a"), &[]);
    assert!(
        stdout.contains("VGPR") && stdout.contains("frames by the model"),
        "{stdout}"
    );
    let rows = j["rows"].as_array().expect("rows");
    let gpus = j["model"]["gpus"].as_array().expect("gpus");
    for family in ["vega10", "navi21"] {
        let mine: Vec<&Value> = rows.iter().filter(|r| r["family"] == family).collect();
        for spec in SPECS.split(',') {
            assert!(
                mine.iter()
                    .any(|r| r["spec"] == spec && r["stage"] == "fragment"),
                "{family} {spec}: no fragment row"
            );
        }
        let resolve: Vec<&&Value> = mine
            .iter()
            .filter(|r| r["pass"] == "resolve" && r["stage"] == "compute")
            .collect();
        let waves: std::collections::BTreeSet<u64> =
            resolve.iter().filter_map(|r| r["wave"].as_u64()).collect();
        let want: &[u64] = if family == "navi21" { &[32, 64] } else { &[64] };
        assert_eq!(waves.into_iter().collect::<Vec<_>>(), want, "{family}");
    }
    // Every modelled row: the formulas again, from the row's own inputs and the file's GPUs.
    let mut modelled = 0;
    for r in rows {
        for s in ["VGPRs", "SGPRs", "Instructions", "Inverse Throughput"] {
            assert!(r["stats"][s].as_f64().is_some(), "{s} missing in {r}");
        }
        let Some(m) = r["model"].as_object() else {
            assert!(r["unmodelled"].is_string(), "{r}");
            continue;
        };
        let m = Value::Object(m.clone());
        let g = gpus
            .iter()
            .find(|g| g["family"] == r["family"])
            .expect("the family's GPU");
        let simds = f(g, "cus") * f(g, "simds_per_cu");
        let alu = r["invocations"].as_f64().expect("invocations") / 64.0
            * f(&r["stats"], "Inverse Throughput")
            / simds
            / f(g, "clock_mhz");
        let memory = r["bytes"].as_f64().expect("bytes") / f(g, "bandwidth_gb_s") / 1e3;
        assert!((f(&m, "alu_us") - alu).abs() <= 0.006, "{r}: alu {alu}");
        assert!(
            (f(&m, "memory_us") - memory).abs() <= 0.006,
            "{r}: memory {memory}"
        );
        assert_eq!(
            f(&m, "predicted_us"),
            f(&m, "alu_us").max(f(&m, "memory_us"))
        );
        let bound = if f(&m, "alu_us") >= f(&m, "memory_us") {
            "alu"
        } else {
            "memory"
        };
        assert_eq!(m["bound"], bound, "{r}");
        assert_eq!(
            (m["width"].as_u64(), m["height"].as_u64()),
            (Some(96), Some(54))
        );
        modelled += 1;
    }
    assert!(modelled >= 20, "{modelled} modelled rows");
    // A frame per spec and family; on navi21 also wave32 where the spec has compute passes
    // (`native` has none).
    assert_eq!(j["frames"].as_array().expect("frames").len(), 3 + 5);
    let csv = std::fs::read_to_string(tmp.path().join("a/gpu-stats.csv")).expect("csv");
    assert_eq!(csv.lines().count(), rows.len() + 1);
    assert!(csv.starts_with("family,spec,pass,stage,wave,"), "{csv}");

    // A rerun writes the same bytes (the traced frame's timings live in another file).
    study(&tmp.path().join("b"), &[]);
    assert_eq!(
        std::fs::read(tmp.path().join("a/gpu-stats.json")).expect("a"),
        std::fs::read(tmp.path().join("b/gpu-stats.json")).expect("b"),
        "reruns differ"
    );

    // --model-only: no scene raster; compute rows keep their figures, raster rows say why not.
    // (--families given twice adds up: vega10,navi21,vega10 compiles each family once.)
    let (m, _) = study(
        &tmp.path().join("m"),
        &["--model-only", "--families", "vega10"],
    );
    assert_eq!(m["families"].as_array().map(Vec::len), Some(2));
    let key = |r: &Value| {
        format!(
            "{} {} {} {} {}",
            r["family"], r["spec"], r["pass"], r["stage"], r["wave"]
        )
    };
    for r in m["rows"].as_array().expect("rows") {
        let full = rows
            .iter()
            .find(|x| key(x) == key(r))
            .expect("the same row");
        if r["stage"] == "compute" {
            assert_eq!(r["model"], full["model"], "{}", key(r));
            assert!(r["model"].is_object(), "{}", key(r));
        } else {
            assert!(r["model"].is_null(), "{}", key(r));
            assert!(
                r["unmodelled"]
                    .as_str()
                    .is_some_and(|w| w.contains("scene raster")),
                "{r}"
            );
        }
    }
}

#[test]
fn gpu_stats_disassembly_per_pass() {
    if no_radv() {
        return;
    }
    let tmp = tempfile::tempdir().expect("tmp");
    let out = cbr(&[
        "gpu-stats",
        "--techniques",
        "checkerboard:rotated:pq4k:pixel:16",
        "--families",
        "vega10",
        "--width",
        "64",
        "--height",
        "36",
        "--disassembly",
        "--model-only",
        "-o",
        tmp.path().to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = std::fs::read_to_string(
        tmp.path()
            .join("disassembly/vega10/checkerboard_rotated_pq4k_pixel_16/resolve.compute.wave64.s"),
    )
    .expect("the resolve's disassembly");
    // GCN: buffer/image loads and an image store in the resolve.
    assert!(s.contains("image_") && s.contains("s_endpgm"), "{s}");
}

#[test]
fn gpu_stats_refuses_an_unknown_family_and_a_missing_icd() {
    let tmp = tempfile::tempdir().expect("tmp");
    let dir = tmp.path().join("x");
    let d = dir.to_str().expect("utf-8");
    let out = cbr(&["gpu-stats", "--families", "vega10,gfx900", "-o", d]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("gfx900") && err.contains("polaris10"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one error line: {err}");
    assert!(!dir.exists(), "nothing written");

    let out = Command::new(env!("CARGO_BIN_EXE_cbr"))
        .args(["gpu-stats", "--families", "vega10", "-o", d])
        .env("CBR_RADEON_ICD", "/nonexistent/radeon_icd.json")
        .output()
        .expect("run cbr");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("/nonexistent/radeon_icd.json") && err.contains("not installed"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing written");

    let out = cbr(&[
        "gpu-stats",
        "--techniques",
        "checkerboard:nolayout",
        "-o",
        d,
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!dir.exists(), "nothing written");
}
