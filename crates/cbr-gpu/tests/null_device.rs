//! RADV's null device (crate::null_device): AMD's compiler without an AMD GPU. Pipelines compile
//! there with their statistics and disassembly captured, compute in wave32 and wave64 on RDNA,
//! with the validation layers on and no message; whatever would allocate or execute is one clear
//! error, and dropping the device does not crash. The driver picks the family from the
//! environment when devices are enumerated, so each case runs this binary again as a child
//! process with that environment (`child_*` tests, ignored in a plain run). Skips with a message
//! where RADV's ICD is not installed.

use std::process::Command;

use cbr_gpu::null_device;
use cbr_gpu::{
    BindingDesc, Buffer, CompileSettings, ComputeDesc, DescriptorKind, Gpu, GpuError, GpuOptions,
    GraphicsDesc, Image, ImageDesc, Location, Pipeline, PipelineExecutables, SetLayout, Shaders,
    StaticTree, vk,
};

const CHILD: &str = "CBR_NULL_DEVICE_CHILD";

/// Runs the ignored test `name` in a child process on `family`'s null device; `false` (after a
/// message) where RADV is not installed.
fn in_child(family: &str, name: &str) -> bool {
    if null_device::radeon_icd().is_none() {
        eprintln!(
            "skipped: RADV's ICD {} is not installed",
            null_device::RADEON_ICD
        );
        return false;
    }
    let mut c = Command::new(std::env::current_exe().expect("test binary"));
    c.args([
        name,
        "--exact",
        "--ignored",
        "--nocapture",
        "--test-threads=1",
    ]);
    null_device::set_env(&mut c, family).expect("family");
    c.env(CHILD, family);
    let out = c.output().expect("run the test binary");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("--- child {name} on {family}:\n{stdout}\n{stderr}");
    assert!(out.status.success(), "{name} on {family}: {:?}", out.status);
    // The child ran the test (an ignored test that is filtered out would succeed too).
    assert!(stdout.contains("1 passed"), "{stdout}");
    true
}

/// The child's device: the family's null device with validation on, or `None` outside a child.
fn child_gpu() -> Option<Gpu> {
    let family = std::env::var(CHILD).ok()?;
    let gpu = Gpu::new(&GpuOptions {
        device: None,
        validation: true,
    })
    .expect("the null device");
    let name = &gpu.info().name;
    assert!(
        name.starts_with("Null hardware") && name.to_lowercase().contains(&family),
        "{name}"
    );
    Some(gpu)
}

const COMPUTE: &str = r#"#version 450
layout(local_size_x = 16, local_size_y = 16) in;
layout(set = 0, binding = 0, rgba16f) uniform image2D img;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec4 c = imageLoad(img, p);
    vec4 n = imageLoad(img, p + ivec2(1, 0));
    imageStore(img, p, sqrt(c * n + vec4(0.5)));
}
"#;

const VERTEX: &str = r#"#version 450
layout(location = 0) out vec2 uv;
void main() {
    uv = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}
"#;

const FRAGMENT: &str = r#"#version 450
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;
layout(set = 0, binding = 0) uniform sampler2D tex;
void main() {
    color = texture(tex, uv) * vec4(uv, 1.0 - uv.x, 1.0);
}
"#;

fn shaders() -> Shaders {
    Shaders::new(Box::new(StaticTree(&[
        ("t.comp", COMPUTE),
        ("t.vert", VERTEX),
        ("t.frag", FRAGMENT),
    ])))
}

fn compute(gpu: &Gpu, shaders: &Shaders) -> Pipeline {
    let set = SetLayout::new(
        gpu,
        "t.set",
        &[BindingDesc::one("img", 0, DescriptorKind::StorageImage)],
    )
    .expect("set layout");
    let cs = shaders.compile("t.comp", &[]).expect("compute shader");
    Pipeline::compute(
        gpu,
        &ComputeDesc {
            name: "t.compute",
            shader: &cs,
            set_layouts: &[&set],
            push_constant_bytes: 0,
        },
    )
    .expect("compute pipeline")
}

fn graphics(gpu: &Gpu, shaders: &Shaders) -> Pipeline {
    let set = SetLayout::new(
        gpu,
        "t.raster_set",
        &[BindingDesc::one(
            "tex",
            0,
            DescriptorKind::CombinedImageSampler,
        )],
    )
    .expect("set layout");
    let vs = shaders.compile("t.vert", &[]).expect("vertex shader");
    let fs = shaders.compile("t.frag", &[]).expect("fragment shader");
    Pipeline::graphics(
        gpu,
        &GraphicsDesc {
            name: "t.raster",
            vertex: &vs,
            geometry: None,
            fragment: &fs,
            set_layouts: &[&set],
            push_constant_bytes: 0,
            color_formats: &[vk::Format::R16G16B16A16_SFLOAT],
            depth_format: Some(vk::Format::D32_SFLOAT),
            depth_compare: vk::CompareOp::GREATER_OR_EQUAL,
            depth_write: true,
            samples: 2,
            min_sample_shading: Some(1.0),
            cull_back_faces: true,
            sample_locations: false,
        },
    )
    .expect("graphics pipeline")
}

/// A register count that must be there and positive.
fn positive(p: &PipelineExecutables, stage: &str, stat: &str) -> f64 {
    let e = p
        .for_stage(stage)
        .next()
        .unwrap_or_else(|| panic!("{}: no {stage} executable: {p:#?}", p.pipeline));
    let v = e
        .stat(stat)
        .unwrap_or_else(|| panic!("{}: no `{stat}` in {:?}", p.pipeline, e.stats))
        .as_f64();
    assert!(v > 0.0, "{} {stage} {stat} = {v}", p.pipeline);
    v
}

fn assert_no_messages(gpu: &Gpu) {
    let m = gpu.validation().messages();
    assert!(m.is_empty(), "{} validation messages: {m:#?}", m.len());
}

#[test]
fn vega10_compiles_with_statistics_and_refuses_to_execute() {
    in_child("vega10", "child_vega10");
}

#[test]
#[ignore = "run by vega10_compiles_with_statistics_and_refuses_to_execute"]
fn child_vega10() {
    let Some(gpu) = child_gpu() else { return };
    let caps = gpu.caps().clone();
    assert!(!caps.can_execute);
    assert!(caps.pipeline_executable_info);
    // GCN runs wave64 only and lets no stage require a size.
    assert!(
        caps.compute_subgroup_sizes.is_empty(),
        "{:?}",
        caps.compute_subgroup_sizes
    );
    assert_eq!(caps.subgroup_size, 64);
    // The per-format answer for the ID target (framebufferIntegerColorSampleCounts says 1).
    assert!(caps.integer_color_sample_counts.contains(&2), "{caps:?}");
    assert_eq!(caps.layout_unsupported(cbr_gpu::Layout::Msaa2x), None);

    // Whatever allocates or executes is refused, naming the device.
    let img = Image::new(
        &gpu,
        &ImageDesc::new_2d(
            "t.image",
            vk::Format::R8G8B8A8_UNORM,
            8,
            8,
            vk::ImageUsageFlags::SAMPLED,
        ),
    );
    let buf = Buffer::new(
        &gpu,
        "t.buffer",
        64,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        Location::GpuOnly,
    );
    let sub = gpu.submit("t.submit", |_| Ok(()));
    for (what, r) in [
        ("the image `t.image`", img.err()),
        ("the buffer `t.buffer`", buf.err()),
        ("submitting `t.submit`", sub.err()),
    ] {
        match r {
            Some(e @ GpuError::CannotExecute { .. }) => {
                let m = e.to_string();
                assert!(m.contains(what), "{m}");
                assert!(m.contains("Null hardware (RADV VEGA10)"), "{m}");
                assert!(m.contains("can only compile pipelines"), "{m}");
            }
            other => panic!("{what}: {other:?}"),
        }
    }
    assert_eq!(gpu.allocations_made(), 0);

    // Without capture nothing is read; a wave size GCN lacks is refused, changing nothing.
    let shaders = shaders();
    assert!(compute(&gpu, &shaders).executables().is_none());
    assert!(gpu.take_captured().is_empty());
    let wave32 = CompileSettings {
        compute_subgroup_size: Some(32),
        ..Default::default()
    };
    let err = gpu.set_compile_settings(wave32).unwrap_err().to_string();
    assert!(err.contains("subgroup size of 32"), "{err}");
    assert_eq!(gpu.compile_settings(), CompileSettings::default());

    // Statistics only, then with the disassembly.
    for representations in [false, true] {
        gpu.set_compile_settings(CompileSettings {
            statistics: true,
            representations,
            compute_subgroup_size: None,
        })
        .expect("capture");
        let c = compute(&gpu, &shaders);
        let g = graphics(&gpu, &shaders);
        let (cs, gs) = (
            c.executables().expect("compute stats"),
            g.executables().expect("raster stats"),
        );
        for stat in ["VGPRs", "SGPRs", "Code size", "Instructions"] {
            positive(cs, "compute", stat);
            positive(gs, "fragment", stat);
            positive(gs, "vertex", stat);
        }
        let cse = cs.for_stage("compute").next().expect("compute executable");
        assert_eq!(cse.subgroup_size, 64);
        assert_eq!(cs.kind, "compute");
        assert_eq!(gs.kind, "graphics");
        // The log holds the same, in creation order.
        let log = gpu.take_captured();
        assert_eq!(
            log.iter().map(|p| p.pipeline.as_str()).collect::<Vec<_>>(),
            ["t.compute", "t.raster"]
        );
        assert_eq!(log[0].executables.len(), cs.executables.len());
        for e in cs.executables.iter().chain(&gs.executables) {
            if representations {
                let asm = e.representation("Assembly").unwrap_or_default();
                assert!(
                    !asm.trim().is_empty(),
                    "{}: {:?}",
                    e.name,
                    e.representations
                );
                // GCN's scalar end of program, or any s_/v_ instruction.
                assert!(asm.contains("s_endpgm") || asm.contains("v_"), "{asm}");
            } else {
                assert!(e.representations.is_empty());
            }
        }
        if representations {
            eprintln!(
                "vega10 compute stats: {}",
                serde_json::to_string(&cse.stats).unwrap_or_default()
            );
        }
    }
    assert_no_messages(&gpu);
    // Dropping the device does not wait on it (RADV's null device crashes in vkDeviceWaitIdle).
    drop(gpu);
}

#[test]
fn navi21_compiles_compute_in_wave32_and_wave64() {
    in_child("navi21", "child_navi21");
}

#[test]
#[ignore = "run by navi21_compiles_compute_in_wave32_and_wave64"]
fn child_navi21() {
    let Some(gpu) = child_gpu() else { return };
    assert_eq!(gpu.caps().compute_subgroup_sizes, vec![32, 64]);
    let shaders = shaders();
    for wave in [32, 64] {
        gpu.set_compile_settings(CompileSettings {
            statistics: true,
            representations: false,
            compute_subgroup_size: Some(wave),
        })
        .expect("wave size");
        let c = compute(&gpu, &shaders);
        let stats = c.executables().expect("stats");
        assert_eq!(stats.required_subgroup_size, Some(wave));
        let e = stats
            .for_stage("compute")
            .next()
            .expect("compute executable");
        assert_eq!(e.subgroup_size, wave, "required wave{wave}");
        positive(stats, "compute", "VGPRs");
    }
    assert_no_messages(&gpu);
}

#[test]
fn an_unknown_family_is_refused_before_mesa_aborts() {
    if null_device::radeon_icd().is_none() {
        eprintln!("skipped: RADV's ICD is not installed");
        return;
    }
    let mut c = Command::new(std::env::current_exe().expect("test binary"));
    c.args([
        "child_unknown_family",
        "--exact",
        "--ignored",
        "--nocapture",
    ]);
    c.env("RADV_FORCE_FAMILY", "gfx900")
        .env("VK_DRIVER_FILES", null_device::RADEON_ICD)
        .env(CHILD, "gfx900");
    let out = c.output().expect("run the test binary");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("1 passed"), "{stdout}");
}

#[test]
#[ignore = "run by an_unknown_family_is_refused_before_mesa_aborts"]
fn child_unknown_family() {
    if std::env::var(CHILD).is_err() {
        return;
    }
    match Gpu::new(&GpuOptions::default()) {
        Err(e @ GpuError::UnknownFamily { .. }) => {
            let m = e.to_string();
            assert!(
                m.contains("RADV_FORCE_FAMILY=gfx900") && m.contains("vega10"),
                "{m}"
            );
        }
        Err(e) => panic!("{e}"),
        Ok(g) => panic!("opened {}", g.info().name),
    }
}
