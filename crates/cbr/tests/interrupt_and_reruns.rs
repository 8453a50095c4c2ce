//! Ctrl-C during `cbr render` and `cbr bench` leaves only complete, readable files and no
//! temporary ones, and exits with 130 and a message; the same render twice gives the same bytes.

mod common;
use common::s;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Every file under `dir` (recursively), relative.
fn files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).expect("under dir").to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// Starts `cbr ARGS`, waits until `ready` exists (then `delay` more), sends SIGINT and returns
/// what the process said.
fn interrupt(args: &[&str], ready: &Path, delay: Duration) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_cbr"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start cbr");
    let start = Instant::now();
    while !ready.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "{} never appeared",
            ready.display()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(delay);
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
    child.wait_with_output().expect("wait")
}

fn assert_interrupted(o: &Output) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "exit status; stderr:\n{err}");
    assert!(err.contains("error: interrupted"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn ctrl_c_during_a_render_leaves_only_complete_frames() {
    let d = tempfile::tempdir().expect("tempdir");
    // Three interrupts at different moments of the frame loop.
    for (i, delay) in [0u64, 130, 370].into_iter().enumerate() {
        let out = d.path().join(format!("out{i}"));
        let o = interrupt(
            &[
                "render",
                "builtin:demo",
                "-o",
                s(&out),
                "--width",
                "160",
                "--height",
                "90",
                "--frames",
                "400",
            ],
            &out.join("frame_0000.png"),
            Duration::from_millis(delay),
        );
        assert_interrupted(&o);
        let list = files(&out);
        assert!(!list.is_empty());
        assert!(list.len() < 800, "the render stopped early");
        for f in &list {
            let name = f.to_string_lossy();
            assert!(
                name.starts_with("frame_") && !name.contains("tmp"),
                "only frames remain: {name}"
            );
            let path = out.join(f);
            if name.ends_with(".exr") {
                cbr_metrics::input::load(&path, None, None)
                    .unwrap_or_else(|e| panic!("{name} is not a whole EXR: {e}"));
            } else {
                let img =
                    image::open(&path).unwrap_or_else(|e| panic!("{name} is not a whole PNG: {e}"));
                assert_eq!((img.width(), img.height()), (160, 90));
            }
        }
    }
}

#[test]
fn ctrl_c_during_a_bench_leaves_no_temporary_files() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("bench");
    let o = interrupt(
        &[
            "bench",
            "builtin:demo",
            "-o",
            s(&out),
            "--width",
            "96",
            "--height",
            "54",
            "--warmup",
            "0",
            "--frames",
            "300",
            "--techniques",
            "native,checkerboard:rotated:ours",
        ],
        &out,
        Duration::from_millis(1500),
    );
    assert_interrupted(&o);
    let list = files(&out);
    assert!(
        list.iter().all(|f| !f.to_string_lossy().contains("tmp")),
        "{list:?}"
    );
    assert!(
        !out.join("bench.json").exists(),
        "an interrupted bench writes no bench.json"
    );
}

#[test]
fn the_same_render_twice_gives_the_same_bytes() {
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("out");
    let render = || {
        let args = [
            "--technique",
            "checkerboard:rotated:ours",
            "--resolve-debug",
        ];
        common::render_demo(&out, (64, 36), 2, &args).expect("render");
    };
    render();
    let first = d.path().join("first");
    std::fs::rename(&out, &first).expect("move the first run");
    render();
    let list = files(&first);
    assert_eq!(list, files(&out), "the same files");
    let mut compared = 0;
    for f in &list {
        let (a, b) = (
            std::fs::read(first.join(f)).expect("read"),
            std::fs::read(out.join(f)).expect("read"),
        );
        if f.extension().is_some_and(|e| e == "json") {
            // run.json: equal but for the wall-clock and GPU timing fields.
            let strip = |bytes: &[u8]| {
                let mut v: serde_json::Value = serde_json::from_slice(bytes).expect("json");
                for k in ["created_unix_s", "wall_s", "passes"] {
                    v.as_object_mut().expect("object").remove(k);
                }
                for f in v["frames"].as_array_mut().expect("frames") {
                    f.as_object_mut().expect("frame").remove("passes");
                }
                v
            };
            assert_eq!(strip(&a), strip(&b), "{}", f.display());
        } else {
            assert!(a == b, "{} differs between two identical runs", f.display());
        }
        compared += 1;
    }
    assert!(compared >= 5, "{list:?}");
}
