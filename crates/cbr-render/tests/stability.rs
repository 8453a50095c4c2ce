//! Numerical stability on the hard-case gallery's stability scenes (docs/hard-cases.md):
//! NaN/Inf containment through every history, geometry far from the origin (placed there, and read
//! from an OBJ whose own coordinates are far), depth precision at a large far/near ratio
//! (reverse-Z), and drift of a static scene through the resolve and TAA.
//! Lavapipe with validation on; every test fails on any validation message.
//!
//! The figures in docs/hard-cases.md come from these tests with larger settings:
//! `CBR_DRIFT_FRAMES=1000 cargo test --release -p cbr-render --test stability drift -- --nocapture`
//! and `cargo test --release -p cbr-render --test stability far -- --nocapture`.

mod common;

use cbr_render::{AnalyticLayers, FrameOutput, RenderSettings, Renderer};
use cbr_scene::Scene;
use common::{assert_clean, gpu, render_spec as render};

fn case(name: &str, w: u32, h: u32) -> Scene {
    let mut s = cbr_scene::builtin(name).expect("built-in case");
    (s.settings.width, s.settings.height) = (w, h);
    s
}

fn color_bits(o: &FrameOutput) -> Vec<u16> {
    o.color.iter().map(|c| c.to_bits()).collect()
}

// ---- NaN and Inf containment -------------------------------------------------------------

/// Every technique and temporal chain: with a material whose shading is NaN and one whose
/// shading is infinite, the frames are those of the same scene with both materials black, bit
/// for bit, over five frames (so through every history), and each frame counts the fragments.
#[test]
fn nan_and_inf_are_counted_and_never_spread() {
    let gpu = gpu();
    let bad = case("nan", 64, 36);
    let mut black = bad.clone();
    for m in &mut black.materials {
        if m.name == "nan" || m.name == "inf" {
            (m.kd, m.ke) = ([0.0; 3], [0.0; 3]);
        }
    }
    let frames = [0, 1, 2, 3, 4];
    for spec in [
        "native",
        "msaa:4",
        "ssaa:2",
        "checkerboard:rotated:ours",
        "checkerboard:split:ours",
        "checkerboard:rotated:pq4k",
        "checkerboard:rotated:fused",
        "interlaced",
        "upscale:bilinear",
        "native+fxaa",
        "native+taa",
        "native+taa:inside",
        "checkerboard:rotated:ours+taa",
        "taau",
        "checkerboard:split:ours+sharpen",
    ] {
        let a = render(&gpu, &bad, spec, &frames);
        let b = render(&gpu, &black, spec, &frames);
        for (fa, fb) in a.iter().zip(&b) {
            assert!(
                fa.color.iter().all(|c| c.is_finite()),
                "{spec} frame {}: a non-finite pixel",
                fa.index
            );
            assert!(
                color_bits(fa) == color_bits(fb),
                "{spec} frame {}: differs from the scene with black materials",
                fa.index
            );
            assert!(
                fa.nonfinite_fragments.unwrap_or(0) > 0,
                "{spec} frame {}: no non-finite fragment counted",
                fa.index
            );
            assert_eq!(
                fb.nonfinite_fragments,
                Some(0),
                "{spec}: counted on a clean scene"
            );
        }
    }
    // analytic shades in its own pass: it drops the fragment (what is behind shows) and flags
    // the pixel.
    for f in render(&gpu, &bad, "analytic", &frames) {
        assert!(
            f.color.iter().all(|c| c.is_finite()),
            "analytic: a non-finite pixel"
        );
        let layers = AnalyticLayers::from_frame(&f).expect("analytic layers");
        let flagged = layers.nonfinite.iter();
        assert!(
            flagged.filter(|&&n| n != 0).count() > 0,
            "analytic flagged nothing"
        );
    }
    assert_clean(&gpu);
}

// ---- Far from the origin -----------------------------------------------------------------

struct Diff {
    mean_abs: f64,
    max_abs: f64,
    /// Pixels whose colour differs by more than 1/256 in a channel.
    pixels: f64,
    /// Pixels whose object ID differs.
    ids: f64,
}

fn diff(a: &FrameOutput, b: &FrameOutput) -> Diff {
    let n = a.ids.len() as f64;
    let (mut sum, mut max, mut pixels) = (0.0f64, 0.0f64, 0usize);
    for (pa, pb) in a.color.chunks(4).zip(b.color.chunks(4)) {
        let mut worst = 0.0f64;
        for k in 0..3 {
            let d = (f64::from(pa[k].to_f32()) - f64::from(pb[k].to_f32())).abs();
            sum += d / 3.0;
            worst = worst.max(d);
        }
        max = max.max(worst);
        pixels += usize::from(worst > 1.0 / 256.0);
    }
    let ids = a
        .ids
        .iter()
        .zip(&b.ids)
        .filter(|(x, y)| x[0] != y[0])
        .count();
    Diff {
        mean_abs: sum / n,
        max_abs: max,
        pixels: pixels as f64 / n,
        ids: ids as f64 / n,
    }
}

const TABLE_HEAD: &str =
    "| distance | mean abs | max abs | pixels off > 1/256 | IDs off |\n|---|---|---|---|---|";

/// One row of the far-from-origin table; returns the difference.
fn row(d: f64, a: &FrameOutput, o: &FrameOutput) -> Diff {
    let e = diff(a, o);
    println!(
        "| {d:.0e} m (frame {}) | {:.2e} | {:.2e} | {:.3}% | {:.3}% |",
        a.index,
        e.mean_abs,
        e.max_abs,
        100.0 * e.pixels,
        100.0 * e.ids
    );
    e
}

/// The same small scene at 1 m, 1 km, 100 km and 1,000 km from the origin, the camera following:
/// against the copy at the origin, the error stays flat (asserted at 1,000 km). Objects keep f32
/// vertices about an f64 origin and the renderer forms camera-relative transforms in f64.
#[test]
fn far_from_the_origin_matches_the_origin_copy() {
    let gpu = gpu();
    let (w, h) = (160, 90);
    let frames = [0, 5];
    let at = |d: f64| {
        let mut s = cbr_scene::cases::far(d);
        (s.settings.width, s.settings.height) = (w, h);
        s
    };
    // The contrast: the same scene with the placement folded into f32 world-space vertices (what
    // a renderer without per-object f64 origins stores). The test must tell the two apart.
    let naive = |d: f64| {
        let mut s = at(d);
        for o in &mut s.objects {
            let off = std::mem::replace(&mut o.origin, [0.0; 3]);
            for v in &mut o.vertices {
                v.pos = [0, 1, 2].map(|k| (off[k] + f64::from(v.pos[k])) as f32);
            }
        }
        s
    };
    let origin = render(&gpu, &at(0.0), "native", &frames);
    println!("native, f32 world-space vertices (the contrast): against the copy at the origin");
    println!("{TABLE_HEAD}");
    for d in [1.0, 1e3, 1e5, 1e6] {
        let away = render(&gpu, &naive(d), "native", &frames);
        for (a, o) in away.iter().zip(&origin) {
            let e = row(d, a, o);
            if d == 1e6 {
                assert!(
                    e.pixels > 0.01,
                    "f32 world vertices at 1,000 km look right: the test cannot see the failure"
                );
            }
        }
    }
    for spec in ["native", "checkerboard:rotated:ours"] {
        let origin = render(&gpu, &at(0.0), spec, &frames);
        println!("{spec} at {w}x{h}, frames {frames:?}: against the copy at the origin");
        println!("{TABLE_HEAD}");
        for d in [1.0, 1e3, 1e5, 1e6] {
            let away = render(&gpu, &at(d), spec, &frames);
            for (a, o) in away.iter().zip(&origin) {
                // Measured: bit for bit the origin copy at every distance (the camera-relative
                // transforms are formed in f64 and differ from the origin copy's by ~1e-10 m).
                if d == 1e6 {
                    assert!(
                        color_bits(a) == color_bits(o) && a.ids == o.ids,
                        "{spec} at 1,000 km, frame {}: not the origin copy's pixels",
                        a.index
                    );
                }
                let e = row(d, a, o);
                if d == 1e6 {
                    assert!(
                        e.mean_abs < 1e-3 && e.pixels < 0.005 && e.ids < 0.005,
                        "{spec} at 1,000 km, frame {}: mean {:.2e}, {:.3}% pixels, {:.3}% IDs off",
                        a.index,
                        e.mean_abs,
                        100.0 * e.pixels,
                        100.0 * e.ids
                    );
                }
            }
        }
    }
    assert_clean(&gpu);
}

/// Loads `cases::far_obj(d)`: an OBJ whose vertices, camera keys and point light carry the
/// distance themselves (x and z shifted by `d`), at `w` x `h`.
fn far_obj(d: f64, w: u32, h: u32) -> Scene {
    let files = cbr_scene::cases::far_obj(d);
    let opts = cbr_scene::LoadOptions::default();
    let mut s =
        cbr_scene::load_from(&files, "far/far.toml", &opts).unwrap_or_else(|e| panic!("{e}"));
    (s.settings.width, s.settings.height) = (w, h);
    s
}

/// How many fp16 steps apart two finite colour channels are (0: the same bits).
fn half_steps(a: half::f16, b: half::f16) -> u32 {
    // Ordered integers for IEEE halves: negative values mirrored below zero.
    let key = |x: half::f16| {
        let b = i32::from(x.to_bits());
        if b & 0x8000 != 0 { -(b & 0x7fff) } else { b }
    };
    key(a).abs_diff(key(b))
}

/// The largest number of fp16 steps between two frames' colours, and the share of pixels with a
/// channel more than one step apart.
fn steps(a: &FrameOutput, b: &FrameOutput) -> (u32, f64) {
    let (mut worst, mut over) = (0, 0usize);
    for (pa, pb) in a.color.chunks(4).zip(b.color.chunks(4)) {
        let s = (0..3).map(|k| half_steps(pa[k], pb[k])).max().unwrap_or(0);
        worst = worst.max(s);
        over += usize::from(s > 1);
    }
    (worst, over as f64 / a.ids.len() as f64)
}

/// An OBJ whose own vertices are far from the origin (a mesh exported in world coordinates, as
/// georeferenced city models, CAD and survey data are): `cases::far_obj` written 1 km, 100 km,
/// 1,000 km and 10,000 km from the origin (vertices, camera keys and point light shifted in x and
/// z), against the same files at the origin, frames 0 and 5 at 320x180. The loader reads the
/// positions in f64 and recentres each object about its bounds into its f64 origin: `native` and
/// `checkerboard:rotated:ours` render every colour within one fp16 step of the origin copy's (as
/// loaded, and stored about its centre as the far copies are), every object ID the same, and every
/// distance the 1 km copy's bits. The contrast: the same far objects with their vertices as f32
/// world coordinates about origin 0 (what the f32 loader stored) is visibly wrong at 1,000 km.
#[test]
fn far_coordinates_in_an_obj_match_the_origin_copy() {
    let gpu = gpu();
    let (w, h) = (320, 180);
    let frames = [0, 5];
    let distances = [1e3, 1e5, 1e6, 1e7];
    let folded = |d: f64| {
        let mut s = far_obj(d, w, h);
        for o in &mut s.objects {
            assert_ne!(o.origin, [0.0; 3], "{} at {d:e} m: not recentred", o.name);
            let off = std::mem::replace(&mut o.origin, [0.0; 3]);
            for v in &mut o.vertices {
                v.pos = [0, 1, 2].map(|k| (off[k] + f64::from(v.pos[k])) as f32);
            }
        }
        s
    };
    println!("native, f32 world-space vertices read from the file (the contrast)");
    println!("{TABLE_HEAD}");
    let origin = render(&gpu, &far_obj(0.0, w, h), "native", &frames);
    for d in distances {
        for (a, o) in render(&gpu, &folded(d), "native", &frames)
            .iter()
            .zip(&origin)
        {
            let e = row(d, a, o);
            if d == 1e6 {
                assert!(
                    e.pixels > 0.01,
                    "f32 vertices at 1,000 km look right: the test cannot see the failure"
                );
            }
        }
    }
    // The origin copy with each object stored about its bounds' centre, as the far copies are
    // (the loader keeps objects near the origin absolute, in the f32 vertices they always had).
    let centred = || {
        let mut s = far_obj(0.0, w, h);
        for o in &mut s.objects {
            let c = cbr_scene::scene::bounds_of(std::slice::from_ref(o)).center();
            o.origin = c.to_array();
            for v in &mut o.vertices {
                v.pos = [0, 1, 2].map(|k| (f64::from(v.pos[k]) - c[k]) as f32);
            }
        }
        s
    };
    for spec in ["native", "checkerboard:rotated:ours"] {
        let origin = render(&gpu, &far_obj(0.0, w, h), spec, &frames);
        let origin_centred = render(&gpu, &centred(), spec, &frames);
        println!(
            "{spec} at {w}x{h}, frames {frames:?}: against the copy at the origin as loaded (absolute) / stored about its centre"
        );
        println!(
            "| distance | largest fp16 steps | channels off at all | pixels > 1 step | largest steps, centred copy |\n|---|---|---|---|---|"
        );
        let mut first: Option<Vec<FrameOutput>> = None;
        for d in distances {
            let away = render(&gpu, &far_obj(d, w, h), spec, &frames);
            for ((a, o), c) in away.iter().zip(&origin).zip(&origin_centred) {
                let (worst, over) = steps(a, o);
                let differ = color_bits(a)
                    .iter()
                    .zip(color_bits(o))
                    .filter(|(x, y)| **x != *y)
                    .count() as f64
                    / a.color.len() as f64;
                let (worst_c, _) = steps(a, c);
                println!(
                    "| {d:.0e} m (frame {}) | {worst} | {:.2}% of channels | {:.3}% | {worst_c} |",
                    a.index,
                    100.0 * differ,
                    100.0 * over
                );
                // Within fp16 rounding (one step) of the origin copy as loaded (absolute f32
                // vertices) and of the one stored about its centre; IDs exact.
                assert!(
                    worst <= 1 && worst_c <= 1 && a.ids == o.ids,
                    "{spec} at {d:e} m, frame {}: {worst} fp16 steps from the origin copy ({:.3}% pixels over one), {worst_c} from the centred one, IDs {}",
                    a.index,
                    100.0 * over,
                    if a.ids == o.ids { "the same" } else { "differ" }
                );
            }
            // The error stays flat: every distance renders the 1 km copy's bits.
            match &first {
                None => first = Some(away),
                Some(f) => {
                    for (a, b) in away.iter().zip(f) {
                        assert!(
                            color_bits(a) == color_bits(b) && a.ids == b.ids,
                            "{spec} at {d:e} m, frame {}: not the 1 km copy's bits",
                            a.index
                        );
                    }
                }
            }
        }
    }
    assert_clean(&gpu);
}

// ---- Depth precision ---------------------------------------------------------------------

/// `zfight`: near plane 1 mm, a decal 2 cm above a ground plane out to 2 km and a wall 10 cm
/// before another at 500 m. Reverse-Z with a float depth buffer resolves both: every pixel where
/// the nearer surface is drawn alone shows it when both are drawn.
#[test]
fn reverse_z_resolves_a_large_far_near_ratio() {
    let gpu = gpu();
    let (w, h) = (320, 180);
    let full = case("zfight", w, h);
    let id = |name: &str| full.objects.iter().position(|o| o.name == name).unwrap() as u32 + 1;
    for (near, far) in [("decal", "ground"), ("front_wall", "back_wall")] {
        // The nearer surface alone: the same objects with the farther one moved out of sight.
        let mut alone = full.clone();
        let k = id(far) as usize - 1;
        alone.objects[k].origin = [0.0, -1.0e4, 0.0];
        let (near_id, far_id) = (id(near), id(far));
        for f in [0, 8] {
            let a = &render(&gpu, &alone, "native", &[f])[0];
            let b = &render(&gpu, &full, "native", &[f])[0];
            let covered = a.ids.iter().filter(|i| i[0] == near_id).count();
            let lost = a
                .ids
                .iter()
                .zip(&b.ids)
                .filter(|(x, y)| x[0] == near_id && y[0] == far_id)
                .count();
            println!("{near} over {far}, frame {f}: {lost} of {covered} pixels lost");
            assert!(covered > 100, "{near} covers only {covered} pixels");
            assert_eq!(lost, 0, "{near} loses {lost} of {covered} pixels to {far}");
        }
    }
    assert_clean(&gpu);
}

// ---- Drift -------------------------------------------------------------------------------

/// fp16 ulps between two non-negative halves (their bit patterns are ordered like the values).
fn ulps(a: half::f16, b: half::f16) -> u32 {
    u32::from(a.to_bits().abs_diff(b.to_bits()))
}

/// A static scene through the resolve and TAA: after convergence every frame is within one fp16
/// ulp of the converged frame at the same phase of the jitter and parity cycle (16 frames covers
/// the checkerboard's 2, TAA's 8 and 16, taau's 16 at 64x36). `CBR_DRIFT_FRAMES` (default 320) sets the length; the
/// first half (rounded to the cycle) settles (checkerboard + TAA needs about 140 frames to be
/// exactly periodic).
#[test]
fn drift_a_static_scene_stays_within_one_ulp() {
    let gpu = gpu();
    let n: u32 = std::env::var("CBR_DRIFT_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(320)
        .max(64);
    let (w, h) = (64, 36);
    let s = common::static_demo(w, h);
    const PERIOD: u32 = 16;
    let verbose = std::env::var("CBR_DRIFT_VERBOSE").is_ok();
    let specs = std::env::var("CBR_DRIFT_SPECS").unwrap_or_else(|_| {
        "checkerboard:rotated:ours,checkerboard:split:ours,native+taa,checkerboard:rotated:ours+taa,\
         checkerboard:rotated:fused,taau"
            .into()
    });
    for spec in specs.split(',') {
        // taau's history is an average whose new sample may weigh as little as 0.15 against the
        // history's 8 (a sample far from the pixel): it takes about 400 frames to come within
        // one fp16 ulp of its cycle, so it runs 1000 (measured: 0 ulp from frame 512 on; at
        // 320 frames it is still 192 ulps away on a dark pixel).
        let n = if spec.starts_with("taau") {
            n.max(1000)
        } else {
            n
        };
        let settle = (n / 2).next_multiple_of(PERIOD) - PERIOD;
        let shaders = cbr_render::shader_library();
        let settings = RenderSettings::parse(w, h, spec).expect("spec");
        let mut r = Renderer::new(&gpu, &shaders, &s, settings).expect("renderer");
        let mut converged: Vec<Vec<half::f16>> = Vec::new();
        let (mut worst, mut worst_at, mut over) = (0u32, 0u32, 0usize);
        for f in 0..n {
            let out = r.render(&s, f).expect("frame");
            if f < settle {
                continue;
            }
            if f < settle + PERIOD {
                converged.push(out.color.clone());
                continue;
            }
            let c = &converged[((f - settle) % PERIOD) as usize];
            let d = out
                .color
                .iter()
                .zip(c)
                .map(|(&a, &b)| ulps(a, b))
                .max()
                .unwrap_or(0);
            over += usize::from(d > 1);
            if verbose {
                println!("{spec} frame {f}: {d} ulp");
            }
            if d > worst {
                (worst, worst_at) = (d, f);
            }
        }
        println!(
            "{spec}: {n} frames at {w}x{h}, frames {}..{n} against the converged frames {settle}..{}: \
             worst {worst} ulp{}, {over} frames over 1 ulp",
            settle + PERIOD,
            settle + PERIOD,
            if worst > 0 {
                format!(" (frame {worst_at})")
            } else {
                String::new()
            }
        );
        assert!(
            worst <= 1,
            "{spec}: drifted {worst} fp16 ulps by frame {worst_at}"
        );
    }
    assert_clean(&gpu);
}
