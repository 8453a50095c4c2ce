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
