//! The CPU reference of taau's passes (shaders/taau/), operation for operation, in f32: each
//! function takes what its pass reads and returns what it writes. Images are rows top to bottom.

use super::config::Kernel;
use crate::cpu_math::{V3, clip_towards, linear_from_perceptual, perceptual};

/// What every pass reads from its push constants.
#[derive(Clone, Copy, Debug)]
pub struct Params {
    /// Output size.
    pub out: (usize, usize),
    /// Render size.
    pub size: (usize, usize),
    /// The frame's jitter (render pixels).
    pub jitter: [f32; 2],
    /// W / w, H / h.
    pub ratio: [f32; 2],
    /// 2^exposure stops.
    pub exposure: f32,
    pub depth_tolerance: f32,
    pub gamma: f32,
    /// The kernel's bias where the history is kept (W / w capped at 1.99).
    pub bias_max: f32,
    /// History weight cap still, moving, the speed of the moving cap, a lock's decay per frame.
    pub accum: [f32; 4],
    pub reset: bool,
    /// The background moved (`F_BACKGROUND`): a pixel whose dilated depth is the background's
    /// (0, all its 3x3 background) is not still.
    pub background_moves: bool,
    pub kernel: Kernel,
    pub stability: bool,
    /// The object test (`without-ids` off).
    pub ids: bool,
    /// The history's Lanczos lobes (2 or 3; with [`Kernel::Lanczos`]).
    pub history_lobes: u32,
    /// A surface (the 3x3 one plane) keeps its own velocity (`without-surface-velocity`).
    pub surface_velocity: bool,
}

use crate::cpu_math::OFF_3X3 as OFF;

fn inside(t: [i32; 2], (w, h): (usize, usize)) -> bool {
    t[0] >= 0 && t[1] >= 0 && (t[0] as usize) < w && (t[1] as usize) < h
}

fn clamp_at(t: [i32; 2], (w, h): (usize, usize)) -> usize {
    let x = t[0].clamp(0, w as i32 - 1) as usize;
    let y = t[1].clamp(0, h as i32 - 1) as usize;
    y * w + x
}

fn finite(c: V3) -> bool {
    c.iter().all(|v| v.is_finite())
}

/// common.glsl's `kernel_weight_sq`: the kernel at squared distance `x2`.
pub fn kernel_weight_sq(kernel: Kernel, x2: f32) -> f32 {
    match kernel {
        Kernel::Bilinear => (1.0 - x2.sqrt()).max(0.0),
        Kernel::Catmull => {
            let x = x2.sqrt();
            if x < 1.0 {
                (1.5 * x - 2.5) * x2 + 1.0
            } else if x < 2.0 {
                ((-0.5 * x + 2.5) * x - 4.0) * x + 2.0
            } else {
                0.0
            }
        }
        Kernel::Lanczos if x2 >= 4.0 => 0.0,
        Kernel::Lanczos => lanczos2_poly(x2),
    }
}

/// Lanczos-2, sinc(x) sinc(x / 2), at squared distance `x2` in [0, 4) as accumulate.comp
/// evaluates it: a degree-9 polynomial in u = x2 / 2 - 1, the Chebyshev least-squares fit on
/// [0, 4] in f64 converted to monomials and rounded to f32, Horner's rule in f32. Within 5e-7 of
/// the sines (`the_lanczos_polynomial_is_the_sines`); the shader's sines cost 15-20% of the
/// accumulate pass on lavapipe (docs/upsampling.md).
pub fn lanczos2_poly(x2: f32) -> f32 {
    const C: [f32; 10] = [
        -0.077_710_345,
        0.095_730_25,
        0.179_758_98,
        -0.424_502_13,
        0.347_350_6,
        -0.160_336_66,
        0.048_782_59,
        -0.010_657_694,
        0.001_818_025_3,
        -0.000_233_766_45,
    ];
    let u = 0.5 * x2 - 1.0;
    C.iter().rev().fold(0.0f32, |r, &c| r * u + c)
}

/// FSR 2's polynomial approximation of Lanczos-2 in x^2, `(25/16 (2/5 x^2 - 1)^2 - 9/16)
/// (x^2/4 - 1)^2`: measured against the exact kernel (not used: docs/upsampling.md).
pub fn lanczos2_fsr2_approx(x2: f32) -> f32 {
    if x2 >= 4.0 {
        return 0.0;
    }
    let a = 0.4 * x2 - 1.0;
    let b = 0.25 * x2 - 1.0;
    (1.5625 * a * a - 0.5625) * b * b
}

/// The prepared colour dilate.comp writes: perceptual, w 1; 0 where not finite.
pub fn prepare(p: &Params, color: &[V3]) -> Vec<[f32; 4]> {
    color
        .iter()
        .map(|&c| match finite(c) {
            true => {
                let y = perceptual(c, p.exposure);
                [y[0], y[1], y[2], 1.0]
            }
            false => [0.0; 4],
        })
        .collect()
}

/// dilate.comp's threshold: the reconstructed depth lands only where the bilinear weight
/// exceeds it (FSR 2's).
pub const RECON_WEIGHT: f32 = 0.05;

/// dilate.comp: per render pixel (velocity x, y, depth, 0) of the nearest 3x3 texel, and with
/// `recon` the reconstructed previous depth (reverse-Z bits, atomic max; 0 where nothing lands).
pub fn dilate(
    p: &Params,
    depth: &[f32],
    velocity: &[[f32; 2]],
    recon: bool,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let (w, h) = p.size;
    let mut dilated = vec![[0.0f32; 4]; w * h];
    let mut rec = vec![0u32; w * h];
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let (mut best, mut at) = (-1.0f32, clamp_at([x, y], p.size));
            let mut nd = [0.0f32; 9];
            for (k, o) in OFF.iter().enumerate() {
                let t = clamp_at([x + o[0], y + o[1]], p.size);
                nd[k] = depth[t];
                if depth[t] > best {
                    best = depth[t];
                    at = t;
                }
            }
            // A surface keeps its own velocity (see the shader); the depth stays the nearest.
            if p.surface_velocity && crate::cpu_math::depth_plane(&nd, p.depth_tolerance) {
                at = clamp_at([x, y], p.size);
            }
            let v = velocity[at];
            dilated[y as usize * w + x as usize] = [v[0], v[1], best, 0.0];
            if recon {
                let g = [x as f32 + 0.5 - v[0] - 0.5, y as f32 + 0.5 - v[1] - 0.5];
                let b = [g[0].floor() as i32, g[1].floor() as i32];
                let f = [g[0] - b[0] as f32, g[1] - b[1] as f32];
                for k in 0..4 {
                    let o = [k & 1, k >> 1];
                    let t = [b[0] + o[0], b[1] + o[1]];
                    let wx = if o[0] == 1 { f[0] } else { 1.0 - f[0] };
                    let wy = if o[1] == 1 { f[1] } else { 1.0 - f[1] };
                    if inside(t, p.size) && wx * wy > RECON_WEIGHT {
                        let i = t[1] as usize * w + t[0] as usize;
                        rec[i] = rec[i].max(best.to_bits());
                    }
                }
            }
        }
    }
    (dilated, rec)
}

/// depth_clip.comp: per render pixel the disocclusion in [0, 1].
pub fn depth_clip(p: &Params, dilated: &[[f32; 4]], recon: &[u32]) -> Vec<f32> {
    let (w, h) = p.size;
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let g = dilated[y * w + x];
            let d = g[2];
            if d <= 0.0 {
                continue;
            }
            let q = [x as f32 + 0.5 - g[0], y as f32 + 0.5 - g[1]];
            if q[0] < 0.0 || q[1] < 0.0 || q[0] >= w as f32 || q[1] >= h as f32 {
                out[y * w + x] = 1.0;
                continue;
            }
            let gq = [q[0] - 0.5, q[1] - 0.5];
            let b = [gq[0].floor() as i32, gq[1].floor() as i32];
            let f = [gq[0] - b[0] as f32, gq[1] - b[1] as f32];
            let (mut keep, mut ws) = (0.0f32, 0.0f32);
            for k in 0..4 {
                let o = [k & 1, k >> 1];
                let t = [b[0] + o[0], b[1] + o[1]];
                let wx = if o[0] == 1 { f[0] } else { 1.0 - f[0] };
                let wy = if o[1] == 1 { f[1] } else { 1.0 - f[1] };
                let wt = wx * wy;
                if !inside(t, p.size) || wt <= 0.0 {
                    continue;
                }
                let pd = f32::from_bits(recon[t[1] as usize * w + t[0] as usize]);
                let mut kept = 1.0f32;
                if pd > d {
                    let z = 1.0 / d;
                    let diff = z - 1.0 / pd;
                    let sep = p.depth_tolerance * z;
                    if diff > sep {
                        kept = sep / diff;
                    }
                }
                keep += wt * kept;
                ws += wt;
            }
            out[y * w + x] = if ws > 0.0 { 1.0 - keep / ws } else { 0.0 };
        }
    }
    out
}

/// lock.comp: the output pixels locked this frame (1), from the thin features of the prepared
/// colour ([`prepare`]).
pub fn lock(p: &Params, prepared: &[[f32; 4]]) -> Vec<u32> {
    let (w, h) = p.size;
    let (ow, oh) = p.out;
    let luma = |t: [i32; 2]| prepared[clamp_at(t, p.size)][0];
    let mut locks = vec![0u32; ow * oh];
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let l = OFF.map(|o| luma([x + o[0], y + o[1]]));
            if !crate::cpu_math::thin_feature(&l) {
                continue;
            }
            let px = ((x as f32 + 0.5 - p.jitter[0]) * p.ratio[0]).floor() as i32;
            let py = ((y as f32 + 0.5 - p.jitter[1]) * p.ratio[1]).floor() as i32;
            locks[clamp_at([px, py], p.out)] = 1;
        }
    }
    locks
}

/// What accumulate.comp writes.
pub struct Accumulated {
    /// Perceptual colour and the history weight.
    pub history: Vec<[f32; 4]>,
    /// Lock strength, the current sample's luma, its change, and the nearest sample's object
    /// and speed ([`object_code`]).
    pub aux: Vec<[f32; 4]>,
    /// Linear HDR (before RCAS).
    pub color: Vec<V3>,
    /// Disocclusion, lock, sample weight, history weight.
    pub debug: Vec<[f32; 4]>,
}

/// What accumulate.comp reads.
pub struct AccumulateInputs<'a> {
    /// The prepared colour ([`prepare`]).
    pub prepared: &'a [[f32; 4]],
    pub dilated: &'a [[f32; 4]],
    /// `None`: without the depth clip.
    pub disocclusion: Option<&'a [f32]>,
    /// `None`: without locks.
    pub new_locks: Option<&'a [u32]>,
    pub history: &'a [[f32; 4]],
    pub aux: &'a [[f32; 4]],
    /// The render's own velocity (render pixels) and object IDs, for the object test.
    pub velocity: &'a [[f32; 2]],
    pub ids: &'a [u32],
    /// Each object's turn by object ID (the reactive rule); `None`: `without-reactive`.
    pub turns: Option<&'a [f32]>,
}

/// The history aux's w ([`object_code`]): the object ID modulo 2^18, shifted past the speed's
/// bits; the speed in steps of 1/4 output pixel a frame, at most 15.75.
const SPEED_BITS: u32 = 6;
const SPEED_MASK: u32 = 63;
const ID_MASK: u32 = 0x3ffff;
const SPEED_STEP: f32 = 0.25;
const SPEED_MAX: f32 = 15.75;

/// The object and speed a history texel remembers (accumulate.comp's aux.w): ID << 6 | speed
/// in quarter output pixels a frame, an integer exact in f32.
pub fn object_code(id: u32, speed: f32) -> f32 {
    (((id & ID_MASK) << SPEED_BITS) | (speed.min(SPEED_MAX) / SPEED_STEP + 0.5) as u32) as f32
}

/// The object test: the history texel (its aux.w `code`) is another object than `id`, moving at
/// least `speed_gap` output pixels a frame faster or slower than `speed`.
pub fn other_object(code: f32, id: u32, speed: f32, speed_gap: f32) -> bool {
    let code = code as u32;
    (code >> SPEED_BITS) != id & ID_MASK
        && ((code & SPEED_MASK) as f32 * SPEED_STEP - speed).abs() >= speed_gap
}

pub const STILL: f32 = 1.0 / 64.0;
/// The rectification box's weight exp(-BOX_CURVE d^2) (FSR 2's).
const BOX_CURVE: f32 = 2.3;

use crate::cpu_math::lanczos3_weights;

fn history_at(p: &Params, hist: &[[f32; 4]], b: [i32; 2], f: [f32; 2], nearest: [i32; 2]) -> [f32; 4] {
    let lanczos3 = p.kernel == Kernel::Lanczos && p.history_lobes == 3;
    let (lo, hi) = match p.kernel {
        Kernel::Bilinear => (0, 1),
        _ if lanczos3 => (-2, 3),
        _ => (-1, 2),
    };
    let w1 = |f: f32| -> [f32; 6] {
        match p.kernel {
            Kernel::Bilinear => [1.0 - f, f, 0.0, 0.0, 0.0, 0.0],
            _ if lanczos3 => lanczos3_weights(f),
            k => std::array::from_fn(|i| {
                let d = i as f32 - 1.0 - f;
                if i < 4 { kernel_weight_sq(k, d * d) } else { 0.0 }
            }),
        }
    };
    let (wx, wy) = (w1(f[0]), w1(f[1]));
    let (mut mn, mut mx) = ([1e30f32; 3], [-1e30f32; 3]);
    let (mut acc, mut ws, mut hw) = ([0.0f32; 3], 0.0f32, 0.0f32);
    for y in lo..=hi {
        for x in lo..=hi {
            let at = [b[0] + x, b[1] + y];
            let t = hist[clamp_at(at, p.out)];
            let w = wx[(x - lo) as usize] * wy[(y - lo) as usize];
            for j in 0..3 {
                acc[j] += w * t[j];
            }
            ws += w;
            if (0..=1).contains(&x) && (0..=1).contains(&y) {
                for j in 0..3 {
                    mn[j] = mn[j].min(t[j]);
                    mx[j] = mx[j].max(t[j]);
                }
                if at == nearest {
                    hw = t[3];
                }
            }
        }
    }
    [
        (acc[0] / ws).clamp(mn[0], mx[0]),
        (acc[1] / ws).clamp(mn[1], mx[1]),
        (acc[2] / ws).clamp(mn[2], mx[2]),
        hw,
    ]
}

/// accumulate.comp: the new history, its auxiliary data, the output colour and the debug views.
pub fn accumulate(p: &Params, i: &AccumulateInputs) -> Accumulated {
    let (ow, oh) = p.out;
    let e = p.exposure;
    let n_out = ow * oh;
    let mut out = Accumulated {
        history: Vec::with_capacity(n_out),
        aux: Vec::with_capacity(n_out),
        color: Vec::with_capacity(n_out),
        debug: Vec::with_capacity(n_out),
    };
    for py in 0..oh {
        for px in 0..ow {
            let src = [
                (px as f32 + 0.5) / p.ratio[0],
                (py as f32 + 0.5) / p.ratio[1],
            ];
            let under = clamp_at([src[0].floor() as i32, src[1].floor() as i32], p.size);
            let g = i.dilated[under];
            let v = [g[0] * p.ratio[0], g[1] * p.ratio[1]];
            let speed = (v[0] * v[0] + v[1] * v[1]).sqrt();
            // How far the pixel is towards SPEED (accum[2]): the cap and the kernel follow it.
            let moving = (speed / p.accum[2]).min(1.0);
            let mut dis = i.disocclusion.map_or(0.0, |d| d[under]);

            let q = [px as f32 + 0.5 - v[0], py as f32 + 0.5 - v[1]];
            let mut use_h = !p.reset
                && q[0] >= 0.0
                && q[1] >= 0.0
                && q[0] < ow as f32
                && q[1] < oh as f32;
            let (mut h, mut hw, mut aux) = ([0.0f32; 3], 0.0f32, [0.0f32; 4]);
            if use_h {
                let g = [q[0] - 0.5, q[1] - 0.5];
                let b = [g[0].floor() as i32, g[1].floor() as i32];
                let f = [g[0] - b[0] as f32, g[1] - b[1] as f32];
                let nearest = [b[0] + i32::from(f[0] >= 0.5), b[1] + i32::from(f[1] >= 0.5)];
                let hc = history_at(p, i.history, b, f, nearest);
                (h, hw) = ([hc[0], hc[1], hc[2]], hc[3]);
                aux = i.aux[clamp_at(nearest, p.out)];
                use_h = finite(h) && finite([aux[0], aux[1], aux[2]]) && hw.is_finite();
            }
            let c0 = [
                (src[0] + p.jitter[0]).floor() as i32,
                (src[1] + p.jitter[1]).floor() as i32,
            ];
            let c0 = [
                c0[0].clamp(0, p.size.0 as i32 - 1),
                c0[1].clamp(0, p.size.1 as i32 - 1),
            ];
            let at0 = c0[1] as usize * p.size.0 + c0[0] as usize;
            let raw_id = i.ids[at0];
            let own_id = raw_id & ID_MASK;
            let ov = i.velocity[at0];
            let (ox, oy) = (ov[0] * p.ratio[0], ov[1] * p.ratio[1]);
            let own_speed = (ox * ox + oy * oy).sqrt().min(SPEED_MAX);
            if p.ids && use_h && other_object(aux[3], own_id, own_speed, p.accum[2]) {
                dis = 1.0;
            }
            let keep = if use_h { 1.0 - dis } else { 0.0 };

            let bias = match p.kernel {
                Kernel::Bilinear => 1.0,
                _ => {
                    let t = keep * (1.0 - moving);
                    1.0 * (1.0 - t) + p.bias_max * t
                }
            };
            let (mut acc, mut m1, mut m2) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
            let (mut mn, mut mx) = ([1e30f32; 3], [-1e30f32; 3]);
            let (mut wsum, mut count, mut ws) = (0.0f32, 0.0f32, 0.0f32);
            let mut nearest = [0.0f32; 3];
            for (k, o) in OFF.iter().enumerate() {
                let t = [c0[0] + o[0], c0[1] + o[1]];
                if !inside(t, p.size) {
                    continue;
                }
                let pre = i.prepared[t[1] as usize * p.size.0 + t[0] as usize];
                if pre[3] == 0.0 {
                    continue;
                }
                let y = [pre[0], pre[1], pre[2]];
                let d = [
                    t[0] as f32 + 0.5 - p.jitter[0] - src[0],
                    t[1] as f32 + 0.5 - p.jitter[1] - src[1],
                ];
                let w = match p.kernel {
                    Kernel::Bilinear => (1.0 - d[0].abs()).max(0.0) * (1.0 - d[1].abs()).max(0.0),
                    k => kernel_weight_sq(k, (d[0] * d[0] + d[1] * d[1]) * bias * bias),
                };
                let b = (-BOX_CURVE * (d[0] * d[0] + d[1] * d[1])).exp();
                for j in 0..3 {
                    acc[j] += w * y[j];
                    m1[j] += b * y[j];
                    m2[j] += b * y[j] * y[j];
                    mn[j] = mn[j].min(y[j]);
                    mx[j] = mx[j].max(y[j]);
                }
                wsum += w;
                count += b;
                if k == 4 {
                    ws = w.max(0.0);
                    nearest = y;
                }
            }
            let cur: V3 = if wsum > 1e-4 {
                std::array::from_fn(|j| (acc[j] / wsum).clamp(mn[j], mx[j]))
            } else {
                nearest
            };

            let mut life = if use_h {
                (aux[0] - p.accum[3]).max(0.0)
            } else {
                0.0
            };
            match i.new_locks {
                Some(l) => {
                    if l[py * ow + px] != 0 {
                        life = 1.0;
                    }
                    if dis > 0.5 {
                        life = 0.0;
                    }
                }
                None => life = 0.0,
            }

            let (mut change, mut result, mut weight) = (0.0f32, cur, ws);
            if use_h {
                let still =
                    speed <= STILL && dis == 0.0 && !(p.background_moves && g[2] == 0.0);
                if !still && count > 0.0 {
                    let mu: V3 = std::array::from_fn(|j| m1[j] / count);
                    let sigma: V3 =
                        std::array::from_fn(|j| (m2[j] / count - mu[j] * mu[j]).max(0.0).sqrt());
                    let lo: V3 = std::array::from_fn(|j| mu[j] - p.gamma * sigma[j]);
                    let hi: V3 = std::array::from_fn(|j| mu[j] + p.gamma * sigma[j]);
                    let clipped = clip_towards(mu, h, lo, hi);
                    h = std::array::from_fn(|j| clipped[j] * (1.0 - life) + h[j] * life);
                }
                change = cur[0] - aux[1];
                if p.stability && change * aux[2] < 0.0 {
                    let (a, b) = (change.abs(), aux[2].abs());
                    ws *= 1.0 - 0.5 * a.min(b) / a.max(b);
                }
                let turn = i
                    .turns
                    .and_then(|t| t.get(raw_id as usize).copied())
                    .unwrap_or(0.0);
                let cap = (p.accum[0] * (1.0 - moving) + p.accum[1] * moving) * (1.0 - turn);
                let hk = (hw * keep).min(cap);
                let total = hk + ws;
                if total > 0.0 {
                    result = std::array::from_fn(|j| (hk * h[j] + ws * cur[j]) / total);
                }
                weight = total;
            }
            out.history.push([result[0], result[1], result[2], weight]);
            out.aux.push([life, cur[0], change, object_code(own_id, own_speed)]);
            out.color.push(linear_from_perceptual(result, e));
            out.debug.push([dis, life, ws, weight]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit tests' case: an 8x8 output of a 6x6 render (W / w = 4/3, the kernel's bias at
    /// its largest), Lanczos, every rule on, with the jitter given.
    fn small(jitter: [f32; 2]) -> Params {
        Params {
            out: (8, 8),
            size: (6, 6),
            jitter,
            ratio: [8.0 / 6.0, 8.0 / 6.0],
            exposure: 1.0,
            depth_tolerance: 0.05,
            gamma: 1.0,
            bias_max: 8.0 / 6.0,
            accum: [8.0, 1.0, 2.0, 1.0 / 16.0],
            reset: false,
            background_moves: false,
            kernel: Kernel::Lanczos,
            stability: true,
            ids: true,
            history_lobes: 3,
            surface_velocity: true,
        }
    }

    /// Lanczos-2 is sinc(x) sinc(x/2): 1 at 0, 0 at 1 and 2, negative between; FSR 2's
    /// polynomial matches it at 0, 1 and 2 and is off by up to 0.049 between (why it is not
    /// used); the tent and Catmull-Rom are the usual ones.
    /// The polynomial against sinc(x) sinc(x/2) in f64, every 1/10000 of x in [0, 2]: within
    /// 5e-7 (a degree one lower is off by 3e-6, FSR 2's polynomial by 0.049).
    #[test]
    fn the_lanczos_polynomial_is_the_sines() {
        let sinc = |x: f64| {
            if x == 0.0 {
                1.0
            } else {
                (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
            }
        };
        let worst = (0..=20000)
            .map(|i| {
                let x = i as f64 / 10000.0;
                let want = if x >= 2.0 { 0.0 } else { sinc(x) * sinc(x / 2.0) };
                (kernel_weight_sq(Kernel::Lanczos, (x * x) as f32) as f64 - want).abs()
            })
            .fold(0.0f64, f64::max);
        assert!(worst < 5e-7, "off by {worst}");
    }

    /// The current frame's kernel narrows (bias `bias_max`) only where the history is long: a
    /// still pixel with a history takes the narrow kernel, one moving at the moving cap's speed
    /// (`accum[2]`) or faster the widest (bias 1), one between them between, one without
    /// history the widest. Read from the sample weight (the kernel's weight of the nearest
    /// sample) on an 8x8 output of a 6x6 render, jittered off the centre.
    #[test]
    fn a_moving_pixel_takes_the_widest_kernel() {
        let p = small([0.31, -0.27]);
        let (out, size, ratio) = (p.out, p.size, p.ratio);
        let prepared: Vec<[f32; 4]> = (0..size.0 * size.1)
            .map(|i| [0.2 + 0.01 * i as f32, 0.0, 0.0, 1.0])
            .collect();
        let history = vec![[0.3, 0.0, 0.0, 4.0]; out.0 * out.1];
        let aux = vec![[0.0; 4]; out.0 * out.1];
        let (velocity, ids) = (vec![[0.0; 2]; size.0 * size.1], vec![0u32; size.0 * size.1]);
        // The sample weight at output pixel (5, 5) with every render pixel moving by `v`
        // output pixels along x (the dilated velocity is in render pixels).
        let weight = |v: f32, reset: bool| {
            let dilated = vec![[v / ratio[0], 0.0, 0.5, 0.0]; size.0 * size.1];
            let i = AccumulateInputs {
                prepared: &prepared,
                dilated: &dilated,
                disocclusion: None,
                new_locks: None,
                history: &history,
                aux: &aux,
                velocity: &velocity,
                ids: &ids,
                turns: None,
            };
            accumulate(&Params { reset, ..p }, &i).debug[5 * out.0 + 5][2]
        };
        // The nearest sample's offset from the output pixel's centre, in render pixels.
        let src = [5.5 / ratio[0], 5.5 / ratio[1]];
        let d: [f32; 2] = std::array::from_fn(|j| {
            (src[j] + p.jitter[j]).floor() + 0.5 - p.jitter[j] - src[j]
        });
        let d2 = d[0] * d[0] + d[1] * d[1];
        let at = |bias: f32| kernel_weight_sq(Kernel::Lanczos, d2 * bias * bias);
        let (narrow, wide) = (at(p.bias_max), at(1.0));
        assert!(wide - narrow > 0.05, "the case tells the kernels apart: {narrow} {wide}");
        assert_eq!(weight(0.0, false), narrow, "still, with a history");
        assert_eq!(weight(2.0, false), wide, "at the moving cap's speed");
        assert_eq!(weight(3.0, false), wide, "faster");
        assert_eq!(weight(0.0, true), wide, "no history");
        let half = weight(1.0, false);
        assert!(narrow < half && half < wide, "halfway: {narrow} < {half} < {wide}");
        assert_eq!(half, at(0.5 + 0.5 * p.bias_max));
    }

    /// The object test: a history of another object that moved differently (a torus that spun
    /// away from the wall behind it) is dropped with its lock; the same object, another
    /// object moving alike (a sub-pixel wire the jitter missed, as the sky around it moves), or
    /// `without-ids` keep it.
    #[test]
    fn another_object_moving_differently_loses_its_history() {
        let p = small([0.0, 0.0]);
        let (out, size) = (p.out, p.size);
        let prepared = vec![[0.2, 0.0, 0.0, 1.0]; size.0 * size.1];
        let history = vec![[0.9, 0.0, 0.0, 4.0]; out.0 * out.1];
        let new_locks = vec![0u32; out.0 * out.1];
        let velocity = vec![[0.0; 2]; size.0 * size.1];
        let dilated = vec![[0.0, 0.0, 0.5, 0.0]; size.0 * size.1];
        // The history remembers object `hid` moving `hspeed` output pixels a frame, locked; this
        // frame every sample is object `id`, still.
        let run = |hid: u32, hspeed: f32, id: u32, ids_on: bool| {
            let aux = vec![[1.0, 0.9, 0.0, object_code(hid, hspeed)]; out.0 * out.1];
            let ids = vec![id; size.0 * size.1];
            let i = AccumulateInputs {
                prepared: &prepared,
                dilated: &dilated,
                disocclusion: None,
                new_locks: Some(&new_locks),
                history: &history,
                aux: &aux,
                velocity: &velocity,
                ids: &ids,
                turns: None,
            };
            let a = accumulate(&Params { ids: ids_on, ..p }, &i);
            let k = 5 * out.0 + 5;
            (a.debug[k], a.history[k][0], a.aux[k][3])
        };
        let (d, h, code) = run(2, 3.0, 1, true);
        assert_eq!((d[0], d[1]), (1.0, 0.0), "dropped, the lock with it");
        assert_eq!((h, d[3]), (0.2, d[2]), "the current frame alone");
        assert_eq!(code, object_code(1, 0.0), "the pixel remembers its own object");
        for (hid, hspeed, ids_on, what) in [
            (1, 3.0, true, "the same object"),
            (2, 1.75, true, "another object moving alike"),
            (2, 3.0, false, "without-ids"),
        ] {
            let (d, h, _) = run(hid, hspeed, 1, ids_on);
            assert_eq!(d[0], 0.0, "{what}: kept");
            assert_eq!(d[1], 1.0 - p.accum[3], "{what}: the lock ages");
            assert!(h > 0.3, "{what}: the history blends in ({h})");
        }
        assert!(other_object(object_code(7, 0.0), 8, 2.0, 2.0));
        assert!(!other_object(object_code(7, 15.75), 7, 0.0, 2.0));
        assert_eq!(object_code(3, 99.0) as u32 >> 6, 3, "the speed saturates in its bits");
    }

    /// The history's Lanczos-3 weights from three sines are the kernel's own (within 1.5e-5 of
    /// sinc(x) sinc(x / 3) in f64 at every 1/1000 of f), 1 and 0 at whole offsets.
    #[test]
    fn the_lanczos3_weights_are_the_kernel() {
        let sinc = |x: f64| {
            if x == 0.0 {
                1.0
            } else {
                (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
            }
        };
        let mut worst = 0.0f64;
        for i in 0..1000 {
            let f = i as f32 / 1000.0;
            let w = lanczos3_weights(f);
            for (k, &wk) in w.iter().enumerate() {
                let x = (k as i32 - 2) as f64 - f64::from(f);
                let want = if x.abs() < 3.0 { sinc(x) * sinc(x / 3.0) } else { 0.0 };
                worst = worst.max((f64::from(wk) - want).abs());
            }
        }
        // f32: the second factor cancels near f = 1 (measured 1.08e-5); S3 rounded to 4
        // digits gives 0.012.
        assert!(worst < 1.5e-5, "worst {worst}");
        let w = lanczos3_weights(0.0);
        assert_eq!(w[2], 1.0);
        assert!(w.iter().enumerate().all(|(k, v)| k == 2 || v.abs() < 1e-6), "{w:?}");
    }

    /// The reactive rule: a turning object keeps (1 - turn) of the cap, at rest as at speed
    /// (none when it turns 10 degrees a frame or more: its shading changes whatever its
    /// pixel's speed); without `turns`, or past their list, the cap is the usual one.
    #[test]
    fn a_turning_object_keeps_less_history() {
        let p = Params {
            gamma: 16.0,
            stability: false,
            ..small([0.0, 0.0])
        };
        let (out, size, ratio) = (p.out, p.size, p.ratio);
        let prepared = vec![[0.2, 0.0, 0.0, 1.0]; size.0 * size.1];
        let history = vec![[0.2, 0.0, 0.0, 6.0]; out.0 * out.1];
        let aux = vec![[0.0, 0.2, 0.0, object_code(3, 0.0)]; out.0 * out.1];
        let ids = vec![3u32; size.0 * size.1];
        // The pixel's history weight after this frame with the object moving `v` output pixels a
        // frame (its own velocity zero: the object test keeps the history), turning `turn`.
        let weight = |v: f32, turns: Option<&[f32]>| {
            let dilated = vec![[v / ratio[0], 0.0, 0.5, 0.0]; size.0 * size.1];
            let velocity = vec![[0.0; 2]; size.0 * size.1];
            let i = AccumulateInputs {
                prepared: &prepared,
                dilated: &dilated,
                disocclusion: None,
                new_locks: None,
                history: &history,
                aux: &aux,
                velocity: &velocity,
                ids: &ids,
                turns,
            };
            let d = accumulate(&p, &i).debug[5 * out.0 + 5];
            d[3] - d[2]
        };
        let (half, full) = ([0.0, 0.0, 0.0, 0.5], [0.0, 0.0, 0.0, 1.0]);
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        assert!(close(weight(2.0, None), 1.0), "the moving cap");
        assert!(close(weight(2.0, Some(&half)), 0.5), "half of it, turning half");
        assert!(close(weight(3.0, Some(&full)), 0.0), "none, turning fully");
        assert!(close(weight(0.0, None), 6.0), "at rest: the history's own weight, under 8");
        assert!(close(weight(0.0, Some(&half)), 4.0), "at rest, turning half: half the cap");
        assert!(close(weight(0.0, Some(&full)), 0.0), "at rest, turning fully: none");
        assert!(close(weight(1.0, Some(&half)), 2.25), "half way: half of 4.5");
        assert!(close(weight(2.0, Some(&[1.0; 3])), 1.0), "no turn past the list (ID 3)");
    }

    #[test]
    fn kernels_are_what_they_say() {
        let k = |kernel, x: f32| kernel_weight_sq(kernel, x * x);
        assert!((k(Kernel::Lanczos, 0.0) - 1.0).abs() < 1e-6);
        let sinc = |x: f32| (std::f32::consts::PI * x).sin() / (std::f32::consts::PI * x);
        assert!((k(Kernel::Lanczos, 0.7) - sinc(0.7) * sinc(0.35)).abs() < 1e-6);
        for x in [1.0f32, 2.0, 2.5] {
            assert!(k(Kernel::Lanczos, x).abs() < 1e-6, "{x}");
            assert!(lanczos2_fsr2_approx(x * x).abs() < 1e-6, "{x}");
        }
        let worst = (0..=2000)
            .map(|i| {
                let x = i as f32 / 1000.0;
                (k(Kernel::Lanczos, x) - lanczos2_fsr2_approx(x * x)).abs()
            })
            .fold(0.0f32, f32::max);
        assert!((0.045..0.05).contains(&worst), "approximation off by {worst}");
        assert!(k(Kernel::Lanczos, 1.5) < 0.0, "the negative lobe");
        assert_eq!(k(Kernel::Bilinear, 0.25), 0.75);
        assert_eq!(k(Kernel::Bilinear, 1.5), 0.0);
        assert!((k(Kernel::Catmull, 0.0) - 1.0).abs() < 1e-6);
        assert!(k(Kernel::Catmull, 1.0).abs() < 1e-6 && k(Kernel::Catmull, 2.0).abs() < 1e-6);
        // Catmull-Rom's weights at offsets -1..2 of f = 0.3 sum to 1.
        let s: f32 = [-1.3f32, -0.3, 0.7, 1.7].iter().map(|d| k(Kernel::Catmull, d.abs())).sum();
        assert!((s - 1.0).abs() < 1e-5, "{s}");
    }
}
