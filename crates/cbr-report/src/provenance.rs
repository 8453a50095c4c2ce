//! Provenance: where each bench folder's numbers come from.

use std::fmt::Write as _;

use serde_json::Value;

use crate::bench::BenchDir;
use crate::util::esc;

pub(crate) fn provenance(html: &mut String, benches: &[BenchDir], created: &str) {
    let _ = writeln!(
        html,
        "<h2 id=\"provenance\">Provenance</h2><p>Report made {}.</p>",
        esc(created)
    );
    for b in benches {
        let j = &b.json;
        let p = &j["protocol"];
        let row =
            |k: &str, v: String| format!("<tr><th class=\"t\">{}</th><td>{}</td></tr>", k, esc(&v));
        let s = |v: &Value| {
            v.as_str()
                .map(str::to_string)
                .unwrap_or_else(|| v.to_string())
        };
        let cmd = j["command"]
            .as_array()
            .map(|a| a.iter().map(s).collect::<Vec<_>>().join(" "))
            .unwrap_or_default();
        let _ = writeln!(
            html,
            "<table class=\"prov\">{}{}{}{}{}{}{}{}{}{}{}</table>",
            row("bench folder", b.dir.display().to_string()),
            row("command", cmd),
            row("git commit", s(&j["git_commit"])),
            row("cbr version", s(&j["cbr_version"])),
            row(
                "device / driver",
                format!(
                    "{} / {}",
                    s(&j["device"]["name"]),
                    s(&j["device"]["driver_info"])
                )
            ),
            row(
                "scene",
                format!(
                    "{} ({}, {} triangles)",
                    s(&j["scene"]["name"]),
                    s(&j["scene"]["source"]),
                    s(&j["scene"]["triangles"])
                )
            ),
            row(
                "frames",
                format!(
                    "{} warm-up, {} measured",
                    s(&p["warmup_frames"]),
                    s(&p["measured_frames"])
                )
            ),
            row(
                "timing",
                format!("{}; {}", s(&p["timing"]), s(&p["frame_ms"]))
            ),
            row("display transform", s(&p["display"])),
            row(
                "reference (every error is against it)",
                match b.recorded_reference() {
                    Some(r) => r.to_string(),
                    None => "native (bench.json from before the reference field)".into(),
                }
            ),
            row(
                "metrics",
                format!("{}; reference: {}", s(&p["metrics"]), s(&p["reference"]))
            ),
        );
    }
}
