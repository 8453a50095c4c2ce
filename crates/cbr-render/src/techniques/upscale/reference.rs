//! The CPU reference of `upscale:fsr1` (shaders/upscale/easu.comp, rcas.comp, fsr1.glsl): the
//! same f32 arithmetic in the shaders' order, written from AMD's description of FSR 1
//! (docs/upscale.md). Images are row-major linear HDR RGB; both passes work on the encoded
//! colour ([`encode`]) and give linear HDR back.

/// Below this squared gradient length EASU has no direction (AMD: 1/32768) and uses +x.
pub const EASU_FLAT: f32 = 1.0 / 32768.0;
/// The most negative RCAS lobe: 1/4 - 1/16 (AMD's FSR_RCAS_LIMIT), so the 5-tap cross never
/// becomes a high-pass.
pub const RCAS_LIMIT: f32 = 0.25 - 1.0 / 16.0;
/// Guards RCAS's limits' divisions (all-black neighbours, neighbours at the peak).
pub const RCAS_EPS: f32 = 1.0 / 65536.0;
/// The smallest `1 - max(t)` [`decode`] divides by: encoded values at the peak decode to at most
/// 4095 (exposure-scaled) rather than infinity.
pub const DECODE_FLOOR: f32 = 1.0 / 4096.0;

fn max3(c: [f32; 3]) -> f32 {
    c[0].max(c[1]).max(c[2])
}

/// Linear HDR to FSR's perceptual [0, 1): exposure-scaled, negatives to 0, the reversible
/// tonemap c / (1 + max(r, g, b)) (each channel below 1, RCAS's peak), then a square root
/// (gamma 2, the perceptual spacing EASU's analysis and RCAS's limits are tuned for).
pub fn encode(c: [f32; 3], exposure: f32) -> [f32; 3] {
    let e = c.map(|v| (v * exposure).max(0.0));
    let d = 1.0 + max3(e);
    e.map(|v| (v / d).sqrt())
}

/// The inverse of [`encode`].
pub fn decode(g: [f32; 3], exposure: f32) -> [f32; 3] {
    let t = g.map(|v| v * v);
    let d = (1.0 - max3(t)).max(DECODE_FLOOR) * exposure;
    t.map(|v| v / d)
}

/// FSR's luma: r/2 + g + b/2.
pub fn luma(c: [f32; 3]) -> f32 {
    0.5 * c[0] + c[1] + 0.5 * c[2]
}

/// A row-major image of RGB.
pub struct Rgb<'a> {
    pub width: usize,
    pub height: usize,
    pub data: &'a [[f32; 3]],
}

impl Rgb<'_> {
    /// The texel at (x, y), clamped to the edge.
    fn at(&self, x: i64, y: i64) -> [f32; 3] {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.data[y * self.width + x]
    }
}

/// EASU's 12 taps around the 2x2 quad f g / j k (offsets from f):
/// ```text
///     b c
///   e f g h
///   i j k l
///     n o
/// ```
pub const TAPS: [(i64, i64); 12] = [
    (0, -1),
    (1, -1),
    (-1, 0),
    (0, 0),
    (1, 0),
    (2, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
    (2, 1),
    (0, 2),
    (1, 2),
];

/// One "+" of the analysis around a quad texel, weighted by its bilinear weight `w`: the
/// gradient (right - left, down - up) adds to `dir`; each axis' edge-ness, |right - left| over
/// the larger one-sided difference (1 on a ramp or a step, below 1 on a one-texel ridge or
/// noise), saturated and squared, adds to `len`.
#[allow(clippy::too_many_arguments)]
fn analyse(
    dir: &mut [f32; 2],
    len: &mut f32,
    w: f32,
    up: f32,
    left: f32,
    c: f32,
    right: f32,
    down: f32,
) {
    let edge = |lo: f32, hi: f32| {
        let m = (hi - c).abs().max((c - lo).abs());
        if m > 0.0 {
            ((hi - lo).abs() / m).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let (lx, ly) = (edge(left, right), edge(up, down));
    dir[0] += (right - left) * w;
    dir[1] += (down - up) * w;
    *len += (lx * lx + ly * ly) * w;
}

/// EASU at one output pixel: `pp` the position in low-resolution texels (centres at integers).
/// Returns the encoded colour.
fn easu_at(low: &Rgb, exposure: f32, pp: [f32; 2]) -> [f32; 3] {
    let fp = [pp[0].floor(), pp[1].floor()];
    let f = [pp[0] - fp[0], pp[1] - fp[1]];
    let (bx, by) = (fp[0] as i64, fp[1] as i64);
    let c: Vec<[f32; 3]> = TAPS
        .iter()
        .map(|&(dx, dy)| encode(low.at(bx + dx, by + dy), exposure))
        .collect();
    let l: Vec<f32> = c.iter().map(|&v| luma(v)).collect();
    // Direction and edge-ness from the four crosses, bilinearly weighted.
    let (mut dir, mut len) = ([0.0f32; 2], 0.0f32);
    let (fx, fy) = (f[0], f[1]);
    analyse(&mut dir, &mut len, (1.0 - fx) * (1.0 - fy), l[0], l[2], l[3], l[4], l[7]);
    analyse(&mut dir, &mut len, fx * (1.0 - fy), l[1], l[3], l[4], l[5], l[8]);
    analyse(&mut dir, &mut len, (1.0 - fx) * fy, l[3], l[6], l[7], l[8], l[10]);
    analyse(&mut dir, &mut len, fx * fy, l[4], l[7], l[8], l[9], l[11]);
    let d2 = dir[0] * dir[0] + dir[1] * dir[1];
    let dir = if d2 < EASU_FLAT {
        [1.0, 0.0]
    } else {
        let r = 1.0 / d2.sqrt();
        [dir[0] * r, dir[1] * r]
    };
    let len = 0.5 * len;
    let len = len * len;
    // The kernel: stretched across the gradient by up to 1/max(|cos|, |sin|) (the taps' square
    // footprint seen along a diagonal), widened along the edge, its negative lobe weaker on
    // edges (lob 0.5 -> 0.21).
    let stretch = 1.0 / dir[0].abs().max(dir[1].abs());
    let len2 = [1.0 + (stretch - 1.0) * len, 1.0 - 0.5 * len];
    let lob = 0.5 - 0.29 * len;
    let clp = 1.0 / lob;
    let (mut acc, mut wsum) = ([0.0f32; 3], 0.0f32);
    for (i, &(dx, dy)) in TAPS.iter().enumerate() {
        let off = [dx as f32 - fx, dy as f32 - fy];
        let vx = (off[0] * dir[0] + off[1] * dir[1]) * len2[0];
        let vy = (off[1] * dir[0] - off[0] * dir[1]) * len2[1];
        let w = lanczos2_approx((vx * vx + vy * vy).min(clp), lob);
        for k in 0..3 {
            acc[k] += c[i][k] * w;
        }
        wsum += w;
    }
    // Deringing: clamp to the range of the quad's four texels.
    let quad = [c[3], c[4], c[7], c[8]];
    std::array::from_fn(|k| {
        let lo = quad.iter().map(|q| q[k]).fold(f32::INFINITY, f32::min);
        let hi = quad.iter().map(|q| q[k]).fold(f32::NEG_INFINITY, f32::max);
        (acc[k] / wsum).clamp(lo, hi)
    })
}

/// FSR 1's polynomial Lanczos-2 of squared distance `x2`: the base (25/16)(2/5 x^2 - 1)^2 -
/// 9/16 (1 at 0, 0 at 1) times the window (lob x^2 - 1)^2 (0 at x^2 = 1/lob; lob = 1/4 is
/// Lanczos-2's support of 2). No sine, no square root.
pub fn lanczos2_approx(x2: f32, lob: f32) -> f32 {
    let wb = 0.4 * x2 - 1.0;
    let wa = lob * x2 - 1.0;
    (25.0 / 16.0 * wb * wb - 9.0 / 16.0) * (wa * wa)
}

/// EASU: `low` upscaled to `width` x `height` (linear HDR out).
pub fn easu(low: &Rgb, width: usize, height: usize, exposure: f32) -> Vec<[f32; 3]> {
    let sx = low.width as f32 / width as f32;
    let sy = low.height as f32 / height as f32;
    let mut out = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let pp = [(x as f32 + 0.5) * sx - 0.5, (y as f32 + 0.5) * sy - 0.5];
            out.push(decode(easu_at(low, exposure, pp), exposure));
        }
    }
    out
}

/// RCAS at one pixel on the encoded cross b (up), d (left), e, f (right), h (down): the lobe
/// (negative: neighbours subtract) is the largest that keeps every channel inside [0, 1] for
/// the cross's own minimum and maximum, capped at [`RCAS_LIMIT`], times 2^-sharpness.
pub fn rcas_at(b: [f32; 3], d: [f32; 3], e: [f32; 3], f: [f32; 3], h: [f32; 3], s: f32) -> [f32; 3] {
    let mut lobe = f32::NEG_INFINITY;
    for k in 0..3 {
        let mn4 = b[k].min(d[k]).min(f[k].min(h[k]));
        let mx4 = b[k].max(d[k]).max(f[k].max(h[k]));
        let hit_min = mn4.min(e[k]) / (4.0 * mx4).max(RCAS_EPS);
        let hit_max = (1.0 - mx4.max(e[k])) / (4.0 * mn4 - 4.0).min(-RCAS_EPS);
        lobe = lobe.max((-hit_min).max(hit_max));
    }
    let lobe = (-RCAS_LIMIT).max(lobe.min(0.0)) * s;
    let r = 4.0 * lobe + 1.0;
    std::array::from_fn(|k| (lobe * (b[k] + d[k] + f[k] + h[k]) + e[k]) / r)
}

/// RCAS over a `width` x `height` image (edges clamped), `s` = 2^-sharpness.
pub fn rcas(img: &Rgb, s: f32, exposure: f32) -> Vec<[f32; 3]> {
    let enc = |x: i64, y: i64| encode(img.at(x, y), exposure);
    let mut out = Vec::with_capacity(img.width * img.height);
    for y in 0..img.height as i64 {
        for x in 0..img.width as i64 {
            let o = rcas_at(
                enc(x, y - 1),
                enc(x - 1, y),
                enc(x, y),
                enc(x + 1, y),
                enc(x, y + 1),
                s,
            );
            out.push(decode(o, exposure));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() <= tol * b[k].abs().max(1.0))
    }

    #[test]
    fn the_encoding_round_trips_and_stays_below_one() {
        for c in [[0.0, 0.0, 0.0], [0.01, 0.5, 2.0], [100.0, 3.0, 0.0], [1000.0, 999.0, 1.0]] {
            for exposure in [1.0, 0.25, 4.0] {
                let g = encode(c, exposure);
                assert!(g.iter().all(|v| (0.0..1.0).contains(v)), "{g:?}");
                assert!(close(decode(g, exposure), c, 1e-3), "{c:?} at {exposure}");
            }
        }
        assert_eq!(encode([-1.0, 0.0, 0.0], 1.0), [0.0; 3]);
    }

    #[test]
    fn the_polynomial_is_lanczos2_like() {
        let lanczos2 = |x: f32| {
            let px = std::f32::consts::PI * x;
            if x == 0.0 { 1.0 } else { 2.0 * px.sin() * (px / 2.0).sin() / (px * px) }
        };
        assert_eq!(lanczos2_approx(0.0, 0.25), 1.0);
        assert!(lanczos2_approx(1.0, 0.25).abs() < 1e-6);
        assert!(lanczos2_approx(4.0, 0.25).abs() < 1e-6);
        for i in 0..=40 {
            let x = i as f32 * 0.05;
            let err = (lanczos2_approx(x * x, 0.25) - lanczos2(x)).abs();
            // 0.049 at most, near x = 0.6: the same zeros, the same lobes.
            assert!(err < 0.05, "x {x}: {err}");
        }
    }

    #[test]
    fn easu_and_rcas_keep_a_constant_image() {
        let data = vec![[0.3, 2.0, 7.5]; 7 * 5];
        let low = Rgb { width: 7, height: 5, data: &data };
        let up = easu(&low, 10, 7, 1.0);
        assert!(up.iter().all(|&c| close(c, data[0], 1e-5)), "{:?}", up[0]);
        let img = Rgb { width: 10, height: 7, data: &up };
        assert!(rcas(&img, 1.0, 1.0).iter().all(|&c| close(c, data[0], 1e-5)));
    }

    #[test]
    fn easu_never_rings_beyond_the_nearest_quad() {
        // A hard vertical edge: every output lies between the two sides.
        let data: Vec<[f32; 3]> =
            (0..8 * 6).map(|i| if i % 8 < 4 { [0.1; 3] } else { [5.0; 3] }).collect();
        let low = Rgb { width: 8, height: 6, data: &data };
        for c in easu(&low, 16, 12, 1.0) {
            assert!(c[0] >= 0.1 - 1e-5 && c[0] <= 5.0 + 1e-4, "{c:?}");
        }
    }

    #[test]
    fn rcas_sharpens_within_its_limits() {
        // A bright centre on a dark cross gets brighter; sharpness 2 stops sharpens less.
        let (n, e) = ([0.2; 3], [0.3; 3]);
        let full = rcas_at(n, n, e, n, n, 1.0);
        let quarter = rcas_at(n, n, e, n, n, 0.25);
        assert!(full[0] > quarter[0] && quarter[0] > 0.3, "{full:?} {quarter:?}");
        // Here the cap binds: (e - 1.6 n lobe) / (1 - 4 lobe) at lobe = RCAS_LIMIT.
        let want = (0.3 - RCAS_LIMIT * 0.8) / (1.0 - 4.0 * RCAS_LIMIT);
        assert!((full[0] - want).abs() < 1e-6, "{full:?} vs {want}");
        // Brighter, the peak's limit binds: the output reaches 1 and no further.
        let peak = rcas_at([0.4; 3], [0.4; 3], [0.6; 3], [0.4; 3], [0.4; 3], 1.0);
        assert!((peak[0] - 1.0).abs() < 1e-5 && peak[0] <= 1.0 + 1e-6, "{peak:?}");
        // All-black neighbours: no division by zero, no sharpening.
        assert_eq!(rcas_at([0.0; 3], [0.0; 3], e, [0.0; 3], [0.0; 3], 1.0), e);
    }
}
