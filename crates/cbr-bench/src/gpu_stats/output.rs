//! The joined study of `cbr gpu-stats` and its files: gpu-stats.json, gpu-stats.csv,
//! lavapipe-timings.json, the disassembly, the stdout table.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use cbr_gpu::PassTiming;
use serde::{Deserialize, Serialize};

use super::model::{self, GpuModel, Prediction};
use super::{ChildOutput, Compiled, Traced, scope_of};

/// The statistic the model reads.
pub const INVERSE_THROUGHPUT: &str = "Inverse Throughput";

/// One executable of one pipeline on one family, with its model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub family: String,
    pub spec: String,
    pub pass: String,
    pub stage: String,
    pub wave: u32,
    pub stats: serde_json::Map<String, serde_json::Value>,
    /// The traced pass it ran in (`None`: it did not run in the traced frame).
    pub scope: Option<String>,
    /// The invocations of its stage in the traced frame (compute: direct dispatches' groups x
    /// local size; raster: the pipeline statistics' vertex or fragment invocations of its
    /// pass, shared by every pipeline of that pass).
    pub invocations: Option<u64>,
    /// Bytes its pass declared it reads and writes.
    pub bytes: Option<u64>,
    pub model: Option<Prediction>,
    /// Why there is no model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unmodelled: Option<String>,
}

/// One pass of a modelled frame.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassModel {
    pub pass: String,
    #[serde(flatten)]
    pub model: Prediction,
}

/// A spec's frame on one family by the model: the sum over its traced passes of each pass's
/// prediction (a pass's ALU time: per stage, the costliest pipeline that ran in it). Its
/// `bound` says which sum is the larger.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameModel {
    pub family: String,
    pub spec: String,
    /// The compute wave size (raster stages run as the driver chose).
    pub wave: u32,
    #[serde(flatten)]
    pub total: Prediction,
    pub passes: Vec<PassModel>,
    /// Pipelines of the frame without a model, and why (the frame's figure leaves them out).
    pub unmodelled: Vec<String>,
    /// Passes left out of the frame: they write only host-visible memory (cbr's readbacks for
    /// its own analysis, such as the raw checkerboard frame), which a GPU frame does not do.
    pub excluded: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FamilyInfo {
    pub family: String,
    pub device: String,
    pub driver: String,
    pub gpu: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Refusal {
    pub family: String,
    pub spec: String,
    pub why: String,
}

/// gpu-stats.json.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Study {
    pub version: u32,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub model_only: bool,
    pub model: ModelInfo,
    pub families: Vec<FamilyInfo>,
    pub rows: Vec<Row>,
    pub frames: Vec<FrameModel>,
    pub refused: Vec<Refusal>,
    /// Pipelines the family's driver crashed compiling (with statistics capture): left out.
    pub crashed: Vec<Refusal>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModelInfo {
    pub alu: String,
    pub memory: String,
    pub predicted: String,
    pub calibration: String,
    pub gpus: Vec<GpuInfo>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GpuInfo {
    pub name: String,
    pub family: String,
    pub cus: u32,
    pub simds_per_cu: u32,
    pub clock_mhz: f64,
    pub bandwidth_gb_s: f64,
    pub source: String,
}

impl From<&GpuModel> for GpuInfo {
    fn from(g: &GpuModel) -> GpuInfo {
        GpuInfo {
            name: g.name.into(),
            family: g.family.into(),
            cus: g.cus,
            simds_per_cu: g.simds_per_cu,
            clock_mhz: g.clock_mhz,
            bandwidth_gb_s: g.bandwidth_gb_s,
            source: g.source.into(),
        }
    }
}

fn stat(stats: &serde_json::Map<String, serde_json::Value>, name: &str) -> Option<f64> {
    stats.get(name).and_then(serde_json::Value::as_f64)
}

/// What the model needs of a compiled executable in its traced pass: (invocations, bytes), or
/// why it cannot have a model.
fn inputs(
    c: &Compiled,
    pass: &PassTiming,
    model_only: bool,
) -> std::result::Result<(u64, u64), String> {
    let bytes = pass.traffic.bytes_read + pass.traffic.bytes_written;
    let raster = c.kind == "graphics";
    if raster && model_only {
        return Err("needs a scene raster (--model-only traced an empty frame)".into());
    }
    let invocations = if raster {
        let s = pass
            .stats
            .ok_or("the tracing device has no pipeline statistics queries")?;
        if c.stage.split('+').any(|s| s == "fragment") {
            s.fragment_invocations
        } else {
            s.vertex_invocations
        }
    } else {
        if pass.traffic.indirect_dispatches > 0 {
            return Err(format!(
                "its pass `{}` dispatches indirectly: the GPU writes its group counts",
                pass.name
            ));
        }
        pass.traffic.compute_invocations
    };
    Ok((invocations, bytes))
}

impl Study {
    pub fn join(
        scene: &str,
        size: (u32, u32),
        model_only: bool,
        children: &[ChildOutput],
        traced: &[Traced],
    ) -> Study {
        let mut rows = Vec::new();
        let mut frames = Vec::new();
        let mut refused = Vec::new();
        for child in children {
            let gpu = model::gpu_for(&child.family);
            for (spec, why) in &child.refused {
                refused.push(Refusal {
                    family: child.family.clone(),
                    spec: spec.clone(),
                    why: why.clone(),
                });
            }
            for t in traced {
                let first = rows.len();
                for c in child.compiled.iter().filter(|c| c.spec == t.spec) {
                    let scope = scope_of(&c.pass, &t.passes);
                    let mut row = Row {
                        family: child.family.clone(),
                        spec: c.spec.clone(),
                        pass: c.pass.clone(),
                        stage: c.stage.clone(),
                        wave: c.wave,
                        stats: c.stats.clone(),
                        scope: scope.map(|p| p.name.clone()),
                        invocations: None,
                        bytes: None,
                        model: None,
                        unmodelled: None,
                    };
                    let answer = match (gpu, scope) {
                        (None, _) => Err(format!(
                            "the model names no GPU of the {} family",
                            child.family
                        )),
                        (_, None) => Err(t
                            .error
                            .clone()
                            .unwrap_or_else(|| "it did not run in the traced frame".to_string())),
                        (Some(g), Some(p)) => inputs(c, p, model_only).and_then(|(n, b)| {
                            row.invocations = Some(n);
                            row.bytes = Some(b);
                            // RADV 22.3 reports 0 for some large programs (gfx1100's wave64
                            // `analytic.resolve`): no estimate, not a free program.
                            let thr = stat(&c.stats, INVERSE_THROUGHPUT)
                                .filter(|t| *t > 0.0)
                                .ok_or_else(|| {
                                    format!("the driver reports no `{INVERSE_THROUGHPUT}` (or 0)")
                                })?;
                            Ok(model::predict(
                                g,
                                size,
                                model::alu_us(g, n, thr),
                                model::memory_us(g, b),
                            ))
                        }),
                    };
                    match answer {
                        Ok(m) => row.model = Some(m),
                        Err(why) => row.unmodelled = Some(why),
                    }
                    rows.push(row);
                }
                if let Some(g) = gpu.filter(|_| !model_only && t.error.is_none()) {
                    frames.extend(frame_models(g, size, t, &rows[first..]));
                }
            }
        }
        Study {
            version: 1,
            scene: scene.to_string(),
            width: size.0,
            height: size.1,
            model_only,
            model: ModelInfo {
                alu: "waves64 x Inverse Throughput / (CUs x SIMDs per CU) / clock; waves64 = invocations / 64".into(),
                memory: "bytes declared read + written (each bound image or buffer once, level 0, all layers and samples) / DRAM bandwidth".into(),
                predicted: "max(alu, memory) per pass; a frame sums its passes".into(),
                calibration: "none".into(),
                gpus: model::GPUS.iter().map(GpuInfo::from).collect(),
            },
            families: children
                .iter()
                .map(|c| FamilyInfo {
                    family: c.family.clone(),
                    device: c.device.clone(),
                    driver: c.driver.clone(),
                    gpu: model::gpu_for(&c.family).map(|g| g.name.to_string()),
                })
                .collect(),
            rows,
            frames,
            refused,
            crashed: children
                .iter()
                .flat_map(|c| {
                    c.crashed.iter().map(|x| Refusal {
                        family: c.family.clone(),
                        spec: x.spec.clone(),
                        why: format!(
                            "the driver crashed ({}) compiling `{}`{} with statistics capture",
                            x.signal,
                            x.pass,
                            x.wave.map(|w| format!(" as wave{w}")).unwrap_or_default()
                        ),
                    })
                })
                .collect(),
        }
    }
}

/// The frame models of one spec on one family: wave64, and wave32 where compute has it.
fn frame_models(g: &GpuModel, size: (u32, u32), t: &Traced, rows: &[Row]) -> Vec<FrameModel> {
    let mut waves: BTreeSet<u32> = rows
        .iter()
        .filter(|r| r.stats.contains_key(INVERSE_THROUGHPUT) && !is_graphics(r))
        .map(|r| r.wave)
        .collect();
    if waves.is_empty() {
        waves.insert(64);
    }
    let Some(first) = rows.first() else {
        return Vec::new();
    };
    waves
        .into_iter()
        .rev()
        .map(|wave| {
            let of_wave = |r: &&Row| is_graphics(r) || r.wave == wave;
            let mut passes = Vec::new();
            let mut excluded = Vec::new();
            for p in &t.passes {
                let w = &p.traffic;
                if w.bytes_written > 0 && w.host_bytes_written == w.bytes_written {
                    excluded.push(format!(
                        "{}: writes only host-visible memory (a readback for cbr's analysis)",
                        p.name
                    ));
                    continue;
                }
                let mine: Vec<&Row> = rows
                    .iter()
                    .filter(of_wave)
                    .filter(|r| r.scope.as_deref() == Some(&p.name))
                    .collect();
                let models: Vec<(&str, &Prediction)> = mine
                    .iter()
                    .filter_map(|r| r.model.as_ref().map(|m| (r.stage.as_str(), m)))
                    .collect();
                if models.is_empty() {
                    continue;
                }
                let stages: BTreeSet<&str> = models.iter().map(|m| m.0).collect();
                let alu: f64 = stages
                    .iter()
                    .map(|s| {
                        models
                            .iter()
                            .filter(|m| m.0 == *s)
                            .map(|m| m.1.alu_us)
                            .fold(0.0, f64::max)
                    })
                    .sum();
                let memory = models[0].1.memory_us;
                passes.push(PassModel {
                    pass: p.name.clone(),
                    model: model::predict(g, size, alu, memory),
                });
            }
            let sum = |f: fn(&Prediction) -> f64| passes.iter().map(|p| f(&p.model)).sum::<f64>();
            let mut total = model::predict(g, size, sum(|p| p.alu_us), sum(|p| p.memory_us));
            // A frame's passes are each bound by one or the other: its time is their sum.
            total.predicted_us = (sum(|p| p.predicted_us) * 100.0).round() / 100.0;
            FrameModel {
                family: first.family.clone(),
                spec: t.spec.clone(),
                wave,
                total,
                passes,
                unmodelled: rows
                    .iter()
                    .filter(of_wave)
                    .filter_map(|r| {
                        r.unmodelled
                            .as_ref()
                            .filter(|_| r.scope.is_some())
                            .map(|w| format!("{} ({}): {w}", r.pass, r.stage))
                    })
                    .collect(),
                excluded,
            }
        })
        .collect()
}

fn is_graphics(r: &Row) -> bool {
    r.stage != "compute"
}

/// A file-name-safe form of a spec or pass name.
fn safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Writes gpu-stats.json, gpu-stats.csv, lavapipe-timings.json and (when asked) the
/// disassembly, each through a temporary name.
pub fn write_outputs(
    dir: &Path,
    study: &Study,
    children: &[ChildOutput],
    traced: &[Traced],
    disassembly: bool,
) -> Result<()> {
    let json = serde_json::to_string_pretty(study)? + "\n";
    cbr_metrics::io::write_bytes(&dir.join("gpu-stats.json"), json.as_bytes())?;
    cbr_metrics::io::write_bytes(&dir.join("gpu-stats.csv"), csv(study).as_bytes())?;
    let timings: Vec<serde_json::Value> = traced
        .iter()
        .map(|t| serde_json::json!({ "spec": t.spec, "passes": t.passes }))
        .collect();
    let timings = serde_json::to_string_pretty(&timings)? + "\n";
    cbr_metrics::io::write_bytes(&dir.join("lavapipe-timings.json"), timings.as_bytes())?;
    if disassembly {
        for child in children {
            for c in &child.compiled {
                let Some(text) = &c.disassembly else { continue };
                let d = dir
                    .join("disassembly")
                    .join(&child.family)
                    .join(safe(&c.spec));
                std::fs::create_dir_all(&d)
                    .with_context(|| format!("cannot create {}", d.display()))?;
                let name = format!("{}.{}.wave{}.s", safe(&c.pass), safe(&c.stage), c.wave);
                cbr_metrics::io::write_bytes(&d.join(name), text.as_bytes())?;
            }
        }
    }
    Ok(())
}

/// gpu-stats.csv: one line per row, every statistic a column (union over rows, by name).
pub fn csv(study: &Study) -> String {
    let names: BTreeSet<&str> = study
        .rows
        .iter()
        .flat_map(|r| r.stats.keys().map(String::as_str))
        .collect();
    let mut s = String::from("family,spec,pass,stage,wave");
    for n in &names {
        s += &format!(",{}", csv_field(n));
    }
    s += ",scope,invocations,bytes,gpu,alu_us,memory_us,predicted_us,bound,unmodelled\n";
    for r in &study.rows {
        let mut line = [&r.family, &r.spec, &r.pass, &r.stage]
            .map(|v| csv_field(v))
            .join(",");
        line += &format!(",{}", r.wave);
        for n in &names {
            line += ",";
            if let Some(v) = r.stats.get(*n) {
                line += &csv_field(&v.to_string());
            }
        }
        let opt = |v: Option<String>| v.map(|v| csv_field(&v)).unwrap_or_default();
        line += &format!(
            ",{},{},{}",
            opt(r.scope.clone()),
            opt(r.invocations.map(|v| v.to_string())),
            opt(r.bytes.map(|v| v.to_string()))
        );
        match &r.model {
            Some(m) => {
                line += &format!(
                    ",{},{},{},{},{},",
                    csv_field(&m.gpu),
                    m.alu_us,
                    m.memory_us,
                    m.predicted_us,
                    m.bound
                )
            }
            None => line += &format!(",,,,,,{}", opt(r.unmodelled.clone())),
        }
        s += &line;
        s += "\n";
    }
    s
}

fn num(stats: &serde_json::Map<String, serde_json::Value>, name: &str) -> String {
    stat(stats, name).map_or("-".into(), |v| format!("{v}"))
}

/// The stdout table: per row the register use, occupancy, instructions, ACO's inverse
/// throughput and the model; then each frame's prediction.
pub fn table(study: &Study) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<9} {:<34} {:<34} {:<9} {:>4} {:>5} {:>5} {:>5} {:>6} {:>7} {:>10} {:>9}  bound",
        "family",
        "spec",
        "pass",
        "stage",
        "wave",
        "VGPR",
        "SGPR",
        "waves",
        "instr",
        "inv.thr",
        "model us",
        "bytes MB"
    );
    for r in &study.rows {
        let (pred, bound) = match &r.model {
            Some(m) => (format!("{:.1}", m.predicted_us), m.bound.clone()),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(
            s,
            "{:<9} {:<34} {:<34} {:<9} {:>4} {:>5} {:>5} {:>5} {:>6} {:>7} {:>10} {:>9}  {}",
            r.family,
            r.spec,
            r.pass,
            r.stage,
            r.wave,
            num(&r.stats, "VGPRs"),
            num(&r.stats, "SGPRs"),
            num(&r.stats, "Subgroups per SIMD"),
            num(&r.stats, "Instructions"),
            num(&r.stats, INVERSE_THROUGHPUT),
            pred,
            r.bytes
                .map_or("-".into(), |b| format!("{:.1}", b as f64 / 1e6)),
            bound
        );
    }
    if !study.frames.is_empty() {
        let _ = writeln!(
            s,
            "\nframes by the model at {}x{} (static estimates, not timings):",
            study.width, study.height
        );
        for f in &study.frames {
            let _ = writeln!(
                s,
                "{:<9} {:<34} wave{:<3} {:<20} {:>10.1} us (ALU {:.1}, memory {:.1}){}",
                f.family,
                f.spec,
                f.wave,
                f.total.gpu,
                f.total.predicted_us,
                f.total.alu_us,
                f.total.memory_us,
                [
                    (f.unmodelled.len(), "pipeline(s) unmodelled"),
                    (f.excluded.len(), "readback pass(es) left out"),
                ]
                .iter()
                .filter(|(n, _)| *n > 0)
                .map(|(n, what)| format!(", {n} {what}"))
                .collect::<String>()
            );
        }
    }
    for r in &study.refused {
        let _ = writeln!(s, "{} refuses `{}`: {}", r.family, r.spec, r.why);
    }
    for r in &study.crashed {
        let _ = writeln!(s, "{} `{}`: {}", r.family, r.spec, r.why);
    }
    s
}
