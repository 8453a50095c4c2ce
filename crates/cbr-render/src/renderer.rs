//! The frame sequencer: one scene, one technique, frames rendered and read back in order.

use cbr_gpu::{Gpu, PassKind, PassTiming, Profiler, Readback, Result, Shaders};
use cbr_scene::Scene;
use half::f16;

use crate::gpu_scene::{FrameView, GpuScene};
use crate::native::ScenePass;
use crate::targets::FrameTargets;

/// How to render.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Added to every texture lookup's LOD.
    pub lod_bias: f32,
}

/// One rendered frame, read back to the host.
pub struct FrameOutput {
    pub index: u32,
    pub time: f64,
    pub width: u32,
    pub height: u32,
    /// Linear HDR radiance, RGBA, rows top to bottom. Alpha 1 where shaded this frame.
    pub color: Vec<f16>,
    /// View-space distance along the camera axis (metres); +inf where nothing was drawn.
    pub depth: Vec<f32>,
    /// Screen-space motion since the previous frame in pixels (current - previous), x right, y down.
    pub velocity: Vec<[f32; 2]>,
    /// [object ID (index + 1, 0 = background), primitive ID within the object].
    pub ids: Vec<[u32; 2]>,
    pub timings: Vec<PassTiming>,
}

struct Readbacks {
    color: Readback,
    depth: Readback,
    velocity: Readback,
    ids: Readback,
}

pub struct Renderer {
    gpu: Gpu,
    scene: GpuScene,
    pass: ScenePass,
    targets: FrameTargets,
    readbacks: Readbacks,
    profiler: Profiler,
    settings: RenderSettings,
}

impl Renderer {
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Renderer> {
        let gpu_scene = GpuScene::new(gpu, scene)?;
        let pass = ScenePass::new(gpu, shaders, &gpu_scene, "native.raster")?;
        let targets = FrameTargets::new(gpu, "native", settings.width, settings.height)?;
        let readbacks = Readbacks {
            color: Readback::for_image(gpu, "readback.color", &targets.color)?,
            depth: Readback::for_image(gpu, "readback.depth", &targets.depth)?,
            velocity: Readback::for_image(gpu, "readback.velocity", &targets.velocity)?,
            ids: Readback::for_image(gpu, "readback.ids", &targets.ids)?,
        };
        let profiler = Profiler::new(gpu, "native.profiler", 8)?;
        Ok(Renderer {
            gpu: gpu.clone(),
            scene: gpu_scene,
            pass,
            targets,
            readbacks,
            profiler,
            settings,
        })
    }

    pub fn view(&self, scene: &Scene, frame: u32) -> FrameView {
        let time = scene.time_of_frame(frame);
        let prev_time = time - 1.0 / scene.settings.fps;
        FrameView {
            camera: scene.camera.at(time),
            prev_camera: scene.camera.at(prev_time),
            time,
            prev_time,
            width: self.settings.width,
            height: self.settings.height,
            jitter: [0.0, 0.0],
            lod_bias: self.settings.lod_bias,
            frame_index: frame,
        }
    }

    /// Renders frame `frame` of `scene` (the scene this renderer was built for) and reads it back.
    pub fn render(&mut self, scene: &Scene, frame: u32) -> Result<FrameOutput> {
        let view = self.view(scene, frame);
        self.scene.update(scene, &view)?;
        self.profiler.begin_frame();
        let (pass, gs, targets, rb, profiler) = (
            &self.pass,
            &self.scene,
            &self.targets,
            &self.readbacks,
            &mut self.profiler,
        );
        self.gpu.submit("frame", |cmd| {
            pass.record(cmd, profiler, gs, targets);
            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            cmd.read_image(&targets.color, &rb.color);
            cmd.read_image(&targets.depth, &rb.depth);
            cmd.read_image(&targets.velocity, &rb.velocity);
            cmd.read_image(&targets.ids, &rb.ids);
            profiler.end(cmd, scope);
            Ok(())
        })?;
        let timings = self.profiler.results()?;
        let near = view.camera.near as f32;
        let depth = bytemuck::cast_slice::<u8, f32>(rb.depth.bytes()?)
            .iter()
            .map(|&d| if d > 0.0 { near / d } else { f32::INFINITY })
            .collect();
        Ok(FrameOutput {
            index: frame,
            time: view.time,
            width: self.settings.width,
            height: self.settings.height,
            color: bytemuck::cast_slice::<u8, f16>(rb.color.bytes()?).to_vec(),
            depth,
            velocity: bytemuck::cast_slice::<u8, [f32; 2]>(rb.velocity.bytes()?).to_vec(),
            ids: bytemuck::cast_slice::<u8, [u32; 2]>(rb.ids.bytes()?).to_vec(),
            timings,
        })
    }
}
