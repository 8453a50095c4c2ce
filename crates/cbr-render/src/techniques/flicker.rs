//! `flicker`: native's frame, plus each pixel's luminance mean and variance over the frames since
//! the history was last reset (Welford's running algorithm, shaders/flicker/welford.comp): where
//! a still camera sees the image shimmer (texture aliasing, specular sparkle, a resolve that
//! does not settle). The worked example of docs/OVERVIEW.md: a technique with two layers of its
//! own and a ping-pong history is this file, its shader folder and its name in the
//! `techniques!` list.
//!
//! Statistics restart with the history (the first frame, a frame that does not follow the last
//! one rendered, a camera cut: [`FrameCtx::reset`]); a camera that moves makes them a measure of
//! the motion, not of flicker. Luminance: Rec. 709 weights of the linear colour.

use cbr_gpu::{Image, Readback, Result, vk};

use super::{LayerReadbacks, no_params};
use crate::frame::{ExrType, FrameOutput, LayerDecl, SampleType, Stat, StatDecl};
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, History, ResourceDecl, Resources, Use};
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::targets::FrameTargets;
use crate::technique::{BuildCtx, FrameCtx, Geometry, Outputs, PassList, Registration, Technique};

/// The running mean of each pixel's luminance.
pub const MEAN: LayerDecl = LayerDecl {
    name: "flicker_mean",
    channels: &["Y"],
    samples: SampleType::F32,
    exr: Some(ExrType::Float),
    about: "each pixel's mean luminance over the frames since the last reset",
};

/// The population variance of each pixel's luminance over the same frames (0 after one frame).
pub const VARIANCE: LayerDecl = LayerDecl {
    name: "flicker_variance",
    channels: &["Y"],
    samples: SampleType::F32,
    exr: Some(ExrType::Float),
    about: "each pixel's luminance variance over the frames since the last reset",
};

/// Frames the statistics hold (1 on a reset frame).
pub const FRAMES: StatDecl = StatDecl {
    name: "flicker.frames",
    about: "frames the statistics hold, this one included",
};

pub const REGISTRATION: Registration = Registration {
    name: "flicker",
    grammar: "flicker",
    about: "native, plus each pixel's luminance mean and variance since the last reset \
            (where a still camera sees shimmer)",
    outputs: Outputs {
        layers: &[MEAN, VARIANCE],
        stats: &[FRAMES],
        pngs: None,
        settings: None,
    },
    check: |p| no_params("flicker", p),
    needs: |_, _| None,
    estimate: |ctx, _| Ok(Flicker::estimate(ctx.width, ctx.height)),
    passes: |ctx, _| {
        Ok(PassList {
            compute: vec![decl()],
            graphics: crate::scene_pass::listed(
                "flicker.raster",
                &RasterConfig::native(ctx.width, ctx.height),
                ctx.materials,
            )?,
            packed_geometry: false,
        })
    },
    build: |ctx, _| Ok(Box::new(Flicker::new(ctx)?)),
};

crate::push_constants! {
    struct Push {
        size: [i32; 2],
        /// 1: the history restarts this frame.
        reset: u32,
    }
}

/// The Welford step: this frame's colour in, last frame's statistics in, this frame's out.
pub fn decl() -> ComputeDecl {
    ComputeDecl::new("flicker.welford", "flicker/welford.comp")
        .bindings(&[
            Binding::sampled("color"),
            Binding::image("hist", Use::Read),
            Binding::image("out_hist", Use::Write),
        ])
        .push::<Push>()
}

/// The statistics history (frames, mean, M2: f32 RGBA, ping-pong) and its readback.
fn resources(w: u32, h: u32) -> [ResourceDecl; 2] {
    let format = vk::Format::R32G32B32A32_SFLOAT;
    [
        ResourceDecl::image("hist", format, w, h).history(),
        ResourceDecl::readback("flicker.hist", format, w, h),
    ]
}

pub struct Flicker {
    pass: ScenePass,
    config: RasterConfig,
    targets: FrameTargets,
    readbacks: LayerReadbacks,
    welford: ComputePass,
    res: Resources,
    hist_rb: Readback,
    size: (u32, u32),
}

impl Flicker {
    /// What [`Flicker::new`] allocates: native's targets and readbacks, the history and its
    /// readback.
    pub fn estimate(w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        FrameTargets::estimate(&mut e, "flicker", w, h, 1, 1);
        LayerReadbacks::estimate(&mut e, w, h);
        let [hist, rb] = resources(w, h);
        e.append(crate::pass::estimate(&[hist], "flicker"));
        e.append(crate::pass::estimate(&[rb], "readback"));
        e
    }

    pub fn new(ctx: &BuildCtx) -> Result<Flicker> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let config = RasterConfig::native(w, h);
        let pass = ScenePass::new(
            gpu,
            ctx.shaders,
            ctx.scene,
            "flicker.raster",
            &config,
            ctx.counter,
        )?;
        let targets = FrameTargets::new(gpu, "flicker", w, h)?;
        let readbacks = LayerReadbacks::new(gpu, targets.layers())?;
        let [hist, rb] = resources(w, h);
        Ok(Flicker {
            pass,
            config,
            readbacks,
            welford: decl().build(gpu, ctx.shaders)?,
            res: Resources::new(gpu, "flicker", &[hist])?,
            hist_rb: rb.make_readback(gpu, "readback")?,
            targets,
            size: (w, h),
        })
    }

    fn history(&self) -> Result<&History<Image>> {
        self.res.history("hist")
    }
}

impl Technique for Flicker {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let (frame, counter) = (ctx.frame, ctx.counter);
        let push = Push {
            size: [view.width as i32, view.height as i32],
            reset: u32::from(ctx.reset),
        };
        let this = &*self;
        let hist = this.history()?;
        ctx.submit("frame", |cmd, profiler, scene| {
            let t = &this.targets;
            this.pass
                .record_targets(cmd, profiler, scene, t, counter, &this.config)?;
            let binds = Binds::new()
                .image("color", &t.color)
                .history(hist, frame, "hist", "out_hist");
            this.welford
                .dispatch_2d(cmd, profiler, &binds, &push, (view.width, view.height))?;
            this.readbacks.record(cmd, profiler, t.layers());
            cmd.read_image(hist.write(frame), &this.hist_rb);
            cmd.use_buffer(counter, cbr_gpu::Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.targets.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(self.targets.geometry())
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let (w, h) = (ctx.view.width, ctx.view.height);
        let mut out = self.readbacks.output(w, h, ctx.view.camera.near)?;
        let texels: &[[f32; 4]] = bytemuck::cast_slice(self.hist_rb.bytes()?);
        let mean = texels.iter().map(|t| t[1]).collect();
        let variance = texels.iter().map(|t| variance(*t)).collect();
        out.layers.push(MEAN.layer(w, h, vec![mean])?);
        out.layers.push(VARIANCE.layer(w, h, vec![variance])?);
        let frames = texels.first().map_or(0.0, |t| t[0]);
        out.stats
            .insert(FRAMES.name.to_string(), Stat::Count(frames as u64));
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let [hist, _] = resources(self.size.0, self.size.1);
        self.targets.bytes() + crate::pass::estimate(&[hist], "flicker").total()
    }
}

/// The population variance of a history texel (frames, mean, M2); 0 before any frame.
fn variance(t: [f32; 4]) -> f32 {
    if t[0] > 0.0 { t[2] / t[0] } else { 0.0 }
}

/// The CPU reference: Welford's step on f32, as the shader takes it.
pub fn welford(state: [f32; 4], y: f32) -> [f32; 4] {
    if !y.is_finite() {
        return state;
    }
    let n = state[0] + 1.0;
    let d = y - state[1];
    let mean = state[1] + d / n;
    [n, mean, state[2] + d * (y - mean), 0.0]
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Welford's running statistics equal the two-pass mean and variance of the same values.
    #[test]
    fn welford_matches_the_two_pass_statistics() {
        let ys = [0.25f32, 1.5, 0.75, 3.0, 0.0, 2.25];
        let s = ys.iter().fold([0.0; 4], |s, &y| welford(s, y));
        let n = ys.len() as f64;
        let mean = ys.iter().map(|&y| f64::from(y)).sum::<f64>() / n;
        let var = ys.iter().map(|&y| (f64::from(y) - mean).powi(2)).sum::<f64>() / n;
        assert_eq!(s[0], 6.0);
        assert!((f64::from(s[1]) - mean).abs() < 1e-6, "{} vs {mean}", s[1]);
        assert!((f64::from(variance(s)) - var).abs() < 1e-5, "{} vs {var}", variance(s));
        // A value that is not finite leaves the statistics as they were.
        assert_eq!(welford(s, f32::NAN), s);
        assert_eq!(welford(s, f32::INFINITY), s);
    }

    /// The GPU's statistics over frames of the moving demo equal the CPU reference's over the
    /// same frames' colour, and restart when the history does (a frame that does not follow).
    #[test]
    fn the_layers_are_welford_over_the_frames_colour() {
        let gpu = cbr_gpu::Gpu::new(&cbr_gpu::GpuOptions {
            device: std::env::var("CBR_TEST_DEVICE").ok(),
            validation: true,
        })
        .expect("a Vulkan device with validation layers");
        let shaders = crate::shader_library();
        let mut scene = cbr_scene::builtin("demo").expect("demo");
        (scene.settings.width, scene.settings.height) = (48, 32);
        let settings = crate::RenderSettings::parse(48, 32, "flicker").expect("spec");
        let mut r = crate::Renderer::new(&gpu, &shaders, &scene, settings).expect("renderer");
        let mut state = vec![[0.0f32; 4]; 48 * 32];
        // Frames 0..4, then 9 (not following 3: the history restarts).
        for f in [0u32, 1, 2, 3, 9] {
            let out = r.render(&scene, f).expect("frame");
            if f == 9 {
                state.fill([0.0; 4]);
            }
            for (i, s) in state.iter_mut().enumerate() {
                let c = &out.color[4 * i..4 * i + 3];
                *s = welford(*s, luminance([c[0].into(), c[1].into(), c[2].into()]));
            }
            let mean = out.channel::<f32>("flicker_mean", "Y").expect("mean");
            let var = out.channel::<f32>("flicker_variance", "Y").expect("variance");
            for (i, s) in state.iter().enumerate() {
                let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * b.abs().max(1.0);
                assert!(close(mean[i], s[1]), "frame {f} pixel {i}: mean {} vs {}", mean[i], s[1]);
                assert!(
                    close(var[i], variance(*s)),
                    "frame {f} pixel {i}: variance {} vs {}",
                    var[i],
                    variance(*s)
                );
            }
            let frames = if f == 9 { 1 } else { u64::from(f) + 1 };
            assert_eq!(out.count("flicker.frames"), Some(frames), "frame {f}");
        }
        let msgs = gpu.validation().messages();
        assert!(msgs.is_empty(), "validation: {}", msgs.join("\n"));
    }
}
