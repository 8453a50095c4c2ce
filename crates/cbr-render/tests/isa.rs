//! The pass declarations rendering uses compile on RADV's null device with the driver's
//! statistics captured, through the device's compile settings alone (`Gpu::set_compile_settings`,
//! `Gpu::take_captured`): `ComputeDecl::build` and `GraphicsDecl::build` need no second list of
//! shaders and no accessor. msaa2x (with and without sample locations) among them, on vega10, with
//! validation on and no message. The driver reads `RADV_FORCE_FAMILY` when devices are enumerated,
//! so the check runs in a child process; skips with a message where RADV's ICD is not installed.

mod common;

use cbr_gpu::{CompileSettings, Gpu, GpuOptions};
use common::null_child;

const CHILD: &str = "CBR_ISA_CHILD";

#[test]
fn declared_passes_compile_on_vega10_with_their_statistics() {
    if null_child::no_radv() {
        return;
    }
    let child = null_child::spawn("child_vega10", "vega10", CHILD, "1");
    null_child::expect_pass("vega10", child);
}

#[test]
#[ignore = "run by declared_passes_compile_on_vega10_with_their_statistics"]
fn child_vega10() {
    if std::env::var(CHILD).is_err() {
        return;
    }
    let gpu = null_child::gpu(
        "Null hardware (RADV VEGA10)",
        CompileSettings {
            statistics: true,
            ..Default::default()
        },
    );
    let shaders = cbr_render::shader_library();
    let scene = common::demo(64, 36);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    let ctx = common::pass_ctx(&gpu, &materials, false);
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

/// Every registered technique (its bare name and the specs below: every layout, msaa2x with and
/// without sample locations, every resolve mode, every post pass) compiles on the null devices
/// of polaris10 (GCN 4), vega10 (GCN 5), navi21 (RDNA 2) and gfx1100 (RDNA 3) through the
/// declarations rendering uses, with validation on and no message: what lavapipe accepts and a
/// GPU driver would not. Where a family lacks a feature a spec needs (RDNA: sample locations),
/// the registration's refusal names it.
#[test]
fn every_registered_pass_compiles_on_four_families() {
    if null_child::no_radv() {
        return;
    }
    // One child per family (the driver reads the family once per process), all at once.
    let children: Vec<_> = ["polaris10", "vega10", "navi21", "gfx1100"]
        .into_iter()
        .map(|family| {
            (
                family,
                null_child::spawn("child_every_pass", family, CHILD, family),
            )
        })
        .collect();
    for (family, child) in children {
        null_child::expect_pass(family, child);
    }
}

#[test]
#[ignore = "run by every_registered_pass_compiles_on_four_families"]
fn child_every_pass() {
    let Ok(family) = std::env::var(CHILD) else {
        return;
    };
    let gpu = Gpu::new(&GpuOptions {
        device: None,
        validation: true,
    })
    .expect("a null device");
    assert!(
        gpu.info().name.to_lowercase().contains(&family),
        "{} is not {family}",
        gpu.info().name
    );
    let shaders = cbr_render::shader_library();
    let scene = common::demo(64, 36);
    let materials = cbr_render::gpu_scene::material_features(&scene);
    let ctx = common::pass_ctx(&gpu, &materials, true);
    let mut specs: Vec<String> = cbr_render::registry::TECHNIQUES
        .iter()
        .map(|t| t.name.to_string())
        .filter(|n| cbr_render::Spec::parse(n).is_ok())
        .collect();
    for layout in ["masked", "split", "rotated", "msaa2x"] {
        specs.push(format!("checkerboard:{layout}:ours"));
    }
    for mode in cbr_render::ResolveMode::ALL {
        specs.push(format!("checkerboard:rotated:{}:quad:8", mode.name()));
    }
    specs.extend(
        [
            "checkerboard:msaa2x:ours:locations",
            "checkerboard:rotated:ours:prepass+taa",
            "checkerboard:rotated:fused",
            "ssaa:2",
            "msaa:4:sample:hdr",
            "analytic:seed:aniso",
            "deferred:vpls=64",
            "interleaved:4x4:vpls=64:seed:direct:debug:floor",
            "interleaved:3x2:vpls=48:implicit",
            "interlaced:debug",
            "upscale:bicubic",
            "upscale:fsr1:0.5",
            "taau",
            "native+taa+sharpen",
            "native+taa:inside+fxaa",
        ]
        .map(String::from),
    );
    let mut built = std::collections::BTreeSet::new();
    let mut refused = Vec::new();
    for text in &specs {
        let spec = cbr_render::Spec::parse(text).expect("spec");
        let t = cbr_render::registry::find(&spec.technique.name).expect("registered");
        if let Some(why) = (t.needs)(&spec.technique.params(), gpu.caps()) {
            refused.push(format!("{text}: {why}"));
            continue;
        }
        let list =
            cbr_render::registry::passes(&spec, &ctx).unwrap_or_else(|e| panic!("{text}: {e}"));
        for d in &list.compute {
            if built.insert(format!("{} {:?}", d.shader, d.all_defines())) {
                d.build(&gpu, &shaders)
                    .unwrap_or_else(|e| panic!("{family} {text}: {}: {e}", d.name));
            }
        }
        for d in &list.graphics {
            if built.insert(format!("{:?} {:?}", d.stages(), d.state)) {
                d.build(&gpu, &shaders)
                    .unwrap_or_else(|e| panic!("{family} {text}: {}: {e}", d.name));
            }
        }
    }
    println!(
        "{family}: {} pipelines of {} specs",
        built.len(),
        specs.len()
    );
    for r in &refused {
        println!("{family}: refused {r}");
    }
    // RDNA has no sample locations: the locations variant is the one refusal there.
    let expected: &[&str] = match family.as_str() {
        "navi21" | "gfx1100" => &["checkerboard:msaa2x:ours:locations"],
        _ => &[],
    };
    assert_eq!(
        refused
            .iter()
            .map(|r| r.split(':').take(4).collect::<Vec<_>>().join(":"))
            .collect::<Vec<_>>(),
        expected,
        "{family}: refusals {refused:?}"
    );
    common::assert_clean(&gpu);
}
