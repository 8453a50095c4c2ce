//! What the `cbr` binary's test files share.

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
