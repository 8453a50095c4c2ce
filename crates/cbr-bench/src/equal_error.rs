//! Equal-error supersampling: what a technique's error is worth in supersamples. A bench run
//! that measures two or more `ssaa:N` rows against a finer reference (a ladder, e.g. `ssaa:8`,
//! `ssaa:10`, `ssaa:12`, `ssaa:16` against `ssaa:32`) places every other row on that ladder: the
//! N (samples per pixel side, fractional) at which supersampling's error would equal the row's,
//! interpolated between the two ladder rungs that bracket it, and the frame time supersampling
//! would take there. bench.json's `equal_error_ssaa` per row, for the edge-pixel FLIP (the
//! antialiasing goals' metric) and the whole frame's FLIP; docs/bench-and-report.md.
//!
//! Interpolation is linear in log N against log error (supersampling's error falls about as a
//! power of N) and in log N against log time (its cost grows about as N^2). Rungs are taken in
//! the order of N; the first pair whose errors bracket the row's is used. An error below every
//! rung's is reported as better than the finest rung, one above every rung's as worse than the
//! coarsest: never extrapolated.

use serde_json::{Value, json};

/// One rung of the ladder: `ssaa:n`'s error and, when it was timed, its frame time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rung {
    pub n: f64,
    pub error: f64,
    pub frame_ms: Option<f64>,
}

/// Where an error falls on the ladder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// Between two rungs: supersampling at `n` per side would have the same error, in `frame_ms`.
    Between {
        n: f64,
        frame_ms: Option<f64>,
        lo: f64,
        hi: f64,
    },
    /// Less error than the finest rung (`n`).
    Below { n: f64 },
    /// More error than the coarsest rung (`n`).
    Above { n: f64 },
}

fn lerp_log(x0: f64, x1: f64, y0: f64, y1: f64, x: f64) -> f64 {
    // log-log interpolation: y = y0 * (y1 / y0)^t with t from log x.
    let t = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
    (y0.ln() + t * (y1.ln() - y0.ln())).exp()
}

/// Places `error` on the ladder; None when the ladder has fewer than two usable rungs (finite,
/// positive errors and N) or the error is not finite.
pub fn place(ladder: &[Rung], error: f64) -> Option<Placement> {
    let mut rungs: Vec<Rung> = ladder
        .iter()
        .copied()
        .filter(|r| r.n > 0.0 && r.error.is_finite() && r.error > 0.0)
        .collect();
    if rungs.len() < 2 || !error.is_finite() || error < 0.0 {
        return None;
    }
    rungs.sort_by(|a, b| a.n.total_cmp(&b.n));
    for w in rungs.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (lo, hi) = (a.error.min(b.error), a.error.max(b.error));
        if error >= lo && error <= hi && hi > lo {
            // N at which the error curve through the two rungs reaches `error` (log-log).
            let n = lerp_log(a.error, b.error, a.n, b.n, error);
            let frame_ms = match (a.frame_ms, b.frame_ms) {
                (Some(ta), Some(tb)) if ta > 0.0 && tb > 0.0 => Some(lerp_log(a.n, b.n, ta, tb, n)),
                _ => None,
            };
            return Some(Placement::Between {
                n,
                frame_ms,
                lo: a.n,
                hi: b.n,
            });
        }
    }
    let finest = rungs.iter().min_by(|a, b| a.error.total_cmp(&b.error))?;
    let coarsest = rungs.iter().max_by(|a, b| a.error.total_cmp(&b.error))?;
    if error < finest.error {
        Some(Placement::Below { n: finest.n })
    } else {
        Some(Placement::Above { n: coarsest.n })
    }
}

/// N of a plain `ssaa:N` configuration (no jitter, no post chain); None otherwise.
pub fn ssaa_n(config: &str) -> Option<f64> {
    let n = config.strip_prefix("ssaa:")?;
    n.parse::<u32>().ok().map(f64::from)
}

fn placement_json(p: Placement, frame_ms: Option<f64>) -> Value {
    match p {
        Placement::Between {
            n,
            frame_ms: t,
            lo,
            hi,
        } => json!({
            "n": n,
            "samples_per_pixel": n * n,
            "between": [lo, hi],
            "frame_ms": t,
            // How many times faster this row is than the supersampling of equal error.
            "speedup": match (t, frame_ms) {
                (Some(t), Some(f)) if f > 0.0 => Some(t / f),
                _ => None,
            },
        }),
        Placement::Below { n } => json!({ "better_than": n }),
        Placement::Above { n } => json!({ "worse_than": n }),
    }
}

/// Adds `equal_error_ssaa` to every measured row of `rows` that is not itself a rung, per
/// resolution, when that resolution's rows hold a ladder (two or more `ssaa:N` rows with errors,
/// the reference excluded: it has none).
pub fn annotate(rows: &mut [Value]) {
    let key = |r: &Value| {
        (
            r["scene"].as_str().map(str::to_string),
            r["width"].as_u64(),
            r["height"].as_u64(),
        )
    };
    let metrics = [("flip_edge", "flip_edge_mean"), ("flip", "flip_mean")];
    let groups: Vec<_> = {
        let mut g = Vec::new();
        for r in rows.iter() {
            if !g.contains(&key(r)) {
                g.push(key(r));
            }
        }
        g
    };
    for g in groups {
        let ladders: Vec<Vec<Rung>> = metrics
            .iter()
            .map(|(_, field)| {
                rows.iter()
                    .filter(|r| key(r) == g)
                    .filter_map(|r| {
                        let n = ssaa_n(r["config"].as_str()?)?;
                        Some(Rung {
                            n,
                            error: r["error"][*field].as_f64()?,
                            frame_ms: r["frame_ms"]["median"].as_f64(),
                        })
                    })
                    .collect()
            })
            .collect();
        if ladders[0].len() < 2 {
            continue;
        }
        for r in rows.iter_mut().filter(|r| key(r) == g) {
            let is_rung = r["config"].as_str().and_then(ssaa_n).is_some();
            if is_rung || r["error"].is_null() {
                continue;
            }
            let frame_ms = r["frame_ms"]["median"].as_f64();
            let mut out = serde_json::Map::new();
            for ((name, field), ladder) in metrics.iter().zip(&ladders) {
                if let Some(p) = r["error"][*field].as_f64().and_then(|e| place(ladder, e)) {
                    out.insert(name.to_string(), placement_json(p, frame_ms));
                }
            }
            out.insert(
                "ladder".into(),
                json!(ladders[0].iter().map(|r| r.n).collect::<Vec<_>>()),
            );
            r["equal_error_ssaa"] = Value::Object(out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rung(n: f64, error: f64, t: f64) -> Rung {
        Rung {
            n,
            error,
            frame_ms: Some(t),
        }
    }

    #[test]
    fn an_error_on_a_power_law_ladder_lands_on_its_n() {
        // error = 0.3 N^-1.5, time = 30 N^2 ms: exact under log-log interpolation.
        let e = |n: f64| 0.3 * n.powf(-1.5);
        let ladder: Vec<Rung> = [8.0, 10.0, 12.0, 16.0]
            .iter()
            .map(|&n| rung(n, e(n), 30.0 * n * n))
            .collect();
        let Some(Placement::Between {
            n,
            frame_ms,
            lo,
            hi,
        }) = place(&ladder, e(11.0))
        else {
            panic!("not placed between rungs");
        };
        assert!((n - 11.0).abs() < 1e-9, "n = {n}");
        assert!((frame_ms.unwrap() - 30.0 * 121.0).abs() < 1e-6);
        assert_eq!((lo, hi), (10.0, 12.0));
        // A rung's own error is its N.
        match place(&ladder, e(16.0)) {
            Some(Placement::Between { n, .. }) => assert!((n - 16.0).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn errors_outside_the_ladder_are_not_extrapolated() {
        let ladder = [rung(12.0, 0.016, 4700.0), rung(8.0, 0.025, 2000.0)];
        assert_eq!(place(&ladder, 0.01), Some(Placement::Below { n: 12.0 }));
        assert_eq!(place(&ladder, 0.03), Some(Placement::Above { n: 8.0 }));
        assert_eq!(place(&ladder[..1], 0.02), None);
        assert_eq!(place(&ladder, f64::NAN), None);
        // Rungs out of order are sorted by N; the measured demo's rungs (ssaa:8 0.0255, ssaa:10
        // 0.0204) put its edge FLIP 0.0209 at about ssaa:9.8.
        let demo = [rung(10.0, 0.0204, 3320.0), rung(8.0, 0.0255, 2100.0)];
        match place(&demo, 0.0209) {
            Some(Placement::Between { n, frame_ms, .. }) => {
                assert!((9.7..9.85).contains(&n), "n = {n}");
                let t = frame_ms.unwrap();
                assert!(t > 2100.0 && t < 3320.0);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn rows_of_a_run_with_a_ladder_are_annotated_per_resolution() {
        let row = |config: &str, w: u64, edge: Option<f64>, t: f64| {
            json!({
                "config": config, "width": w, "height": w / 2,
                "frame_ms": {"median": t},
                "error": edge.map(|e| json!({"flip_edge_mean": e, "flip_mean": e / 2.0})),
            })
        };
        let mut rows = vec![
            row("ssaa:32", 320, None, 0.0),
            row("ssaa:8", 320, Some(0.025), 2000.0),
            row("ssaa:12", 320, Some(0.016), 4500.0),
            row("analytic", 320, Some(0.02), 400.0),
            row("native", 320, Some(0.16), 30.0),
            // Another resolution without a ladder: left alone.
            row("analytic", 160, Some(0.02), 100.0),
        ];
        annotate(&mut rows);
        let e = &rows[3]["equal_error_ssaa"];
        let n = e["flip_edge"]["n"].as_f64().unwrap();
        assert!(n > 8.0 && n < 12.0, "{e}");
        let speedup = e["flip_edge"]["speedup"].as_f64().unwrap();
        let t = e["flip_edge"]["frame_ms"].as_f64().unwrap();
        assert!((speedup - t / 400.0).abs() < 1e-9 && t > 2000.0 && t < 4500.0);
        assert_eq!(e["flip"]["between"], json!([8.0, 12.0]));
        assert_eq!(
            rows[4]["equal_error_ssaa"]["flip_edge"]["worse_than"],
            json!(8.0)
        );
        assert!(
            rows[1].get("equal_error_ssaa").is_none(),
            "a rung is not placed on itself"
        );
        assert!(rows[0].get("equal_error_ssaa").is_none());
        assert!(rows[5].get("equal_error_ssaa").is_none());
    }
}
