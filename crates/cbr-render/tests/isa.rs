//! The pass declarations rendering uses compile on RADV's null device with the driver's
//! statistics captured, through the device's compile settings alone (`Gpu::set_compile_settings`,
//! `Gpu::take_captured`): `ComputeDecl::build` and `GraphicsDecl::build` need no second list of
//! shaders and no accessor. msaa2x (with and without sample locations) among them, on vega10, with
//! validation on and no message. The driver reads `RADV_FORCE_FAMILY` when devices are enumerated,
//! so the check runs in a child process; skips with a message where RADV's ICD is not installed.

mod common;

use std::process::Command;

use cbr_gpu::{CompileSettings, Gpu, GpuOptions, null_device};

const CHILD: &str = "CBR_ISA_CHILD";

#[test]
fn declared_passes_compile_on_vega10_with_their_statistics() {
    if null_device::radeon_icd().is_none() {
        eprintln!(
            "skipped: RADV's ICD {} is not installed",
            null_device::RADEON_ICD
        );
        return;
    }
    let mut c = Command::new(std::env::current_exe().expect("test binary"));
    c.args(["child_vega10", "--exact", "--ignored", "--nocapture"]);
    null_device::set_env(&mut c, "vega10").expect("vega10");
    c.env(CHILD, "1");
    let out = c.output().expect("run the test binary");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{:?}", out.status);
    assert!(stdout.contains("1 passed"), "{stdout}");
}

#[test]
#[ignore = "run by declared_passes_compile_on_vega10_with_their_statistics"]
fn child_vega10() {
    if std::env::var(CHILD).is_err() {
        return;
    }
    let gpu = Gpu::new(&GpuOptions {
        device: None,
        validation: true,
    })
    .expect("vega10's null device");
    assert_eq!(gpu.info().name, "Null hardware (RADV VEGA10)");
    gpu.set_compile_settings(CompileSettings {
        statistics: true,
        ..Default::default()
    })
    .expect("capture");
    let shaders = cbr_render::shader_library();
    let scene = common::demo(64, 36);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    let ctx = cbr_render::technique::PassCtx {
        caps: gpu.caps(),
        width: 64,
        height: 36,
        instrument: false,
        geometry: false,
        materials: &materials,
    };
    for text in [
        "checkerboard:msaa2x:ours",
        "checkerboard:msaa2x:ours:locations",
        "checkerboard:rotated:pq4k:quad:8+taa",
    ] {
        let settings = cbr_render::RenderSettings::parse(64, 36, text).expect("spec");
        let list = cbr_render::registry::passes(&settings.spec, &ctx)
            .unwrap_or_else(|e| panic!("{text}: {e}"));
        let mut names: Vec<String> = Vec::new();
        for d in &list.compute {
            d.build(&gpu, &shaders)
                .unwrap_or_else(|e| panic!("{text}: {}: {e}", d.name));
            names.push(d.name.clone());
        }
        for d in &list.graphics {
            d.build(&gpu, &shaders)
                .unwrap_or_else(|e| panic!("{text}: {}: {e}", d.name));
            names.push(d.name.clone());
        }
        assert!(!list.graphics.is_empty(), "{text}: no raster pass");
        let captured = gpu.take_captured();
        assert_eq!(
            captured
                .iter()
                .map(|p| p.pipeline.clone())
                .collect::<Vec<_>>(),
            names,
            "{text}: one capture per declared pipeline, in build order"
        );
        for p in &captured {
            let stage = if p.kind == "compute" {
                "compute"
            } else {
                "fragment"
            };
            let e = p
                .for_stage(stage)
                .next()
                .unwrap_or_else(|| panic!("{text}: {}: no {stage} executable", p.pipeline));
            for stat in ["VGPRs", "SGPRs", "Instructions"] {
                let v = e.stat(stat).map_or(0.0, |v| v.as_f64());
                assert!(v > 0.0, "{text}: {} {stage} {stat} = {v}", p.pipeline);
            }
            println!(
                "{text}: {} {stage}: VGPRs {} SGPRs {} waves/SIMD {}",
                p.pipeline,
                e.stat("VGPRs").map_or(0.0, |v| v.as_f64()),
                e.stat("SGPRs").map_or(0.0, |v| v.as_f64()),
                e.stat("Subgroups per SIMD").map_or(0.0, |v| v.as_f64()),
            );
        }
    }
    common::assert_clean(&gpu);
}
