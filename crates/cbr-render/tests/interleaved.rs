//! `interleaved:MxN` (docs/interleaved.md): 1x1 is `deferred` with the same VPLs; the split,
//! subset shading and gather put each pixel's subset estimate where it belongs (against an f64
//! CPU model on the floor-and-wall scene); the geometry-aware filter is its CPU model too; and on
//! the demo the filter brings the frame closer to the reference than no filter, and than the box
//! at object edges. Lavapipe with validation on; every test fails on any validation message.
//!
//! The figures in docs/interleaved.md come from
//! `cargo test -p cbr-render --test interleaved -- --nocapture`.

mod common;

use cbr_gpu::Gpu;
use cbr_render::gpu_types::Vpl;
use cbr_render::{FrameOutput, RenderSettings, Renderer, Spec};
use cbr_scene::Scene;
use common::lighting::{compare, direct, floor_and_wall, fp16_step, irradiance, surface};
use common::{assert_clean, gpu};

fn render(gpu: &Gpu, shaders: &cbr_gpu::Shaders, s: &Scene, spec: &str) -> FrameOutput {
    let (w, h) = (s.settings.width, s.settings.height);
    let settings = RenderSettings::parse(w, h, spec).expect("spec");
    let mut r = Renderer::new(gpu, shaders, s, settings).expect("renderer");
    r.render(s, 0).expect("frame")
}

/// 1x1: one sub-image, every VPL, a window of one pixel: `deferred` within fp16 rounding (and
/// the same VPLs bit for bit).
#[test]
fn one_by_one_is_deferred() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (96, 54);
    let reference = render(&gpu, &shaders, &s, "deferred:vpls=256");
    for spec in ["interleaved:1x1:vpls=256", "interleaved:1x1:vpls=256:raw"] {
        let got = render(&gpu, &shaders, &s, spec);
        assert!(got.vpls == reference.vpls, "{spec}: other VPLs");
        let diff = compare(spec, &reference, &got);
        println!("{spec} against deferred:vpls=256: {diff:?}");
        assert!(diff.max_ulps <= 1, "{spec}: {diff:?}");
    }
    assert_clean(&gpu);
}

const CLAMP: f32 = 0.3;

/// Subset k of M x N: every (M N)-th VPL from the k-th.
fn subset(vpls: &[Vpl], k: usize, subsets: usize) -> impl Iterator<Item = &Vpl> {
    vpls.iter().skip(k).step_by(subsets)
}

fn subset_of(x: i64, y: i64, m: i64, n: i64) -> usize {
    (y.rem_euclid(n) * m + x.rem_euclid(m)) as usize
}

/// Checks every pixel of `out` (the floor-and-wall frame) against `want(x, y)` within 1.05 fp16
/// steps (as the deferred reference test: lavapipe's fp16 stores round towards zero); returns the
/// worst error in steps.
fn check(s: &Scene, out: &FrameOutput, want: impl Fn(u32, u32) -> Option<f64>) -> f64 {
    let (w, h) = (s.settings.width, s.settings.height);
    let mut worst = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            let Some(want) = want(x, y) else { continue };
            let got = f64::from(out.color[4 * (y * w + x) as usize].to_f32());
            let err = (got - want).abs() / fp16_step(want.max(1e-6));
            assert!(
                err <= 1.05,
                "pixel ({x}, {y}): {got} vs {want}: {err} fp16 steps"
            );
            worst = worst.max(err);
        }
    }
    worst
}

/// `raw` (no filter) on the floor-and-wall scene at 4x4 and 3x2: each pixel is the sun plus
/// albedo x M N x its own subset's irradiance, the subset given by its position (x mod M,
/// y mod N): the split, the subset shading and the gather are a permutation and its inverse.
#[test]
fn raw_pixels_hold_their_own_subset() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = floor_and_wall(true, 64, 48);
    for (m, n) in [(4u32, 4u32), (3, 2)] {
        let spec = format!("interleaved:{m}x{n}:vpls=96:rsm=64:clamp={CLAMP}:raw");
        let out = render(&gpu, &shaders, &s, &spec);
        let vpls = out.vpls.clone().expect("VPLs");
        let subsets = (m * n) as usize;
        let clamp_d2 = f64::from(CLAMP * CLAMP);
        let worst = check(&s, &out, |x, y| {
            let (p, normal, albedo) = surface(&s, out.ids[(y * 64 + x) as usize][0], x, y)?;
            let k = subset_of(x.into(), y.into(), m.into(), n.into());
            let e = subsets as f64 * irradiance(p, normal, subset(&vpls, k, subsets), clamp_d2);
            Some(direct(normal, albedo) + albedo * e)
        });
        println!("{spec}: worst {worst:.3} fp16 steps from the f64 model");
    }
    assert_clean(&gpu);
}

/// The geometry-aware filter against its f64 model on the floor-and-wall scene (4x4, 96 VPLs):
/// over the window, a neighbour on the same plane (same object: the floor and the wall are flat)
/// gives its own subset's estimate at its own point; a neighbour off the screen or on the other
/// object is replaced by its subset shaded at the pixel. `box` takes every on-screen neighbour.
#[test]
fn the_filters_match_their_cpu_model() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = floor_and_wall(true, 64, 48);
    let (m, n) = (4i64, 4i64);
    let subsets = 16usize;
    let clamp_d2 = f64::from(CLAMP * CLAMP);
    for (mode, geometric) in [("", true), (":box", false)] {
        let spec = format!("interleaved:4x4:vpls=96:rsm=64:clamp={CLAMP}{mode}");
        let out = render(&gpu, &shaders, &s, &spec);
        let vpls = out.vpls.clone().expect("VPLs");
        let id = |x: i64, y: i64| out.ids[(y * 64 + x) as usize][0];
        let worst = check(&s, &out, |x, y| {
            let (x, y) = (i64::from(x), i64::from(y));
            let (p, normal, albedo) = surface(&s, id(x, y), x as u32, y as u32)?;
            let mut sum = 0.0;
            for oy in -(n - 1) / 2..=n / 2 {
                for ox in -(m - 1) / 2..=m / 2 {
                    let (qx, qy) = (x + ox, y + oy);
                    let k = subset_of(qx, qy, m, n);
                    let on = (0..64).contains(&qx) && (0..48).contains(&qy);
                    let q = if on {
                        surface(&s, id(qx, qy), qx as u32, qy as u32)
                    } else {
                        None
                    };
                    let at = match q {
                        Some((pq, nq, _)) if !geometric || id(qx, qy) == id(x, y) => (pq, nq),
                        // `box` uses a background neighbour's estimate: zero.
                        None if on && !geometric => {
                            continue;
                        }
                        _ => (p, normal),
                    };
                    sum += subsets as f64
                        * irradiance(at.0, at.1, subset(&vpls, k, subsets), clamp_d2);
                }
            }
            Some(direct(normal, albedo) + albedo * sum / subsets as f64)
        });
        println!("{spec}: worst {worst:.3} fp16 steps from the f64 model");
    }
    assert_clean(&gpu);
}

/// Mean absolute difference of the colour channels, over all pixels and over `mask`.
fn error(a: &FrameOutput, b: &FrameOutput, mask: &[bool]) -> (f64, f64) {
    let (mut all, mut masked, mut count) = (0.0, 0.0, 0usize);
    for (i, (x, y)) in a.color.iter().zip(&b.color).enumerate() {
        if i % 4 == 3 {
            continue;
        }
        let d = (x.to_f64() - y.to_f64()).abs();
        all += d;
        if mask[i / 4] {
            masked += d;
            count += 1;
        }
    }
    (
        all / (a.color.len() * 3 / 4) as f64,
        masked / count.max(1) as f64,
    )
}

/// On the demo (160x90, 1024 VPLs, 4x4): the error against `deferred:vpls=1024` (every VPL at
/// every pixel) without a filter, with the box, with the geometry-aware filter. The geometry-aware
/// filter is closer than no filter everywhere, and closer than the box on the pixels whose window
/// holds another object (edges), where the box mixes two surfaces' light.
#[test]
fn the_geometry_aware_filter_beats_raw_and_box_at_edges() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    let (w, h) = (160i64, 90i64);
    (s.settings.width, s.settings.height) = (w as u32, h as u32);
    let reference = render(&gpu, &shaders, &s, "deferred:vpls=1024");
    let id =
        |x: i64, y: i64| reference.ids[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize][0];
    let edge: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            (-1..=2).any(|oy| (-1..=2).any(|ox| id(x + ox, y + oy) != id(x, y))) && id(x, y) != 0
        })
        .collect();
    let mut errors = Vec::new();
    for mode in ["raw", "box", "geometry"] {
        let spec = match mode {
            "geometry" => "interleaved:4x4:vpls=1024".to_string(),
            m => format!("interleaved:4x4:vpls=1024:{m}"),
        };
        let out = render(&gpu, &shaders, &s, &spec);
        let (all, at_edges) = error(&reference, &out, &edge);
        println!(
            "demo 160x90, {spec}: mean abs error {all:.4e}, at edges ({} px) {at_edges:.4e}",
            edge.iter().filter(|&&e| e).count()
        );
        errors.push((all, at_edges));
    }
    let [(raw, _), (_, box_edges), (geo, geo_edges)] = errors[..] else {
        unreachable!()
    };
    assert!(geo < raw, "geometry-aware {geo} vs raw {raw}");
    assert!(
        geo_edges < box_edges,
        "at edges: geometry-aware {geo_edges} vs box {box_edges}"
    );
    assert_clean(&gpu);
}

/// Sub-images and VPL counts that cannot work are refused, naming what would.
#[test]
fn bad_tiles_and_counts_are_refused() {
    for (spec, needle) in [
        ("interleaved", "MxN"),
        ("interleaved:4", "MxN"),
        ("interleaved:0x4", "from 1 to 8"),
        ("interleaved:9x1", "from 1 to 8"),
        ("interleaved:4x4:vpls=1000", "a positive multiple of 16"),
        ("interleaved:4x4:vpls=0", "a positive multiple of 16"),
        ("interleaved:4x4:vpls=99999", "at most 16384"),
        ("interleaved:4x4:sharp", "not a parameter of interleaved"),
    ] {
        let err = Spec::parse(spec).expect_err(spec);
        assert!(err.contains(needle), "{spec}: {err}");
    }
    assert!(Spec::parse("interleaved:4x4").is_ok());
    assert!(Spec::parse("interleaved:2x3:vpls=600:box:rsm=256").is_ok());
}
