//! `interleaved:MxN` (docs/interleaved.md): 1x1 is `deferred` with the same VPLs; the split,
//! subset shading and gather put each pixel's subset estimate where it belongs (against an f64
//! CPU model on the floor-and-wall scene), and gather(split(x)) == x bit for bit; `implicit` is
//! the split's frame bit for bit; every filter (none, box, ours with its search and threshold,
//! the seed's) is its CPU model, which is the identity on a constant image; and on the demo ours
//! brings the frame closer to the reference than no filter, and than the box and the seed's filter
//! at object edges. Lavapipe with validation on; every test fails on any validation message.
//!
//! The figures in docs/interleaved.md come from
//! `cargo test -p cbr-render --test interleaved -- --nocapture`.

mod common;

use cbr_gpu::Gpu;
use cbr_render::gpu_types::Vpl;
use cbr_render::techniques::deferred;
use cbr_render::{FrameOutput, InterleavedLayers, Spec};
use cbr_scene::Scene;
use common::lighting::{
    FLOOR_ALBEDO, SUN, WALL_ALBEDO, compare, direct, floor_and_wall, fp16_step, hit, irradiance,
    surface,
};
use common::{assert_clean, gpu};
use glam::DVec3;

fn render(gpu: &Gpu, shaders: &cbr_gpu::Shaders, s: &Scene, spec: &str) -> FrameOutput {
    common::render_with(gpu, shaders, s, common::settings_of(s, spec), &[0]).remove(0)
}

/// 1x1: one sub-image, every VPL, a window of one pixel: `deferred` within fp16 rounding (and
/// the same VPLs bit for bit); with `direct` too (every point light in the one subset, through
/// the split, the gather, `implicit` and the seed's blur, which at 1x1 has one tap).
#[test]
fn one_by_one_is_deferred() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (96, 54);
    let reference = render(&gpu, &shaders, &s, "deferred:vpls=256");
    for spec in [
        "interleaved:1x1:vpls=256",
        "interleaved:1x1:vpls=256:raw",
        "interleaved:1x1:vpls=256:direct",
        "interleaved:1x1:vpls=256:direct:implicit",
        "interleaved:1x1:vpls=256:direct:seed",
    ] {
        let got = render(&gpu, &shaders, &s, spec);
        assert!(
            deferred::vpls(&got) == deferred::vpls(&reference),
            "{spec}: other VPLs"
        );
        let diff = compare(spec, &reference, &got);
        println!("{spec} against deferred:vpls=256: {diff:?}");
        assert!(diff.max_ulps <= 1, "{spec}: {diff:?}");
    }
    assert_clean(&gpu);
}

/// Past the light buffers' uniform parts (2048 point lights, 1360 VPLs: gpu_types.rs,
/// SplitBuffer): 1x1 with 1600 VPLs and 2100 extra point lights, `direct` (the sub-image shades
/// them all in shaders/interleaved/subsets.glsl) and not (the lighting pass does), is `deferred`
/// with the same lights (whose own paths past the parts tests/deferred.rs holds to native and to
/// the CPU reference) within fp16 rounding.
#[test]
fn lights_past_the_uniform_parts_are_deferred() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (64, 36);
    let lights = "vpls=1600:points=2100";
    let reference = render(&gpu, &shaders, &s, &format!("deferred:{lights}"));
    for spec in [
        format!("interleaved:1x1:{lights}"),
        format!("interleaved:1x1:{lights}:direct"),
        format!("interleaved:1x1:{lights}:direct:implicit"),
    ] {
        let got = render(&gpu, &shaders, &s, &spec);
        let diff = compare(&spec, &reference, &got);
        println!("{spec} against deferred:{lights}: {diff:?}");
        assert!(diff.max_ulps <= 1, "{spec}: {diff:?}");
    }
    assert_clean(&gpu);
}

const CLAMP: f32 = 0.3;

/// Subset k of M x N: the k-th contiguous block of the VPLs.
fn subset(vpls: &[Vpl], k: usize, subsets: usize) -> impl Iterator<Item = &Vpl> {
    let size = vpls.len() / subsets;
    vpls[k * size..(k + 1) * size].iter()
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
/// y mod N): the split, the subset shading and the gather are a permutation and its inverse. The
/// split mosaic (the shade pass's output, read back with `debug`) holds the same estimates, at
/// split texel (i Ws + x div M, j Hs + y div N), within 1e-4 relative of the f64 model (f32
/// positions interpolated across the triangles, then 1/d^4 in the light term: measured 1.6e-5).
#[test]
fn raw_pixels_hold_their_own_subset() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let s = floor_and_wall(true, 64, 48);
    for (m, n) in [(4u32, 4u32), (3, 2)] {
        let spec = format!("interleaved:{m}x{n}:vpls=96:rsm=64:clamp={CLAMP}:raw:debug");
        let out = render(&gpu, &shaders, &s, &spec);
        let vpls = deferred::vpls(&out).expect("VPLs");
        let subsets = (m * n) as usize;
        let clamp_d2 = f64::from(CLAMP * CLAMP);
        let (mw, _, mosaic) = InterleavedLayers::from_frame(&out)
            .expect("debug")
            .mosaic
            .expect("mosaic");
        let (ws, hs) = (64u32.div_ceil(m), 48u32.div_ceil(n));
        let mut lit = 0;
        for y in 0..48u32 {
            for x in 0..64u32 {
                let (sx, sy) = ((x % m) * ws + x / m, (y % n) * hs + y / n);
                let got = f64::from(mosaic[(sy * mw + sx) as usize][0]);
                let want = match surface(&s, out.ids[(y * 64 + x) as usize][0], x, y) {
                    Some((p, normal, _)) => {
                        let k = subset_of(x.into(), y.into(), m.into(), n.into());
                        subsets as f64 * irradiance(p, normal, subset(&vpls, k, subsets), clamp_d2)
                    }
                    None => 0.0,
                };
                lit += usize::from(want > 0.0);
                assert!(
                    (got - want).abs() <= 1e-4 * want.abs() + 1e-9,
                    "{spec}: mosaic at ({x}, {y}): {got} vs {want}"
                );
            }
        }
        assert!(lit > 500, "{spec}: {lit} lit pixels");
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

/// The filters as the CPU model holds them (shaders/interleaved/filter.glsl, seed_blur.comp).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    None,
    Box,
    /// `enough`: found subsets that spare the fallback (M N: always shade the missing ones);
    /// `exact_edges`: R > 0, a pixel with a pixel off its surface within R (a square) shades
    /// every subset; with `band_objects` (`band=object`) only a pixel of another object (or
    /// none drawn) within R makes that band; with `band_contrast` T > 0 (`band=albedo`,
    /// `contrast=T`) only such a pixel whose tone differs from p's by at least T of the
    /// brighter of the two (`band=albedo`), or, with `band_depth` (`band=depth`), the
    /// background or a pixel whose distance from the camera differs by at least T of the
    /// farther; `band_side` (`side=`) 0 both sides of such a step, 1 p the nearer (the
    /// background counts as farther), 2 p the farther.
    Ours {
        search: bool,
        enough: usize,
        exact_edges: i64,
        band_objects: bool,
        band_contrast: f64,
        band_depth: bool,
        band_side: u8,
    },
    Seed,
}

impl Mode {
    /// `ours` with `search`, `enough` and `exact-edges=R` (R = 0: none), the band `surface`'s.
    fn ours(search: bool, enough: usize, exact_edges: i64) -> Mode {
        Mode::Ours {
            search,
            enough,
            exact_edges,
            band_objects: false,
            band_contrast: 0.0,
            band_depth: false,
            band_side: 0,
        }
    }

    /// The same with the object band (`band=object`: `depth` false, `contrast` 0), or of it only
    /// the pixels past a contrast (`band=albedo` or, with `depth`, `band=depth`; `contrast=T`),
    /// on `side` 0 both, 1 near, 2 far.
    fn band(self, depth: bool, contrast: f64, side: u8) -> Mode {
        match self {
            Mode::Ours {
                search,
                enough,
                exact_edges,
                ..
            } => Mode::Ours {
                search,
                enough,
                exact_edges,
                band_objects: true,
                band_contrast: contrast,
                band_depth: depth,
                band_side: side,
            },
            other => other,
        }
    }
}

type Px = (i64, i64);

/// What the model of the filters reads of a frame, in f64.
struct Frame<'a> {
    w: i64,
    h: i64,
    m: i64,
    n: i64,
    /// A surface was drawn at q.
    drawn: &'a dyn Fn(Px) -> bool,
    /// q lies on p's surface (`ours`' test), both drawn.
    same: &'a dyn Fn(Px, Px) -> bool,
    /// q shows p's object (drawn or not: `band=object`'s test).
    same_object: &'a dyn Fn(Px, Px) -> bool,
    /// `band=albedo`'s tone at q: the luminance of its albedo (drawn) or of the background's
    /// radiance.
    tone: &'a dyn Fn(Px) -> f64,
    /// `band=depth`'s distance of drawn q from the camera.
    distance: &'a dyn Fn(Px) -> f64,
    /// The seed's edge test at q (drawn).
    edge: &'a dyn Fn(Px) -> bool,
    /// The gathered estimate at q: M N x q's own subset at q's point (0 where nothing is drawn).
    estimate: &'a dyn Fn(Px) -> f64,
    /// M N x subset k at p's point.
    at_p: &'a dyn Fn(Px, usize) -> f64,
}

impl Frame<'_> {
    fn on(&self, (x, y): Px) -> bool {
        (0..self.w).contains(&x) && (0..self.h).contains(&y)
    }

    /// The seed's blur along one direction of the image `f` (edge pixels and pixels without a
    /// surface keep their own value and are skipped as taps).
    fn seed_blur(&self, p: Px, step: Px, period: i64, f: &dyn Fn(Px) -> f64) -> f64 {
        if !(self.drawn)(p) || (self.edge)(p) {
            return f(p);
        }
        let sigma = 0.5 * period as f64;
        let (mut sum, mut weights) = (0.0, 0.0);
        for d in -(period - 1)..=period - 1 {
            let q = (p.0 + d * step.0, p.1 + d * step.1);
            if !self.on(q) || !(self.drawn)(q) || (self.edge)(q) {
                continue;
            }
            let wgt = (-((d * d) as f64) / (2.0 * sigma * sigma)).exp();
            sum += wgt * f(q);
            weights += wgt;
        }
        sum / weights
    }

    /// The filtered irradiance at drawn pixel p and the subsets p shaded itself.
    fn filter(&self, mode: Mode, p: Px) -> (f64, u32) {
        let (m, n) = (self.m, self.n);
        match mode {
            Mode::None => return ((self.estimate)(p), 0),
            Mode::Seed => {
                let h = |q: Px| self.seed_blur(q, (1, 0), m, self.estimate);
                return (self.seed_blur(p, (0, 1), n, &h), 0);
            }
            _ => {}
        }
        let (mut sum, mut count, mut missing) = (0.0, 0usize, Vec::new());
        for oy in -(n - 1) / 2..=n / 2 {
            for ox in -(m - 1) / 2..=m / 2 {
                let q = (p.0 + ox, p.1 + oy);
                let found = match mode {
                    Mode::Box => self.on(q).then_some(q),
                    Mode::Ours { search, .. } => {
                        let ok = |c: Px| self.on(c) && (self.drawn)(c) && (self.same)(p, c);
                        let mut hit = ok(q).then_some(q);
                        // One period further, nearest first (filter.glsl's candidate order).
                        let cand = |o: i64, period: i64, i: usize| -> Option<i64> {
                            match (i, o.signum()) {
                                (0, _) => Some(o),
                                (1, 1) => Some(o - period),
                                (1, -1) => Some(o + period),
                                (1, _) => Some(-period),
                                (2, 0) => Some(period),
                                _ => None,
                            }
                        };
                        for sum_rank in 1..=4 {
                            if hit.is_some() || !search {
                                break;
                            }
                            for i in sum_rank.max(2) - 2..=sum_rank.min(2) {
                                let (Some(dx), Some(dy)) =
                                    (cand(ox, m, i), cand(oy, n, sum_rank - i))
                                else {
                                    continue;
                                };
                                let c = (p.0 + dx, p.1 + dy);
                                if ok(c) {
                                    hit = Some(c);
                                    break;
                                }
                            }
                        }
                        hit
                    }
                    Mode::None | Mode::Seed => unreachable!(),
                };
                match found {
                    Some(q) => {
                        sum += (self.estimate)(q);
                        count += 1;
                    }
                    None => missing.push(subset_of(q.0, q.1, m, n)),
                }
            }
        }
        if let Mode::Ours {
            exact_edges: r,
            band_objects,
            band_contrast,
            band_depth,
            band_side,
            ..
        } = mode
            && r > 0
        {
            let differ = |a: f64, b: f64| (a - b).abs() >= band_contrast * a.max(b);
            let contrasts = |q: Px| {
                if band_contrast == 0.0 {
                    true
                } else if band_depth {
                    let (a, b) = ((self.distance)(p), (self.distance)(q));
                    match band_side {
                        0 => !(self.drawn)(q) || differ(a, b),
                        1 => !(self.drawn)(q) || b - a >= band_contrast * b,
                        _ => (self.drawn)(q) && a - b >= band_contrast * a,
                    }
                } else {
                    differ((self.tone)(p), (self.tone)(q))
                }
            };
            let boundary = (-r..=r).any(|dy| {
                (-r..=r).any(|dx| {
                    let q = (p.0 + dx, p.1 + dy);
                    self.on(q)
                        && if band_objects {
                            !(self.same_object)(p, q) && contrasts(q)
                        } else {
                            !((self.drawn)(q) && (self.same)(p, q))
                        }
                })
            });
            if boundary {
                let every: f64 = (0..(m * n) as usize).map(|k| (self.at_p)(p, k)).sum();
                return (every / (m * n) as f64, (m * n) as u32);
            }
        }
        // `box`: the mean of the window's on-screen pixels (p's own among them).
        if let Mode::Box = mode {
            return (sum / count as f64, 0);
        }
        if let Mode::Ours { enough, .. } = mode
            && count >= enough
        {
            return (sum / count as f64, 0);
        }
        for &k in &missing {
            sum += (self.at_p)(p, k);
        }
        (sum / (m * n) as f64, missing.len() as u32)
    }
}

/// The debug bits' fields (filter.glsl) as the frame reads them back.
fn fallback_of(out: &FrameOutput, x: i64, y: i64) -> u32 {
    let i = InterleavedLayers::from_frame(out).expect("debug layers");
    u32::from(i.fallback[(y * i64::from(out.width) + x) as usize])
}

/// Every filter against its f64 model on the floor-and-wall scene (96 VPLs, 64 x 48, at 4x4 and
/// 3x2): `none`, `box`, `ours` with and without the search beyond the window (and, exactly, the
/// subsets each pixel shaded itself, from the debug layer), and `seed` (on the edges the GPU's
/// debug layer reports, themselves checked against the f64 edge test away from its thresholds).
/// Both surfaces are planes, so "on p's surface" is "the same object". Every colour within 1.05
/// fp16 steps.
#[test]
fn the_filters_match_their_cpu_model() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let (w, h) = (64i64, 48i64);
    let s = floor_and_wall(true, w as u32, h as u32);
    let clamp_d2 = f64::from(CLAMP * CLAMP);
    for (m, n) in [(4i64, 4i64), (3, 2)] {
        let subsets = (m * n) as usize;
        for (mode, param) in [
            (Mode::None, "none"),
            (Mode::Box, "box"),
            (Mode::ours(false, subsets, 0), "ours"),
            (Mode::ours(true, subsets, 0), "search=1"),
            (Mode::ours(false, subsets / 2, 0), "enough=HALF"),
            (Mode::ours(false, subsets, 1), "exact-edges"),
            (Mode::ours(true, subsets, 2), "exact-edges=2:search=1"),
            (
                Mode::ours(true, subsets, 2).band(false, 0.0, 0),
                "exact-edges=2:band=object:search=1",
            ),
            // The background (black) against the floor and the wall makes the band, the
            // floor against the wall (tones 0.5 and 0.75: a contrast of 1/3) does not.
            (
                Mode::ours(true, subsets, 2).band(false, 0.5, 0),
                "exact-edges=2:band=albedo:contrast=0.5:search=1",
            ),
            // The same band by distance: only the background is that far from the floor or
            // the wall (their contact is within a few per cent).
            (
                Mode::ours(true, subsets, 2).band(true, 0.1, 0),
                "exact-edges=2:band=depth:contrast=0.1:search=1",
            ),
            (
                Mode::ours(true, subsets, 2).band(true, 0.1, 1),
                "exact-edges=2:band=depth:contrast=0.1:side=near:search=1",
            ),
            (Mode::Seed, "seed"),
        ] {
            let param = param.replace("HALF", &(subsets / 2).to_string());
            let spec = format!("interleaved:{m}x{n}:vpls=96:rsm=64:clamp={CLAMP}:{param}:debug");
            let out = render(&gpu, &shaders, &s, &spec);
            let vpls = deferred::vpls(&out).expect("VPLs");
            let layers = InterleavedLayers::from_frame(&out).expect("debug layers");
            assert_eq!(layers.roundtrip_mismatches, 0, "{spec}");
            let id = |(x, y): Px| out.ids[(y * w + x) as usize][0];
            let surf = |q: Px| surface(&s, id(q), q.0 as u32, q.1 as u32);
            let drawn = |q: Px| id(q) != 0;
            let same = |p: Px, q: Px| id(p) == id(q);
            let same_object = same;
            let tone = |q: Px| surf(q).map_or(0.0, |(_, _, albedo)| albedo);
            let distance = |q: Px| surf(q).map_or(0.0, |(p, _, _)| p.length());
            let gpu_edge = |(x, y): Px| layers.edge[(y * w + x) as usize] != 0;
            let estimate = |q: Px| {
                let Some((pq, nq, _)) = surf(q) else {
                    return 0.0;
                };
                let k = subset_of(q.0, q.1, m, n);
                subsets as f64 * irradiance(pq, nq, subset(&vpls, k, subsets), clamp_d2)
            };
            let at_p = |p: Px, k: usize| {
                let (pp, np, _) = surf(p).expect("drawn");
                subsets as f64 * irradiance(pp, np, subset(&vpls, k, subsets), clamp_d2)
            };
            let frame = Frame {
                w,
                h,
                m,
                n,
                drawn: &drawn,
                same: &same,
                same_object: &same_object,
                tone: &tone,
                distance: &distance,
                edge: &gpu_edge,
                estimate: &estimate,
                at_p: &at_p,
            };
            if mode == Mode::Seed {
                // The seed's edges from the GPU against the f64 test (4-neighbours: nothing
                // drawn, normals off by more than dot 0.9, distance off by more than 2%), except
                // where a distance ratio lies within 1e-3 of the threshold.
                let mut checked = 0;
                for y in 0..h {
                    for x in 0..w {
                        let Some((p, np, _)) = surf((x, y)) else {
                            continue;
                        };
                        let (mut edge, mut close) = (false, false);
                        for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                            let q = (x + dx, y + dy);
                            if !frame.on(q) {
                                continue;
                            }
                            let Some((pq, nq, _)) = surf(q) else {
                                edge = true;
                                continue;
                            };
                            let ratio = (pq.length() - p.length()).abs() / p.length();
                            close |= (ratio - 0.02).abs() < 1e-3;
                            edge |= np.dot(nq) < 0.9 || ratio > 0.02;
                        }
                        if !close {
                            assert_eq!(gpu_edge((x, y)), edge, "{spec}: seed edge at ({x}, {y})");
                            checked += 1;
                        }
                    }
                }
                assert!(checked > 1500, "{spec}: {checked} edge decisions checked");
            }
            let worst = check(&s, &out, |x, y| {
                let p = (i64::from(x), i64::from(y));
                let (_, normal, albedo) = surf(p)?;
                let (e, fallback) = frame.filter(mode, p);
                if matches!(mode, Mode::Ours { .. }) {
                    assert_eq!(
                        fallback_of(&out, p.0, p.1),
                        fallback,
                        "{spec}: subsets shaded at ({x}, {y})"
                    );
                }
                Some(direct(normal, albedo) + albedo * e)
            });
            println!("{spec}: worst {worst:.3} fp16 steps from the f64 model");
        }
    }
    assert_clean(&gpu);
}

/// The point lights of `direct_scene`: world position and red irradiance at 1 m.
const POINTS: [([f64; 3], f32); 7] = [
    ([0.5, 0.6, -1.0], 1.0),
    ([2.0, 0.4, 1.0], 0.8),
    ([-0.5, 1.5, 0.5], 1.2),
    ([1.0, 1.0, 0.0], 0.6),
    ([0.0, 0.3, 1.5], 0.9),
    ([2.5, 1.2, -1.5], 1.5),
    ([-0.7, 0.5, -0.5], 0.7),
];
/// The specular colour (red) and exponent of the wall (object 1) and the floor (object 2).
const SPECULAR: [(f32, f32); 2] = [(0.3, 8.0), (0.5, 20.0)];

/// The floor and wall with the point lights of POINTS (no range window) and specular materials.
fn direct_scene(w: u32, h: u32) -> Scene {
    let mut s = floor_and_wall(true, w, h);
    for (material, (ks, ns)) in [(1, SPECULAR[0]), (0, SPECULAR[1])] {
        s.materials[material].ks = [ks; 3];
        s.materials[material].ns = ns;
    }
    s.points = POINTS
        .iter()
        .map(|&(position, red)| cbr_scene::PointLight {
            position,
            color: [red, 0.5, 0.25],
            intensity: 1.0,
            range: 0.0,
        })
        .collect();
    s
}

/// The diffuse n.l E and specular (n.h)^ns n.l E terms (red) at camera-relative p, normal n, of
/// the point lights of subset k of `subsets` (light j in subset j mod subsets), times `subsets`,
/// in f64 (shading.glsl's add_light_terms).
fn direct_terms(s: &Scene, p: DVec3, n: DVec3, ns: f64, k: usize, subsets: usize) -> (f64, f64) {
    let camera = s.camera.at(0.0).position;
    let v = (-p).normalize();
    let (mut diffuse, mut specular) = (0.0, 0.0);
    for (position, red) in POINTS.iter().skip(k).step_by(subsets) {
        let d = DVec3::from(*position) - camera - p;
        let dist2 = d.length_squared().max(1e-8);
        let l = d / dist2.sqrt();
        let e = f64::from(*red) / dist2;
        let ndl = n.dot(l);
        if ndl <= 0.0 {
            continue;
        }
        let h = (l + v).normalize();
        diffuse += ndl * e;
        specular += n.dot(h).max(0.0).powf(ns) * ndl * e;
    }
    (diffuse * subsets as f64, specular * subsets as f64)
}

/// `direct` against the f64 model on the floor and wall with 7 point lights and specular
/// materials (at 4x4, 3x2): the sub-images shade point-light subset k with VPL subset k; the
/// diffuse term filtered with the VPLs' irradiance and the specular term beside it, by the same
/// choices (`none`, `box`, `ours`, `exact-edges`, `seed`, and `implicit`): each pixel is
/// the sun + albedo x filtered (VPL + point diffuse) + ks x filtered specular, within 1.05 fp16
/// steps, and `ours`' fallback counts are the model's exactly.
#[test]
fn direct_matches_its_cpu_model() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let (w, h) = (64i64, 48i64);
    let s = direct_scene(w as u32, h as u32);
    let clamp_d2 = f64::from(CLAMP * CLAMP);
    for (m, n) in [(4i64, 4i64), (3, 2)] {
        let subsets = (m * n) as usize;
        let ours = |exact_edges| Mode::ours(false, subsets, exact_edges);
        for (mode, param) in [
            (Mode::None, "none"),
            (Mode::Box, "box"),
            (ours(0), "ours"),
            (ours(0), "ours:implicit"),
            (ours(1), "exact-edges"),
            (Mode::Seed, "seed"),
        ] {
            let spec =
                format!("interleaved:{m}x{n}:vpls=96:rsm=64:clamp={CLAMP}:{param}:direct:debug");
            let out = render(&gpu, &shaders, &s, &spec);
            let vpls = deferred::vpls(&out).expect("VPLs");
            let layers = InterleavedLayers::from_frame(&out).expect("debug layers");
            let id = |(x, y): Px| out.ids[(y * w + x) as usize][0];
            let surf = |q: Px| surface(&s, id(q), q.0 as u32, q.1 as u32);
            let ns = |q: Px| f64::from(SPECULAR[id(q) as usize - 1].1);
            let drawn = |q: Px| id(q) != 0;
            let same = |p: Px, q: Px| id(p) == id(q);
            let same_object = same;
            let tone = |q: Px| surf(q).map_or(0.0, |(_, _, albedo)| albedo);
            let distance = |q: Px| surf(q).map_or(0.0, |(p, _, _)| p.length());
            let gpu_edge = |(x, y): Px| layers.edge[(y * w + x) as usize] != 0;
            // Subset k's terms at drawn pixel q: (VPLs + point diffuse, point specular).
            let terms = |q: Px, k: usize| {
                let (pq, nq, _) = surf(q).expect("drawn");
                let vpl = subsets as f64 * irradiance(pq, nq, subset(&vpls, k, subsets), clamp_d2);
                let (d, sp) = direct_terms(&s, pq, nq, ns(q), k, subsets);
                (vpl + d, sp)
            };
            let own = |q: Px| match drawn(q) {
                true => terms(q, subset_of(q.0, q.1, m, n)),
                false => (0.0, 0.0),
            };
            let diffuse = |q: Px| own(q).0;
            let specular = |q: Px| own(q).1;
            let diffuse_at_p = |p: Px, k: usize| terms(p, k).0;
            let specular_at_p = |p: Px, k: usize| terms(p, k).1;
            let diffuse_frame = Frame {
                w,
                h,
                m,
                n,
                drawn: &drawn,
                same: &same,
                same_object: &same_object,
                tone: &tone,
                distance: &distance,
                edge: &gpu_edge,
                estimate: &diffuse,
                at_p: &diffuse_at_p,
            };
            let specular_frame = Frame {
                estimate: &specular,
                at_p: &specular_at_p,
                ..diffuse_frame
            };
            let worst = check(&s, &out, |x, y| {
                let p = (i64::from(x), i64::from(y));
                let (pp, normal, albedo) = surf(p)?;
                let (e, fallback) = diffuse_frame.filter(mode, p);
                let (sp, _) = specular_frame.filter(mode, p);
                // The sun (straight down) is shaded in full at the pixel, specular term included.
                let sun = {
                    let (l, v) = (DVec3::Y, (-pp).normalize());
                    let ndl = normal.dot(l).max(0.0);
                    normal.dot((l + v).normalize()).max(0.0).powf(ns(p)) * ndl * f64::from(SUN)
                };
                if matches!(mode, Mode::Ours { .. }) {
                    assert_eq!(
                        fallback_of(&out, p.0, p.1),
                        fallback,
                        "{spec}: subsets shaded at ({x}, {y})"
                    );
                }
                let ks = f64::from(SPECULAR[id(p) as usize - 1].0);
                Some(direct(normal, albedo) + albedo * e + ks * (sp + sun))
            });
            // The specular term matters: pixels where it is above 1e-3.
            let lit = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .filter(|&q| drawn(q) && specular_frame.filter(mode, q).0 > 1e-3)
                .count();
            // (`none` at 4x4: 7 of the 16 subsets hold a light.)
            assert!(lit > 400, "{spec}: {lit} pixels with a specular term");
            println!("{spec}: worst {worst:.3} fp16 steps from the f64 model");
        }
    }
    assert_clean(&gpu);
}

/// The filters' model on a constant image is the identity, whatever the geometry: every pixel's
/// estimate and every subset shaded anywhere equal to c, on a frame of random objects (with
/// background pixels, which `box` counts as an estimate, and `seed` skips), random seed edges,
/// several tile shapes. The GPU filters are held to this model by
/// `the_filters_match_their_cpu_model` (within 1.05 fp16 steps).
#[test]
fn the_filters_are_the_identity_on_a_constant_image() {
    let (w, h) = (37i64, 23i64);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let ids: Vec<u64> = (0..w * h).map(|_| next() % 4).collect();
    let edges: Vec<bool> = (0..w * h).map(|_| next() % 3 == 0).collect();
    let id = |(x, y): Px| ids[(y * w + x) as usize];
    let c = 0.731;
    let drawn = |q: Px| id(q) != 0;
    let same = |p: Px, q: Px| id(p) == id(q);
    let same_object = same;
    let tones = [0.05, 0.6, 0.2, 0.9];
    let tone = |q: Px| tones[id(q) as usize];
    let distances = [0.0, 3.0, 1.0, 1.2];
    let distance = |q: Px| distances[id(q) as usize];
    let edge = |(x, y): Px| edges[(y * w + x) as usize];
    let estimate = |q: Px| if drawn(q) { c } else { 0.0 };
    let at_p = |_: Px, _: usize| c;
    for (m, n) in [(1, 1), (2, 2), (4, 4), (3, 5), (8, 1)] {
        let frame = Frame {
            w,
            h,
            m,
            n,
            drawn: &drawn,
            same: &same,
            same_object: &same_object,
            tone: &tone,
            distance: &distance,
            edge: &edge,
            estimate: &estimate,
            at_p: &at_p,
        };
        let all = (m * n) as usize;
        for mode in [
            Mode::None,
            Mode::ours(false, all, 0),
            Mode::ours(true, all, 0),
            Mode::ours(false, all.div_ceil(2), 0),
            Mode::ours(true, 1, 0),
            Mode::ours(false, all, 1),
            Mode::ours(true, all, 2).band(false, 0.0, 0),
            Mode::ours(true, all, 2).band(false, 0.5, 0),
            Mode::ours(true, all, 2).band(true, 0.5, 0),
            Mode::ours(false, all, 1).band(true, 0.2, 1),
            Mode::ours(true, all, 3).band(true, 0.2, 2),
            Mode::Seed,
        ] {
            for y in 0..h {
                for x in 0..w {
                    if !drawn((x, y)) {
                        continue;
                    }
                    let (e, _) = frame.filter(mode, (x, y));
                    assert!((e - c).abs() < 1e-12, "{mode:?} {m}x{n} at ({x}, {y}): {e}");
                }
            }
        }
        // `box` takes background neighbours' zero estimates: the identity where the whole window
        // is drawn.
        for y in 0..h {
            for x in 0..w {
                let window = (-(n - 1) / 2..=n / 2).all(|oy| {
                    (-(m - 1) / 2..=m / 2).all(|ox| {
                        let q = (x + ox, y + oy);
                        !frame.on(q) || drawn(q)
                    })
                });
                if drawn((x, y)) && window {
                    let (e, _) = frame.filter(Mode::Box, (x, y));
                    assert!((e - c).abs() < 1e-12, "box {m}x{n} at ({x}, {y}): {e}");
                }
            }
        }
    }
}

/// gather(split(x)) == x bit for bit, through the real passes: with `debug` the gather pass also
/// gathers the split G-buffer (position and normal) back and compares it with the G-buffer at
/// every pixel. On the demo at an odd size (67 x 45, so that M and N do not divide it) for several
/// tile shapes; the debug layers hold each pixel's subset and, for `none`, no fallback; the mosaic
/// is M ceil(W/M) x N ceil(H/N) and zero in its texels past the screen.
#[test]
fn gather_of_split_is_the_identity() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    let (w, h) = (67u32, 45u32);
    (s.settings.width, s.settings.height) = (w, h);
    for (m, n) in [(4u32, 4u32), (3, 5), (8, 1), (1, 1), (5, 8)] {
        let spec = format!("interleaved:{m}x{n}:vpls={}:none:debug", 8 * m * n);
        let out = render(&gpu, &shaders, &s, &spec);
        let l = InterleavedLayers::from_frame(&out).expect("debug layers");
        assert_eq!(l.roundtrip_mismatches, 0, "{spec}");
        assert_eq!(l.tile, (m, n));
        let drawn = out.ids.iter().filter(|i| i[0] != 0).count();
        assert!(drawn > 1000, "{spec}: {drawn} pixels drawn");
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if out.ids[i][0] == 0 {
                    continue;
                }
                let k = subset_of(x.into(), y.into(), m.into(), n.into());
                assert_eq!(usize::from(l.subset[i]), k, "{spec} ({x}, {y})");
                assert_eq!(l.fallback[i], 0, "{spec} ({x}, {y})");
            }
        }
        let (mw, mh, texels) = l.mosaic.as_ref().expect("mosaic");
        let (ws, hs) = (w.div_ceil(m), h.div_ceil(n));
        assert_eq!((*mw, *mh), (m * ws, n * hs), "{spec}");
        for sy in 0..*mh {
            for sx in 0..*mw {
                // The pixel of split texel (sx, sy) (interleave.glsl's pixel_of).
                let (i, j) = (sx / ws, sy / hs);
                let (x, y) = ((sx % ws) * m + i, (sy % hs) * n + j);
                if x >= w || y >= h {
                    assert_eq!(texels[(sy * mw + sx) as usize], [0.0; 3], "{spec}");
                }
            }
        }
        println!("{spec}: {drawn} pixels, gather(split(G-buffer)) == G-buffer bit for bit");
    }
    assert_clean(&gpu);
}

/// `implicit` (each pixel shades its own subset at full resolution, no split) gives the split's
/// frame bit for bit: the same estimates by the same arithmetic, only where they are computed
/// differs; with `box` within one fp16 step (the window's sum in another order).
#[test]
fn implicit_equals_the_split() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (96, 54);
    // `box`: the split's gather sums each window row first (BOX_ROWS), `implicit` adds the M N
    // taps in one run: the same terms in another order, within an fp16 step (0 seen).
    for (base, ulps) in [
        ("interleaved:4x4:vpls=256", 0),
        ("interleaved:3x2:vpls=96:none", 0),
        ("interleaved:4x4:vpls=256:direct", 0),
        ("interleaved:4x4:vpls=256:box", 1),
        ("interleaved:3x2:vpls=96:box:direct", 1),
    ] {
        let split = render(&gpu, &shaders, &s, base);
        let implicit = render(&gpu, &shaders, &s, &format!("{base}:implicit"));
        let diff = compare(base, &split, &implicit);
        println!("{base}: implicit against the split: {diff:?}");
        assert!(diff.max_ulps <= ulps, "{base}: {diff:?}");
    }
    assert_clean(&gpu);
}

/// The default `ours` (without `direct`) runs the fallback in passes of its own (`fallback=pairs`:
/// the fallback's (pixel, subset) pairs listed by the lighting pass, shaded by
/// `interleaved.fallback`, summed back by `interleaved.finish`) and reads the filter's window from
/// a tile in shared memory (`window=tile`); both give the frame of the inline loop with per-window
/// fetches bit for bit: the same values, the same sums in the same order. With the debug views,
/// the same debug layers; on `nan`, the same non-finite count. The 8x8 `exact-edges=3` case lists
/// more pairs than the buffers hold (up to 64 a pixel against a capacity of 4 a pixel), so its
/// overflowing pixels take the inline loop in the same pass.
#[test]
fn the_fallback_passes_and_the_window_tile_change_no_bit() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut demo = cbr_scene::builtin("demo").expect("demo");
    (demo.settings.width, demo.settings.height) = (67, 45);
    let mut nan = cbr_scene::builtin("nan").expect("nan");
    (nan.settings.width, nan.settings.height) = (64, 36);
    for (s, base) in [
        (&demo, "interleaved:4x4:vpls=256"),
        (&demo, "interleaved:3x2:vpls=96:debug"),
        (&demo, "interleaved:4x4:vpls=256:enough=8"),
        (&demo, "interleaved:4x4:vpls=256:search=1"),
        (
            &demo,
            "interleaved:3x2:vpls=96:search=1:exact-edges=3:debug",
        ),
        (&demo, "interleaved:4x4:vpls=256:exact-edges=2:debug"),
        (&demo, "interleaved:8x8:vpls=256:exact-edges=3"),
        (&demo, "interleaved:4x4:vpls=256:implicit"),
        (&demo, "interleaved:4x4:vpls=256:direct"),
        (&nan, "interleaved:4x4:vpls=256"),
    ] {
        let default = render(&gpu, &shaders, s, base);
        // `search=1` reads its candidates from the tile too (since 2026-12-01).
        let variants: &[&str] = if base.contains("direct") {
            &["window=fetch"]
        } else {
            &[
                "fallback=inline",
                "window=fetch",
                "fallback=inline:window=fetch",
            ]
        };
        for v in variants {
            let other = render(&gpu, &shaders, s, &format!("{base}:{v}"));
            let diff = compare(base, &other, &default);
            println!("{base}: the default against {v}: {diff:?}");
            assert_eq!(diff.max_ulps, 0, "{base} against {v}: {diff:?}");
            assert_eq!(
                default.nonfinite_fragments, other.nonfinite_fragments,
                "{base} against {v}: non-finite pixels"
            );
            let views = |o: &FrameOutput| {
                InterleavedLayers::from_frame(o).map(|i| (i.subset, i.edge, i.fallback))
            };
            assert!(
                views(&default) == views(&other),
                "{base} against {v}: debug views"
            );
        }
        if base.contains("debug") {
            let i = InterleavedLayers::from_frame(&default).expect("debug layers");
            let fallback: u64 = i.fallback.iter().map(|&f| u64::from(f)).sum();
            assert!(fallback > 0, "{base}: no fallback to compare");
        }
    }
    let bad = render(&gpu, &shaders, &nan, "interleaved:4x4:vpls=256");
    assert!(
        bad.nonfinite_fragments.unwrap_or(0) > 0,
        "nan: no non-finite pixel counted"
    );
    assert_clean(&gpu);
}

/// floor_and_wall as one object (the wall's material), with a panel parallel to the wall 0.4 m
/// in front of it: a crease (floor and wall) and a step between parallel planes (panel and wall)
/// within one object, which only the flat tiles' bound on the normals and on the distances from
/// the reference texel's plane keep rough.
fn one_folded_object(w: u32, h: u32) -> Scene {
    let mut s = floor_and_wall(true, w, h);
    let panel = common::lighting::quad(
        "panel",
        [
            [-0.6, 0.9, 0.4],
            [-0.6, 0.9, -0.4],
            [-0.6, 1.5, -0.4],
            [-0.6, 1.5, 0.4],
        ],
        [1.0, 0.0, 0.0],
        1,
    );
    let mut one = s.objects.remove(0);
    for o in s.objects.drain(..).chain([panel]) {
        let base = one.vertices.len() as u32;
        one.vertices.extend(o.vertices);
        one.indices.extend(o.indices.iter().map(|i| i + base));
    }
    one.name = "folded".into();
    s.objects = vec![one];
    s
}

/// floor_and_wall whose wall is two coplanar halves with normals 30 degrees apart (the half at
/// z < 0 turned towards -z: a shading normal, as a smoothing group or normal map gives), seen
/// through a 5-degree field of view at the seam: the tiles there lie on one plane, and only the
/// flat tiles' bound on the normals keeps them rough (at this footprint the bound on the
/// distances alone would let them through).
fn bent_wall(w: u32, h: u32) -> Scene {
    let mut s = floor_and_wall(true, w, h);
    let turned = [30f32.to_radians().cos(), 0.0, -(30f32.to_radians().sin())];
    let halves = [
        (
            [
                [-1.0, 0.0, 2.0],
                [-1.0, 0.0, 0.0],
                [-1.0, 2.0, 0.0],
                [-1.0, 2.0, 2.0],
            ],
            [1.0, 0.0, 0.0],
        ),
        (
            [
                [-1.0, 0.0, 0.0],
                [-1.0, 0.0, -2.0],
                [-1.0, 2.0, -2.0],
                [-1.0, 2.0, 0.0],
            ],
            turned,
        ),
    ];
    let mut wall = common::lighting::quad("wall", halves[0].0, halves[0].1, 1);
    let other = common::lighting::quad("wall", halves[1].0, halves[1].1, 1);
    let base = wall.vertices.len() as u32;
    wall.vertices.extend(other.vertices);
    wall.indices.extend(other.indices.iter().map(|i| i + base));
    s.objects[0] = wall;
    let key = &mut s.camera.keys[0];
    (key.position, key.target, key.fov_y_deg) = ([2.5, 1.0, 0.0], [-1.0, 1.0, 0.0], 5.0);
    s
}

/// `flat=on` (the default of `ours` with its tile): a workgroup whose tile lies on one
/// plane-like surface takes each window's mean without the same-surface tests
/// (shaders/interleaved/filter.glsl, FLAT_TILES), which by its bound would all pass there. The
/// frame, its non-finite pixels and the debug views are `flat=off`'s bit for bit, with and without
/// `debug` (its define changes the shader), with the tile and with `window=fetch`, on the demo (floor, wall, the curved torus, leaves), the
/// floor-and-wall scene (two planes), the same as one object with a crease and a step between
/// parallel planes (one_folded_object: only the flatness bound keeps its tiles there rough) and `nan` (non-finite G-buffer texels
/// make their tiles rough), with `search`, the bands, `direct`, `enough`, the 3x2 and 8x8 tiles;
/// and flat tiles are taken (neither none nor every pixel, where the scene has both).
#[test]
fn flat_tiles_change_no_bit() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut demo = cbr_scene::builtin("demo").expect("demo");
    (demo.settings.width, demo.settings.height) = (160, 90);
    let planes = floor_and_wall(true, 96, 64);
    let folded = one_folded_object(96, 64);
    let bent = bent_wall(64, 64);
    let mut nan = cbr_scene::builtin("nan").expect("nan");
    (nan.settings.width, nan.settings.height) = (64, 36);
    let band = "exact-edges=2:band=depth:contrast=0.1:side=near:search=1";
    for (name, s, base, some_rough) in [
        (
            "floor and wall",
            &planes,
            "interleaved:4x4:vpls=256:search=1".to_string(),
            true,
        ),
        (
            "one folded object",
            &folded,
            "interleaved:4x4:vpls=256".into(),
            true,
        ),
        (
            "one folded object",
            &folded,
            "interleaved:4x4:vpls=256:search=1".into(),
            true,
        ),
        ("bent wall", &bent, "interleaved:4x4:vpls=256".into(), true),
        ("demo", &demo, "interleaved:4x4:vpls=256".into(), true),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:search=1".into(),
            true,
        ),
        (
            "demo",
            &demo,
            format!("interleaved:4x4:vpls=256:{band}"),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:exact-edges=2".into(),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:exact-edges=2:band=object".into(),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:exact-edges=1:band=albedo:contrast=0.5".into(),
            true,
        ),
        (
            "one folded object",
            &folded,
            format!("interleaved:4x4:vpls=256:{band}"),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:direct:search=1".into(),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:4x4:vpls=256:enough=8".into(),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:3x2:vpls=96:search=1".into(),
            true,
        ),
        (
            "demo",
            &demo,
            "interleaved:8x8:vpls=256:exact-edges=3".into(),
            true,
        ),
        ("nan", &nan, "interleaved:4x4:vpls=256".into(), true),
    ] {
        for debug in ["", ":debug", ":window=fetch", ":window=fetch:debug"] {
            let on = render(&gpu, &shaders, s, &format!("{base}{debug}"));
            let off = render(&gpu, &shaders, s, &format!("{base}:flat=off{debug}"));
            let diff = compare(base.as_str(), &off, &on);
            assert_eq!(
                diff.max_ulps, 0,
                "{name} {base}{debug}: flat=on against off: {diff:?}"
            );
            assert_eq!(
                on.nonfinite_fragments, off.nonfinite_fragments,
                "{name} {base}{debug}: non-finite pixels"
            );
            if !debug.ends_with("debug") {
                continue;
            }
            let (a, b) = (
                InterleavedLayers::from_frame(&on).expect("debug layers"),
                InterleavedLayers::from_frame(&off).expect("debug layers"),
            );
            assert!(
                (&a.subset, &a.edge, &a.fallback) == (&b.subset, &b.edge, &b.fallback),
                "{name} {base}: debug views"
            );
            let visible = on.ids.iter().filter(|id| id[0] != 0).count() as u64;
            println!(
                "{name} {base}: {} of {visible} visible pixels in flat tiles",
                a.flat_tile_pixels
            );
            assert_eq!(
                b.flat_tile_pixels, 0,
                "{name} {base}: flat=off took flat tiles"
            );
            assert!(a.flat_tile_pixels > 0, "{name} {base}: no flat tile");
            if some_rough {
                assert!(
                    a.flat_tile_pixels < visible,
                    "{name} {base}: every tile flat"
                );
            }
        }
    }
    assert_clean(&gpu);
}

/// `ours`' same-surface thresholds reach the filter: `normal=C` and `plane=T` at their defaults
/// give the default's frame bit for bit; tighter ones make more pixels shade subsets themselves
/// (the demo has curved and creased surfaces within one object), looser ones fewer.
#[test]
fn the_same_surface_thresholds_move_the_fallback() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    (s.settings.width, s.settings.height) = (96, 54);
    let base = "interleaved:4x4:vpls=256:debug";
    let fallback = |out: &FrameOutput| -> u64 {
        let i = InterleavedLayers::from_frame(out).expect("debug layers");
        i.fallback.iter().map(|&f| u64::from(f)).sum()
    };
    let default = render(&gpu, &shaders, &s, base);
    let same = render(&gpu, &shaders, &s, &format!("{base}:normal=0.9:plane=0.02"));
    let diff = compare(base, &default, &same);
    assert_eq!(diff.max_ulps, 0, "the defaults spelled out: {diff:?}");
    assert_eq!(fallback(&default), fallback(&same));
    let n0 = fallback(&default);
    for (params, more) in [
        ("normal=0.99", true),
        ("plane=0.002", true),
        ("normal=-1:plane=1000", false),
    ] {
        let got = render(&gpu, &shaders, &s, &format!("{base}:{params}"));
        let n = fallback(&got);
        println!("{params}: {n} subsets shaded by their pixels, default {n0}");
        assert!(
            if more { n > n0 } else { n < n0 },
            "{params}: {n} against {n0}"
        );
    }
    assert_clean(&gpu);
}

/// `exact-edges=R:band=object`: a pixel with another object (or the background) within R (a
/// square) is the surface band's (`exact-edges=R`) pixel bit for bit, and shades all M N
/// subsets; every other pixel is plain `ours`' bit for bit, with its fallback count. On the demo
/// (96 x 54), whose objects have creases and curved parts that the surface band takes too, the
/// object band shades strictly fewer subsets than the surface band and more than plain `ours`.
#[test]
fn the_object_band_is_exact_at_other_objects_and_ours_elsewhere() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let mut s = cbr_scene::builtin("demo").expect("demo");
    let (w, h) = (96i64, 54i64);
    (s.settings.width, s.settings.height) = (w as u32, h as u32);
    let base = "interleaved:4x4:vpls=256:debug";
    let fallback = |o: &FrameOutput| InterleavedLayers::from_frame(o).expect("debug").fallback;
    let ours = render(&gpu, &shaders, &s, base);
    for r in [1i64, 2] {
        let surface = render(&gpu, &shaders, &s, &format!("{base}:exact-edges={r}"));
        let object = render(
            &gpu,
            &shaders,
            &s,
            &format!("{base}:exact-edges={r}:band=object"),
        );
        let (fo, fs, fb) = (fallback(&ours), fallback(&surface), fallback(&object));
        let id = |x: i64, y: i64| object.ids[(y * w + x) as usize][0];
        let (mut band, mut rest) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                if id(x, y) == 0 {
                    continue;
                }
                let i = (y * w + x) as usize;
                let near_other = (-r..=r).any(|dy| {
                    (-r..=r).any(|dx| {
                        let (qx, qy) = (x + dx, y + dy);
                        (0..w).contains(&qx) && (0..h).contains(&qy) && id(qx, qy) != id(x, y)
                    })
                });
                let want = if near_other { &surface } else { &ours };
                for c in 0..3 {
                    assert_eq!(
                        object.color[4 * i + c].to_bits(),
                        want.color[4 * i + c].to_bits(),
                        "exact-edges={r}:band=object at ({x}, {y}), channel {c} (near another \
                         object: {near_other})"
                    );
                }
                if near_other {
                    assert_eq!(fb[i], 16, "exact-edges={r}:band=object at ({x}, {y})");
                    band += 1;
                } else {
                    assert_eq!(fb[i], fo[i], "exact-edges={r}:band=object at ({x}, {y})");
                    rest += 1;
                }
            }
        }
        let sum = |f: &[u8]| f.iter().map(|&v| u64::from(v)).sum::<u64>();
        println!(
            "exact-edges={r}: {band} pixels in the object band, {rest} outside; subsets shaded by \
             their pixels: ours {}, object band {}, surface band {}",
            sum(&fo),
            sum(&fb),
            sum(&fs)
        );
        assert!(
            band > 100 && rest > 1000,
            "{band} band pixels, {rest} others"
        );
        assert!(sum(&fo) < sum(&fb) && sum(&fb) < sum(&fs));
    }
    assert_clean(&gpu);
}

/// The floor and wall with a card (object 3, albedo CARD_ALBEDO, x = 0.8 facing the camera like
/// the wall, 0.6 m wide, from 0.4 to 1.0 m above the floor) in front of the wall under a dark
/// grey background (0.1): the contrast bands' scene, with object boundaries of every kind: the
/// wall on the floor (a contact: the same distance, tones 0.75 and 0.5), the card before the wall
/// and over the floor (about half the distance; tones 0.6 against 0.75 and 0.5), and the
/// background beside and above them.
fn floor_wall_and_card(w: u32, h: u32) -> Scene {
    let mut s = floor_and_wall(true, w, h);
    s.settings.background = [0.1; 3];
    let mut card = cbr_scene::Material::named("card");
    card.kd = [CARD_ALBEDO as f32; 3];
    s.materials.push(card);
    let (x, z, y0, y1) = (0.8, 0.3, 0.4, 1.0);
    s.objects.push(common::lighting::quad(
        "card",
        [[x, y0, z], [x, y0, -z], [x, y1, -z], [x, y1, z]],
        [1.0, 0.0, 0.0],
        2,
    ));
    s
}
const CARD_ALBEDO: f64 = 0.6;

/// `exact-edges=R:band=albedo|depth:contrast=T`: a pixel with, within R (a square), the
/// background or another object whose tone (`albedo`: its albedo's luminance, the background's
/// radiance's) or distance from the camera (`depth`; the background always) differs from the
/// pixel's by at least T of the larger is the object band's pixel bit for bit and shades all M N
/// subsets; every other pixel is plain `ours`' bit for bit, with its fallback count. On
/// `floor_wall_and_card` (64 x 48; tones: wall 0.75, floor 0.5, card 0.6, background 0.1):
/// `albedo` with T = 0.15 is the object band, 0.25 leaves out the card against the wall and the
/// floor, 0.5 the contact too, 0.85 the floor's silhouette, 0.9 everything; `depth` with
/// T = 0.05 leaves out the contact only and
/// T = 1 keeps the background's boundaries only; `depth:side=near` keeps the nearer side of
/// each depth step (the card's pixels before the wall, the floor's and the wall's before the
/// background), `depth:side=far` the farther (the wall's and the floor's around the card), and
/// the two together are both sides' band. A pixel with a pair of sides within 1e-3 of T
/// is not judged (counted: none for `albedo`, a few for `depth`, whose distances vary).
#[test]
fn the_contrast_bands_are_exact_at_contrasting_objects_and_ours_elsewhere() {
    let gpu = gpu();
    let shaders = cbr_render::shader_library();
    let (w, h) = (64i64, 48i64);
    let s = floor_wall_and_card(w as u32, h as u32);
    let base = "interleaved:4x4:vpls=96:rsm=64:debug";
    let fallback = |o: &FrameOutput| InterleavedLayers::from_frame(o).expect("debug").fallback;
    let sum = |f: &[u8]| f.iter().map(|&v| u64::from(v)).sum::<u64>();
    let ours = render(&gpu, &shaders, &s, base);
    let id = |x: i64, y: i64| ours.ids[(y * w + x) as usize][0];
    let ids: std::collections::BTreeSet<u32> = ours.ids.iter().map(|i| i[0]).collect();
    assert_eq!(
        ids.len(),
        4,
        "wall, floor, card and background on screen: {ids:?}"
    );
    // Tone and distance of a pixel (`None`: the background).
    let side = |x: i64, y: i64| -> Option<(f64, f64)> {
        let (xu, yu) = (x as u32, y as u32);
        match id(x, y) {
            1 => Some((f64::from(WALL_ALBEDO), hit(&s, xu, yu, 0, -1.0).length())),
            2 => Some((f64::from(FLOOR_ALBEDO), hit(&s, xu, yu, 1, 0.0).length())),
            3 => Some((CARD_ALBEDO, hit(&s, xu, yu, 0, 0.8).length())),
            _ => None,
        }
    };
    for r in [1i64, 2] {
        let object = render(
            &gpu,
            &shaders,
            &s,
            &format!("{base}:exact-edges={r}:band=object"),
        );
        let (fo, fb) = (fallback(&ours), fallback(&object));
        let mut sides = Vec::new();
        for (band, thresholds) in [
            ("albedo", &[0.15, 0.25, 0.5, 0.85, 0.9][..]),
            ("depth", &[0.05, 1.0][..]),
            ("depth:side=near", &[0.05, 1.0][..]),
            ("depth:side=far", &[0.05][..]),
        ] {
            let mut shaded = Vec::new();
            for &t in thresholds {
                let spec = format!("{base}:exact-edges={r}:band={band}:contrast={t}");
                let contrast = render(&gpu, &shaders, &s, &spec);
                let fc = fallback(&contrast);
                let (mut inside, mut rest, mut close) = (0, 0, 0);
                for y in 0..h {
                    for x in 0..w {
                        let Some(a) = side(x, y) else { continue };
                        let i = (y * w + x) as usize;
                        let (mut near, mut near_t) = (false, false);
                        for (dx, dy) in (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (dx, dy))) {
                            let (qx, qy) = (x + dx, y + dy);
                            if !(0..w).contains(&qx)
                                || !(0..h).contains(&qy)
                                || id(qx, qy) == id(x, y)
                            {
                                continue;
                            }
                            // The share of the larger by which the sides differ (depth with a
                            // side: signed, p nearer (`near`) or farther (`far`) than q).
                            let share = match (side(qx, qy), band) {
                                (Some(b), "albedo") => (a.0 - b.0).abs() / a.0.max(b.0),
                                (None, "albedo") => (a.0 - 0.1f64).abs() / a.0.max(0.1),
                                (Some(b), "depth") => (a.1 - b.1).abs() / a.1.max(b.1),
                                (Some(b), "depth:side=near") => (b.1 - a.1) / b.1,
                                (Some(b), _) => (a.1 - b.1) / a.1,
                                (None, "depth:side=far") => f64::NEG_INFINITY,
                                (None, _) => f64::INFINITY,
                            };
                            near |= share >= t;
                            near_t |= (share - t).abs() < 1e-3;
                        }
                        if near_t {
                            close += 1;
                            continue;
                        }
                        let want = if near { &object } else { &ours };
                        for c in 0..3 {
                            assert_eq!(
                                contrast.color[4 * i + c].to_bits(),
                                want.color[4 * i + c].to_bits(),
                                "{spec} at ({x}, {y}), channel {c} (near a contrasting side: \
                                 {near})"
                            );
                        }
                        if near {
                            assert_eq!(fc[i], 16, "{spec} at ({x}, {y})");
                            inside += 1;
                        } else {
                            assert_eq!(fc[i], fo[i], "{spec} at ({x}, {y})");
                            rest += 1;
                        }
                    }
                }
                println!(
                    "{spec}: {inside} pixels in the band, {rest} outside, {close} not judged; \
                     subsets shaded by their pixels: ours {}, this band {}, object band {}",
                    sum(&fo),
                    sum(&fc),
                    sum(&fb)
                );
                // The tones are constants; distances vary continuously (f32 on the GPU).
                assert!(
                    close <= if band == "albedo" { 0 } else { 20 },
                    "{spec}: {close} pixels with a side within 1e-3 of T"
                );
                assert!(rest > 1000, "{spec}: {rest} pixels outside the band");
                assert_eq!(inside == 0, t == 0.9, "{spec}: {inside} band pixels");
                shaded.push(sum(&fc));
            }
            // Each threshold's band strictly inside the one before: from the object band (or
            // less) down to plain `ours` (or more).
            assert!(
                shaded.windows(2).all(|p| p[0] > p[1]),
                "exact-edges={r}:band={band}: subsets shaded {shaded:?}"
            );
            assert!(shaded[0] <= sum(&fb) && *shaded.last().unwrap() >= sum(&fo));
            sides.push(shaded[0]);
            if band == "albedo" {
                assert_eq!(shaded[0], sum(&fb), "albedo T = 0.15 is the object band");
                assert_eq!(shaded[4], sum(&fo), "albedo T = 0.9 is plain ours");
            } else {
                assert!(
                    shaded[0] < sum(&fb),
                    "{band} T = 0.05 leaves the contact out"
                );
            }
        }
        // At T = 0.05 each side of the depth steps takes part of both sides' band, and each
        // band holds pixels the other lacks (both 0.05 bands above 0: `near` holds the card's
        // and the background's boundaries, `far` the wall's and floor's behind the card).
        let (both, near, far) = (
            sides[1] - sum(&fo),
            sides[2] - sum(&fo),
            sides[3] - sum(&fo),
        );
        assert!(
            near < both && far < both && near > 0 && far > 0 && near + far >= both,
            "exact-edges={r}: extra subsets, both sides {both}, near {near}, far {far}"
        );
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
/// every pixel) without a filter, with the box, the seed's filter and ours. Ours is closer than no
/// filter everywhere, and closer than the box and the seed's filter on the pixels whose window
/// holds another object (edges), where the box mixes two surfaces' light and the seed's filter
/// leaves each edge pixel its own subset (the seed's noisy edge lines).
#[test]
fn our_filter_beats_none_box_and_seed_at_edges() {
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
    for mode in ["none", "box", "seed", "ours"] {
        let spec = format!("interleaved:4x4:vpls=1024:{mode}");
        let out = render(&gpu, &shaders, &s, &spec);
        let (all, at_edges) = error(&reference, &out, &edge);
        println!(
            "demo 160x90, {spec}: mean abs error {all:.4e}, at edges ({} px) {at_edges:.4e}",
            edge.iter().filter(|&&e| e).count()
        );
        errors.push((all, at_edges));
    }
    let [
        (none, _),
        (_, box_edges),
        (_, seed_edges),
        (ours, ours_edges),
    ] = errors[..]
    else {
        unreachable!()
    };
    assert!(ours < none, "ours {ours} vs none {none}");
    assert!(
        ours_edges < box_edges,
        "at edges: ours {ours_edges} vs box {box_edges}"
    );
    assert!(
        ours_edges < seed_edges,
        "at edges: ours {ours_edges} vs seed {seed_edges}"
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
        ("interleaved:4x4:box:seed", "one filter at a time"),
        ("interleaved:4x4:search=2", "search=0 or search=1"),
        ("interleaved:4x4:band=object", "give `exact-edges` too"),
        (
            "interleaved:4x4:exact-edges:band=crease",
            "band=surface, band=object, band=albedo or band=depth",
        ),
        (
            "interleaved:4x4:exact-edges:contrast=0.5",
            "the threshold of a contrast band",
        ),
        (
            "interleaved:4x4:exact-edges:band=object:contrast=0.5",
            "the threshold of a contrast band",
        ),
        ("interleaved:4x4:band=depth", "give `exact-edges` too"),
        (
            "interleaved:4x4:exact-edges:band=albedo:side=near",
            "give `band=depth` too",
        ),
        (
            "interleaved:4x4:exact-edges:band=depth:side=left",
            "side=both, side=near or side=far",
        ),
        (
            "interleaved:4x4:exact-edges:band=albedo:contrast=0",
            "above 0 and at most 1",
        ),
        (
            "interleaved:4x4:exact-edges:band=depth:contrast=1.5",
            "above 0 and at most 1",
        ),
        (
            "interleaved:4x4:exact-edges:band=albedo:contrast=nan",
            "above 0 and at most 1",
        ),
        ("interleaved:4x4:enough=17", "K from 1 to 16"),
        ("interleaved:4x4:flat=maybe", "flat=on or flat=off"),
        ("interleaved:4x4:box:flat=off", "`box` does not have"),
        ("interleaved:2x2:enough=0", "K from 1 to 4"),
        ("interleaved:4x4:implicit:floor", "`implicit` does not have"),
        ("interleaved:4x4:normal=1.5", "a cosine from -1 to 1"),
        ("interleaved:4x4:normal=x", "a cosine from -1 to 1"),
        ("interleaved:4x4:plane=0", "a positive share"),
        ("interleaved:4x4:plane=inf", "a positive share"),
        (
            "interleaved:4x4:box:normal=0.95",
            "same-surface test of the `ours` filter",
        ),
        (
            "interleaved:4x4:box:exact-edges",
            "a variant of the `ours` filter",
        ),
    ] {
        let err = Spec::parse(spec).expect_err(spec);
        assert!(err.contains(needle), "{spec}: {err}");
    }
    assert!(Spec::parse("interleaved:4x4").is_ok());
    assert!(Spec::parse("interleaved:2x3:vpls=600:box:rsm=256").is_ok());
    assert!(Spec::parse("interleaved:4x4:seed:debug:floor").is_ok());
    assert!(Spec::parse("interleaved:4x4:raw:none").is_ok());
    assert!(Spec::parse("interleaved:8x8:enough=32:search=1:implicit").is_ok());
    assert!(Spec::parse("interleaved:4x4:exact-edges:search=1").is_ok());
    assert!(Spec::parse("interleaved:4x4:exact-edges=2:band=depth:contrast=1").is_ok());
    assert!(Spec::parse("interleaved:4x4:normal=0.98:plane=0.01:direct").is_ok());
    let err = Spec::parse("interleaved:4x4:exact-edges=4").expect_err("R = 4");
    assert!(err.contains("R from 0 to 3"), "{err}");
}
