//! The binary on RADV's null device (`RADV_FORCE_FAMILY`): a device that compiles pipelines but
//! cannot execute. `cbr render` and `cbr bench` end with one clear error and exit status 1, never a
//! signal (they used to die of SIGSEGV in the device's drop); `cbr info` works there and finds
//! msaa2x supported (RADV's per-format answer for the ID target). Skips with a message where RADV's
//! ICD is not installed.

mod common;

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::Output;

use common::{cbr, s, stderr};

const RADEON_ICD: &str = "/usr/share/vulkan/icd.d/radeon_icd.x86_64.json";

fn on_vega10(args: &[&str]) -> Option<Output> {
    if !Path::new(RADEON_ICD).is_file() {
        eprintln!("skipped: RADV's ICD {RADEON_ICD} is not installed");
        return None;
    }
    Some(cbr(
        args,
        &[
            ("RADV_FORCE_FAMILY", "vega10"),
            ("VK_DRIVER_FILES", RADEON_ICD),
            ("CBR_ANY_DEVICE", "1"),
        ],
    ))
}

/// Exit status 1 from the process itself (no signal), one `error:` line that names the device
/// and says it only compiles.
fn assert_one_clear_error(o: &Output, what: &str) {
    let err = stderr(o);
    assert_eq!(o.status.signal(), None, "{what}: killed by a signal\n{err}");
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{what}: {err}");
    assert!(
        errors[0].contains("Null hardware (RADV VEGA10)")
            && errors[0].contains("can only compile pipelines"),
        "{what}: {err}"
    );
}

#[test]
fn render_and_bench_give_one_clear_error() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("out");
    let render = [
        "render",
        "builtin:demo",
        "--width",
        "64",
        "--height",
        "36",
        "--frames",
        "1",
        "-o",
        s(&out),
    ];
    let Some(o) = on_vega10(&render) else { return };
    assert_one_clear_error(&o, "render");
    let bench_out = d.path().join("bench");
    let bench = [
        "bench",
        "builtin:demo",
        "--techniques",
        "native",
        "--width",
        "64",
        "--height",
        "36",
        "--warmup",
        "0",
        "--frames",
        "1",
        "-o",
        s(&bench_out),
    ];
    let Some(o) = on_vega10(&bench) else { return };
    assert_one_clear_error(&o, "bench");
}

#[test]
fn info_works_and_finds_msaa2x_supported() {
    let Some(o) = on_vega10(&["info", "--json"]) else {
        return;
    };
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["chosen"]["name"], "Null hardware (RADV VEGA10)");
    assert_eq!(v["caps"]["can_execute"], false);
    let msaa2x = v["layouts"]
        .as_array()
        .expect("layouts")
        .iter()
        .find(|l| l["layout"] == "msaa2x")
        .expect("msaa2x row");
    assert_eq!(msaa2x["supported"], true, "{msaa2x}");
    let text = on_vega10(&["info"]).expect("ran above");
    assert!(text.status.success(), "{}", stderr(&text));
    let out = String::from_utf8_lossy(&text.stdout);
    assert!(out.contains("msaa2x   yes"), "{out}");
    assert!(out.contains("can only compile pipelines"), "{out}");
}
