//! Pass chains: `ssaa:1` is native bit for bit; `ssaa:N` converges to the exact area-weighted
//! colour (polygon clipping in f64) within the stratification bound; the coverage layer; the
//! frame cache; post passes against their CPU reference, chained and after a ping-pong history.
//! Lavapipe with validation on; every test fails on any validation message.

mod common;

use cbr_render::post::sharpen;
use cbr_render::{Coverage, FrameOutput, RenderSettings, Renderer, Spec};
use cbr_scene::{CameraKey, CameraPath, LoadStats, Material, Object, Scene, Settings, Vertex};
use common::{assert_clean, demo, gpu};
use glam::{DVec3, DVec4};

fn frames(gpu: &cbr_gpu::Gpu, s: &Scene, settings: RenderSettings, f: &[u32]) -> Vec<FrameOutput> {
    let shaders = cbr_render::shader_library();
    let mut r = Renderer::new(gpu, &shaders, s, settings).expect("renderer");
    f.iter().map(|&f| r.render(s, f).expect("frame")).collect()
}

fn spec(w: u32, h: u32, s: &str) -> RenderSettings {
    RenderSettings::parse(w, h, s).expect("spec")
}

/// Every bit of the four common layers, in one vector per layer.
fn bits(o: &FrameOutput) -> [Vec<u32>; 4] {
    [
        o.color.iter().map(|c| u32::from(c.to_bits())).collect(),
        o.depth.iter().map(|d| d.to_bits()).collect(),
        o.velocity
            .iter()
            .flat_map(|v| v.map(f32::to_bits))
            .collect(),
        o.ids.iter().flatten().copied().collect(),
    ]
}

#[test]
fn ssaa_1_is_native_bit_for_bit() {
    let gpu = gpu();
    let s = demo(96, 54);
    let native = &frames(&gpu, &s, spec(96, 54, "native"), &[3])[0];
    let ssaa = &frames(&gpu, &s, spec(96, 54, "ssaa:1"), &[3])[0];
    assert!(bits(native) == bits(ssaa), "ssaa:1 differs from native");
    let cov = Coverage::from_frame(ssaa).expect("coverage layer");
    assert!(cov.edge.iter().all(|&e| e == 0), "one sample: no edges");
    for (f, id) in cov.fraction.iter().zip(&ssaa.ids) {
        assert_eq!(*f, if id[0] != 0 { 1.0 } else { 0.0 });
    }
    assert_clean(&gpu);
}

// ---- One emissive triangle over a black background ---------------------------------------

const W: u32 = 48;
const H: u32 = 32;

fn triangle_scene() -> (Scene, [[f64; 2]; 3]) {
    let world = [[-1.3, -0.9, 0.0], [1.7, -0.4, 0.0], [-0.2, 1.35, 0.0]];
    let v = |p: [f32; 3]| Vertex {
        pos: p,
        normal: [0.0, 0.0, 1.0],
        uv: [0.0, 0.0],
    };
    let tri = Object {
        name: "tri".into(),
        vertices: world.iter().map(|p| v(p.map(|x| x as f32))).collect(),
        indices: vec![0, 1, 2],
        material: 0,
        origin: [0.0; 3],
    };
    let mut m = Material::named("emit");
    (m.kd, m.ks, m.ke) = ([0.0; 3], [0.0; 3], [1.0; 3]);
    let key = CameraKey {
        time: 0.0,
        position: [0.0, 0.0, 5.0],
        target: [0.0, 0.0, 0.0],
        fov_y_deg: 40.0,
        cut: false,
    };
    let s = Scene {
        name: "triangle".into(),
        source: "test".into(),
        objects: vec![tri],
        materials: vec![m],
        textures: vec![],
        camera: CameraPath {
            keys: vec![key],
            near: 0.1,
        },
        directional: vec![],
        points: vec![],
        motions: vec![],
        settings: Settings {
            width: W,
            height: H,
            ambient: [0.0; 3],
            background: [0.0; 3],
            ..Settings::default()
        },
        stats: LoadStats::default(),
    };
    // Screen positions in f64 with the shaders' mapping (clip -> NDC -> pixels, y down).
    let cam = s.camera.at(0.0);
    let clip_from_rel = cam.projection(f64::from(W) / f64::from(H)) * cam.rotation();
    let screen = world.map(|p| {
        let c = clip_from_rel * DVec4::from((DVec3::from(p) - cam.position, 1.0));
        [
            (c.x / c.w * 0.5 + 0.5) * f64::from(W),
            (c.y / c.w * 0.5 + 0.5) * f64::from(H),
        ]
    });
    (s, screen)
}

/// Sutherland-Hodgman: the polygon clipped to the half-plane a x + b y <= c.
fn clip(poly: &[[f64; 2]], a: f64, b: f64, c: f64) -> Vec<[f64; 2]> {
    let inside = |p: &[f64; 2]| a * p[0] + b * p[1] <= c;
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        if inside(&p) {
            out.push(p);
        }
        if inside(&p) != inside(&q) {
            let (fp, fq) = (a * p[0] + b * p[1] - c, a * q[0] + b * q[1] - c);
            let t = fp / (fp - fq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    out
}

/// The exact fraction of pixel (x, y)'s square that the triangle covers.
fn exact_coverage(tri: &[[f64; 2]; 3], x: u32, y: u32) -> f64 {
    let (x0, y0) = (f64::from(x), f64::from(y));
    let mut p = tri.to_vec();
    for (a, b, c) in [
        (-1.0, 0.0, -x0),
        (1.0, 0.0, x0 + 1.0),
        (0.0, -1.0, -y0),
        (0.0, 1.0, y0 + 1.0),
    ] {
        p = clip(&p, a, b, c);
    }
    let n = p.len();
    (0..n)
        .map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1])
        .sum::<f64>()
        .abs()
        * 0.5
}

#[test]
fn clipping_gives_known_areas() {
    let tri = [[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]];
    assert_eq!(exact_coverage(&tri, 0, 0), 1.0);
    assert_eq!(exact_coverage(&tri, 1, 2), 0.5, "the hypotenuse halves it");
    assert_eq!(exact_coverage(&tri, 3, 3), 0.0);
    let total: f64 = (0..5)
        .flat_map(|y| (0..5).map(move |x| (x, y)))
        .map(|(x, y)| exact_coverage(&tri, x, y))
        .sum();
    assert!((total - 8.0).abs() < 1e-12, "{total}");
}

/// `ssaa:N` (ordered grid) of one flat triangle: the colour is the fraction of the N^2 samples
/// inside it. A straight edge crosses at most 2N - 1 of a pixel's N x N strata, and only crossed
/// strata can be misclassified, each by at most 1/N^2: so per pixel
/// |ssaa:N - exact| <= e (2N - 1) / N^2 with e the triangle's edges crossing the pixel (<= 3),
/// plus the raster's vertex snapping (1/256 px: area error < 0.01 of a pixel here) and f16
/// rounding (< 1e-3). The mean error over edge pixels falls roughly as 1/N.
#[test]
fn ssaa_converges_to_the_exact_area_weighted_colour() {
    let gpu = gpu();
    let (s, tri) = triangle_scene();
    let mut mean_errors = Vec::new();
    for n in [1u32, 2, 4, 8, 16] {
        let out = &frames(&gpu, &s, spec(W, H, &format!("ssaa:{n}")), &[0])[0];
        let cov = Coverage::from_frame(out).expect("coverage");
        let bound = 3.0 * f64::from(2 * n - 1) / f64::from(n * n) + 0.011;
        let (mut sum, mut count, mut worst) = (0.0, 0usize, 0.0f64);
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                let exact = exact_coverage(&tri, x, y);
                let got = f64::from(out.color[4 * i].to_f32());
                let err = (got - exact).abs();
                worst = worst.max(err - bound);
                assert!(
                    err <= bound,
                    "ssaa:{n} pixel ({x},{y}): {got} vs exact {exact}"
                );
                // Colour is coverage here: the coverage layer's fraction says the same.
                assert!((f64::from(cov.fraction[i]) - got).abs() < 2e-3);
                if exact > 0.0 && exact < 1.0 {
                    sum += err;
                    count += 1;
                }
                if exact == 0.0 || exact == 1.0 {
                    // Wholly outside or inside (up to snapping): one object ID, no edge.
                    let snapped_edge = cov.edge[i] == 1;
                    assert!(!snapped_edge || n > 1, "ssaa:1 has no edges");
                }
            }
        }
        assert!(count > 40, "the triangle has edge pixels");
        mean_errors.push((n, sum / count as f64));
    }
    eprintln!("ssaa:N mean |error| over edge pixels: {mean_errors:?}");
    for w in mean_errors.windows(2) {
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        assert!(
            e1 < e0 * 0.75,
            "ssaa:{n1} ({e1}) must be well below ssaa:{n0} ({e0})"
        );
    }
    assert!(mean_errors[4].1 < 0.01, "ssaa:16 within 1% on edges");
    assert_clean(&gpu);
}

#[test]
fn coverage_marks_edges_and_counts_hits() {
    let gpu = gpu();
    let (s, tri) = triangle_scene();
    let out = &frames(&gpu, &s, spec(W, H, "ssaa:4"), &[0])[0];
    let cov = Coverage::from_frame(out).expect("coverage");
    let mut edges = 0;
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let e = exact_coverage(&tri, x, y);
            // Pixels far from the edges (exact 0 or 1 and no sample near an edge) are not edges;
            // a pixel whose samples saw both the triangle and the background is.
            let f = cov.fraction[i];
            assert_eq!(
                cov.edge[i] == 1,
                f > 0.0 && f < 1.0,
                "pixel ({x},{y}) {f} {e}"
            );
            edges += usize::from(cov.edge[i]);
        }
    }
    assert!(edges > 30);
    assert_clean(&gpu);
}

#[test]
fn the_cache_returns_the_same_frame_and_recomputes_corrupt_entries() {
    let gpu = gpu();
    let s = demo(40, 24);
    let dir = tempfile::tempdir().expect("tempdir");
    let settings = || RenderSettings {
        cache: Some(dir.path().to_path_buf()),
        ..spec(40, 24, "ssaa:2")
    };
    let first = frames(&gpu, &s, settings(), &[2, 3]);
    // Rendered now (timed), and stored.
    assert!(
        first
            .iter()
            .all(|f| !f.timings.is_empty() && f.cached.is_some())
    );
    let entries: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .collect();
    assert_eq!(entries.len(), 2, "one file per frame: {entries:?}");
    let again = frames(&gpu, &s, settings(), &[2, 3]);
    for (a, b) in first.iter().zip(&again) {
        assert!(
            b.cached.is_some() && b.timings.is_empty(),
            "frame {} from the cache",
            b.index
        );
        assert!(bits(a) == bits(b));
        assert_eq!(a.layers, b.layers);
        assert!(
            Coverage::from_frame(a).is_some(),
            "the coverage layer from the cache"
        );
    }
    // Corrupt one entry: it is detected, recomputed and rewritten.
    let path = again[0].cached.clone().expect("path");
    let mut bytes = std::fs::read(&path).expect("read");
    bytes[100] ^= 0xff;
    std::fs::write(&path, &bytes).expect("write");
    let third = frames(&gpu, &s, settings(), &[2]);
    assert!(bits(&third[0]) == bits(&first[0]));
    assert_eq!(third[0].cached.as_ref(), Some(&path), "rewritten");
    assert!(!third[0].timings.is_empty(), "rendered afresh");
    // Another N is another key.
    let other = frames(
        &gpu,
        &s,
        RenderSettings {
            cache: Some(dir.path().to_path_buf()),
            ..spec(40, 24, "ssaa:3")
        },
        &[2],
    );
    assert!(other[0].timings.iter().any(|t| t.name == "ssaa.raster"));
    assert_clean(&gpu);
}

/// The cache key holds what the cached technique's shader modules compute, not every source: an
/// edit of a post pass, a comment, or code in a branch of another layout keeps the references;
/// a change of what the scene shaders compute recomputes them.
#[test]
fn the_cache_key_holds_the_shaders_the_frame_depends_on() {
    let gpu = gpu();
    let s = demo(24, 16);
    let cache = tempfile::tempdir().expect("tempdir");
    let src = tempfile::tempdir().expect("tempdir");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    for e in walk(&root) {
        let to = src.path().join(e.strip_prefix(&root).expect("prefix"));
        std::fs::create_dir_all(to.parent().expect("parent")).expect("mkdir");
        std::fs::copy(&e, &to).expect("copy");
    }
    let render = || {
        let shaders = cbr_gpu::Shaders::new(Box::new(cbr_gpu::DirTree(src.path().into())));
        let settings = RenderSettings {
            cache: Some(cache.path().to_path_buf()),
            ..spec(24, 16, "ssaa:2")
        };
        let mut r = Renderer::new(&gpu, &shaders, &s, settings).expect("renderer");
        r.render(&s, 1).expect("frame")
    };
    let append = |rel: &str| {
        let p = src.path().join(rel);
        let text = std::fs::read_to_string(&p).expect("read") + "\n// edited\n";
        std::fs::write(&p, text).expect("write");
    };
    let replace = |rel: &str, from: &str, to: &str| {
        let p = src.path().join(rel);
        let text = std::fs::read_to_string(&p).expect("read");
        assert!(text.contains(from), "{rel} has no `{from}`");
        std::fs::write(&p, text.replacen(from, to, 1)).expect("write");
    };
    assert!(!render().timings.is_empty(), "first: rendered");
    append("post/sharpen.comp");
    assert!(
        render().timings.is_empty(),
        "a post shader edit keeps the entry"
    );
    append("scene/forward.frag");
    replace(
        "scene/forward.frag",
        "void main() {",
        "// a comment that shifts every line below\nvoid main() {",
    );
    assert!(
        render().timings.is_empty(),
        "comments and line shifts keep it"
    );
    replace(
        "scene/forward.frag",
        "#if LAYOUT == LAYOUT_MASKED\n",
        "#if LAYOUT == LAYOUT_MASKED\n    if (frame.counts.z == 12345u) demote;\n",
    );
    assert!(
        render().timings.is_empty(),
        "code only another layout compiles keeps it"
    );
    replace("inc/shading.glsl", "1e-8", "2e-8");
    assert!(
        !render().timings.is_empty(),
        "a change of what it computes recomputes it"
    );
    assert_clean(&gpu);
}

fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).expect("read_dir") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

fn rgba(o: &FrameOutput) -> Vec<f32> {
    o.color.iter().map(|c| c.to_f32()).collect()
}

/// Within f16 rounding relative to the image's range: each link stores f16 (2^-11 relative), and
/// a neighbour's rounding enters a sharpened pixel with weight `amount`, so errors are relative
/// to the brightest value, not to the pixel's own.
fn assert_close(name: &str, got: &[f32], want: &[f32]) {
    let range = want.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let worst = got
        .iter()
        .zip(want)
        .map(|(g, w)| (g - w).abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst <= 3e-3 * range,
        "{name}: worst difference {worst} of range {range}"
    );
}

#[test]
fn post_passes_chain_and_match_their_cpu_reference() {
    let gpu = gpu();
    let (w, h) = (64, 36);
    let s = demo(w, h);
    let (wu, hu) = (w as usize, h as usize);
    let base = frames(&gpu, &s, spec(w, h, "native"), &[2])[0].clone();
    let one = &frames(&gpu, &s, spec(w, h, "native+sharpen:0.5"), &[2])[0];
    let want = sharpen::reference(wu, hu, &rgba(&base), 0.5);
    assert_close("native+sharpen", &rgba(one), &want);
    assert!(one.timings.iter().any(|t| t.name == "sharpen"));
    let two = &frames(&gpu, &s, spec(w, h, "native+sharpen:0.5+sharpen:1"), &[2])[0];
    let once: Vec<f32> = sharpen::reference(wu, hu, &rgba(&base), 0.5)
        .iter()
        .map(|&v| half::f16::from_f32(v).to_f32())
        .collect();
    assert_close(
        "two links",
        &rgba(two),
        &sharpen::reference(wu, hu, &once, 1.0),
    );
    // After a technique with a ping-pong history, each frame sharpens its own output.
    let cb = frames(
        &gpu,
        &s,
        spec(w, h, "checkerboard:rotated:ours"),
        &[0, 1, 2],
    );
    let cbs = frames(
        &gpu,
        &s,
        spec(w, h, "checkerboard:rotated:ours+sharpen"),
        &[0, 1, 2],
    );
    for (a, b) in cb.iter().zip(&cbs) {
        let want = sharpen::reference(wu, hu, &rgba(a), sharpen::DEFAULT_AMOUNT);
        assert_close(
            &format!("checkerboard+sharpen frame {}", a.index),
            &rgba(b),
            &want,
        );
    }
    // A technique with no full frame refuses post passes, naming why.
    let shaders = cbr_render::shader_library();
    let err = Renderer::new(
        &gpu,
        &shaders,
        &s,
        spec(w, h, "checkerboard:split:none+sharpen"),
    )
    .err()
    .expect("refused")
    .to_string();
    assert!(err.contains("full frame"), "{err}");
    // Two jittering passes are refused naming both, not the technique (which does not jitter).
    let err = Renderer::new(&gpu, &shaders, &s, spec(w, h, "native+taa+taa"))
        .err()
        .expect("refused")
        .to_string();
    assert!(err.contains("(`+taa`, `+taa`)"), "{err}");
    assert!(!err.contains("`native` jitters"), "{err}");
    // A configuration a technique refuses is an error of its own kind, naming the spec.
    let bad = RenderSettings::new(w, h, Spec::of("ssaa:0"));
    match Renderer::new(&gpu, &shaders, &s, bad) {
        Err(cbr_gpu::GpuError::Config { spec, message }) => {
            assert_eq!(spec, "ssaa:0");
            assert!(message.contains("ssaa N `0`"), "{message}");
        }
        Err(e) => panic!("expected a configuration error, got {e}"),
        Ok(_) => panic!("ssaa:0 accepted"),
    }
    assert!(Spec::parse("native+blur").is_err());
    assert_clean(&gpu);
}

/// `+fxaa` against its CPU reference on rendered frames (the demo: edges, foliage, wires; the
/// flat triangle: one hard edge), every preset. FXAA takes `>=`/`<` decisions between lumas that
/// tie exactly on flat colours (a search end at exactly a quarter of the gradient, equal second
/// differences both ways); the shader's rounding (pow, fused multiply-adds) decides those. A
/// pixel passes when it matches, within f16, the reference or one of its variants with ties
/// (within 1e-5 relative) taken the other way; any other difference fails, and tie-decided
/// pixels must stay rare.
#[test]
fn fxaa_matches_its_cpu_reference() {
    use cbr_render::post::fxaa::{FxaaConfig, reference, reference_variants};
    let gpu = gpu();
    let (w, h) = (96, 54);
    let demo = demo(w, h);
    let (tri, _) = triangle_scene();
    for (name, s, sw, sh) in [("demo", &demo, w, h), ("triangle", &tri, W, H)] {
        let base = frames(&gpu, s, spec(sw, sh, "native"), &[2])[0].clone();
        let input = rgba(&base);
        let exposure = s.settings.exposure.exp2();
        let mut outputs = Vec::new();
        for preset in ["12", "29", "39"] {
            let out = &frames(
                &gpu,
                s,
                spec(sw, sh, &format!("native+fxaa:{preset}")),
                &[2],
            )[0];
            outputs.push(out.color.clone());
            let c = FxaaConfig::parse(&[preset]).expect("preset");
            let (wu, hu) = (sw as usize, sh as usize);
            let want = reference(wu, hu, &input, &c, exposure);
            let got = rgba(out);
            let close = |r: &[f32], i: usize| {
                (0..3).all(|k| (got[4 * i + k] - r[k]).abs() <= 2e-3 * r[k].abs().max(0.05))
            };
            let off: Vec<usize> = (0..wu * hu)
                .filter(|&i| !close(&want[4 * i..4 * i + 3], i))
                .collect();
            let bad: Vec<usize> = off
                .iter()
                .copied()
                .filter(|&i| {
                    let v = reference_variants(wu, hu, &input, &c, exposure, i % wu, i / wu, 1e-5);
                    !v.iter().any(|r| close(r, i))
                })
                .collect();
            let changed = (0..wu * hu)
                .filter(|&i| base.color[4 * i] != out.color[4 * i])
                .count();
            eprintln!(
                "{name} fxaa:{preset}: {changed} pixels filtered, {} decided by a tie, {} off",
                off.len() - bad.len(),
                bad.len()
            );
            assert!(
                bad.is_empty(),
                "{name} fxaa:{preset}: {} pixels match no variant, e.g. {:?}",
                bad.len(),
                &bad[..bad.len().min(8)]
            );
            assert!(off.len() * 10 <= changed, "tie-decided pixels stay rare");
            assert!(
                changed > 10,
                "{name} fxaa:{preset} filters edges ({changed})"
            );
            assert!(out.timings.iter().any(|t| t.name == "fxaa"));
        }
        // The presets search differently: their outputs differ.
        assert!(
            outputs[0] != outputs[2],
            "{name}: fxaa:12 and fxaa:39 differ"
        );
    }
    assert_clean(&gpu);
}
