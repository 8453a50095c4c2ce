//! The frame sequencer: one scene, one technique spec, frames rendered and read back in order.
//! It uploads the frame, runs the technique's chain and then the post passes, reads the result
//! back, collects timings and decides history resets. It knows no technique by name: they come
//! from the registries (crate::technique, crate::post) through the spec.

use cbr_gpu::{Buffer, Gpu, GpuError, PassKind, Profiler, Readback, Result};
use cbr_gpu::{Caps, Shaders};
use cbr_scene::Scene;
use half::f16;

use crate::cache::FrameCache;
use crate::frame::FrameOutput;
use crate::gpu_scene::{FrameView, GpuScene, RasterUniforms};
use crate::gpu_types::{FLAG_COUNT_SHADED, FLAG_DEBUG_LOD};
use crate::memory::MemoryEstimate;
use crate::post::{PostBuildCtx, PostFrame, PostPass};
use crate::spec::Spec;
use crate::technique::{BuildCtx, EstimateCtx, FrameCtx, Registration, Technique};

/// How to render.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// The technique and its post chain (crate::spec).
    pub spec: Spec,
    /// Added to every texture lookup's LOD; `None`: the technique's default.
    pub lod_bias: Option<f32>,
    /// With `lod_bias` set: (b, 1 / V), the part of it a moving fragment sheds, all of it at V
    /// pixels per frame ([`FrameView::lod_motion`]); `None`: the bias applies everywhere (tests
    /// render what `+taa` blends in with it).
    pub lod_motion: Option<[f32; 2]>,
    /// With `lod_bias` set: the part of it a turning object's fragments withdraw
    /// ([`FrameView::lod_turn`]); `None`: none (tests).
    pub lod_turn: Option<f32>,
    /// Count shaded (non-helper) fragments with an atomic counter (tests, `--count-shaded`).
    pub count_shaded: bool,
    /// Write each sample's albedo level of detail to colour.r instead of radiance (tests, docs).
    pub debug_lod: bool,
    /// Also build instrumentation passes (the resolve's copy-kernel floor): benchmarks.
    pub instrument: bool,
    /// A sub-pixel offset of the projection, in output pixels (+x right, +y down moves the
    /// geometry): pixel centres then see the scene at centre - jitter. Every technique and layout
    /// applies it (on top of the samples they place themselves); a jittering post pass (`+taa`)
    /// adds its own.
    pub jitter: [f32; 2],
    /// Where frames of cacheable techniques (`ssaa`) are kept between runs; `None`: no cache.
    #[serde(skip)]
    pub cache: Option<std::path::PathBuf>,
}

impl RenderSettings {
    pub fn native(width: u32, height: u32) -> RenderSettings {
        RenderSettings::new(width, height, Spec::of("native"))
    }

    pub fn new(width: u32, height: u32, spec: Spec) -> RenderSettings {
        RenderSettings {
            width,
            height,
            spec,
            lod_bias: None,
            lod_motion: None,
            lod_turn: None,
            count_shaded: false,
            debug_lod: false,
            instrument: false,
            jitter: [0.0; 2],
            cache: None,
        }
    }

    /// Settings for a spec string (checked against the registries).
    pub fn parse(width: u32, height: u32, spec: &str) -> std::result::Result<Self, String> {
        Ok(RenderSettings::new(width, height, Spec::parse(spec)?))
    }
}

/// The registration of `spec`'s technique.
fn registration(spec: &Spec) -> Result<&'static Registration> {
    crate::registry::find(&spec.technique.name).ok_or_else(|| {
        GpuError::Other(
            Spec::parse(&spec.to_string())
                .err()
                .unwrap_or_else(|| format!("no technique `{}`", spec.technique.name)),
        )
    })
}

/// The shaded-fragment and non-finite-fragment counters the scene shaders add to (two words,
/// read by the host after each frame).
fn counter_decl() -> crate::pass::ResourceDecl {
    crate::pass::ResourceDecl::host_buffer("fragment_counters", 8)
}

/// The readback of the post chain's last output.
fn post_readback(w: u32, h: u32) -> crate::pass::ResourceDecl {
    crate::pass::ResourceDecl::readback("post", crate::targets::COLOR_FORMAT, w, h)
}

pub struct Renderer {
    gpu: Gpu,
    scene: GpuScene,
    technique: Box<dyn Technique>,
    post: Vec<Box<dyn PostPass>>,
    /// A post pass reads the technique's geometry.
    geometry: bool,
    /// The post chain's final colour, read back (with post passes only).
    post_rb: Option<Readback>,
    counter: Buffer,
    profiler: Profiler,
    settings: RenderSettings,
    cache: Option<FrameCache>,
    /// The last frame rendered (frames that do not follow it reset histories).
    last_frame: Option<u32>,
    progress: Option<Box<dyn FnMut(u32, u32)>>,
}

impl Renderer {
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Renderer> {
        // Unknown specs, missing device features and memory that cannot fit: refused before
        // anything is allocated.
        Renderer::check(gpu, scene, &settings)?;
        let spec = &settings.spec;
        let reg = registration(spec)?;
        let params = spec.technique.params();
        let gpu_scene = GpuScene::new(gpu, scene)?;
        let counter = counter_decl().make_buffer(gpu, "renderer")?;
        let (w, h) = (settings.width, settings.height);
        let mut post_regs = Vec::new();
        for part in &spec.post {
            let pr = crate::registry::find_post(&part.name)
                .ok_or_else(|| GpuError::Other(format!("no post pass `+{}`", part.name)))?;
            post_regs.push((pr, part));
        }
        let geometry = post_regs.iter().any(|(pr, _)| pr.geometry);
        // The shader modules the technique and its post chain are built from key the frame cache.
        let mark = shaders.request_mark();
        let ctx = BuildCtx {
            gpu,
            shaders,
            scene: &gpu_scene,
            counter: &counter,
            width: w,
            height: h,
            instrument: settings.instrument,
            geometry,
        };
        let technique = (reg.build)(&ctx, &params)?;
        let geometries = match geometry {
            false => Vec::new(),
            true => (0..2)
                .map(|f| technique.geometry(f))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| {
                    let needs: Vec<String> = post_regs
                        .iter()
                        .filter(|(pr, _)| pr.geometry)
                        .map(|(_, part)| format!("`+{part}`"))
                        .collect();
                    GpuError::Other(format!(
                        "`{spec}`: {} needs the frame's geometry (velocity, depth, IDs), and `{}` \
                         gives none",
                        needs.join(", "),
                        spec.technique
                    ))
                })?,
        };
        if !post_regs.is_empty() && (0..2).any(|f| technique.color(f).is_none()) {
            return Err(GpuError::Other(format!(
                "`{spec}`: post passes need a full frame, and `{}` gives none",
                spec.technique
            )));
        }
        let mut post: Vec<Box<dyn PostPass>> = Vec::new();
        for (pr, part) in &post_regs {
            let pctx = PostBuildCtx {
                gpu,
                shaders,
                width: w,
                height: h,
                exposure_stops: scene.settings.exposure,
                geometry: &geometries,
            };
            let p = (pr.build)(&pctx, &part.params()).map_err(|e| match e {
                e @ GpuError::Config { .. } => e,
                e => GpuError::Other(format!("`+{part}`: {e}")),
            })?;
            post.push(p);
        }
        // At most one pass jitters the frame: name them.
        let mut jittering: Vec<String> = post
            .iter()
            .zip(&post_regs)
            .filter(|(p, _)| p.jitter(0).is_some())
            .map(|(_, (_, part))| format!("`+{part}`"))
            .collect();
        if technique.jitters() {
            jittering.insert(0, format!("`{}`", spec.technique));
        }
        if jittering.len() > 1 {
            return Err(GpuError::Other(format!(
                "`{spec}`: more than one pass jitters the frame ({}); keep one of them (a \
                 technique that jitters its own frames, like checkerboard `fused`, takes no +taa)",
                jittering.join(", ")
            )));
        }
        drop(geometries);
        let post_rb = match post.last() {
            Some(_) => Some(post_readback(w, h).make_readback(gpu, "readback")?),
            None => None,
        };
        let cache = match (&settings.cache, technique.cacheable()) {
            (Some(dir), true) => {
                let modules = shaders.requests_since(mark);
                Some(FrameCache::new(
                    dir, gpu, shaders, scene, &settings, &modules,
                )?)
            }
            _ => None,
        };
        // Timed passes per frame: interleaved:MxN:seed:floor has the most (12).
        let profiler = Profiler::new(gpu, "renderer.profiler", 16)?;
        Ok(Renderer {
            gpu: gpu.clone(),
            scene: gpu_scene,
            technique,
            post,
            geometry,
            post_rb,
            counter,
            profiler,
            settings,
            cache,
            last_frame: None,
            progress: None,
        })
    }

    /// The GPU memory a renderer of `settings` for `scene` allocates on a device with `caps`
    /// (crate::memory): the technique's and each post pass's estimates, the renderer's own
    /// buffers (the shaded-fragment counter, the post chain's readback) and the scene's. `Err`:
    /// a spec the registries do not know, or the technique's own refusal of the size (`analytic`'s
    /// fragment lists).
    pub fn estimate(
        caps: &Caps,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> std::result::Result<MemoryEstimate, String> {
        let spec = &settings.spec;
        let reg = registration(spec).map_err(|e| e.to_string())?;
        let ctx = EstimateCtx {
            caps,
            width: settings.width,
            height: settings.height,
            instrument: settings.instrument,
        };
        let mut e = (reg.estimate)(&ctx, &spec.technique.params())?;
        for part in &spec.post {
            let pr = crate::registry::find_post(&part.name)
                .ok_or_else(|| format!("no post pass `+{}`", part.name))?;
            e.append((pr.estimate)(&ctx, &part.params()));
        }
        e.append(crate::pass::estimate(&[counter_decl()], "renderer"));
        if !spec.post.is_empty() {
            let (w, h) = (settings.width, settings.height);
            e.append(crate::pass::estimate(&[post_readback(w, h)], "readback"));
        }
        e.append(GpuScene::estimate(scene));
        Ok(e)
    }

    /// What [`Renderer::new`] refuses before it allocates anything: a device that cannot execute
    /// (RADV's null device), an unknown spec, parameters the technique does not read, a device
    /// feature it lacks, and memory the device cannot hold (crate::memory::check: the estimate, its largest allocation and the device's
    /// limits in one message). `cbr bench` calls it for every configuration before it renders.
    pub fn check(gpu: &Gpu, scene: &Scene, settings: &RenderSettings) -> Result<MemoryEstimate> {
        let spec = &settings.spec;
        gpu.require_execution(&format!("rendering `{spec}`"))?;
        let reg = registration(spec)?;
        let params = spec.technique.params();
        (reg.check)(&params).map_err(|message| GpuError::Config {
            spec: spec.to_string(),
            message,
        })?;
        if let Some(feature) = (reg.needs)(&params, gpu.caps()) {
            return Err(GpuError::Unsupported {
                device: gpu.info().name.clone(),
                feature: format!("`{}` ({feature})", spec.technique),
            });
        }
        let estimate = Renderer::estimate(gpu.caps(), scene, settings).map_err(GpuError::Other)?;
        crate::memory::check(
            &spec.to_string(),
            settings.width,
            settings.height,
            &estimate,
            gpu.caps(),
            &gpu.info().name,
        )
        .map_err(GpuError::Other)?;
        Ok(estimate)
    }

    /// Called with (samples done, samples total) while a frame of a many-pass technique renders.
    pub fn set_progress(&mut self, f: impl FnMut(u32, u32) + 'static) {
        self.progress = Some(Box::new(f));
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The texture LOD bias in effect: the setting, else the technique's matching bias plus the
    /// post passes' (TAA's sharper inputs).
    pub fn lod_bias(&self) -> f32 {
        self.settings.lod_bias.unwrap_or_else(|| {
            self.technique.default_lod_bias() + self.post.iter().map(|p| p.lod_bias()).sum::<f32>()
        })
    }

    /// The part of the LOD bias a moving fragment sheds, and 1 / the speed (pixels per frame) at
    /// which it is all shed ([`FrameView::lod_motion`]): a post pass's (TAA), unless the setting
    /// `--lod-bias` fixes the bias.
    pub fn lod_motion(&self) -> [f32; 2] {
        if self.settings.lod_bias.is_some() {
            return self.settings.lod_motion.unwrap_or([0.0; 2]);
        }
        self.post
            .iter()
            .find_map(|p| {
                let v = p.lod_speed();
                (v > 0.0).then(|| [p.lod_shed(), 1.0 / v])
            })
            .unwrap_or([0.0; 2])
    }

    /// The LOD bias a turning object's fragments withdraw ([`FrameView::lod_turn`]): the
    /// temporal part of the bias (the technique's own, `taau`'s, and the post passes', TAA's;
    /// a centred frame takes no post pass's bias); with `--lod-bias`, the `lod_turn` setting's
    /// (none from the command line).
    pub fn lod_turn(&self, centred: bool) -> f32 {
        if self.settings.lod_bias.is_some() {
            return self.settings.lod_turn.unwrap_or(0.0);
        }
        let post: f32 = match centred {
            true => 0.0,
            false => self.post.iter().map(|p| p.lod_turn()).sum(),
        };
        self.technique.temporal_lod_bias() + post
    }

    /// Whether the objects' turns reach the scene pass ([`FrameView::turns`]): the technique or
    /// (but in a centred frame) a post pass applies a reactive rule; with `--lod-bias`, whether
    /// the `lod_turn` setting is given (tests).
    pub fn turns(&self, centred: bool) -> bool {
        if self.settings.lod_bias.is_some() {
            return self.settings.lod_turn.is_some();
        }
        self.technique.reactive() || (!centred && self.post.iter().any(|p| p.reactive()))
    }

    /// Bytes of the raster targets (what a technique costs in memory).
    pub fn target_bytes(&self) -> u64 {
        self.technique.target_bytes()
    }

    /// The cache folder frames are read from and written to, when caching.
    pub fn cache_dir(&self) -> Option<&std::path::Path> {
        self.cache.as_ref().map(FrameCache::dir)
    }

    /// Forgets every history: the next frame renders without it (a camera cut).
    pub fn reset_history(&mut self) {
        self.last_frame = None;
    }

    /// The frame's sub-pixel jitter: the setting plus the jittering post pass's (TAA).
    fn jitter(&self, frame: u32) -> [f32; 2] {
        let j = self.settings.jitter;
        match self.post.iter().find_map(|p| p.jitter(frame)) {
            Some(p) => [j[0] + p[0], j[1] + p[1]],
            None => j,
        }
    }

    /// Whether frame `frame` renders centred: it has no history (`reset`) and the jittering
    /// post pass asks for its resets unjittered ([`PostPass::centred_at_reset`]).
    fn centred(&self, reset: bool) -> bool {
        reset
            && self
                .post
                .iter()
                .any(|p| p.jitter(0).is_some() && p.centred_at_reset())
    }

    fn view(&self, scene: &Scene, frame: u32, centred: bool) -> FrameView {
        let time = scene.time_of_frame(frame);
        let s = &self.settings;
        // A centred frame takes neither the post pass's jitter nor its LOD bias (the setting
        // `--lod-bias`, with its motion setting, still holds).
        let (jitter, lod_bias, lod_motion) = match centred {
            true => (
                s.jitter,
                s.lod_bias
                    .unwrap_or_else(|| self.technique.default_lod_bias()),
                match s.lod_bias {
                    Some(_) => s.lod_motion.unwrap_or([0.0; 2]),
                    None => [0.0; 2],
                },
            ),
            false => (self.jitter(frame), self.lod_bias(), self.lod_motion()),
        };
        let mut flags = if s.count_shaded { FLAG_COUNT_SHADED } else { 0 };
        if s.debug_lod {
            flags |= FLAG_DEBUG_LOD;
        }
        FrameView {
            camera: scene.camera.at(time),
            prev_camera: scene.camera.at(time - 1.0 / scene.settings.fps),
            time,
            prev_time: time - 1.0 / scene.settings.fps,
            width: s.width,
            height: s.height,
            aspect: f64::from(s.width) / f64::from(s.height),
            lod_bias,
            lod_motion,
            lod_turn: self.lod_turn(centred),
            turns: self.turns(centred),
            frame_index: frame,
            screen_jitter: jitter,
            raster: RasterUniforms {
                viewport: (s.width as f32, s.height as f32),
                jitter: [[0.0; 2]; 2],
                flags,
                ..Default::default()
            },
        }
    }

    /// Renders frame `frame` of `scene` (the scene this renderer was built for) and reads it back.
    /// Histories (resolves, post passes) continue from frame f - 1 when that was the last frame
    /// rendered and no camera cut lies between the two, and reset otherwise.
    pub fn render(&mut self, scene: &Scene, frame: u32) -> Result<FrameOutput> {
        let time = scene.time_of_frame(frame);
        let reset = frame == 0
            || self.last_frame != Some(frame - 1)
            || scene
                .camera
                .cut_between(time - 1.0 / scene.settings.fps, time);
        let view = self.view(scene, frame, self.centred(reset));
        let key = self.cache.as_ref().map(|c| c.key(&view, frame));
        if let (Some(c), Some(k)) = (&self.cache, &key)
            && let Some(out) = c.load(k, frame, view.time)
        {
            self.last_frame = Some(frame);
            return Ok(out);
        }
        self.counter.write(0, &[0u8; 8])?;
        let mut progress = self.progress.take();
        let mut ctx = FrameCtx {
            gpu: &self.gpu,
            scene,
            gpu_scene: &mut self.scene,
            profiler: &mut self.profiler,
            counter: &self.counter,
            frame,
            reset,
            view,
            timings: Vec::new(),
            progress: progress
                .as_mut()
                .map(|p| p.as_mut() as &mut dyn FnMut(u32, u32)),
        };
        let rendered = self.technique.render(&mut ctx);
        let rendered = rendered.and_then(|()| {
            if self.post.is_empty() {
                return Ok(());
            }
            let turns = crate::gpu_scene::object_turns(scene, ctx.view.time, ctx.view.prev_time);
            let pf = PostFrame {
                frame,
                reset,
                turns: &turns,
                jitter: ctx.view.screen_jitter,
                geometry: match self.geometry {
                    true => self.technique.geometry(frame),
                    false => None,
                },
            };
            let (post, rb, technique) = (&mut self.post, &self.post_rb, &self.technique);
            ctx.submit("post", |cmd, profiler, _| {
                let mut input = technique.color(frame);
                for p in post.iter_mut() {
                    if let Some(i) = input {
                        p.record(cmd, profiler, &pf, i)?;
                    }
                    input = Some(p.output(frame)?);
                }
                if let (Some(last), Some(rb)) = (post.last(), rb) {
                    let scope = profiler.begin(cmd, "readback.post", PassKind::Transfer);
                    cmd.read_image(last.output(frame)?, rb);
                    profiler.end(cmd, scope);
                }
                Ok(())
            })
        });
        let out = rendered.and_then(|()| self.technique.output(&ctx));
        let timings = std::mem::take(&mut ctx.timings);
        drop(ctx);
        self.progress = progress;
        let mut out = out?;
        self.last_frame = Some(frame);
        out.index = frame;
        out.time = scene.time_of_frame(frame);
        out.timings = timings;
        if let Some(rb) = &self.post_rb {
            out.color = bytemuck::cast_slice::<u8, f16>(rb.bytes()?).to_vec();
        }
        let b = self.counter.bytes()?;
        if self.settings.count_shaded {
            out.shaded_fragments = Some(u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])));
        }
        out.nonfinite_fragments = Some(u64::from(u32::from_le_bytes([b[4], b[5], b[6], b[7]])));
        if let (Some(c), Some(k)) = (&self.cache, &key) {
            out.cached = c.store(k, &out);
        }
        Ok(out)
    }
}
