//! What the `cbr` binary's test files share.
// Each test file is its own crate and uses part of this.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `cbr` binary with `args` and extra environment variables, and waits for it.
pub fn cbr(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cbr"));
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run cbr")
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

/// What the process wrote to stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `cbr render builtin:demo --width W --height H --frames N -o OUT ARGS...`: run.json, or stderr
/// when it failed.
pub fn render_demo(
    out: &Path,
    (w, h): (u32, u32),
    frames: u32,
    args: &[&str],
) -> Result<serde_json::Value, String> {
    let (w, h, n) = (w.to_string(), h.to_string(), frames.to_string());
    let mut all = vec!["render", "builtin:demo", "--width", &w, "--height", &h];
    all.extend(["--frames", &n, "-o", s(out)]);
    all.extend_from_slice(args);
    let o = cbr(&all, &[]);
    if !o.status.success() {
        return Err(stderr(&o));
    }
    let run = std::fs::read(out.join("run.json")).expect("run.json");
    Ok(serde_json::from_slice(&run).expect("json"))
}
