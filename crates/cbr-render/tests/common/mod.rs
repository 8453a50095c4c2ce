//! Shared by the GPU test files: the test device (validation + synchronization validation on) and
//! the check that it reported nothing.
#![allow(dead_code)]

pub mod lighting;
pub mod null_child;

use cbr_gpu::{Gpu, GpuOptions};

/// The test device: `CBR_TEST_DEVICE` (index or name) or the default pick, validation on.
pub fn gpu() -> Gpu {
    Gpu::new(&GpuOptions {
        device: std::env::var("CBR_TEST_DEVICE").ok(),
        validation: true,
    })
    .expect("a Vulkan device with validation layers")
}

/// Fails the test on any validation message.
pub fn assert_clean(gpu: &Gpu) {
    let msgs = gpu.validation().messages();
    assert!(
        msgs.is_empty(),
        "{} validation messages:\n{}",
        msgs.len(),
        msgs.join("\n")
    );
}

/// Removes every texture from the scene's materials: LOD-independent shading for exact comparisons.
pub fn strip_textures(s: &mut cbr_scene::Scene) {
    for m in &mut s.materials {
        m.kd_tex = None;
        m.alpha = cbr_scene::AlphaSource::Opaque;
        m.bump_tex = None;
    }
}

/// The built-in demo at w x h.
pub fn demo(w: u32, h: u32) -> cbr_scene::Scene {
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (w, h);
    s
}

/// The demo with a still camera (its first key) and nothing moving.
/// The demo whose camera cuts at frame `at` (a key flagged `cut`, 3 m to the side): histories
/// must reset there.
pub fn demo_with_cut(w: u32, h: u32, at: u32) -> cbr_scene::Scene {
    let mut s = demo(w, h);
    let mut cut = s.camera.keys[0].clone();
    cut.time = f64::from(at) / s.settings.fps;
    cut.cut = true;
    cut.position[0] += 3.0;
    s.camera.keys.retain(|k| k.time < cut.time);
    s.camera.keys.push(cut);
    s
}

pub fn static_demo(w: u32, h: u32) -> cbr_scene::Scene {
    let mut s = demo(w, h);
    s.motions.clear();
    s.camera.keys.truncate(1);
    s
}

/// Uploads bytes into images (level 0, each left in ComputeSampled) through one staging buffer:
/// synthetic inputs for the resolves' CPU-reference tests.
pub fn upload(gpu: &Gpu, parts: &[(&cbr_gpu::Image, Vec<u8>)]) -> cbr_gpu::Result<()> {
    use cbr_gpu::{Access, Buffer, LevelCopy, Location, vk};
    let mut bytes = Vec::new();
    let mut offsets = Vec::new();
    for (_, b) in parts {
        bytes.resize(bytes.len().next_multiple_of(16), 0);
        offsets.push(bytes.len() as u64);
        bytes.extend_from_slice(b);
    }
    let mut staging = Buffer::new(
        gpu,
        "test.staging",
        bytes.len() as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        Location::CpuToGpu,
    )?;
    staging.write(0, &bytes)?;
    gpu.submit("test.upload", |cmd| {
        for ((img, _), off) in parts.iter().zip(&offsets) {
            let l = [LevelCopy {
                buffer_offset: *off,
                level: 0,
                width: img.width,
                height: img.height,
            }];
            cmd.upload_levels(&staging, img, &l, Access::ComputeSampled);
        }
        Ok(())
    })
}

/// Frames `frames` of `settings` over `s`, one renderer, with `shaders` (tests that render
/// many configurations share one library: its compile cache).
pub fn render_with(
    gpu: &Gpu,
    shaders: &cbr_gpu::Shaders,
    s: &cbr_scene::Scene,
    settings: cbr_render::RenderSettings,
    frames: &[u32],
) -> Vec<cbr_render::FrameOutput> {
    let mut r = cbr_render::Renderer::new(gpu, shaders, s, settings).expect("renderer");
    frames
        .iter()
        .map(|&f| r.render(s, f).expect("frame"))
        .collect()
}

/// Frames `frames` of `settings` over `s` (a fresh renderer and shader library).
pub fn render_settings(
    gpu: &Gpu,
    s: &cbr_scene::Scene,
    settings: cbr_render::RenderSettings,
    frames: &[u32],
) -> Vec<cbr_render::FrameOutput> {
    render_with(gpu, &cbr_render::shader_library(), s, settings, frames)
}

/// `spec` at the scene's resolution.
pub fn settings_of(s: &cbr_scene::Scene, spec: &str) -> cbr_render::RenderSettings {
    cbr_render::RenderSettings::parse(s.settings.width, s.settings.height, spec).expect("spec")
}

/// Frames `frames` of `spec` over `s` at the scene's resolution (a fresh renderer).
pub fn render_spec(
    gpu: &Gpu,
    s: &cbr_scene::Scene,
    spec: &str,
    frames: &[u32],
) -> Vec<cbr_render::FrameOutput> {
    render_settings(gpu, s, settings_of(s, spec), frames)
}

/// The compile-only build's context at 64 x 36 for `gpu` and the demo's material variants
/// (`materials`: `gpu_scene::material_features` of the scene).
pub fn pass_ctx<'a>(
    gpu: &'a Gpu,
    materials: &'a [u32],
    instrument: bool,
) -> cbr_render::technique::PassCtx<'a> {
    cbr_render::technique::PassCtx {
        caps: gpu.caps(),
        width: 64,
        height: 36,
        instrument,
        geometry: false,
        materials,
    }
}
