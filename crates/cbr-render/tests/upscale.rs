//! `upscale:fsr1` on lavapipe with validation on: EASU and RCAS against their CPU reference
//! (src/techniques/upscale/reference.rs) on synthetic low-resolution frames (edges at many
//! angles, a disc, one-texel lines, noise, HDR up to 60, black), at two scales and two
//! exposures; the demo rendered with no validation message; bad parameters refused in one line.

mod common;

use cbr_gpu::{Gpu, Image, Profiler, Readback};
use cbr_render::targets::FrameTargets;
use cbr_render::upscale::reference::{self, Rgb};
use cbr_render::upscale::{self, UpscalePass};
use common::{assert_clean, demo, render_spec};
use half::f16;

/// xorshift64*: deterministic synthetic data without a dependency.
struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A low-resolution frame: bands with a straight edge at an angle that changes per band, a
/// bright disc, one-texel lines (a ridge, which EASU must not treat as an edge), a noisy
/// corner, black, and HDR values; each colour rounded to f16 as the target stores it.
fn synthetic(w: usize, h: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut r = Rng(seed | 1);
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            let angle = 0.4 + 1.3 * (y * 4 / h) as f32;
            let side = (fx - w as f32 / 2.0) * angle.cos() + (fy - h as f32 / 2.0) * angle.sin();
            let mut c = if side > 0.0 {
                [2.5, 1.2, 0.3]
            } else {
                [0.05, 0.1, 0.4]
            };
            let (dx, dy) = (fx - w as f32 * 0.7, fy - h as f32 * 0.3);
            if dx * dx + dy * dy < (h as f32 / 5.0).powi(2) {
                c = [60.0, 40.0, 20.0];
            }
            if x == w / 4 || y == h - 3 {
                c = [0.9, 0.9, 0.9];
            }
            if x < w / 5 && y < h / 3 {
                c = [r.unit() * 4.0, r.unit(), r.unit() * 0.5];
            }
            if x + 2 >= w && y < 3 {
                c = [0.0; 3];
            }
            out.push(c.map(|v| f16::from_f32(v).to_f32()));
        }
    }
    out
}

fn rgb_of(rb: &Readback) -> Vec<[f32; 3]> {
    let px: &[f16] = bytemuck::cast_slice(rb.bytes().expect("readback"));
    px.chunks(4)
        .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32()])
        .collect()
}

/// Pixels whose channels differ from the reference by more than the bound: f16 storage
/// (2^-11 relative) and f32 arithmetic in another order (lavapipe may fuse, its square roots
/// and divisions round differently), 2e-3 relative + 1e-5. Returns (count, worst relative).
fn mismatches(got: &[[f32; 3]], want: &[[f32; 3]]) -> (usize, f32) {
    let mut bad = 0;
    let mut worst = 0.0f32;
    for (g, r) in got.iter().zip(want) {
        let mut over = false;
        for k in 0..3 {
            let err = (g[k] - r[k]).abs();
            worst = worst.max(err / r[k].abs().max(1e-3));
            over |= err > 2e-3 * r[k].abs() + 1e-5;
        }
        bad += usize::from(over);
    }
    (bad, worst)
}

struct Run {
    easu: Vec<[f32; 3]>,
    out: Vec<[f32; 3]>,
    ids: Vec<[u32; 2]>,
}

/// The low frame uploaded, `spec`'s upscale recorded at `exposure` stops, its EASU output,
/// final colour and IDs read back.
fn run(
    gpu: &Gpu,
    low: (u32, u32),
    out: (u32, u32),
    colour: &[[f32; 3]],
    spec: &[&str],
    exposure: f32,
) -> Run {
    let shaders = cbr_render::shader_library();
    let targets = FrameTargets::new(gpu, "test.low", low.0, low.1).expect("targets");
    let n = (low.0 * low.1) as usize;
    let rgba: Vec<f16> = colour
        .iter()
        .flat_map(|c| [c[0], c[1], c[2], 1.0].map(f16::from_f32))
        .collect();
    let ids: Vec<u32> = (0..n as u32).flat_map(|i| [i, 7]).collect();
    let velocity = vec![0.0f32; 2 * n];
    let depth = vec![0.5f32; n];
    common::upload(
        gpu,
        &[
            (&targets.color, bytemuck::cast_slice(&rgba).to_vec()),
            (&targets.velocity, bytemuck::cast_slice(&velocity).to_vec()),
            (&targets.ids, bytemuck::cast_slice(&ids).to_vec()),
            (&targets.depth, bytemuck::cast_slice(&depth).to_vec()),
        ],
    )
    .expect("upload");
    let config = upscale::parse(spec).expect("spec");
    let pass = UpscalePass::new(gpu, &shaders, &config, &targets, out.0, out.1).expect("pass");
    let easu: &Image = pass.easu().expect("fsr1 has an EASU output");
    let [color, _, _, ids_img] = pass.layers().expect("layers");
    let rb = |name, img| Readback::for_image(gpu, name, img).expect("readback");
    let (rb_easu, rb_out, rb_ids) = (
        rb("test.easu", easu),
        rb("test.out", color),
        rb("test.ids", ids_img),
    );
    let mut profiler = Profiler::new(gpu, "test.profiler", 4).expect("profiler");
    profiler.begin_frame();
    gpu.submit("test.upscale", |cmd| {
        pass.record(cmd, &mut profiler, &targets, exposure)?;
        cmd.read_image(easu, &rb_easu);
        cmd.read_image(color, &rb_out);
        cmd.read_image(ids_img, &rb_ids);
        Ok(())
    })
    .expect("submit");
    Run {
        easu: rgb_of(&rb_easu),
        out: rgb_of(&rb_out),
        ids: bytemuck::cast_slice(rb_ids.bytes().expect("ids")).to_vec(),
    }
}

/// EASU against the reference on the same low frame; RCAS against the reference applied to
/// the GPU's own EASU output (so EASU's differences do not carry into RCAS's comparison).
#[test]
fn easu_and_rcas_match_their_cpu_reference_on_synthetic_frames() {
    let gpu = common::gpu();
    for (low, out, spec, exposure) in [
        ((23u32, 17u32), (32u32, 24u32), &["fsr1"][..], 0.0f32),
        ((16, 9), (32, 18), &["fsr1", "0.5", "sharpness=0"], -1.5),
        ((25, 18), (32, 24), &["fsr1", "0.77", "sharpness=1"], 2.0),
    ] {
        let colour = synthetic(low.0 as usize, low.1 as usize, 0x5eed + u64::from(low.0));
        let got = run(&gpu, low, out, &colour, spec, exposure);
        let c = upscale::parse(spec).expect("spec");
        assert_eq!(c.low_resolution(out.0, out.1), low, "{spec:?}");
        let e = exposure.exp2();
        let (w, h) = (out.0 as usize, out.1 as usize);
        let lo = Rgb {
            width: low.0 as usize,
            height: low.1 as usize,
            data: &colour,
        };
        let want_easu = reference::easu(&lo, w, h, e);
        let (bad, worst) = mismatches(&got.easu, &want_easu);
        assert!(
            bad == 0,
            "{spec:?} EASU: {bad} of {} pixels off (worst {worst})",
            w * h
        );
        let mid = Rgb {
            width: w,
            height: h,
            data: &got.easu,
        };
        let want_out = reference::rcas(&mid, c.sharpness_linear(), e);
        let (bad, worst) = mismatches(&got.out, &want_out);
        assert!(
            bad == 0,
            "{spec:?} RCAS: {bad} of {} pixels off (worst {worst})",
            w * h
        );
        // Not vacuous: RCAS changed pixels, and EASU is not the bilinear upscale.
        let moved = got
            .out
            .iter()
            .zip(&got.easu)
            .filter(|(a, b)| a != b)
            .count();
        assert!(moved > w * h / 10, "{spec:?}: RCAS changed {moved} pixels");
        // IDs: the nearest low-resolution texel, as every filter's.
        for (i, id) in got.ids.iter().enumerate() {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let nx = ((x * low.0 as f32 / w as f32) as u32).min(low.0 - 1);
            let ny = ((y * low.1 as f32 / h as f32) as u32).min(low.1 - 1);
            assert_eq!(*id, [ny * low.0 + nx, 7], "pixel {i}");
        }
    }
    assert_clean(&gpu);
}

/// The demo through `upscale:fsr1` at two scales: no validation message, finite colour, both
/// passes timed, the geometry bilinear's own (the same nearest samples), and the frame's mean
/// within 5% of the bilinear upscale's at the same LOD bias (FSR sharpens; it does not brighten
/// or darken: measured 3.3% at 1/sqrt(2), where the -0.5 bias gives it more texture contrast).
#[test]
fn fsr1_renders_the_demo_with_no_validation_message() {
    let gpu = common::gpu();
    let s = demo(64, 36);
    let mean = |o: &cbr_render::FrameOutput| {
        o.color.iter().map(|v| f64::from(v.to_f32())).sum::<f64>() / o.color.len() as f64
    };
    for (fsr, bilinear) in [
        // The same raster: fsr1's default LOD bias is log2(SCALE), bilinear's 0.
        ("upscale:fsr1", "upscale:bilinear:lod=-0.5"),
        (
            "upscale:fsr1:0.5:sharpness=0",
            "upscale:bilinear:0.5:lod=-1",
        ),
    ] {
        let f = render_spec(&gpu, &s, fsr, &[0, 3]);
        let b = render_spec(&gpu, &s, bilinear, &[0, 3]);
        for (a, b) in f.iter().zip(&b) {
            assert!(a.color.iter().all(|v| v.is_finite()), "{fsr}");
            for pass in ["upscale.easu", "upscale.rcas"] {
                assert!(a.timings.iter().any(|t| t.name == pass), "{fsr}: {pass}");
            }
            assert_eq!(
                (&a.ids, &a.depth, &a.velocity),
                (&b.ids, &b.depth, &b.velocity)
            );
            let (ma, mb) = (mean(a), mean(b));
            assert!((ma / mb - 1.0).abs() < 0.05, "{fsr}: mean {ma} vs {mb}");
            assert_ne!(a.color, b.color, "{fsr}");
        }
    }
    assert_clean(&gpu);
}

/// A bad scale or sharpness is one line naming the parameter, refused when the spec is read.
#[test]
fn bad_upscale_parameters_are_one_clear_error() {
    for (spec, says) in [
        ("upscale:fsr1:1.5", "scale `1.5`"),
        ("upscale:fsr1:0", "scale `0`"),
        ("upscale:fsr1:sharpness=5", "sharpness `5`"),
        ("upscale:bicubic:sharpness=0.5", "fsr1 only"),
        ("upscale:fsr1:0.5:0.6", "one scale"),
        ("upscale:fsr2", "`fsr2` is not a parameter of upscale"),
    ] {
        let e = cbr_render::RenderSettings::parse(64, 36, spec).expect_err(spec);
        assert!(e.contains(says), "{spec}: {e}");
        assert_eq!(e.lines().count(), 1, "{spec}: {e}");
    }
}
