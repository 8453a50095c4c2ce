//! The checkerboard resolve's cost in GCN ISA: every mode x {pixel, quad} x {8, 16} x
//! {f32, fp16} compiled by ACO for vega10 (GCN5, Vega 56) on RADV's null device, as a table of
//! the driver's static statistics (VGPRs, SGPRs, waves per SIMD, instructions, VMEM clauses,
//! inverse throughput) and the inverse throughput per output pixel (per wave64 over the 64
//! pixels a pixel-mapped wave writes, or the 256 of a quad-mapped one). They are ACO's static
//! estimates, not timings (docs/resolve.md, "GCN ISA"). `ours`' figures are asserted as a
//! regression bound. `CBR_ISA_DUMP=DIR` writes each pipeline's NIR, ACO IR and assembly there.
//!
//! The driver reads `RADV_FORCE_FAMILY` when devices are enumerated, so the compile runs in a
//! child process; skips with a message where RADV's ICD is not installed.

mod common;

use cbr_gpu::CompileSettings;
use common::null_child;

const CHILD: &str = "CBR_ISA_RESOLVE_CHILD";

/// `ours`' regression bounds on vega10, (mapping, group, fp16, at most VGPRs, at least waves per
/// SIMD, at most inverse throughput per output pixel): the figures of docs/resolve.md's table
/// ("GCN ISA") plus a small margin (4 VGPRs, the same waves, 5%). Before the changes that table
/// describes, pixel/16 took 80 VGPRs, 3 waves and 73.2 per pixel, quad/8 96, 2 and 36.5.
const OURS_BOUNDS: &[(&str, u32, bool, f64, f64, f64)] = &[
    ("pixel", 16, false, 68.0, 4.0, 21.8),
    ("pixel", 16, true, 64.0, 4.0, 22.0),
    ("quad", 8, false, 84.0, 3.0, 11.8),
    ("quad", 8, true, 84.0, 3.0, 12.0),
];

#[test]
fn resolve_isa_on_vega10() {
    if null_child::no_radv() {
        return;
    }
    let child = null_child::spawn("child_resolve_isa", "vega10", CHILD, "1");
    null_child::expect_pass("vega10", child);
}

/// One compiled variant's figures.
struct Row {
    mode: String,
    mapping: &'static str,
    group: u32,
    fp16: bool,
    vgprs: f64,
    sgprs: f64,
    waves: f64,
    instructions: f64,
    vmem: f64,
    inv_throughput: f64,
}

impl Row {
    /// Output pixels one wave64 writes.
    fn pixels_per_wave(&self) -> f64 {
        if self.mapping == "quad" { 256.0 } else { 64.0 }
    }

    fn per_pixel(&self) -> f64 {
        self.inv_throughput / self.pixels_per_wave()
    }
}

#[test]
#[ignore = "run by resolve_isa_on_vega10"]
fn child_resolve_isa() {
    if std::env::var(CHILD).is_err() {
        return;
    }
    let dump = std::env::var_os("CBR_ISA_DUMP").map(std::path::PathBuf::from);
    let gpu = null_child::gpu(
        "Null hardware (RADV VEGA10)",
        CompileSettings {
            statistics: true,
            representations: dump.is_some(),
            ..Default::default()
        },
    );
    if let Some(dir) = &dump {
        std::fs::create_dir_all(dir).expect("CBR_ISA_DUMP directory");
    }
    let shaders = cbr_render::shader_library();
    let scene = common::demo(64, 36);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    let ctx = common::pass_ctx(&gpu, &materials, false);
    let mut rows = Vec::new();
    for mode in cbr_render::ResolveMode::ALL {
        for mapping in ["pixel", "quad"] {
            for group in [8u32, 16] {
                for fp16 in [false, true] {
                    let text = format!(
                        "checkerboard:rotated:{}:{mapping}:{group}{}",
                        mode.name(),
                        if fp16 { ":fp16" } else { "" }
                    );
                    let settings = cbr_render::RenderSettings::parse(64, 36, &text).expect("spec");
                    let list = cbr_render::registry::passes(&settings.spec, &ctx)
                        .unwrap_or_else(|e| panic!("{text}: {e}"));
                    let d = list
                        .compute
                        .iter()
                        .find(|d| d.name == "resolve")
                        .unwrap_or_else(|| panic!("{text}: no resolve pass"));
                    d.build(&gpu, &shaders)
                        .unwrap_or_else(|e| panic!("{text}: {e}"));
                    let captured = gpu.take_captured();
                    assert_eq!(captured.len(), 1, "{text}: one pipeline");
                    let e = captured[0]
                        .for_stage("compute")
                        .next()
                        .unwrap_or_else(|| panic!("{text}: no compute executable"));
                    let stat = |name: &str| e.stat(name).map_or(f64::NAN, |v| v.as_f64());
                    if let Some(dir) = &dump {
                        let stem = text.replace(':', "_");
                        for (name, body) in &e.representations {
                            let file = dir.join(format!(
                                "{stem}.{}.txt",
                                name.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
                            ));
                            std::fs::write(&file, body).expect("dump");
                        }
                        let stats: String = e
                            .stats
                            .iter()
                            .map(|(n, v)| format!("{n}: {}\n", v.as_f64()))
                            .collect();
                        std::fs::write(dir.join(format!("{stem}.stats.txt")), stats).expect("dump");
                    }
                    rows.push(Row {
                        mode: mode.name().to_string(),
                        mapping,
                        group,
                        fp16,
                        vgprs: stat("VGPRs"),
                        sgprs: stat("SGPRs"),
                        waves: stat("Subgroups per SIMD"),
                        instructions: stat("Instructions"),
                        vmem: stat("VMEM Clause"),
                        inv_throughput: stat("Inverse Throughput"),
                    });
                }
            }
        }
    }
    println!(
        "| mode | mapping | group | precision | VGPRs | SGPRs | waves/SIMD | instructions | VMEM clauses | inverse throughput (per wave64) | per output pixel |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |",
            r.mode,
            r.mapping,
            r.group,
            if r.fp16 { "fp16" } else { "f32" },
            r.vgprs,
            r.sgprs,
            r.waves,
            r.instructions,
            r.vmem,
            r.inv_throughput,
            r.per_pixel()
        );
    }
    for r in &rows {
        for stat in [r.vgprs, r.sgprs, r.waves, r.instructions, r.inv_throughput] {
            assert!(
                stat > 0.0,
                "{} {} {}: a statistic is {stat}",
                r.mode,
                r.mapping,
                r.group
            );
        }
    }
    let mut failures = Vec::new();
    for &(mapping, group, fp16, max_vgprs, min_waves, max_per_pixel) in OURS_BOUNDS {
        let r = rows
            .iter()
            .find(|r| {
                r.mode == "ours" && r.mapping == mapping && r.group == group && r.fp16 == fp16
            })
            .expect("ours row");
        if r.vgprs > max_vgprs || r.waves < min_waves || r.per_pixel() > max_per_pixel {
            failures.push(format!(
                "ours {mapping}/{group}{}: {} VGPRs (bound {max_vgprs}), {} waves/SIMD (bound \
                 {min_waves}), {:.1} per pixel (bound {max_per_pixel})",
                if fp16 { " fp16" } else { "" },
                r.vgprs,
                r.waves,
                r.per_pixel()
            ));
        }
    }
    assert!(failures.is_empty(), "regressions: {failures:#?}");
    common::assert_clean(&gpu);
}
