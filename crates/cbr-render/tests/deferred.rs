//! `deferred` (docs/interleaved.md): the G-buffer + lighting pass equals forward `native` within
//! fp16 rounding on every built-in scene (and with bump mapping and extra point lights); the VPLs
//! are deterministic per scene seed; the VPL lighting of a small scene matches an f64 CPU
//! reference; and the edge cases (no VPLs, absurd counts, a sun that sees nothing, no sun, NaN).
//! Lavapipe with validation on; every test fails on any validation message.
//!
//! The per-scene figures in docs/interleaved.md come from
//! `cargo test -p cbr-render --test deferred every_builtin -- --nocapture`.

mod common;

use cbr_gpu::Gpu;
use cbr_render::gpu_types::Vpl;
use cbr_render::techniques::deferred::vpl::{SunView, random_point_lights, vpl_texels};
use cbr_render::techniques::deferred::{self, DEFAULT_REACH};
use cbr_render::{FrameOutput, RenderSettings, Renderer, Spec};
use cbr_scene::Scene;
use common::lighting::{FLOOR_ALBEDO, SUN, compare, floor_and_wall, fp16_step, reference, surface};
use common::{assert_clean, gpu};
use glam::DVec3;

fn render(
    gpu: &Gpu,
    shaders: &cbr_gpu::Shaders,
    s: &Scene,
    spec: &str,
    f: &[u32],
) -> Vec<FrameOutput> {
    common::render_with(gpu, shaders, s, common::settings_of(s, spec), f)
}

fn builtin(name: &str, w: u32, h: u32) -> Scene {
    let mut s = cbr_scene::builtin(name).expect("built-in");
    (s.settings.width, s.settings.height) = (w, h);
    s
}

/// Pixels showing an object whose material is named `names`: the NaN/Inf case's bad pixels.
fn pixels_of(s: &Scene, o: &FrameOutput, names: &[&str]) -> u64 {
    let bad: Vec<u32> = (0..s.objects.len())
        .filter(|&i| names.contains(&s.materials[s.objects[i].material as usize].name.as_str()))
        .map(|i| i as u32 + 1)
        .collect();
    o.ids.iter().filter(|id| bad.contains(&id[0])).count() as u64
}

/// Deferred equals native within fp16 rounding: every colour channel is native's fp16 value or
/// a neighbour of it (at most 1 ulp); depth, velocity and IDs are native's bits. On every
/// built-in, frames 0 and 3 (moving cameras and objects), NaN/Inf case included: its bad
/// fragments are black in both and deferred counts exactly the bad pixels it shows.
#[test]
fn every_builtin_matches_native_within_fp16_rounding() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    for name in cbr_scene::BUILTINS {
        let s = builtin(name, 96, 54);
        let native = render(&gpu, &shaders, &s, "native", &[0, 3]);
        let deferred = render(&gpu, &shaders, &s, "deferred", &[0, 3]);
        for (n, d) in native.iter().zip(&deferred) {
            let diff = compare(name, n, d);
            println!(
                "{name:12} frame {}: max {} ulp, max abs {:.3e}, {} of {} channels differ",
                n.index, diff.max_ulps, diff.max_abs, diff.differing, diff.channels
            );
            assert!(diff.max_ulps <= 1, "{name} frame {}: {diff:?}", n.index);
            let bad = pixels_of(&s, d, &["nan", "inf"]);
            assert_eq!(d.nonfinite_fragments, Some(bad), "{name}: deferred's count");
            // Native counts fragments, hidden ones too: at least the visible ones.
            assert!(n.nonfinite_fragments >= Some(bad), "{name}: native's count");
            assert_eq!(*name == "nan", bad > 0, "{name}");
        }
    }
    assert_clean(&gpu);
}

/// Bump mapping (off in every built-in) through the G-buffer: the demo with a height map on
/// every textured material matches native within fp16 rounding, and the bump changed the
/// picture (so the comparison covered it).
#[test]
fn bump_mapping_matches_native() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let flat = builtin("demo", 96, 54);
    let mut s = flat.clone();
    s.settings.bump = true;
    for m in &mut s.materials {
        if m.kd_tex.is_some() {
            m.bump_tex = m.kd_tex;
            m.bump_scale = 30.0;
        }
    }
    let native = render(&gpu, &shaders, &s, "native", &[0]);
    let deferred = render(&gpu, &shaders, &s, "deferred", &[0]);
    let diff = compare("bump", &native[0], &deferred[0]);
    println!("demo with bump: {diff:?}");
    assert!(diff.max_ulps <= 1, "{diff:?}");
    let plain = render(&gpu, &shaders, &flat, "deferred", &[0]);
    assert!(
        plain[0].color != deferred[0].color,
        "the bump changed nothing"
    );
    assert_clean(&gpu);
}

/// `points=N` through the same light term: native with the N lights appended to the scene's
/// equals `deferred:points=N` within fp16 rounding; and they are lights (the frame changed).
/// With 2100 lights, past the 2048 of a light buffer's uniform part, the rest come through its
/// storage view (gpu_types.rs, SplitBuffer): native's scene lights and deferred's extra ones.
#[test]
fn extra_point_lights_match_native_with_the_same_lights() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("demo", 96, 54);
    let mut with = s.clone();
    with.points
        .extend(random_point_lights(&s, 48, DEFAULT_REACH.into()));
    let native = render(&gpu, &shaders, &with, "native", &[0, 2]);
    let deferred = render(&gpu, &shaders, &s, "deferred:points=48", &[0, 2]);
    for (n, d) in native.iter().zip(&deferred) {
        let diff = compare("points", n, d);
        println!("demo + 48 points frame {}: {diff:?}", n.index);
        assert!(diff.max_ulps <= 1, "{diff:?}");
    }
    let mut many = s.clone();
    many.points
        .extend(random_point_lights(&s, 2100, DEFAULT_REACH.into()));
    let n = render(&gpu, &shaders, &many, "native", &[0]);
    let d = render(&gpu, &shaders, &s, "deferred:points=2100", &[0]);
    let diff = compare("points", &n[0], &d[0]);
    println!("demo + 2100 points: {diff:?}");
    assert!(diff.max_ulps <= 1, "{diff:?}");
    assert!(
        n[0].color != native[0].color,
        "the 2100 lights changed nothing"
    );
    let plain = render(&gpu, &shaders, &s, "deferred", &[0]);
    assert!(plain[0].color != deferred[0].color);
    let again = random_point_lights(&s, 48, DEFAULT_REACH.into());
    assert_eq!(
        format!("{again:?}"),
        format!("{:?}", &with.points[s.points.len()..])
    );
    assert_clean(&gpu);
}

fn vpl_bits(v: &[Vpl]) -> Vec<u32> {
    bytemuck::cast_slice::<Vpl, u32>(v).to_vec()
}

/// The same seed gives the same VPLs and the same frame, bit for bit, in two renderers; another
/// seed gives other VPLs and another frame; and the indirect light is there (the frame differs
/// from `vpls=0`'s and some VPLs live).
#[test]
fn vpls_are_deterministic_per_seed() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("demo", 64, 36);
    let spec = "deferred:vpls=256";
    let a = render(&gpu, &shaders, &s, spec, &[0]).remove(0);
    let b = render(&gpu, &shaders, &s, spec, &[0]).remove(0);
    let (va, vb) = (
        &deferred::vpls(&a).expect("VPLs"),
        &deferred::vpls(&b).expect("VPLs"),
    );
    assert_eq!(va.len(), 256);
    assert!(vpl_bits(va) == vpl_bits(vb), "same seed, other VPLs");
    assert!(a.color == b.color, "same seed, other frame");
    let alive = va.iter().filter(|v| v.position[3] == 1.0).count();
    assert!(alive > 128, "{alive} of 256 VPLs alive");
    let mut other = s.clone();
    other.settings.seed = s.settings.seed + 1;
    let c = render(&gpu, &shaders, &other, spec, &[0]).remove(0);
    let vc = &deferred::vpls(&c).expect("VPLs");
    let same = va.iter().zip(vc).filter(|(x, y)| x == y).count();
    assert!(same < 16, "{same} of 256 VPLs equal under another seed");
    assert!(a.color != c.color);
    let direct = render(&gpu, &shaders, &s, "deferred", &[0]).remove(0);
    assert!(direct.color != a.color, "the VPLs added nothing");
    assert_clean(&gpu);
}

// ---- the CPU reference of the VPL lighting --------------------------------------------------

/// The VPLs are the floor's RSM texels of the seeded pattern: alive exactly where the floor is,
/// at the texel centre's point of the floor, facing up, carrying albedo x sun x the map's area /
/// N. The frame is the f64 reference of those VPLs within 1.05 fp16 steps (the frame is fp16,
/// and lavapipe's f32 -> fp16 conversion is not always to nearest: values a hair below an fp16
/// value come out one step lower; the 0.05 covers f32 arithmetic and interpolated positions,
/// about 1e-5 relative), for 16 VPLs on a 64 x 64 map and 256 on 512 x 512, with a clamp that is
/// active near the wall's foot.
#[test]
fn vpl_lighting_matches_the_cpu_reference() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = floor_and_wall(true, 64, 48);
    let cam = s.camera.at(0.0).position;
    let clamp = 0.3f32;
    let clamp_d2 = f64::from(clamp * clamp);
    let mut total_clamped = 0;
    // 2048 VPLs: past the 1360 of the VPL buffer's uniform part, the rest come through its
    // storage view (gpu_types.rs, SplitBuffer).
    for (n, side) in [(16u32, 64u32), (256, 512), (2048, 512)] {
        let spec = format!("deferred:vpls={n}:rsm={side}:clamp={clamp}");
        let out = render(&gpu, &shaders, &s, &spec, &[0]).remove(0);
        let vpls = &deferred::vpls(&out).expect("VPLs");
        // The VPLs against the map's geometry.
        let view = SunView::new([0.0, -1.0, 0.0], s.bounds(), cam, side).expect("sun");
        let inv = view.clip_from_world.inverse();
        let area = 4.0 * view.radius * view.radius;
        let flux = f64::from(FLOOR_ALBEDO * SUN) * area / f64::from(n);
        let mut alive = 0;
        for (v, t) in vpls.iter().zip(vpl_texels(s.settings.seed, n, side)) {
            let c = |i: u32| (f64::from(i) + 0.5) / f64::from(side) * 2.0 - 1.0;
            let q = inv.transform_point3(DVec3::new(c(t[0]), c(t[1]), 0.5));
            let world = q + cam;
            let on_floor = (-1.0..=3.0).contains(&world.x) && (-2.0..=2.0).contains(&world.z);
            // Texel centres on the floor's edge are ambiguous; the floor's edges are no centre's.
            assert_eq!(v.position[3] == 1.0, on_floor, "VPL at texel {t:?}: {v:?}");
            if !on_floor {
                assert_eq!(v.flux, [0.0; 4]);
                continue;
            }
            alive += 1;
            let want = DVec3::new(q.x, -cam.y, q.z);
            let got = DVec3::new(
                v.position[0].into(),
                v.position[1].into(),
                v.position[2].into(),
            );
            assert!(
                (got - want).length() < 1e-4,
                "VPL at {got}, texel centre {want}"
            );
            assert_eq!(v.normal, [0.0, 1.0, 0.0, 0.0]);
            assert!(
                (f64::from(v.flux[0]) - flux).abs() < 1e-5 * flux,
                "{v:?} vs {flux}"
            );
        }
        assert!(alive >= n as usize / 4, "{alive} of {n} VPLs alive");
        // The frame against the f64 reference.
        let (w, h) = (s.settings.width, s.settings.height);
        let (mut worst, mut clamped, mut wall) = (0.0f64, 0, 0);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let Some((p, normal, albedo)) = surface(&s, out.ids[i][0], x, y) else {
                    continue;
                };
                if out.ids[i][0] == 1 {
                    wall += 1;
                    let near = vpls.iter().any(|v| {
                        let x = DVec3::new(
                            v.position[0].into(),
                            v.position[1].into(),
                            v.position[2].into(),
                        );
                        v.position[3] == 1.0 && (p - x).length_squared() < clamp_d2
                    });
                    clamped += usize::from(near);
                }
                let want = reference(p, normal, albedo, vpls, clamp_d2);
                let got = f64::from(out.color[4 * i].to_f32());
                let err = (got - want).abs() / fp16_step(want);
                worst = worst.max(err);
                assert!(
                    err <= 1.05,
                    "pixel ({x}, {y}): {got} vs {want}: {err} fp16 steps"
                );
            }
        }
        println!(
            "{n} VPLs on {side}^2: {alive} alive; {wall} wall pixels, {clamped} within the clamp \
             of a VPL; worst error {worst:.3} fp16 steps"
        );
        assert!(wall > 200, "{wall} wall pixels");
        total_clamped += clamped;
    }
    assert!(total_clamped > 0, "the clamp was never active");
    assert_clean(&gpu);
}

/// The clamp 1/max(d^2, c) only ever removes light: per pixel, the indirect light (the frame
/// minus `vpls=0`'s) with the default clamp (c = the VPLs' spacing squared) is at most the
/// nearly unclamped one's (c = 1 mm^2), and the mean removed (the clamp's bias, for these VPLs)
/// is printed for docs/interleaved.md.
#[test]
fn the_clamp_only_removes_light() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("demo", 96, 54);
    let direct = render(&gpu, &shaders, &s, "deferred", &[0]).remove(0);
    let clamped = render(&gpu, &shaders, &s, "deferred:vpls=1024", &[0]).remove(0);
    let loose = render(&gpu, &shaders, &s, "deferred:vpls=1024:clamp=0.001", &[0]).remove(0);
    let (mut sum_c, mut sum_l, mut n) = (0.0f64, 0.0f64, 0usize);
    for i in 0..direct.color.len() {
        if i % 4 == 3 || direct.ids[i / 4][0] == 0 {
            continue;
        }
        let d = direct.color[i].to_f64();
        let (c, l) = (clamped.color[i].to_f64() - d, loose.color[i].to_f64() - d);
        // One fp16 step of the totals' rounding either way.
        let step = fp16_step(clamped.color[i].to_f64().max(1e-7));
        assert!(
            c <= l + 2.0 * step,
            "channel {i}: clamped {c} > unclamped {l}"
        );
        (sum_c, sum_l, n) = (sum_c + c, sum_l + l, n + 1);
    }
    assert!(
        sum_c > 0.0 && sum_c < sum_l,
        "indirect {sum_c} vs unclamped {sum_l}"
    );
    println!(
        "demo 96x54, 1024 VPLs: mean indirect {:.4e} clamped, {:.4e} with c = 1 mm^2: the clamp \
         removes {:.1}%",
        sum_c / n as f64,
        sum_l / n as f64,
        100.0 * (1.0 - sum_c / sum_l)
    );
    assert_clean(&gpu);
}

// ---- edge cases ---------------------------------------------------------------------------

/// `vpls=0` (and `points=0`) is plain `deferred`, bit for bit, with no VPL layer.
#[test]
fn zero_vpls_is_plain_deferred() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("demo", 64, 36);
    let plain = render(&gpu, &shaders, &s, "deferred", &[1]).remove(0);
    let zero = render(&gpu, &shaders, &s, "deferred:vpls=0:points=0", &[1]).remove(0);
    assert!(plain.color == zero.color);
    assert!(deferred::vpls(&zero).is_none() && deferred::vpls(&plain).is_none());
    assert_clean(&gpu);
}

/// Counts beyond the limits, and numbers that are none, are refused naming the limit.
#[test]
fn absurd_parameters_are_refused_naming_the_limit() {
    for (spec, needle) in [
        ("deferred:vpls=16385", "at most 16384 VPLs"),
        ("deferred:vpls=99999999999999", "at most 16384 VPLs"),
        ("deferred:points=1000000", "at most 16384 point lights"),
        ("deferred:vpls=-4", "a whole number from 0 to 16384"),
        ("deferred:vpls=lots", "a whole number from 0 to 16384"),
        ("deferred:rsm=8", "from 16 to 4096"),
        (
            "deferred:vpls=1024:rsm=16",
            "more VPLs than the 16x16 reflective shadow map",
        ),
        ("deferred:clamp=0", "above 0"),
        ("deferred:clamp=nan", "above 0"),
        ("deferred:reach=-1", "above 0"),
        ("deferred:reach=inf", "above 0"),
        ("deferred:sun", "not a parameter of deferred"),
    ] {
        let err = Spec::parse(spec).expect_err(spec);
        assert!(err.contains(needle), "{spec}: {err}");
    }
    assert!(Spec::parse("deferred:vpls=16384:points=16384:rsm=128:reach=100:clamp=0.25").is_ok());
}

/// A sun that sees nothing (the wall alone, edge-on to it): every VPL is dead, the frame is
/// `vpls=0`'s bit for bit, nothing is NaN.
#[test]
fn a_sun_that_sees_nothing_adds_nothing() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = floor_and_wall(false, 48, 32);
    let lit = render(&gpu, &shaders, &s, "deferred:vpls=64", &[0]).remove(0);
    let vpls = &deferred::vpls(&lit).expect("VPLs");
    assert!(
        vpls.iter().all(|v| *v == Vpl::default()),
        "{:?}",
        &vpls[..4]
    );
    let direct = render(&gpu, &shaders, &s, "deferred", &[0]).remove(0);
    assert!(lit.color == direct.color);
    assert_eq!(lit.nonfinite_fragments, Some(0));
    assert!(lit.color.iter().all(|c| c.is_finite()));
    assert_clean(&gpu);
}

/// A scene without a directional light: `vpls=N` is refused with the reason; `vpls=0` renders.
#[test]
fn no_sun_is_a_clear_error() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("specular", 32, 18);
    assert!(
        s.directional.is_empty(),
        "builtin:specular has a sun now: pick another scene"
    );
    let settings = RenderSettings::parse(32, 18, "deferred:vpls=256").expect("spec");
    let err = Renderer::new(&gpu, &shaders, &s, settings)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("directional light") && err.contains("has none"),
        "{err}"
    );
    render(&gpu, &shaders, &s, "deferred:points=8", &[0]);
    assert_clean(&gpu);
}

/// The NaN/Inf case with VPLs: the NaN albedo's RSM texels give dead VPLs, not NaN light, so
/// only the bad objects' own pixels are black and counted.
#[test]
fn nan_albedo_makes_dead_vpls_not_nan_light() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = builtin("nan", 64, 36);
    let out = render(&gpu, &shaders, &s, "deferred:vpls=16384", &[0]).remove(0);
    let vpls = &deferred::vpls(&out).expect("VPLs");
    assert!(vpls.iter().all(|v| v.flux.iter().all(|f| f.is_finite())));
    let alive = vpls.iter().filter(|v| v.position[3] == 1.0).count();
    assert!(alive > 1000, "{alive} VPLs alive");
    let bad = pixels_of(&s, &out, &["nan", "inf"]);
    assert!(bad > 0);
    assert_eq!(out.nonfinite_fragments, Some(bad));
    assert_clean(&gpu);
}
