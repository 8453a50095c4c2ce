//! The frame sequencer: one scene, one technique, frames rendered and read back in order.

use cbr_gpu::{
    Buffer, Gpu, GpuError, Layout, Location, PassKind, PassTiming, Profiler, Readback, Result,
    Shaders, vk,
};
use cbr_scene::Scene;
use half::f16;

use crate::checkerboard::{UnpackPass, UnpackedPixel};
use crate::gpu_scene::{FrameView, GpuScene, RasterUniforms};
use crate::gpu_types::{FLAG_COUNT_SHADED, FLAG_DEBUG_LOD, FLAG_LOD_GRADIENTS, FLAG_PARITY};
use crate::layouts::LayoutPlan;
use crate::native::{RasterConfig, ScenePass};
use crate::resolve::{ResolveFrame, ResolvePass, ResolveReadbacks, ResolveSettings};
use crate::targets::FrameTargets;
use crate::upscale::{UpscaleFilter, UpscalePass, low_resolution};

/// How texture LOD follows the sample spacing of a layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LodMode {
    /// A LOD bias (`lod_bias`, default per layout).
    Bias,
    /// `textureGrad` with the derivatives turned into full-res screen derivatives.
    Gradients,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase", tag = "technique")]
pub enum Technique {
    Native,
    Checkerboard {
        layout: Layout,
        lod_mode: LodMode,
    },
    /// Render at W/sqrt(2) x H/sqrt(2), then upscale (the baseline checkerboard must beat).
    Upscale {
        filter: UpscaleFilter,
    },
}

impl Technique {
    /// The mip bias that matches the layout's sample spacing: 2 px (split, msaa2x) is one level,
    /// sqrt(2) px (rotated) half a level.
    pub fn default_lod_bias(&self) -> f32 {
        match self {
            Technique::Native | Technique::Upscale { .. } => 0.0,
            Technique::Checkerboard { layout, .. } => match layout {
                Layout::Masked => 0.0,
                Layout::Split | Layout::Msaa2x => -1.0,
                Layout::Rotated => -0.5,
            },
        }
    }

    pub fn name(&self) -> String {
        match self {
            Technique::Native => "native".into(),
            Technique::Checkerboard { layout, .. } => format!("checkerboard:{}", layout.name()),
            Technique::Upscale { filter } => format!("upscale:{}", filter.name()),
        }
    }
}

/// How to render.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub technique: Technique,
    /// Added to every texture lookup's LOD; `None`: the technique's default.
    pub lod_bias: Option<f32>,
    /// Count shaded (non-helper) fragments with an atomic counter (tests, `--count-shaded`).
    pub count_shaded: bool,
    /// Write each sample's albedo level of detail to colour.r instead of radiance (tests, docs).
    pub debug_lod: bool,
    /// Checkerboard only: a native-resolution depth + ID pass before the checkerboard raster, no
    /// shading (what PS4 Pro hardware gives Decima); its outputs go to `FrameOutput::prepass`.
    pub id_prepass: bool,
    /// Checkerboard only: the resolve; `None` writes the raw checkerboard frame.
    pub resolve: Option<ResolveSettings>,
    /// msaa2x only: odd frames move the samples (VK_EXT_sample_locations) instead of shifting the
    /// viewport.
    pub msaa2x_sample_locations: bool,
}

impl RenderSettings {
    pub fn native(width: u32, height: u32) -> RenderSettings {
        RenderSettings {
            width,
            height,
            technique: Technique::Native,
            lod_bias: None,
            count_shaded: false,
            debug_lod: false,
            id_prepass: false,
            resolve: None,
            msaa2x_sample_locations: false,
        }
    }

    pub fn effective_lod_bias(&self) -> f32 {
        self.lod_bias
            .unwrap_or_else(|| self.technique.default_lod_bias())
    }
}

/// One rendered frame, read back to the host.
#[derive(Clone)]
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
    /// Checkerboard frames: 1 where this frame shaded the pixel, and the frame's parity.
    pub mask: Option<Vec<u8>>,
    pub parity: Option<u32>,
    /// Shaded (non-helper) fragments, when counted.
    pub shaded_fragments: Option<u64>,
    /// The `id_prepass` outputs at full resolution: view depth (+inf where empty) and IDs.
    pub prepass: Option<(Vec<f32>, Vec<[u32; 2]>)>,
    /// Resolved checkerboard frames: whether history was reset, and with `debug` the debug bits
    /// (resolve::DEBUG_VIEWS) and the velocity each pixel used.
    pub resolve: Option<ResolveOutput>,
    pub timings: Vec<PassTiming>,
}

struct NativeReadbacks {
    color: Readback,
    depth: Readback,
    velocity: Readback,
    ids: Readback,
}

/// The native-resolution depth + ID prepass.
struct Prepass {
    pass: ScenePass,
    config: RasterConfig,
    ids: cbr_gpu::Image,
    depth: cbr_gpu::Image,
    ids_rb: Readback,
    depth_rb: Readback,
}

impl Prepass {
    fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &GpuScene,
        w: u32,
        h: u32,
        counter: &Buffer,
    ) -> Result<Prepass> {
        let config = RasterConfig {
            id_only: true,
            ..RasterConfig::native(w, h)
        };
        let pass = ScenePass::new(gpu, shaders, scene, "id_prepass.raster", &config, counter)?;
        let t = FrameTargets::new(gpu, "id_prepass", w, h)?;
        // Only the ID and depth targets are kept; colour and velocity are dropped unused.
        let FrameTargets { ids, depth, .. } = t;
        let ids_rb = Readback::for_image(gpu, "readback.prepass_ids", &ids)?;
        let depth_rb = Readback::for_image(gpu, "readback.prepass_depth", &depth)?;
        Ok(Prepass {
            pass,
            config,
            ids,
            depth,
            ids_rb,
            depth_rb,
        })
    }
}

/// What the resolve adds to a frame's output.
#[derive(Clone)]
pub struct ResolveOutput {
    pub reset: bool,
    /// Per pixel: the resolve::DBG_* bits (with `debug`).
    pub debug_bits: Option<Vec<u32>>,
    /// Per pixel: the velocity the resolve used (with `debug`).
    pub velocity: Option<Vec<[f32; 2]>>,
}

struct Resolve {
    pass: ResolvePass,
    rb: ResolveReadbacks,
}

// One per renderer, built once: variant sizes do not matter.
#[allow(clippy::large_enum_variant)]
enum Mode {
    Native {
        readbacks: NativeReadbacks,
        config: RasterConfig,
    },
    Checkerboard {
        plans: [LayoutPlan; 2],
        configs: [RasterConfig; 2],
        unpack: UnpackPass,
        resolve: Option<Resolve>,
    },
    Upscale {
        config: RasterConfig,
        pass: UpscalePass,
        readbacks: NativeReadbacks,
        low: (u32, u32),
    },
}

pub struct Renderer {
    prepass: Option<Prepass>,
    gpu: Gpu,
    scene: GpuScene,
    pass: ScenePass,
    targets: FrameTargets,
    mode: Mode,
    counter: Buffer,
    profiler: Profiler,
    settings: RenderSettings,
    /// The last frame resolved into the history (frames that do not follow it reset it).
    last_frame: Option<u32>,
}

impl Renderer {
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Renderer> {
        let gpu_scene = GpuScene::new(gpu, scene)?;
        let counter = Buffer::new(
            gpu,
            "shaded_fragments",
            4,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            Location::GpuToCpu,
        )?;
        let (w, h) = (settings.width, settings.height);
        let prepass = match (settings.id_prepass, settings.technique) {
            (false, _) => None,
            (true, Technique::Checkerboard { .. }) => {
                Some(Prepass::new(gpu, shaders, &gpu_scene, w, h, &counter)?)
            }
            (true, _) => {
                return Err(GpuError::Other(
                    "--id-prepass applies to the checkerboard technique".into(),
                ));
            }
        };
        if settings.resolve.is_some()
            && !matches!(settings.technique, Technique::Checkerboard { .. })
        {
            return Err(GpuError::Other(
                "a resolve applies to the checkerboard technique".into(),
            ));
        }
        let native_readbacks = |color: &cbr_gpu::Image,
                                depth: &cbr_gpu::Image,
                                velocity: &cbr_gpu::Image,
                                ids: &cbr_gpu::Image|
         -> Result<NativeReadbacks> {
            Ok(NativeReadbacks {
                color: Readback::for_image(gpu, "readback.color", color)?,
                depth: Readback::for_image(gpu, "readback.depth", depth)?,
                velocity: Readback::for_image(gpu, "readback.velocity", velocity)?,
                ids: Readback::for_image(gpu, "readback.ids", ids)?,
            })
        };
        let (pass, targets, mode) = match settings.technique {
            Technique::Native => {
                let config = RasterConfig::native(w, h);
                let pass =
                    ScenePass::new(gpu, shaders, &gpu_scene, "native.raster", &config, &counter)?;
                let targets = FrameTargets::new(gpu, "native", w, h)?;
                let readbacks = native_readbacks(
                    &targets.color,
                    &targets.depth,
                    &targets.velocity,
                    &targets.ids,
                )?;
                (pass, targets, Mode::Native { readbacks, config })
            }
            Technique::Upscale { filter } => {
                let (lw, lh) = low_resolution(w, h);
                let config = RasterConfig::native(lw, lh);
                let pass = ScenePass::new(
                    gpu,
                    shaders,
                    &gpu_scene,
                    "upscale.raster",
                    &config,
                    &counter,
                )?;
                let targets = FrameTargets::new(gpu, "upscale.low", lw, lh)?;
                let up = UpscalePass::new(gpu, shaders, filter, &targets, w, h)?;
                let o = &up.out;
                let readbacks = native_readbacks(&o.color, &o.depth, &o.velocity, &o.ids)?;
                (
                    pass,
                    targets,
                    Mode::Upscale {
                        config,
                        pass: up,
                        readbacks,
                        low: (lw, lh),
                    },
                )
            }
            Technique::Checkerboard { layout, .. } => {
                if let Some(missing) = gpu.caps().layout_unsupported(layout) {
                    let portable: Vec<&str> = gpu
                        .caps()
                        .supported_layouts()
                        .iter()
                        .map(|l| l.name())
                        .collect();
                    return Err(GpuError::Unsupported {
                        device: gpu.info().name.clone(),
                        feature: format!(
                            "the {} layout (it needs {missing}); layouts this device runs: {}",
                            layout.name(),
                            portable.join(", ")
                        ),
                    });
                }
                let mut plans = [
                    LayoutPlan::new(layout, w, h, 0),
                    LayoutPlan::new(layout, w, h, 1),
                ];
                if settings.msaa2x_sample_locations {
                    if layout != Layout::Msaa2x {
                        return Err(GpuError::Other(
                            "--msaa2x-sample-locations applies to the msaa2x layout".into(),
                        ));
                    }
                    if let Some(missing) = gpu.caps().sample_locations_unsupported() {
                        return Err(GpuError::Unsupported {
                            device: gpu.info().name.clone(),
                            feature: format!(
                                "msaa2x with toggled sample locations (it needs {missing})"
                            ),
                        });
                    }
                    plans = plans.map(LayoutPlan::with_sample_locations);
                }
                let configs = [
                    RasterConfig::for_plan(&plans[0]),
                    RasterConfig::for_plan(&plans[1]),
                ];
                let name = format!("checkerboard.{}.raster", layout.name());
                let pass = ScenePass::new(gpu, shaders, &gpu_scene, &name, &configs[0], &counter)?;
                let (tw, th) = plans[0].target;
                let targets = FrameTargets::layered(
                    gpu,
                    &format!("checkerboard.{}", layout.name()),
                    tw,
                    th,
                    plans[0].layers,
                    plans[0].samples,
                    plans[0].sample_locations.is_some(),
                )?;
                let unpack = UnpackPass::new(gpu, shaders, &plans[0], &targets)?;
                let resolve = match &settings.resolve {
                    Some(rs) => {
                        let pre = prepass.as_ref().map(|p| (&p.ids, &p.depth));
                        let pass = ResolvePass::new(gpu, shaders, rs, &plans[0], &targets, pre)?;
                        let rb = pass.readbacks(gpu)?;
                        Some(Resolve { pass, rb })
                    }
                    None => None,
                };
                (
                    pass,
                    targets,
                    Mode::Checkerboard {
                        plans,
                        configs,
                        unpack,
                        resolve,
                    },
                )
            }
        };
        let profiler = Profiler::new(gpu, "renderer.profiler", 8)?;
        Ok(Renderer {
            prepass,
            gpu: gpu.clone(),
            scene: gpu_scene,
            pass,
            targets,
            mode,
            counter,
            profiler,
            settings,
            last_frame: None,
        })
    }

    /// Bytes of the raster targets (what a layout costs in memory).
    pub fn target_bytes(&self) -> u64 {
        let t = &self.targets.color;
        u64::from(t.width)
            * u64::from(t.height)
            * u64::from(t.layers)
            * u64::from(t.samples)
            * crate::targets::BYTES_PER_SAMPLE
    }

    /// Forgets the resolve's history: the next frame resolves without it (a camera cut).
    pub fn reset_history(&mut self) {
        self.last_frame = None;
    }

    fn view(&self, scene: &Scene, frame: u32) -> FrameView {
        let time = scene.time_of_frame(frame);
        let prev_time = time - 1.0 / scene.settings.fps;
        let s = &self.settings;
        let mut flags = if s.count_shaded { FLAG_COUNT_SHADED } else { 0 };
        if s.debug_lod {
            flags |= FLAG_DEBUG_LOD;
        }
        let (mut width, mut height) = (s.width, s.height);
        let raster = match (&self.mode, s.technique) {
            (Mode::Checkerboard { plans, .. }, Technique::Checkerboard { lod_mode, .. }) => {
                let plan = &plans[(frame % 2) as usize];
                flags |= plan.parity * FLAG_PARITY;
                if lod_mode == LodMode::Gradients {
                    flags |= FLAG_LOD_GRADIENTS;
                }
                let vp = RasterConfig::for_plan(plan).viewport;
                RasterUniforms {
                    viewport: (vp[2], vp[3]),
                    jitter: plan.jitter,
                    flags,
                    tangram: plan.tangram,
                    pieces: plan.pieces.clone(),
                }
            }
            (Mode::Upscale { low, .. }, _) => {
                (width, height) = *low;
                RasterUniforms {
                    viewport: (low.0 as f32, low.1 as f32),
                    flags,
                    ..Default::default()
                }
            }
            _ => RasterUniforms {
                viewport: (s.width as f32, s.height as f32),
                flags,
                ..Default::default()
            },
        };
        FrameView {
            camera: scene.camera.at(time),
            prev_camera: scene.camera.at(prev_time),
            time,
            prev_time,
            width,
            height,
            aspect: f64::from(s.width) / f64::from(s.height),
            lod_bias: s.effective_lod_bias(),
            frame_index: frame,
            raster,
        }
    }

    /// Previous clip from current clip (NDC x, NDC y, reverse-Z depth, 1), composed in f64 with
    /// the camera translation, for the `intel` resolve's camera-only reprojection.
    fn reprojection(&self, view: &FrameView) -> [f32; 16] {
        let (cam, prev) = (&view.camera, &view.prev_camera);
        let clip_from_rel = cam.projection(view.aspect) * cam.rotation();
        let prev_clip_from_rel = prev.projection(view.aspect) * prev.rotation();
        let m = prev_clip_from_rel
            * glam::DMat4::from_translation(cam.position - prev.position)
            * clip_from_rel.inverse();
        m.as_mat4().to_cols_array()
    }

    /// Renders frame `frame` of `scene` (the scene this renderer was built for) and reads it back.
    /// Checkerboard frames alternate parity: frame f shades the pixels with (x + y) mod 2 = f mod 2.
    /// The resolve uses the history of frame f - 1 when that was the last frame rendered, and
    /// resets otherwise.
    pub fn render(&mut self, scene: &Scene, frame: u32) -> Result<FrameOutput> {
        let view = self.view(scene, frame);
        self.scene.update(scene, &view)?;
        self.counter.write(0, &0u32.to_le_bytes())?;
        self.profiler.begin_frame();
        let parity = frame % 2;
        let reset = frame == 0 || self.last_frame != Some(frame - 1);
        let resolve_frame = ResolveFrame {
            slot: parity as usize,
            parity,
            reset,
            reproj: self.reprojection(&view),
        };
        let (pass, gs, targets, counter, profiler, mode) = (
            &self.pass,
            &self.scene,
            &self.targets,
            &self.counter,
            &mut self.profiler,
            &self.mode,
        );
        let prepass = &self.prepass;
        self.gpu.submit("frame", |cmd| {
            if let Some(p) = prepass {
                // Native resolution: the frame constants' raster fields describe the checkerboard
                // pass; the ID-only native variant ignores them (no jitter, tangram or layers).
                p.pass
                    .record(cmd, profiler, gs, &[&p.ids], &p.depth, counter, &p.config);
                cmd.read_image(&p.ids, &p.ids_rb);
                cmd.read_image(&p.depth, &p.depth_rb);
            }
            let config = match mode {
                Mode::Native { config, .. } | Mode::Upscale { config, .. } => config,
                Mode::Checkerboard { configs, .. } => &configs[parity as usize],
            };
            pass.record(
                cmd,
                profiler,
                gs,
                &targets.colors(),
                &targets.depth,
                counter,
                config,
            );
            let read_native = |cmd: &mut cbr_gpu::Cmd,
                               profiler: &mut Profiler,
                               rb: &NativeReadbacks,
                               imgs: [&cbr_gpu::Image; 4]| {
                let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
                cmd.read_image(imgs[0], &rb.color);
                cmd.read_image(imgs[1], &rb.depth);
                cmd.read_image(imgs[2], &rb.velocity);
                cmd.read_image(imgs[3], &rb.ids);
                profiler.end(cmd, scope);
            };
            match mode {
                Mode::Native { readbacks: rb, .. } => read_native(
                    cmd,
                    profiler,
                    rb,
                    [
                        &targets.color,
                        &targets.depth,
                        &targets.velocity,
                        &targets.ids,
                    ],
                ),
                Mode::Upscale {
                    pass: up,
                    readbacks: rb,
                    ..
                } => {
                    up.record(cmd, profiler, targets);
                    let o = &up.out;
                    read_native(cmd, profiler, rb, [&o.color, &o.depth, &o.velocity, &o.ids]);
                }
                Mode::Checkerboard {
                    plans,
                    unpack,
                    resolve,
                    ..
                } => {
                    if let Some(r) = resolve {
                        let pre = prepass.as_ref().map(|p| (&p.ids, &p.depth));
                        r.pass.record(cmd, profiler, targets, pre, &resolve_frame);
                        r.pass.read(cmd, resolve_frame.slot, &r.rb, false);
                    }
                    unpack.record(cmd, profiler, targets, &plans[parity as usize])
                }
            }
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })?;
        self.last_frame = Some(frame);
        let timings = self.profiler.results()?;
        let near = view.camera.near as f32;
        let linear = |d: f32| if d > 0.0 { near / d } else { f32::INFINITY };
        let shaded = self
            .settings
            .count_shaded
            .then(|| {
                self.counter
                    .bytes()
                    .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            })
            .transpose()?;
        let prepass = match &self.prepass {
            Some(p) => Some((
                bytemuck::cast_slice::<u8, f32>(p.depth_rb.bytes()?)
                    .iter()
                    .map(|&d| linear(d))
                    .collect(),
                bytemuck::cast_slice::<u8, [u32; 2]>(p.ids_rb.bytes()?).to_vec(),
            )),
            None => None,
        };
        let base = |color, depth, velocity, ids, mask, parity| FrameOutput {
            index: frame,
            time: view.time,
            width: self.settings.width,
            height: self.settings.height,
            color,
            depth,
            velocity,
            ids,
            mask,
            parity,
            shaded_fragments: shaded,
            prepass: prepass.clone(),
            resolve: None,
            timings: timings.clone(),
        };
        let native_output = |rb: &NativeReadbacks| -> Result<FrameOutput> {
            Ok(base(
                bytemuck::cast_slice::<u8, f16>(rb.color.bytes()?).to_vec(),
                bytemuck::cast_slice::<u8, f32>(rb.depth.bytes()?)
                    .iter()
                    .map(|&d| linear(d))
                    .collect(),
                bytemuck::cast_slice::<u8, [f32; 2]>(rb.velocity.bytes()?).to_vec(),
                bytemuck::cast_slice::<u8, [u32; 2]>(rb.ids.bytes()?).to_vec(),
                None,
                None,
            ))
        };
        Ok(match &self.mode {
            Mode::Native { readbacks: rb, .. } | Mode::Upscale { readbacks: rb, .. } => {
                native_output(rb)?
            }
            Mode::Checkerboard {
                unpack, resolve, ..
            } => {
                let px: &[UnpackedPixel] = bytemuck::cast_slice(unpack.out.bytes()?);
                let mut out = base(
                    px.iter().flat_map(|p| p.color.map(f16::from_f32)).collect(),
                    px.iter()
                        .map(|p| linear(p.velocity_depth_mask[2]))
                        .collect(),
                    px.iter()
                        .map(|p| [p.velocity_depth_mask[0], p.velocity_depth_mask[1]])
                        .collect(),
                    px.iter().map(|p| [p.ids[0], p.ids[1]]).collect(),
                    Some(
                        px.iter()
                            .map(|p| u8::from(p.velocity_depth_mask[3] > 0.5))
                            .collect(),
                    ),
                    Some(parity),
                );
                if let Some(r) = resolve {
                    // The resolved frame replaces the raw colour; depth, velocity, IDs and the
                    // mask stay the raw checkerboard samples (what was rendered this frame).
                    let f32_history = r.pass.settings().f32_history;
                    out.color =
                        r.rb.color_rgb(f32_history)?
                            .iter()
                            .flat_map(|c| [c[0], c[1], c[2], 1.0].map(f16::from_f32))
                            .collect();
                    let debug = r.pass.settings().debug;
                    out.resolve = Some(ResolveOutput {
                        reset,
                        debug_bits: debug
                            .then(|| {
                                r.rb.debug_bits
                                    .bytes()
                                    .map(|b| bytemuck::cast_slice::<u8, u32>(b).to_vec())
                            })
                            .transpose()?,
                        velocity: debug
                            .then(|| {
                                r.rb.debug_velocity
                                    .bytes()
                                    .map(|b| bytemuck::cast_slice::<u8, [f32; 2]>(b).to_vec())
                            })
                            .transpose()?,
                    });
                }
                out
            }
        })
    }
}
