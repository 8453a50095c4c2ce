//! `+taa` on lavapipe with validation on: the shader against its CPU reference on a moving
//! camera (ours, INSIDE, ablations); the known answer (clipping off, weight 1 / (n + 1): a
//! static scene's frame n is the mean of the n + 1 jittered native frames); convergence with
//! clipping on; NaN/Inf never entering the history; camera cuts resetting it; the chain on every
//! technique with a full frame.

mod common;

use cbr_render::post::taa::{self, RefInputs, TaaConfig};
use cbr_render::{FrameOutput, RenderSettings, Renderer};
use cbr_scene::Scene;
use common::{assert_clean, demo, gpu, render_settings as render, static_demo};

fn spec(w: u32, h: u32, s: &str) -> RenderSettings {
    RenderSettings::parse(w, h, s).expect("spec")
}

fn rgb(o: &FrameOutput) -> Vec<[f32; 3]> {
    o.color
        .chunks(4)
        .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32()])
        .collect()
}

/// Mean over pixels and channels of |a - b|.
fn mean_abs(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).abs()).sum::<f32>() / 3.0)
        .sum::<f32>()
        / a.len() as f32
}

/// The native frames 1..=8 of a static scene rendered with TAA's jitters and LOD bias (the 8
/// phases of its cycle: frame 0 renders centred), and their per-pixel mean (8 samples per pixel).
fn jittered_cycle(
    gpu: &cbr_gpu::Gpu,
    s: &Scene,
    w: u32,
    h: u32,
) -> (Vec<Vec<[f32; 3]>>, Vec<[f32; 3]>) {
    let natives: Vec<Vec<[f32; 3]>> = (1..=8)
        .map(|f| rgb(&jittered_native(gpu, s, w, h, 8, f)))
        .collect();
    let mean = (0..(w * h) as usize)
        .map(|i| [0, 1, 2].map(|c| natives.iter().map(|f| f[i][c]).sum::<f32>() / 8.0))
        .collect();
    (natives, mean)
}

/// Native frame `f` rendered with TAA's jitter for it (what `native+taa` blends in).
fn jittered_native(gpu: &cbr_gpu::Gpu, s: &Scene, w: u32, h: u32, len: u32, f: u32) -> FrameOutput {
    let c = TaaConfig {
        length: len,
        ..TaaConfig::OURS
    };
    jittered_native_for(gpu, s, w, h, &c, f)
}

/// The same for configuration `c`: its jitter, its LOD bias, withdrawn from moving fragments up
/// to its speed with `motionlod`, and its moving fragments shaded at the pixel centre with
/// `unjitter` (or `motionlod`).
fn jittered_native_for(
    gpu: &cbr_gpu::Gpu,
    s: &Scene,
    w: u32,
    h: u32,
    c: &TaaConfig,
    f: u32,
) -> FrameOutput {
    let motion = c.unjitter && c.unjitter_speed() > 0.0;
    let shed = if c.motion_lod { c.lod_bias } else { 0.0 };
    let settings = RenderSettings {
        jitter: taa::jitter(c.length, f),
        lod_bias: Some(c.lod_bias),
        lod_motion: motion.then(|| [shed, 1.0 / c.unjitter_speed()]),
        lod_turn: c.reactive.then_some(c.lod_bias),
        ..spec(w, h, "native")
    };
    render(gpu, s, settings, &[f]).remove(0)
}

/// The frame `+taa` with configuration `c` renders at frame `f`, the first of its run when
/// `first`: with no history to blend (a reset) ours renders it centred, as `native` does
/// (`centred_reset`); every other frame is jittered ([`jittered_native_for`]).
fn taa_input(
    gpu: &cbr_gpu::Gpu,
    s: &Scene,
    (w, h): (u32, u32),
    c: &TaaConfig,
    f: u32,
    first: bool,
) -> FrameOutput {
    match first && c.centred_reset {
        true => render(gpu, s, spec(w, h, "native"), &[f]).remove(0),
        false => jittered_native_for(gpu, s, w, h, c, f),
    }
}

/// The shader against the CPU reference, frame by frame: each frame's reference takes the GPU's
/// previous output as its history, so differences do not compound. The history is fetched
/// through the hardware bilinear filter (Catmull-Rom's five taps, INSIDE's one; Lanczos-3's
/// 36 texels are read as they are), whose weights
/// lavapipe quantises to 8 bits (subTexelPrecisionBits): the bound is f16 rounding plus 2^-8
/// of the local history range; and the depth test, done on reverse-Z on the GPU and on linear
/// depth here, may decide a pixel at its tolerance differently: at most 0.3% of pixels.
#[test]
fn the_shader_matches_its_cpu_reference_on_a_moving_camera() {
    let gpu = gpu();
    let (w, h) = (64u32, 36u32);
    let frames: Vec<u32> = (4..10).collect();
    let params = [
        "",
        "inside",
        "without-catmull:without-dilation",
        "without-lanczos",
        "sharp=1",
        "gamma=1.5:alpha=0.2:filter",
        "without-count:without-luma",
        "adaptive",
        "motionlod",
        "motionlod:speed=0.05:uspeed=0.05:ispeed=0.05",
        "unjitter:speed=0.05:uspeed=0.05",
        "interior:speed=0.05:uspeed=0.05:ispeed=0.05",
        "without-locks",
        "without-surface-velocity",
        "motionlod:uspeed=0.1:ispeed=0.1",
    ];
    shader_matches_reference(&gpu, &demo(w, h), &frames, &params);
    assert_clean(&gpu);
}

/// The same with the camera held and the spinner turning: still pixels go through their jitter
/// cycles (complete at frames 11, 19 and 27 with 8 phases, 19 with 16), the spinner's
/// pixels move, and the floor under its shadow and reflections changes (the cycle's range test).
#[test]
fn the_shader_matches_its_cpu_reference_with_the_camera_held() {
    let gpu = gpu();
    let (w, h) = (64u32, 36u32);
    let mut s = demo(w, h);
    s.camera.keys.truncate(1);
    let frames: Vec<u32> = (4..30).collect();
    shader_matches_reference(&gpu, &s, &frames, &["", "16:ctol=0.002", "without-cycle"]);
    assert_clean(&gpu);
}

fn shader_matches_reference(gpu: &cbr_gpu::Gpu, s: &Scene, frames: &[u32], params: &[&str]) {
    let (w, h) = (s.settings.width, s.settings.height);
    for &params in params {
        let taa_spec = if params.is_empty() {
            "native+taa".to_string()
        } else {
            format!("native+taa:{params}")
        };
        let p: Vec<&str> = params.split(':').filter(|p| !p.is_empty()).collect();
        let c = TaaConfig::parse(&p).expect("config");
        let outs = render(gpu, s, spec(w, h, &taa_spec), frames);
        let mut worst = (0.0f32, 0usize);
        let natives: Vec<FrameOutput> = frames
            .iter()
            .enumerate()
            .map(|(k, &f)| taa_input(gpu, s, (w, h), &c, f, k == 0))
            .collect();
        let inputs: Vec<(Vec<[f32; 3]>, Vec<u32>)> = natives
            .iter()
            .map(|n| (rgb(n), n.ids.iter().map(|i| i[0]).collect()))
            .collect();
        let turns: Vec<Vec<f32>> = frames
            .iter()
            .map(|&f| {
                let t = s.time_of_frame(f);
                cbr_render::gpu_scene::object_turns(s, t, t - 1.0 / s.settings.fps)
            })
            .collect();
        let input = |k: usize| RefInputs {
            width: w as usize,
            height: h as usize,
            color: &inputs[k].0,
            velocity: &natives[k].velocity,
            depth: &natives[k].depth,
            ids: &inputs[k].1,
            history: None,
            n: k as u32,
            exposure_scale: s.settings.exposure.exp2(),
            jitter: match k == 0 && c.centred_reset {
                true => [0.0; 2],
                false => taa::jitter(c.length, frames[k]),
            },
            cycle: None,
            turns: Some(&turns[k]),
        };
        // The history geometry the GPU wrote last frame: the first frame is a reset (it depends
        // on no history); after it, the reference's own (it carries the per-pixel frame count).
        let (_, mut hgeom, mut cycle) = taa::reference_cycle(&c, &input(0));
        for k in 1..outs.len() {
            let f = frames[k];
            let hist = rgb(&outs[k - 1]);
            let (want, next, next_cycle) = taa::reference_cycle(
                &c,
                &RefInputs {
                    history: Some((&hist, &hgeom)),
                    cycle: Some(&cycle),
                    ..input(k)
                },
            );
            hgeom = next;
            cycle = next_cycle;
            let got = rgb(&outs[k]);
            let mut bad = 0;
            for (i, (g, r)) in got.iter().zip(&want).enumerate() {
                // The history's range around the pixel: what filter precision can move.
                let (x, y) = ((i % w as usize) as i32, (i / w as usize) as i32);
                let mut range = 0.0f32;
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        let q = ((y + dy).clamp(0, h as i32 - 1) * w as i32
                            + (x + dx).clamp(0, w as i32 - 1))
                            as usize;
                        for ch in 0..3 {
                            range = range.max((hist[q][ch] - r[ch]).abs());
                        }
                    }
                }
                let err = (0..3).map(|ch| (g[ch] - r[ch]).abs()).fold(0.0, f32::max);
                let bound =
                    2e-3 * r.iter().fold(0.0f32, |a, v| a.max(v.abs())) + range / 128.0 + 1e-4;
                if err > bound {
                    bad += 1;
                }
                if err / bound > worst.0 {
                    worst = (err / bound, i);
                }
            }
            assert!(
                bad * 1000 <= 3 * got.len(),
                "{taa_spec} frame {f}: {bad} of {} pixels off the reference (worst {:.2}x the bound at {})",
                got.len(),
                worst.0,
                worst.1
            );
        }
        eprintln!("{taa_spec}: worst {:.3}x the bound", worst.0);
    }
}

/// Clipping off, weight 1 / (n + 1): frame n of a static scene is the mean of the n + 1 native
/// frames rendered as `+taa` renders frames 0..=n (frame 0 centred, the reset, the others with
/// their jitters; within f16: each frame's output is rounded to f16 before it is the next
/// frame's history).
#[test]
fn without_clipping_the_mean_weight_gives_the_mean_of_the_jittered_frames() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let frames: Vec<u32> = (0..8).collect();
    let outs = render(
        &gpu,
        &s,
        spec(w, h, "native+taa:mean:without-clip"),
        &frames,
    );
    let c = TaaConfig::parse(&["mean", "without-clip"]).expect("config");
    let natives: Vec<Vec<[f32; 3]>> = frames
        .iter()
        .map(|&f| rgb(&taa_input(&gpu, &s, (w, h), &c, f, f == 0)))
        .collect();
    for n in [0usize, 3, 7] {
        let got = rgb(&outs[n]);
        let mut worst = 0.0f32;
        for (i, g) in got.iter().enumerate() {
            for c in 0..3 {
                let mean = natives[..=n].iter().map(|f| f[i][c]).sum::<f32>() / (n + 1) as f32;
                // n + 1 roundings to f16 (relative 2^-11 each) of values up to the largest sample.
                let scale = natives[..=n]
                    .iter()
                    .map(|f| f[i][c].abs())
                    .fold(0.0, f32::max);
                let err = (g[c] - mean).abs() / (scale * (n as f32 + 1.0) * 2f32.powi(-11) + 1e-6);
                worst = worst.max(err);
            }
        }
        assert!(
            worst <= 1.0,
            "frame {n}: {worst:.2}x the f16 bound off the mean"
        );
        // The jitter matters: frame n differs from frame 0 on edges.
        if n > 0 {
            let diff = got.iter().zip(&natives[0]).filter(|(a, b)| a != b).count();
            assert!(diff > 0, "frame {n} equals the unjittered first frame");
        }
    }
    assert_clean(&gpu);
}

/// With clipping on, a static scene converges: over the last Halton cycle (frames 24-31) the
/// output changes from frame to frame by a small fraction of what the jittered native frames
/// change (the residual the variance box lets through), and it is nearer the mean of a cycle of
/// jittered frames (8 samples per pixel) than a single native frame is.
#[test]
fn with_clipping_a_static_scene_converges() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let frames: Vec<u32> = (0..32).collect();
    let outs: Vec<Vec<[f32; 3]>> = render(&gpu, &s, spec(w, h, "native+taa"), &frames)
        .iter()
        .map(rgb)
        .collect();
    let (natives, mean) = jittered_cycle(&gpu, &s, w, h);
    let taa_change = (24..32)
        .map(|f| mean_abs(&outs[f], &outs[f - 1]))
        .sum::<f32>()
        / 8.0;
    let native_change = (1..8)
        .map(|f| mean_abs(&natives[f], &natives[f - 1]))
        .sum::<f32>()
        / 7.0;
    let taa_off = mean_abs(&outs[31], &mean);
    let native_off = natives.iter().map(|n| mean_abs(n, &mean)).sum::<f32>() / 8.0;
    eprintln!(
        "frame-to-frame change: taa {taa_change:.5}, jittered native {native_change:.5}; \
         distance to the 8-sample mean: taa {taa_off:.5}, native {native_off:.5}"
    );
    assert!(
        taa_change < 0.25 * native_change,
        "residual change {taa_change} vs native's {native_change}"
    );
    assert!(
        taa_off < 0.75 * native_off,
        "no nearer the supersampled mean than one frame: {taa_off} vs {native_off}"
    );
    assert_clean(&gpu);
}

/// The jitter cycle (`+taa`'s default): on a static scene every pixel is still, so frame 8 (the
/// first complete cycle of 8 phases, frames 1-8: frame 0, the reset, renders centred and is no
/// phase of it) is the mean of the 8 jittered native frames, within one f16 rounding of the
/// output and the f32 running mean's, and every later frame is frame 8 bit for bit: a converged
/// still pixel does not flicker at all. `without-cycle` keeps moving by its weight 0.1 times
/// each new sample's distance from the mean.
#[test]
fn a_still_pixel_shows_the_mean_of_its_last_jitter_cycle() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let frames: Vec<u32> = (0..20).collect();
    let outs = render(&gpu, &s, spec(w, h, "native+taa"), &frames);
    let (_, mean) = jittered_cycle(&gpu, &s, w, h);
    let got = rgb(&outs[8]);
    let mut worst = 0.0f32;
    for (g, m) in got.iter().zip(&mean) {
        for c in 0..3 {
            worst = worst.max((g[c] - m[c]).abs() / (m[c].abs() * 2f32.powi(-10) + 1e-6));
        }
    }
    assert!(
        worst <= 1.0,
        "frame 8: {worst:.2}x one f16 step off the 8-frame mean"
    );
    for f in 9..20 {
        let same = outs[f].color == outs[8].color;
        assert!(same, "frame {f} differs from frame 8");
    }
    // Before the cycle is complete the output is the running blend, and it differs.
    assert!(outs[7].color != outs[8].color);
    let old = render(&gpu, &s, spec(w, h, "native+taa:without-cycle"), &frames);
    let changed = (8..20)
        .filter(|&f| old[f].color != old[f - 1].color)
        .count();
    assert_eq!(changed, 12, "without-cycle: every frame still changes");
    assert_clean(&gpu);
}

/// A still pixel whose shading changes leaves its cycle: the static demo held for 17 frames (the
/// centred frame 0, then two complete cycles), then every light dimmed to 30% from frame 17 on.
/// Every sample of frame 17 lit enough to leave the tolerance lies below the range of the last
/// cycle, so its history is rejected and the output is the dimmed jittered frame; with a
/// tolerance wider than the change (`ctol=1`) frame 17 would still show the old cycle's mean,
/// bit for bit.
#[test]
fn a_still_pixel_whose_shading_changes_leaves_its_cycle() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let mut dim = s.clone();
    for l in &mut dim.directional {
        l.intensity *= 0.3;
    }
    for l in &mut dim.points {
        l.intensity *= 0.3;
    }
    let run = |spec_: &str| -> Vec<FrameOutput> {
        let shaders = cbr_render::shader_library();
        let mut r = Renderer::new(&gpu, &shaders, &s, spec(w, h, spec_)).expect("renderer");
        (0..19u32)
            .map(|f| r.render(if f < 17 { &s } else { &dim }, f).expect("frame"))
            .collect()
    };
    let ours = run("native+taa");
    let held = run("native+taa:ctol=1");
    assert!(
        ours[16].color == ours[15].color,
        "converged before the change"
    );
    assert!(
        held[17].color == held[16].color,
        "ctol=1: the old mean is held"
    );
    // Pixel by pixel: where the dimmed sample's perceptual luma leaves the range of the 8
    // jittered samples of scene A by more than the tolerance (0.01; 1e-3 of margin for the
    // range's f16 rounding), frame 17 is that sample, bit for bit (the history rejected); where
    // it stays inside, frame 16's cycle mean, bit for bit (the sky, dark texels).
    let dimmed = jittered_native(&gpu, &dim, w, h, 8, 17);
    let (cycle_a, _) = jittered_cycle(&gpu, &s, w, h);
    let e = s.settings.exposure.exp2();
    let l = |c: [f32; 3]| taa::to_p(c, e)[0];
    let px = |o: &FrameOutput, i: usize| o.color[4 * i..4 * i + 3].to_vec();
    let fresh = rgb(&dimmed);
    let (mut followed, mut kept) = (0, 0);
    for i in 0..(w * h) as usize {
        let lo = cycle_a.iter().map(|f| l(f[i])).fold(f32::MAX, f32::min);
        let hi = cycle_a.iter().map(|f| l(f[i])).fold(f32::MIN, f32::max);
        let lf = l(fresh[i]);
        if lf < lo - 0.011 || lf > hi + 0.011 {
            assert!(
                px(&ours[17], i) == px(&dimmed, i),
                "pixel {i} changed but kept its mean"
            );
            followed += 1;
        } else if lf > lo - 0.009 && lf < hi + 0.009 {
            assert!(
                px(&ours[17], i) == px(&ours[16], i),
                "pixel {i} did not change but left"
            );
            kept += 1;
        }
    }
    eprintln!("frame 17: {followed} pixels left their cycle, {kept} kept it");
    assert!(followed > 200 && kept > 200, "{followed} left, {kept} kept");
    assert_clean(&gpu);
}

/// `+taa:motionlod` withdraws the LOD bias from moving fragments: the renderer asks the scene
/// pass for bias -1 at rest and 0 from 2 px per frame (by default, with `without-speed`, in
/// INSIDE's mode and with a fixed `--lod-bias` it applies everywhere), and on the moving demo
/// each textured pixel's albedo LOD
/// (`debug_lod`) rises over the fixed bias's by min(|v| / V, 1), v its own velocity (where both
/// show the same triangle: the sharper mask moves alpha-tested edges).
#[test]
fn the_lod_bias_is_withdrawn_from_moving_fragments() {
    let gpu = gpu();
    let (w, h) = (64u32, 36u32);
    let s = demo(w, h);
    let shaders = cbr_render::shader_library();
    let motion = |spec_: &str| {
        Renderer::new(&gpu, &shaders, &s, spec(w, h, spec_))
            .expect("renderer")
            .lod_motion()
    };
    assert_eq!(motion("native+taa:motionlod"), [-1.0, 0.5]);
    assert_eq!(motion("native+taa:motionlod:uspeed=4"), [-1.0, 0.25]);
    // `speed` is the weight's ramp only (1 by default); the centring's is `uspeed` (2).
    assert_eq!(motion("native+taa:motionlod:speed=4"), [-1.0, 0.5]);
    // `unjitter`: moving fragments shaded at the centre, at the full bias.
    assert_eq!(motion("native+taa:unjitter"), [0.0, 0.5]);
    assert_eq!(motion("native+taa"), [0.0, 0.5], "unjitter is the default");
    assert_eq!(motion("native+taa:uspeed=0.25"), [0.0, 4.0]);
    for fixed in [
        "native",
        "native+taa:without-unjitter",
        "native+taa:motionlod:without-unjitter",
        "native+taa:inside",
        "native+taa:motionlod:without-speed",
    ] {
        assert_eq!(motion(fixed), [0.0; 2], "{fixed}");
    }
    let lod = |m: Option<[f32; 2]>| {
        let settings = RenderSettings {
            debug_lod: true,
            lod_bias: Some(-1.0),
            lod_motion: m,
            ..spec(w, h, "native")
        };
        render(&gpu, &s, settings, &[5]).remove(0)
    };
    // The demo's camera moves slowly at 64x36: all of the bias is shed from 1/4 px per frame.
    let (fixed, moving) = (lod(None), lod(Some([-1.0, 4.0])));
    let (mut worst, mut fast, mut still) = (0.0f32, 0, 0);
    for (i, v) in fixed.velocity.iter().enumerate() {
        let a = fixed.color[4 * i].to_f32();
        // Textured, and the same triangle in both: a sharper mask moves alpha-tested edges.
        if a <= -99.0 || fixed.ids[i] != moving.ids[i] {
            continue;
        }
        let want = ((v[0] * v[0] + v[1] * v[1]).sqrt() * 4.0).min(1.0);
        let got = moving.color[4 * i].to_f32() - a;
        worst = worst.max((got - want).abs());
        fast += usize::from(want == 1.0);
        still += usize::from(want < 0.05);
    }
    eprintln!("LOD rise off min(4 |v|, 1) by at most {worst}; {fast} fast, {still} still pixels");
    assert!(worst < 0.02, "the LOD rise is off by {worst}");
    assert!(
        fast > 50 && still > 50,
        "{fast} fast and {still} still textured pixels"
    );
    assert_clean(&gpu);
}

/// A turning object's fragments withdraw the temporal LOD bias by their object's turn
/// (`FrameView::lod_turn`: `taau`'s own bias, the post passes' `+taa` bias; none without a
/// temporal bias, with `taau:without-reactive` or with a fixed `--lod-bias`): on the demo the
/// torus turns 18 degrees a frame (turn 1), and each of its textured pixels' albedo LOD
/// (`debug_lod`) rises by the whole withdrawn bias, where every other object's stays.
#[test]
fn a_turning_object_withdraws_the_lod_bias() {
    let gpu = gpu();
    let (w, h) = (128u32, 72u32);
    let s = demo(w, h);
    let shaders = cbr_render::shader_library();
    let turn = |spec_: &str| {
        Renderer::new(&gpu, &shaders, &s, spec(w, h, spec_))
            .expect("renderer")
            .lod_turn(false)
    };
    assert_eq!(turn("native+taa"), -1.0);
    assert_eq!(
        turn("checkerboard:rotated:ours+taa"),
        -1.0,
        "the post's part only"
    );
    assert!((turn("taau") - (0.5f32.sqrt().log2() - 1.0)).abs() < 1e-6);
    for none in ["native", "taau:without-reactive", "upscale:fsr1"] {
        assert_eq!(turn(none), 0.0, "{none}");
    }
    let fixed = RenderSettings {
        lod_bias: Some(-1.0),
        ..spec(w, h, "native+taa")
    };
    let r = Renderer::new(&gpu, &shaders, &s, fixed).expect("renderer");
    assert_eq!(r.lod_turn(false), 0.0, "a fixed --lod-bias");
    let lod = |t: Option<f32>| {
        let settings = RenderSettings {
            debug_lod: true,
            lod_bias: Some(-1.0),
            lod_turn: t,
            ..spec(w, h, "native")
        };
        render(&gpu, &s, settings, &[5]).remove(0)
    };
    let torus = s.object_id("spinner").expect("torus");
    let (fixed, turning) = (lod(None), lod(Some(-1.0)));
    let (mut worst, mut on_torus, mut elsewhere) = (0.0f32, 0, 0);
    for i in 0..fixed.ids.len() {
        let a = fixed.color[4 * i].to_f32();
        if a <= -99.0 || fixed.ids[i] != turning.ids[i] {
            continue;
        }
        let want = if fixed.ids[i][0] == torus { 1.0 } else { 0.0 };
        worst = worst.max((turning.color[4 * i].to_f32() - a - want).abs());
        on_torus += usize::from(want == 1.0);
        elsewhere += usize::from(want == 0.0);
    }
    eprintln!("LOD rise off by at most {worst}; {on_torus} torus, {elsewhere} other pixels");
    assert!(worst < 0.01, "the LOD rise is off by {worst}");
    assert!(
        on_torus > 50 && elsewhere > 500,
        "{on_torus} torus, {elsewhere} other pixels"
    );
    assert_clean(&gpu);
}

/// Under `unjitter` (the default) a turning object is rasterised without the projection's
/// jitter in proportion to its turn (forward.vert), and its shading is not moved again
/// (forward.frag): in the jittered frame `+taa` renders, the demo's torus (18 degrees a frame,
/// its turn 1, its LOD bias withdrawn to 0) covers the pixels it covers in `native`'s frame and
/// shows `native`'s colours bit for bit, while the rest of the frame moved with the jitter.
/// Without `unjitter` or `reactive` the torus is jittered as everything else.
#[test]
fn a_turning_object_is_rasterised_without_the_jitter() {
    let gpu = gpu();
    let (w, h) = (128u32, 72u32);
    let s = demo(w, h);
    let torus = s.object_id("spinner").expect("torus");
    let f = 5;
    let native = render(&gpu, &s, spec(w, h, "native"), &[f]).remove(0);
    let rgb = |o: &FrameOutput, i: usize| [0, 1, 2].map(|k| o.color[4 * i + k].to_bits());
    // Of the pixels either frame's torus covers: how many show the same object and primitive
    // in both, and how many the same colour bit for bit; and of the other pixels, how many
    // changed colour.
    let compare = |c: &TaaConfig| {
        let j = jittered_native_for(&gpu, &s, w, h, c, f);
        let (mut on, mut covered, mut same, mut moved) = (0, 0, 0, 0);
        for i in 0..native.ids.len() {
            if native.ids[i][0] == torus || j.ids[i][0] == torus {
                on += 1;
                covered += usize::from(native.ids[i] == j.ids[i]);
                same += usize::from(native.ids[i] == j.ids[i] && rgb(&native, i) == rgb(&j, i));
            } else {
                moved += usize::from(rgb(&native, i) != rgb(&j, i));
            }
        }
        (on, covered, same, moved)
    };
    let (on, covered, same, moved) = compare(&TaaConfig::OURS);
    eprintln!(
        "torus: {covered} of {on} pixels native's triangles, {same} native's colours; \
         elsewhere {moved} pixels moved with the jitter"
    );
    assert!(
        on > 100 && covered == on,
        "{covered} of {on} torus pixels are native's triangles"
    );
    // Bit for bit: the turn reaches the fragment shader as a flat varying. Read from the
    // objects buffer there, a quad's helper lanes read 0 on llvmpipe and were centred as if
    // the torus did not turn, and 15 of these pixels took another texture level.
    assert!(
        same == on,
        "{same} of {on} torus pixels are native's colours"
    );
    assert!(moved > 1000, "only {moved} pixels moved with the jitter");
    for off in ["without-reactive", "without-unjitter"] {
        let c = TaaConfig::parse(&[off]).expect("config");
        let (on, covered, same, _) = compare(&c);
        eprintln!("{off}: {covered} of {on} torus pixels native's triangles, {same} its colours");
        assert!(
            covered * 10 < on * 8,
            "{off}: {covered} of {on} torus pixels are native's"
        );
    }
    assert_clean(&gpu);
}

/// `+taa:motionlod` moves a moving fragment's shading inputs (UV, position, normal) back to the
/// unjittered pixel centre by its share of the jitter (forward.frag's `unjittered`): with a fixed
/// jitter and every moving fragment's share 1 (1/4 px per frame sheds it all), the textured
/// interior of the moving demo is native's unjittered shading to first order, where the jittered
/// raster is off by the jitter; with the camera held, every pixel outside the spinning torus keeps
/// the jittered raster's bits.
#[test]
fn motionlod_shades_moving_fragments_at_the_pixel_centre() {
    let gpu = gpu();
    let (w, h) = (128u32, 72u32);
    let jitter = [0.31f32, -0.27];
    let one = |s: &Scene, jit: [f32; 2], m: Option<[f32; 2]>| {
        let settings = RenderSettings {
            jitter: jit,
            lod_bias: Some(0.0),
            lod_motion: m,
            ..spec(w, h, "native")
        };
        render(&gpu, s, settings, &[5]).remove(0)
    };
    // Pixels whose 3 x 3 neighbourhood is one object in every frame given: no edge moved by the
    // jitter.
    let interior = |frames: &[&FrameOutput], i: usize| {
        let (x, y) = ((i as u32 % w) as i64, (i as u32 / w) as i64);
        let id = frames[0].ids[i];
        id[0] != 0
            && (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    u >= 0
                        && v >= 0
                        && u < i64::from(w)
                        && v < i64::from(h)
                        && frames
                            .iter()
                            .all(|f| f.ids[(v * i64::from(w) + u) as usize] == id)
                })
            })
    };
    let s = demo(w, h);
    let centre = one(&s, [0.0; 2], None);
    let jittered = one(&s, jitter, None);
    let moved = one(&s, jitter, Some([0.0, 4.0]));
    let (c, j, m) = (rgb(&centre), rgb(&jittered), rgb(&moved));
    let (mut sum_j, mut sum_m, mut n) = (0.0f64, 0.0f64, 0usize);
    for i in 0..c.len() {
        let v = centre.velocity[i];
        if (v[0] * v[0] + v[1] * v[1]).sqrt() < 0.25 || !interior(&[&centre, &jittered, &moved], i)
        {
            continue;
        }
        let d = |a: [f32; 3]| f64::from((0..3).map(|k| (a[k] - c[i][k]).abs()).sum::<f32>() / 3.0);
        sum_j += d(j[i]);
        sum_m += d(m[i]);
        n += 1;
    }
    let (err_j, err_m) = (sum_j / n as f64, sum_m / n as f64);
    eprintln!(
        "{n} moving interior pixels: mean |jittered - centred| {err_j:.5}, with the inputs moved \
         back {err_m:.5}"
    );
    assert!(n > 1000, "{n} moving interior pixels");
    // Measured at 128 x 72: 0.1411 jittered, 0.0071 moved back (the rest: second-order terms of
    // the perspective division, and the jittered LOD's derivatives).
    assert!(
        err_m < 0.1 * err_j,
        "moved back: {err_m} against the jittered raster's {err_j}"
    );
    // The camera held: the fragments that do not move keep the jittered raster's bits.
    let held = static_demo(w, h);
    let jittered = one(&held, jitter, None);
    let moved = one(&held, jitter, Some([0.0, 4.0]));
    let (mut same, mut still) = (0usize, 0usize);
    for (i, v) in jittered.velocity.iter().enumerate() {
        if v[0] == 0.0 && v[1] == 0.0 && jittered.ids[i][0] != 0 {
            still += 1;
            same += usize::from(jittered.color[4 * i..4 * i + 4] == moved.color[4 * i..4 * i + 4]);
        }
    }
    assert!(still > 3000, "{still} still pixels");
    // A material without textures is wholly centred whatever its speed; a textured one by its
    // share, here speed / 1000 (nearly none). `specular`'s spheres and floor are untextured; the
    // moving demo's interior above is mostly textured.
    let slow = Some([0.0, 1.0 / 1000.0]);
    let mut sp = cbr_scene::builtin("specular").expect("specular");
    (sp.settings.width, sp.settings.height) = (w, h);
    for (s, untextured) in [(&sp, true), (&s, false)] {
        let centre = one(s, [0.0; 2], None);
        let jittered = one(s, jitter, None);
        let slow_moved = one(s, jitter, slow);
        let (c, j, m) = (rgb(&centre), rgb(&jittered), rgb(&slow_moved));
        let (mut sum_j, mut sum_m, mut n) = (0.0f64, 0.0f64, 0usize);
        for i in 0..c.len() {
            let v = centre.velocity[i];
            // Object ID k is the scene's object k - 1 (0: the background); textured as the
            // shader reads it: an albedo, bump or alpha-mask texture.
            let textured = |id: u32| {
                let m = &s.materials[s.objects[id as usize - 1].material as usize];
                m.kd_tex.is_some()
                    || m.bump_tex.is_some()
                    || matches!(m.alpha, cbr_scene::AlphaSource::Texture { .. })
            };
            if (v[0] * v[0] + v[1] * v[1]).sqrt() < 0.25
                || !interior(&[&centre, &jittered, &slow_moved], i)
                || textured(centre.ids[i][0]) == untextured
            {
                continue;
            }
            let d =
                |a: [f32; 3]| f64::from((0..3).map(|k| (a[k] - c[i][k]).abs()).sum::<f32>() / 3.0);
            sum_j += d(j[i]);
            sum_m += d(m[i]);
            n += 1;
        }
        let (err_j, err_m) = (sum_j / n as f64, sum_m / n as f64);
        eprintln!(
            "untextured {untextured}: {n} slowly moving interior pixels, |jittered - centred| \
             {err_j:.5}, at speed / 1000 of the jitter {err_m:.5}"
        );
        assert!(n > 200, "{n} pixels");
        match untextured {
            true => assert!(err_m < 0.1 * err_j, "untextured: {err_m} against {err_j}"),
            false => assert!(err_m > 0.9 * err_j, "textured: {err_m} against {err_j}"),
        }
    }
    assert_eq!(
        same,
        still,
        "still pixels whose colour changed: {}",
        still - same
    );
    assert_clean(&gpu);
}

/// A point light of infinite intensity makes frame 3's lit fragments NaN or Inf: the scene pass
/// counts them and writes them black (native shows no non-finite pixel), and TAA's output has
/// none, that frame or the next. (TAA's own guard against a non-finite current sample is checked
/// against the CPU reference in post::taa's unit tests.)
#[test]
fn nan_and_inf_never_enter_the_history() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let mut poisoned = s.clone();
    assert!(!poisoned.points.is_empty() || !poisoned.directional.is_empty());
    for l in &mut poisoned.directional {
        l.intensity = f32::INFINITY;
    }
    for l in &mut poisoned.points {
        l.intensity = f32::INFINITY;
    }
    let shaders = cbr_render::shader_library();
    let check = |spec_text: &str| {
        let mut r = Renderer::new(&gpu, &shaders, &s, spec(w, h, spec_text)).expect("renderer");
        let mut outs = Vec::new();
        for f in 0..6 {
            let scene = if f == 3 { &poisoned } else { &s };
            outs.push(r.render(scene, f).expect("frame"));
        }
        outs
    };
    let native = check("native");
    let bad = |o: &FrameOutput| o.color.iter().filter(|c| !c.to_f32().is_finite()).count();
    assert!(
        native[3].nonfinite_fragments.unwrap_or(0) > 0,
        "the injection made no non-finite fragment"
    );
    assert_eq!(
        bad(&native[3]),
        0,
        "a non-finite fragment reached the frame"
    );
    assert_eq!(native[4].nonfinite_fragments, Some(0));
    assert_eq!(bad(&native[4]), 0);
    for t in [
        "native+taa",
        "native+taa:inside",
        "native+taa:without-clip:mean",
    ] {
        let outs = check(t);
        for (f, o) in outs.iter().enumerate() {
            assert_eq!(bad(o), 0, "{t}: frame {f} has non-finite pixels");
        }
    }
    assert_clean(&gpu);
}

/// A camera cut (a key flagged `cut`) resets the history: the first frame after it is
/// `native`'s own frame (rendered centred: nothing to blend a jittered sample with), with no
/// trace of the previous shot; with `without-centred-reset` it is the jittered native frame.
#[test]
fn a_camera_cut_resets_the_history() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = common::demo_with_cut(w, h, 4);
    let taa = "native+taa";
    let outs = render(&gpu, &s, spec(w, h, taa), &(0..6).collect::<Vec<_>>());
    let native4 = render(&gpu, &s, spec(w, h, "native"), &[4]).remove(0);
    assert!(
        outs[4].color == native4.color,
        "frame 4 (the cut) is not native's frame"
    );
    let old = render(
        &gpu,
        &s,
        spec(w, h, "native+taa:without-centred-reset"),
        &(0..5).collect::<Vec<_>>(),
    );
    assert!(
        old[4].color == jittered_native(&gpu, &s, w, h, 8, 4).color,
        "without-centred-reset: frame 4 (the cut) is not the jittered native frame"
    );
    assert!(old[4].color != native4.color);
    assert!(
        outs[3].color != jittered_native(&gpu, &s, w, h, 8, 3).color,
        "frame 3 blends history"
    );
    assert!(
        outs[5].color != jittered_native(&gpu, &s, w, h, 8, 5).color,
        "frame 5 blends again"
    );
    assert_clean(&gpu);
}

/// A frame without history is the technique's own: frame 0 of `T+taa` is `T`'s frame 0 bit for
/// bit (rendered unjittered at `T`'s LOD bias, passed through), for native and checkerboard;
/// the next frame is jittered and blends. INSIDE's TAA (as published) and
/// `without-centred-reset` jitter frame 0 as well, so theirs differs from the technique's.
#[test]
fn a_frame_without_history_is_the_techniques_own() {
    let gpu = gpu();
    let (w, h) = (48u32, 27u32);
    let s = demo(w, h);
    for t in ["native", "checkerboard:rotated:ours"] {
        let own = render(&gpu, &s, spec(w, h, t), &[0, 1]);
        let taa = render(&gpu, &s, spec(w, h, &format!("{t}+taa")), &[0, 1]);
        assert!(
            taa[0].color == own[0].color,
            "{t}+taa: frame 0 is not {t}'s"
        );
        assert!(taa[1].color != own[1].color, "{t}+taa: frame 1 blends");
        for other in ["inside", "without-centred-reset"] {
            let o = render(&gpu, &s, spec(w, h, &format!("{t}+taa:{other}")), &[0]);
            assert!(
                o[0].color != own[0].color,
                "{t}+taa:{other}: frame 0 is jittered"
            );
        }
    }
    // A `--lod-bias` setting holds on the centred frame as on the technique's own.
    let biased = |s_: &str| RenderSettings {
        lod_bias: Some(-2.0),
        ..spec(w, h, s_)
    };
    let own = render(&gpu, &s, biased("native"), &[0]);
    let taa = render(&gpu, &s, biased("native+taa"), &[0]);
    assert!(own[0].color == taa[0].color, "--lod-bias -2: frame 0");
    let plain = render(&gpu, &s, spec(w, h, "native"), &[0]);
    assert!(own[0].color != plain[0].color, "the bias changes the frame");
    assert_clean(&gpu);
}

/// TAA runs after every technique with a full frame, including msaa:4 and checkerboard with a
/// prepass, with no validation message; a technique without geometry is a clear error.
#[test]
fn taa_chains_after_every_technique_with_a_full_frame() {
    let gpu = gpu();
    let (w, h) = (40u32, 24u32);
    let s = demo(w, h);
    for t in [
        "msaa:4+taa",
        "upscale:bicubic+taa",
        "checkerboard:rotated:ours+taa",
        "checkerboard:split:ours:prepass+taa:inside",
        "checkerboard:masked:pq4k+fxaa+taa",
        "native+taa+fxaa",
        "interlaced+taa",
    ] {
        let outs = render(&gpu, &s, spec(w, h, t), &[0, 1, 2, 3]);
        assert!(
            outs.iter()
                .all(|o| o.color.iter().all(|c| c.to_f32().is_finite())),
            "{t}"
        );
    }
    // The next link reads the history slot TAA wrote this frame: `+sharpen:0` passes it through
    // unchanged, frame after frame.
    let taa = render(&gpu, &s, spec(w, h, "native+taa"), &[0, 1, 2, 3]);
    let then = render(&gpu, &s, spec(w, h, "native+taa+sharpen:0"), &[0, 1, 2, 3]);
    for (a, b) in taa.iter().zip(&then) {
        assert!(
            a.color == b.color,
            "frame {}: the link after taa reads another slot",
            a.index
        );
    }
    let shaders = cbr_render::shader_library();
    let err = Renderer::new(&gpu, &shaders, &s, spec(w, h, "ssaa:2+taa"))
        .err()
        .expect("ssaa gives no geometry")
        .to_string();
    assert!(err.contains("geometry") && err.contains("ssaa:2"), "{err}");
    let err = Renderer::new(&gpu, &shaders, &s, spec(w, h, "native+taa+taa"))
        .err()
        .expect("two jitters")
        .to_string();
    assert!(err.contains("jitters"), "{err}");
    let err = Renderer::new(
        &gpu,
        &shaders,
        &s,
        spec(w, h, "checkerboard:rotated:fused+taa"),
    )
    .err()
    .expect("fused jitters already")
    .to_string();
    assert!(err.contains("jitters"), "{err}");
    assert_clean(&gpu);
}

/// Checkerboard under TAA, chained (two histories) and fused (one), on every layout this device
/// runs (msaa2x needs 2x MSAA: GPUs), with and without the prepass.
#[test]
fn checkerboard_with_taa_chained_and_fused_runs_on_every_layout() {
    let gpu = gpu();
    let (w, h) = (40u32, 24u32);
    let s = demo(w, h);
    for layout in cbr_gpu::Layout::ALL {
        if let Some(missing) = gpu.caps().layout_unsupported(layout) {
            eprintln!("skipped: the {} layout needs {missing}", layout.name());
            continue;
        }
        for t in [
            "ours+taa",
            "ours:prepass+taa:inside",
            "fused",
            "fused:prepass+fxaa",
        ] {
            let spec_text = format!("checkerboard:{}:{t}", layout.name());
            let outs = render(&gpu, &s, spec(w, h, &spec_text), &[0, 1, 2, 3]);
            assert!(
                outs.iter()
                    .all(|o| o.color.iter().all(|c| c.to_f32().is_finite())),
                "{spec_text}"
            );
        }
    }
    assert_clean(&gpu);
}

/// `fused` on a static scene: the jitter advances every second frame, rendered pixels accumulate
/// into the one history, missing pixels take it as it is; after four cycles the output changes
/// from frame to frame by a small fraction of what the raw jittered checkerboard frames change,
/// and it is nearer the mean of the 8 jittered native frames than one native frame is.
#[test]
fn fused_converges_on_a_static_scene() {
    let gpu = gpu();
    let (w, h) = (48u32, 28u32);
    let s = static_demo(w, h);
    let frames: Vec<u32> = (0..40).collect();
    let outs: Vec<Vec<[f32; 3]>> =
        render(&gpu, &s, spec(w, h, "checkerboard:masked:fused"), &frames)
            .iter()
            .map(rgb)
            .collect();
    let plain: Vec<Vec<[f32; 3]>> = render(
        &gpu,
        &s,
        spec(w, h, "checkerboard:masked:ours"),
        &frames[..8],
    )
    .iter()
    .map(rgb)
    .collect();
    let (natives, mean) = jittered_cycle(&gpu, &s, w, h);
    let native_change = (1..8)
        .map(|f| mean_abs(&natives[f], &natives[f - 1]))
        .sum::<f32>()
        / 7.0;
    let fused_change = (33..40)
        .map(|f| mean_abs(&outs[f], &outs[f - 1]))
        .sum::<f32>()
        / 7.0;
    let fused_off = mean_abs(&outs[39], &mean);
    let native_off = natives.iter().map(|n| mean_abs(n, &mean)).sum::<f32>() / 8.0;
    let plain_off = mean_abs(&plain[7], &mean);
    eprintln!(
        "change: fused {fused_change:.5}, jittered native {native_change:.5}; distance to the \
         8-sample mean: fused {fused_off:.5}, native {native_off:.5}, unjittered ours {plain_off:.5}"
    );
    assert!(
        fused_change < 0.25 * native_change,
        "{fused_change} vs {native_change}"
    );
    assert!(fused_off < 0.75 * native_off, "{fused_off} vs {native_off}");
    assert_clean(&gpu);
}
