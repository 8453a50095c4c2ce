//! `taau` (docs/upsampling.md): every pass against its CPU reference
//! (crates/cbr-render/src/techniques/taau/reference.rs) over several frames of synthetic render
//! frames, each frame's reference fed the GPU's own inputs (its previous history included); the
//! technique on the demo with every option, NaN/Inf, a camera cut and a still scene's
//! convergence. Lavapipe, validation on.

mod common;

use cbr_gpu::{Gpu, Image, Profiler, Readback};
use cbr_render::taau::reference::{self, AccumulateInputs};
use cbr_render::taau::{self, TaauFrame, TaauPasses};
use cbr_render::targets::FrameTargets;
use cbr_render::upscale::reference::{self as fsr1, Rgb};
use cbr_render::{FrameOutput, RenderSettings, Renderer};
use common::{assert_clean, demo, render_settings, static_demo};
use half::f16;

type V3 = [f32; 3];
type V4 = [f32; 4];

/// One synthetic render frame `f` (w x h): a background plane far away moving slowly, a nearer
/// square moving fast over it (disocclusions behind it), a one-texel bright line and dot (thin
/// features for the locks), sky (depth 0) in the top rows, HDR values, and in frame 2 a NaN and
/// an Inf.
struct Synthetic {
    color: Vec<V3>,
    velocity: Vec<[f32; 2]>,
    depth: Vec<f32>,
    ids: Vec<[u32; 2]>,
}

fn synthetic(w: usize, h: usize, f: usize) -> Synthetic {
    let mut s = Synthetic {
        color: Vec::new(),
        velocity: Vec::new(),
        depth: Vec::new(),
        ids: Vec::new(),
    };
    let sq = (3 + 2 * f, 4);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let mut c = [
                0.2 + 0.05 * ((fx + f as f32 * 0.4) * 0.9).sin(),
                0.3 + 0.2 * (fy * 0.7).cos(),
                0.1 + 0.02 * fx,
            ];
            // The floor's velocity grows with y (a camera's parallax), so that the nearest
            // texel's and the pixel's own differ (`surface_velocity`).
            let (mut v, mut d, mut id) = ([0.4f32 + 0.03 * fy, 0.0], 0.05f32, 1u32);
            if y < 2 {
                // The background (nothing drawn: depth 0, no velocity) changes from frame to
                // frame, so that its history is what rectification (F_BACKGROUND) changes.
                (c, v, d, id) = ([0.5, 0.6, 0.9 - 0.1 * f as f32], [0.0, 0.0], 0.0, 0);
            }
            if x >= sq.0 && x < sq.0 + 6 && y >= sq.1 && y < sq.1 + 5 {
                c = [3.0, 1.0 + 0.1 * fx, 0.2];
                (v, d, id) = ([2.0, 0.0], 0.5, 2);
            }
            if x == w - 5 && y > 2 {
                c = [4.0, 4.0, 4.0];
            }
            if (x, y) == (5, h - 3) {
                c = [0.0, 0.0, 8.0];
            }
            if f == 2 && (x, y) == (w / 2, h - 2) {
                c = [f32::NAN, 0.0, 0.0];
            }
            if f == 2 && (x, y) == (w / 2 + 1, h - 2) {
                c = [f32::INFINITY, 1.0, 1.0];
            }
            s.color.push(c.map(|v| f16::from_f32(v).to_f32()));
            s.velocity.push(v);
            s.depth.push(d);
            s.ids.push([id, 0]);
        }
    }
    s
}

fn upload(gpu: &Gpu, t: &FrameTargets, s: &Synthetic) {
    let rgba: Vec<f16> = s
        .color
        .iter()
        .flat_map(|c| [c[0], c[1], c[2], 1.0].map(f16::from_f32))
        .collect();
    common::upload(
        gpu,
        &[
            (&t.color, bytemuck::cast_slice(&rgba).to_vec()),
            (&t.velocity, bytemuck::cast_slice(&s.velocity).to_vec()),
            (&t.ids, bytemuck::cast_slice(&s.ids).to_vec()),
            (&t.depth, bytemuck::cast_slice(&s.depth).to_vec()),
        ],
    )
    .expect("upload");
}

fn f16x4(rb: &Readback) -> Vec<V3> {
    let h: &[f16] = bytemuck::cast_slice(rb.bytes().expect("bytes"));
    h.chunks(4)
        .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32()])
        .collect()
}

fn f32s<T: bytemuck::Pod>(rb: &Readback) -> Vec<T> {
    bytemuck::cast_slice(rb.bytes().expect("bytes")).to_vec()
}

/// Values that differ by more than `abs + rel |want|` (NaN always differs).
fn off(got: &[f32], want: &[f32], abs: f32, rel: f32) -> (usize, f32) {
    assert_eq!(got.len(), want.len());
    let mut n = 0;
    let mut worst = 0.0f32;
    for (g, w) in got.iter().zip(want) {
        let d = (g - w).abs();
        if d.is_nan() || d > abs + rel * w.abs() {
            n += 1;
            worst = worst.max(if d.is_nan() { f32::INFINITY } else { d });
        }
    }
    (n, worst)
}

fn flat<const N: usize>(v: &[[f32; N]]) -> Vec<f32> {
    v.iter().flatten().copied().collect()
}

/// What one frame's passes wrote, read back.
struct Got {
    dilated: Vec<V4>,
    prepared: Vec<V4>,
    recon: Option<Vec<u32>>,
    disocclusion: Option<Vec<f32>>,
    locks: Option<Vec<u32>>,
    history: Vec<V4>,
    aux: Vec<V4>,
    accumulated: Vec<V3>,
    color: Vec<V3>,
}

fn run_frame(gpu: &Gpu, p: &TaauPasses, t: &FrameTargets, f: &TaauFrame) -> Got {
    let res = &p.res;
    let rb = |name: &str, img: &Image| Readback::for_image(gpu, name, img).expect("readback");
    let rbb = |name: &str| {
        res.buffer(name).ok().map(|b| {
            let (w, h) = (b.size() / 4, 1);
            Readback::for_buffer(gpu, name, b.size(), w as u32, h).expect("readback")
        })
    };
    let (hist, aux) = p.history(f.frame).expect("history");
    let dilated = rb("t.dilated", res.image("dilated").expect("dilated"));
    let prepared = rb("t.prepared", res.image("prepared").expect("prepared"));
    let dis = res.image("disocclusion").ok().map(|i| rb("t.dis", i));
    let (recon, locks) = (rbb("recon"), rbb("new_locks"));
    let (h_rb, a_rb) = (rb("t.hist", hist), rb("t.aux", aux));
    let acc = rb("t.acc", res.image("accumulated").expect("accumulated"));
    let color = p.color().expect("colour");
    let c_rb = rb("t.color", color);
    let mut profiler = Profiler::new(gpu, "t.profiler", 8).expect("profiler");
    profiler.begin_frame();
    gpu.submit("t.taau", |cmd| {
        p.record(cmd, &mut profiler, t, f)?;
        cmd.read_image(res.image("dilated")?, &dilated);
        cmd.read_image(res.image("prepared")?, &prepared);
        if let Some(d) = &dis {
            cmd.read_image(res.image("disocclusion")?, d);
        }
        if let Some(r) = &recon {
            cmd.read_buffer(res.buffer("recon")?, r);
        }
        if let Some(l) = &locks {
            cmd.read_buffer(res.buffer("new_locks")?, l);
        }
        cmd.read_image(hist, &h_rb);
        cmd.read_image(aux, &a_rb);
        cmd.read_image(res.image("accumulated")?, &acc);
        cmd.read_image(color, &c_rb);
        Ok(())
    })
    .expect("submit");
    Got {
        dilated: f32s(&dilated),
        prepared: f32s(&prepared),
        recon: recon.as_ref().map(f32s),
        disocclusion: dis.as_ref().map(f32s),
        locks: locks.as_ref().map(f32s),
        history: f32s(&h_rb),
        aux: f32s(&a_rb),
        accumulated: f16x4(&acc),
        color: f16x4(&c_rb),
    }
}

/// The synthetic frames' turns by object ID: the square (2) turns half of the full turn.
const TURNS: [f32; 3] = [0.0, 0.0, 0.5];

/// Each pass against its reference, frames 0-4 (frame 0 and 3 reset... frame 0 only), for
/// the default and every option that changes a shader.
#[test]
fn every_pass_matches_its_cpu_reference_over_frames() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let out = (32u32, 18u32);
    for spec in [
        &[][..],
        &["catmull", "without-stability", "without-surface-velocity"],
        &[
            "bilinear",
            "without-locks",
            "without-rcas",
            "without-ids",
            "without-reactive",
        ],
        &[
            "0.5",
            "without-depth-clip",
            "sharpness=1",
            "debug",
            "lobes=2",
        ],
    ] {
        let c = taau::parse(spec).expect("spec");
        let (w, h) = c.render_resolution(out.0, out.1);
        let targets = FrameTargets::new(&gpu, "t.render", w, h).expect("targets");
        let mut passes = TaauPasses::new(&gpu, &shaders, &c, out).expect("passes");
        let phases = c.phases(out.0, out.1);
        let (mut prev_h, mut prev_a): (Vec<V4>, Vec<V4>) = (Vec::new(), Vec::new());
        let (mut locked, mut disoccluded, mut clipped_or_blended) = (0usize, 0usize, 0usize);
        let (mut object_drops, mut reactive) = (0usize, 0usize);
        passes.set_turns(&TURNS).expect("turns");
        for frame in 0..5u32 {
            let s = synthetic(w as usize, h as usize, frame as usize);
            upload(&gpu, &targets, &s);
            let f = TaauFrame {
                frame,
                reset: frame == 0,
                jitter: taau::jitter(phases, frame),
                exposure_stops: 0.5,
                background_moves: frame % 2 == 1,
            };
            let got = run_frame(&gpu, &passes, &targets, &f);
            let p = passes.params(&f);
            let what = format!("{spec:?} frame {frame}");
            // 1. Dilate: a selection, exact; the reconstructed depth exact (a max of bits).
            let (dil, rec) = reference::dilate(&p, &s.depth, &s.velocity, c.depth_clip);
            assert_eq!(got.dilated, dil, "{what}: dilate");
            if let Some(r) = &got.recon {
                assert_eq!(r, &rec, "{what}: reconstructed previous depth");
            }
            // The prepared colour (f32 arithmetic on both sides); the non-finite pixels flagged.
            let pre = reference::prepare(&p, &s.color);
            let (n, worst) = off(&flat(&got.prepared), &flat(&pre), 1e-6, 1e-5);
            assert_eq!(n, 0, "{what}: prepared colour, worst {worst}");
            let flagged = got.prepared.iter().filter(|v| v[3] == 0.0).count();
            assert_eq!(
                flagged,
                if frame == 2 { 2 } else { 0 },
                "{what}: non-finite flags"
            );
            // 2. Depth clip on the GPU's dilated frame and reconstruction.
            if let (Some(d), Some(r)) = (&got.disocclusion, &got.recon) {
                let want = reference::depth_clip(&p, &got.dilated, r);
                let (n, worst) = off(d, &want, 1e-5, 1e-5);
                assert_eq!(n, 0, "{what}: depth clip, worst {worst}");
                disoccluded += d.iter().filter(|&&v| v > 0.0).count();
            }
            // 3. Locks on the uploaded colour.
            if let Some(l) = &got.locks {
                assert_eq!(l, &reference::lock(&p, &got.prepared), "{what}: locks");
                locked += l.iter().filter(|&&v| v != 0).count();
            }
            // 4. Accumulate on the GPU's inputs and its previous history (the object test: the
            // square moves 2 render pixels a frame over a floor moving under 1).
            let ids: Vec<u32> = s.ids.iter().map(|id| id[0]).collect();
            let blank = vec![[0.0f32; 4]; (out.0 * out.1) as usize];
            let inputs = AccumulateInputs {
                prepared: &got.prepared,
                dilated: &got.dilated,
                disocclusion: got.disocclusion.as_deref(),
                new_locks: got.locks.as_deref(),
                history: if frame == 0 { &blank } else { &prev_h },
                aux: if frame == 0 { &blank } else { &prev_a },
                velocity: &s.velocity,
                ids: &ids,
                turns: c.reactive.then_some(&TURNS[..]),
            };
            let want = reference::accumulate(&p, &inputs);
            if c.reactive {
                let still = AccumulateInputs {
                    turns: None,
                    ..inputs
                };
                let without = reference::accumulate(&p, &still);
                reactive += (want.history.iter().zip(&without.history))
                    .filter(|(a, b)| a != b)
                    .count();
            }
            if c.ids {
                let without =
                    reference::accumulate(&reference::Params { ids: false, ..p }, &inputs);
                object_drops += (want.debug.iter().zip(&without.debug))
                    .filter(|(a, b)| a[0] == 1.0 && b[0] < 1.0)
                    .count();
            }
            // The box's edges come from exp() and a variance (m2 - mu^2) whose rounding differs
            // between lavapipe's JIT and Rust by ulps that the cancellation magnifies: a
            // clipped history may move by up to 2e-3 (perceptual units, the display range is
            // about 1). A wrong weight or kernel moves it by 0.1 or more.
            let (n, worst) = off(&flat(&got.history), &flat(&want.history), 2e-3, 2e-4);
            assert_eq!(n, 0, "{what}: history, worst {worst}");
            let (n, worst) = off(&flat(&got.aux), &flat(&want.aux), 2e-5, 2e-4);
            assert_eq!(n, 0, "{what}: history aux, worst {worst}");
            let (n, worst) = off(&flat(&got.accumulated), &flat(&want.color), 1e-3, 1e-2);
            assert_eq!(n, 0, "{what}: accumulated colour, worst {worst}");
            assert!(
                got.history.iter().flatten().all(|v| v.is_finite()),
                "{what}: NaN/Inf entered the history"
            );
            if frame > 0 {
                clipped_or_blended += want.debug.iter().filter(|d| d[3] > d[2]).count();
            }
            // 5. RCAS on the GPU's accumulation.
            if c.rcas {
                let (ow, oh) = (out.0 as usize, out.1 as usize);
                let mid = Rgb {
                    width: ow,
                    height: oh,
                    data: &got.accumulated,
                };
                let want = fsr1::rcas(&mid, c.sharpness_linear(), p.exposure);
                let (n, worst) = off(&flat(&got.color), &flat(&want), 1e-4, 2e-3);
                assert_eq!(n, 0, "{what}: RCAS, worst {worst}");
            } else {
                assert_eq!(got.color, got.accumulated, "{what}: without RCAS");
            }
            (prev_h, prev_a) = (got.history, got.aux);
        }
        // Not vacuous: the square disoccludes (depth clip and object test), the line and the dot
        // lock, history blends in.
        if c.depth_clip {
            assert!(disoccluded > 10, "{spec:?}: {disoccluded} disoccluded");
        }
        if c.locks {
            assert!(locked > 10, "{spec:?}: {locked} locks");
        }
        if c.ids {
            assert!(
                object_drops > 10,
                "{spec:?}: {object_drops} dropped by the object test"
            );
        }
        if c.reactive {
            assert!(
                reactive > 10,
                "{spec:?}: {reactive} pixels the reactive rule changed"
            );
        }
        assert!(
            clipped_or_blended > 500,
            "{spec:?}: {clipped_or_blended} blended"
        );
    }
    assert_clean(&gpu);
}

fn settings(w: u32, h: u32, s: &str) -> RenderSettings {
    RenderSettings::parse(w, h, s).expect("spec")
}

fn nonfinite(o: &FrameOutput) -> usize {
    o.color.iter().filter(|c| !c.to_f32().is_finite()).count()
}

/// The demo (moving camera, spinning torus) through `taau` with each kernel and option: no
/// validation message, every pixel finite, the debug layer's values in their ranges (the torus
/// and the moving camera disocclude, the lines lock, the history accumulates), and the
/// geometry of every option the same (the render sample under each pixel).
#[test]
fn taau_renders_the_demo_with_every_option() {
    let gpu = common::gpu();
    let (w, h) = (64u32, 36u32);
    let s = demo(w, h);
    let frames: Vec<u32> = (0..6).collect();
    let mut ids: Option<Vec<[u32; 2]>> = None;
    for spec in [
        "taau:debug",
        "taau:0.5:catmull:debug",
        "taau:0.77:bilinear:without-locks:without-depth-clip:without-rcas:without-stability",
        "taau:accum=16:moving=0.5:gamma=1.5:tol=0.1:sharpness=1",
        "taau:lod=-1",
    ] {
        let outs = render_settings(&gpu, &s, settings(w, h, spec), &frames);
        for (f, o) in outs.iter().enumerate() {
            assert_eq!(nonfinite(o), 0, "{spec} frame {f}");
        }
        let last = outs.last().expect("frames");
        if spec.contains("debug") {
            let ch = |c| last.channel::<f32>("taau", c).expect("debug layer");
            let (dis, lock, ws, hw) = (
                ch("disocclusion"),
                ch("lock"),
                ch("sample_weight"),
                ch("history_weight"),
            );
            let n = dis.len() as f32;
            assert!(dis.iter().all(|v| (0.0..=1.0).contains(v)), "{spec}");
            assert!(lock.iter().all(|v| (0.0..=1.0).contains(v)), "{spec}");
            assert!(ws.iter().all(|v| (0.0..=1.0).contains(v)), "{spec}");
            let frac = |v: &[f32], t: f32| v.iter().filter(|&&x| x > t).count() as f32 / n;
            eprintln!(
                "{spec}: disoccluded {:.3}, locked {:.3}, history weight over 1 {:.3}",
                frac(dis, 0.5),
                frac(lock, 0.0),
                frac(hw, 1.0)
            );
            assert!(frac(dis, 0.5) > 0.001, "{spec}: nothing disoccluded");
            assert!(frac(lock, 0.0) > 0.001, "{spec}: nothing locked");
            assert!(frac(hw, 1.0) > 0.3, "{spec}: no history accumulated");
        } else {
            assert!(
                last.layer("taau").is_none(),
                "{spec}: a debug layer without debug"
            );
        }
        // The same scene at the same render scale gives the same IDs whatever the options.
        if spec.starts_with("taau:accum") || spec == "taau:debug" {
            match &ids {
                None => ids = Some(last.ids.clone()),
                Some(i) => assert!(i == &last.ids, "{spec}: IDs differ"),
            }
        }
    }
    assert_clean(&gpu);
}

/// A camera cut (a key flagged `cut`) resets the history and the locks: the frame at the cut
/// is, bit for bit, the frame a fresh renderer makes of it; the frames around it blend.
#[test]
fn a_camera_cut_resets_taau() {
    let gpu = common::gpu();
    let (w, h) = (48u32, 27u32);
    let s = common::demo_with_cut(w, h, 4);
    let spec = "taau";
    let outs = render_settings(&gpu, &s, settings(w, h, spec), &(0..6).collect::<Vec<_>>());
    let alone = |f: u32| render_settings(&gpu, &s, settings(w, h, spec), &[f]).remove(0);
    assert!(
        outs[4].color == alone(4).color,
        "frame 4 (the cut) kept history"
    );
    assert!(outs[3].color != alone(3).color, "frame 3 blends history");
    assert!(outs[5].color != alone(5).color, "frame 5 blends again");
    assert_clean(&gpu);
}

/// Infinite light intensity in frame 3: the scene pass counts the NaN/Inf fragments and writes
/// them black, and no frame of `taau` has a non-finite pixel. (`taau`'s own guard against a
/// non-finite render sample is held by `every_pass_matches_its_cpu_reference_over_frames`,
/// whose frame 2 carries a NaN and an Inf: dropping the guard fails it there.)
#[test]
fn nan_and_inf_never_enter_the_taau_history() {
    let gpu = common::gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let mut poisoned = s.clone();
    for l in &mut poisoned.directional {
        l.intensity = f32::INFINITY;
    }
    for l in &mut poisoned.points {
        l.intensity = f32::INFINITY;
    }
    let shaders = cbr_render::shader_library();
    for spec in ["taau", "taau:catmull:without-locks"] {
        let mut r = Renderer::new(&gpu, &shaders, &s, settings(w, h, spec)).expect("renderer");
        for f in 0..6 {
            let o = r
                .render(if f == 3 { &poisoned } else { &s }, f)
                .expect("frame");
            assert_eq!(nonfinite(&o), 0, "{spec} frame {f}");
            if f == 3 {
                assert!(o.nonfinite_fragments.unwrap_or(0) > 0, "no injection");
            }
        }
    }
    assert_clean(&gpu);
}

/// A still camera over a static scene: after two jitter cycles the output changes frame to
/// frame by under a quarter of what it does with the history capped at one sample's weight
/// (`accum=1`: next to no accumulation); tests/stability.rs checks it then stays within one fp16
/// ulp of the converged cycle.
#[test]
fn taau_converges_on_a_static_scene() {
    let gpu = common::gpu();
    let (w, h) = (48u32, 27u32);
    let s = static_demo(w, h);
    let c = taau::parse(&[]).expect("default");
    let n = 2 * c.phases(w, h) + 8;
    let frames: Vec<u32> = (0..n).collect();
    let change = |spec: &str| {
        let outs = render_settings(&gpu, &s, settings(w, h, spec), &frames);
        let d = |a: &FrameOutput, b: &FrameOutput| {
            a.color
                .iter()
                .zip(&b.color)
                .map(|(x, y)| (x.to_f32() - y.to_f32()).abs())
                .sum::<f32>()
                / a.color.len() as f32
        };
        (n - 8..n)
            .map(|f| d(&outs[f as usize], &outs[f as usize - 1]))
            .sum::<f32>()
            / 8.0
    };
    let (full, one) = (change("taau"), change("taau:accum=1"));
    eprintln!("taau on a static scene, frame-to-frame change: {full:.5}; accum=1: {one:.5}");
    assert!(
        full < 0.25 * one,
        "change {full} vs {one} without accumulation"
    );
    assert_clean(&gpu);
}
