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
use common::{assert_clean, demo, render_spec};
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
            let (mut v, mut d, mut id) = ([0.4f32, 0.0], 0.05f32, 1u32);
            if y < 2 {
                (c, v, d, id) = ([0.5, 0.6, 0.9], [0.0, 0.0], 0.0, 0);
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
        if !(d <= abs + rel * w.abs()) {
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
        recon: recon.as_ref().map(f32s),
        disocclusion: dis.as_ref().map(f32s),
        locks: locks.as_ref().map(f32s),
        history: f32s(&h_rb),
        aux: f32s(&a_rb),
        accumulated: f16x4(&acc),
        color: f16x4(&c_rb),
    }
}

/// Each pass against its reference, frames 0-4 (frame 0 and 3 reset... frame 0 only), for
/// the default and every option that changes a shader.
#[test]
fn every_pass_matches_its_cpu_reference_over_frames() {
    let gpu = common::gpu();
    let shaders = cbr_render::shader_library();
    let out = (32u32, 18u32);
    for spec in [
        &[][..],
        &["catmull", "without-stability"],
        &["bilinear", "without-locks", "without-rcas"],
        &["0.5", "without-depth-clip", "sharpness=1", "debug"],
    ] {
        let c = taau::parse(spec).expect("spec");
        let (w, h) = c.render_resolution(out.0, out.1);
        let targets = FrameTargets::new(&gpu, "t.render", w, h).expect("targets");
        let passes = TaauPasses::new(&gpu, &shaders, &c, out).expect("passes");
        let phases = c.phases(out.0, out.1);
        let (mut prev_h, mut prev_a): (Vec<V4>, Vec<V4>) = (Vec::new(), Vec::new());
        let (mut locked, mut disoccluded, mut clipped_or_blended) = (0usize, 0usize, 0usize);
        for frame in 0..5u32 {
            let s = synthetic(w as usize, h as usize, frame as usize);
            upload(&gpu, &targets, &s);
            let f = TaauFrame {
                frame,
                reset: frame == 0,
                jitter: taau::jitter(phases, frame),
                exposure_stops: 0.5,
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
            // 2. Depth clip on the GPU's dilated frame and reconstruction.
            if let (Some(d), Some(r)) = (&got.disocclusion, &got.recon) {
                let want = reference::depth_clip(&p, &got.dilated, r);
                let (n, worst) = off(d, &want, 1e-5, 1e-5);
                assert_eq!(n, 0, "{what}: depth clip, worst {worst}");
                disoccluded += d.iter().filter(|&&v| v > 0.0).count();
            }
            // 3. Locks on the uploaded colour.
            if let Some(l) = &got.locks {
                assert_eq!(l, &reference::lock(&p, &s.color), "{what}: locks");
                locked += l.iter().filter(|&&v| v != 0).count();
            }
            // 4. Accumulate on the GPU's inputs and its previous history.
            let blank = vec![[0.0f32; 4]; (out.0 * out.1) as usize];
            let inputs = AccumulateInputs {
                color: &s.color,
                dilated: &got.dilated,
                disocclusion: got.disocclusion.as_deref(),
                new_locks: got.locks.as_deref(),
                history: if frame == 0 { &blank } else { &prev_h },
                aux: if frame == 0 { &blank } else { &prev_a },
            };
            let want = reference::accumulate(&p, &inputs);
            let (n, worst) = off(&flat(&got.history), &flat(&want.history), 2e-5, 2e-4);
            assert_eq!(n, 0, "{what}: history, worst {worst}");
            let (n, worst) = off(&flat(&got.aux), &flat(&want.aux), 2e-5, 2e-4);
            assert_eq!(n, 0, "{what}: history aux, worst {worst}");
            let (n, worst) = off(&flat(&got.accumulated), &flat(&want.color), 1e-4, 2e-3);
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
        // Not vacuous: the square disoccludes, the line and the dot lock, history blends in.
        if c.depth_clip {
            assert!(disoccluded > 10, "{spec:?}: {disoccluded} disoccluded");
        }
        if c.locks {
            assert!(locked > 10, "{spec:?}: {locked} locks");
        }
        assert!(clipped_or_blended > 500, "{spec:?}: {clipped_or_blended} blended");
    }
    assert_clean(&gpu);
}
