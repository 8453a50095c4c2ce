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
            "<table class=\"prov\">{}{}{}{}{}{}{}{}{}{}{}{}</table>",
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
                "machine (the host; lavapipe runs on its CPU)",
                machine_line(&j["machine"])
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

/// bench.json's `machine` in one line: `Intel(R) Xeon(R) Processor (GenuineIntel family 6 model
/// 167 stepping 1), 2 logical CPUs, 23.4 GiB, SIMD avx2 fma avx512f; load average 0.03 at the
/// start, 0.63 at the end`. A merged run of shards on one kind of machine says where each shard's
/// load is; one on several kinds, or a bench.json from before the field, says so.
pub(crate) fn machine_line(m: &Value) -> String {
    if m.is_null() {
        return "not recorded (a bench.json from before the field, or shards merged from \
                different machines: see merged_from)"
            .into();
    }
    let mut s = m["cpu"].as_str().unwrap_or("an unnamed CPU").to_string();
    if let Some(id) = m["cpu_id"].as_str() {
        s.push_str(&format!(" ({id})"));
    }
    if let Some(n) = m["logical_cpus"].as_u64() {
        s.push_str(&format!(", {n} logical CPUs"));
    }
    if let Some(g) = m["memory_gib"].as_f64() {
        s.push_str(&format!(", {g:.1} GiB"));
    }
    if let Some(simd) = m["simd"].as_array() {
        let names: Vec<&str> = simd.iter().filter_map(Value::as_str).collect();
        if names.is_empty() {
            s.push_str(", no SIMD extension named");
        } else {
            s.push_str(&format!(", SIMD {}", names.join(" ")));
        }
    }
    let first = |k: &str| m["load_average"][k][0].as_f64();
    match (first("start"), first("end")) {
        (Some(a), Some(b)) => s.push_str(&format!(
            "; load average {a:.2} at the start, {b:.2} at the end"
        )),
        _ if m["per_shard"].is_string() => s.push_str("; each shard's load average in merged_from"),
        _ => s.push_str("; load average not recorded"),
    }
    s
}

#[cfg(test)]
mod tests {
    use super::machine_line;
    use serde_json::{Value, json};

    #[test]
    fn the_machine_line_names_the_cpu_and_the_load() {
        let m = json!({"cpu": "Intel(R) Xeon(R) Processor",
            "cpu_id": "GenuineIntel family 6 model 167 stepping 1", "simd": ["avx2", "avx512f"],
            "logical_cpus": 2, "memory_gib": 23.4,
            "load_average": {"start": [0.03, 0.1, 0.2], "end": [0.63, 0.2, 0.2]}});
        assert_eq!(
            machine_line(&m),
            "Intel(R) Xeon(R) Processor (GenuineIntel family 6 model 167 stepping 1), 2 logical \
             CPUs, 23.4 GiB, SIMD avx2 avx512f; load average 0.03 at the start, 0.63 at the end"
        );
        let merged =
            json!({"cpu": "c", "simd": [], "per_shard": "hostname and load average: merged_from"});
        assert_eq!(
            machine_line(&merged),
            "c, no SIMD extension named; each shard's load average in merged_from"
        );
        assert!(machine_line(&Value::Null).starts_with("not recorded"));
        assert_eq!(
            machine_line(&json!({"load_average": {"start": null, "end": null}})),
            "an unnamed CPU; load average not recorded"
        );
    }
}
