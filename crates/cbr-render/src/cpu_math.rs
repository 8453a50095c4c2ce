//! The colour and filter arithmetic the CPU references share with their shaders (the resolve,
//! `interlaced`, `+taa`): one definition each, in the shaders' operation order.

pub type V3 = [f32; 3];

/// Rec. 709 luminance.
pub fn luma(c: V3) -> f32 {
    c[0] * 0.2126 + c[1] * 0.7152 + c[2] * 0.0722
}

pub fn to_ycocg(c: V3) -> V3 {
    [
        0.25 * c[0] + 0.5 * c[1] + 0.25 * c[2],
        0.5 * c[0] - 0.5 * c[2],
        -0.25 * c[0] + 0.5 * c[1] - 0.25 * c[2],
    ]
}

pub fn from_ycocg(y: V3) -> V3 {
    [y[0] + y[1] - y[2], y[0] + y[2], y[0] - y[1] - y[2]]
}

/// |a - b| / max(a, b) of reverse-Z depths (0 when both are 0): the relative difference of the
/// linear depths they stand for.
pub fn depth_rel_diff(a: f32, b: f32) -> f32 {
    let m = a.max(b);
    if m > 0.0 { (a - b).abs() / m } else { 0.0 }
}

/// Length of a 2-vector (a velocity in pixels).
pub fn length(v: [f32; 2]) -> f32 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Catmull-Rom weights of the taps at -1, 0, 1, 2 for fractional position f.
pub fn catmull_rom(f: f32) -> [f32; 4] {
    let f2 = f * f;
    let f3 = f2 * f;
    [
        -0.5 * f3 + f2 - 0.5 * f,
        1.5 * f3 - 2.5 * f2 + 1.0,
        -1.5 * f3 + 2.0 * f2 + 0.5 * f,
        0.5 * f3 - 0.5 * f2,
    ]
}

/// Lanczos-3, 3 sin(pi x) sin(pi x / 3) / (pi x)^2, at the 6 taps x = j - f (j = -2..3, f in
/// [0, 1)), from three sines as inc/lanczos3.glsl's `lanczos3_weights`: sin(pi (j - f)) =
/// -(-1)^j sin(pi f), sin(pi (j - f) / 3) = sin(pi j / 3) cos(pi f / 3) - cos(pi j / 3)
/// sin(pi f / 3).
pub fn lanczos3_weights(f: f32) -> [f32; 6] {
    const PI: f32 = std::f32::consts::PI;
    const S3: f32 = 0.866_025_4;
    const SJ: [f32; 6] = [-S3, -S3, 0.0, S3, S3, 0.0];
    const CJ: [f32; 6] = [-0.5, 0.5, 1.0, 0.5, -0.5, -1.0];
    // sin(pi f) = sin(pi (1 - f)): the smaller argument keeps its precision near f = 1.
    let s = (PI * f.min(1.0 - f)).sin();
    let (s3, c3) = ((PI * f / 3.0).sin(), (PI * f / 3.0).cos());
    std::array::from_fn(|k| {
        let x = (k as i32 - 2) as f32 - f;
        let a = PI * x;
        let sx = if k % 2 == 0 { -s } else { s };
        if x.abs() < 1e-4 {
            1.0
        } else {
            3.0 * sx * (SJ[k] * c3 - CJ[k] * s3) / (a * a)
        }
    })
}

/// The 3x3 neighbourhood's offsets, row by row (the shaders' `OFF`).
pub const OFF_3X3: [[i32; 2]; 9] = [
    [-1, -1],
    [0, -1],
    [1, -1],
    [-1, 0],
    [0, 0],
    [1, 0],
    [-1, 1],
    [0, 1],
    [1, 1],
];

/// Whether a 3x3 of reverse-Z depths (or of any quantity affine in screen space on a plane, such
/// as 1 / linear depth), in [`OFF_3X3`]'s order, is one plane within `tol` times the centre's
/// (inc/plane.glsl's `depth_plane`): on each line through the centre d(-o) + d(o) - 2 d(0).
pub fn depth_plane(d: &[f32; 9], tol: f32) -> bool {
    (0..4).all(|k| (d[k] + d[8 - k] - 2.0 * d[4]).abs() <= tol * d[4])
}

/// A thin feature (inc/thin_feature.glsl, FSR 2's lock test: `+taa`'s locks and `taau.lock`):
/// `l`, a 3x3 of perceptual lumas in [`OFF_3X3`]'s order, whose centre is a ridge over the
/// neighbours not similar to it (a ratio under 1.05), with no all-similar 2x2 quad around it.
pub fn thin_feature(l: &[f32; 9]) -> bool {
    let similar = |a: f32, b: f32| {
        let (lo, hi) = (a.min(b), a.max(b));
        hi <= 0.0 || (lo > 0.0 && hi < 1.05 * lo)
    };
    let n = l[4];
    let sim: [bool; 9] = std::array::from_fn(|k| k == 4 || similar(l[k], n));
    let (mut lo, mut hi) = (1e30f32, -1e30f32);
    for k in (0..9).filter(|&k| !sim[k]) {
        lo = lo.min(l[k]);
        hi = hi.max(l[k]);
    }
    let quad = |a: usize, b: usize, c: usize| sim[a] && sim[b] && sim[c];
    (n > hi || n < lo) && !(quad(0, 1, 3) || quad(1, 2, 5) || quad(3, 6, 7) || quad(5, 7, 8))
}

/// Rec. 709 luminance weights (inc/perceptual.glsl's `LUMA_709`).
pub const LUMA_709: V3 = [0.2126, 0.7152, 0.0722];

fn dot3(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// inc/perceptual.glsl's `perceptual`: linear HDR exposure-scaled, Reinhard on luminance, YCoCg.
pub fn perceptual(c: V3, exposure: f32) -> V3 {
    let x = c.map(|v| v * exposure);
    let k = 1.0 + dot3(x, LUMA_709).max(0.0);
    let t = x.map(|v| v / k);
    [
        0.25 * t[0] + 0.5 * t[1] + 0.25 * t[2],
        0.5 * t[0] - 0.5 * t[2],
        -0.25 * t[0] + 0.5 * t[1] - 0.25 * t[2],
    ]
}

/// inc/perceptual.glsl's `linear_from_perceptual`: the inverse of [`perceptual`], negative RGB
/// (clipping in YCoCg can leave the gamut) clamped to 0.
pub fn linear_from_perceptual(y: V3, exposure: f32) -> V3 {
    let t = [y[0] + y[1] - y[2], y[0] + y[2], y[0] - y[1] - y[2]].map(|v| v.max(0.0));
    let k = (1.0 - dot3(t, LUMA_709)).max(1e-3);
    t.map(|v| v / k / exposure)
}

/// inc/perceptual.glsl's `clip_towards`: moves h towards p until it lies in [lo, hi].
pub fn clip_towards(p: V3, h: V3, lo: V3, hi: V3) -> V3 {
    let r: V3 = std::array::from_fn(|i| h[i] - p[i]);
    let mut t = 1.0f32;
    for i in 0..3 {
        if r[i] > 1e-7 {
            t = t.min((hi[i] - p[i]) / r[i]);
        } else if r[i] < -1e-7 {
            t = t.min((lo[i] - p[i]) / r[i]);
        }
    }
    let t = t.max(0.0);
    std::array::from_fn(|i| p[i] + r[i] * t)
}
