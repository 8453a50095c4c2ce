//! The CPU reference of shaders/resolve/resolve.comp, operation for operation in f32 (the
//! shader's fp32 path matches it within 1e-5; its fp16 path within the tolerance the tests
//! state). Inputs are full-resolution images; only the pixels of the frame's parity are read
//! from `current`.

use super::{
    DBG_CLAMPED, DBG_MISSING, DBG_REJECT_DEPTH, DBG_REJECT_ID, DBG_RENDERED, DBG_REPROJECTED,
    DBG_SPATIAL, DBG_STILL, ID_MASK, ID_MOVED, ResolveMode, ResolveSettings,
};

/// One checkerboard sample as the resolve reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    pub c: [f32; 3],
    pub v: [f32; 2],
    /// Reverse-Z depth (0 = infinitely far).
    pub d: f32,
    /// Object, primitive.
    pub ids: [u32; 2],
}

/// The previous resolved frame (colour as stored: already rounded to the history format).
pub struct HistoryRef<'a> {
    pub color: &'a [[f32; 3]],
    pub depth: &'a [f32],
    pub ids: &'a [u32],
}

pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    pub parity: u32,
    pub current: &'a [Sample],
    /// `None`: reset (first frame, camera cut).
    pub history: Option<HistoryRef<'a>>,
    /// The native-resolution prepass: reverse-Z depth and object IDs.
    pub prepass: Option<(&'a [f32], &'a [u32])>,
    /// Column-major previous clip from current (NDC x, NDC y, depth, 1) (`intel`).
    pub reproj: [f32; 16],
}

#[derive(Clone, Debug, Default)]
pub struct Output {
    pub color: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
    pub ids: Vec<u32>,
    pub debug: Vec<u32>,
    pub velocity: Vec<[f32; 2]>,
}

use crate::cpu_math::{V3, catmull_rom, depth_rel_diff, from_ycocg, length, luma, to_ycocg};

/// What a history texel must show for a hypothesis: object `id` (when `ids`) at a reverse-Z depth
/// in [lo, hi] or within the depth tolerance of either end (when `depth`).
struct Test {
    id: u32,
    lo: f32,
    hi: f32,
    ids: bool,
    depth: bool,
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn div(a: V3, s: f32) -> V3 {
    [a[0] / s, a[1] / s, a[2] / s]
}
pub fn tonemap(c: V3) -> V3 {
    div(c, 1.0 + luma(c).max(0.0))
}
pub fn untonemap(t: V3) -> V3 {
    div(t, (1.0 - luma(t)).max(1e-3))
}

/// `ours`' history share in the moving blend (resolve.comp's `history_share`): from the
/// tonemapped luminance differences of the horizontal and vertical pairs, more history where both
/// differ (detail), none where one differs much more than the other (an edge through the pixel).
fn history_share(n: &[Sample; 4]) -> f32 {
    use super::{DETAIL_CONTRAST, EDGE_CONTRAST, HISTORY_WEIGHT, HISTORY_WEIGHT_DETAIL};
    let l = |i: usize| luma(tonemap(n[i].c));
    let dh = (l(0) - l(1)).abs();
    let dv = (l(2) - l(3)).abs();
    let lo = dh.min(dv);
    let detail = (lo / DETAIL_CONTRAST).clamp(0.0, 1.0);
    let edge = ((dh.max(dv) - lo) / EDGE_CONTRAST).clamp(0.0, 1.0);
    let w =
        HISTORY_WEIGHT + (HISTORY_WEIGHT_DETAIL - HISTORY_WEIGHT) * detail - HISTORY_WEIGHT * edge;
    w.clamp(0.0, 1.0)
}

/// The differential blend's weight offset (BLEND_EPS in resolve.comp).
pub const BLEND_EPS: f32 = 1.0 / 64.0;

const NEIGHBOUR: [[i32; 2]; 4] = [[-1, 0], [1, 0], [0, -1], [0, 1]];
const TAP: [[i32; 2]; 4] = [[0, 0], [1, 0], [0, 1], [1, 1]];

struct Ctx<'a> {
    i: &'a Inputs<'a>,
    s: &'a ResolveSettings,
    w: i32,
    h: i32,
    reset: bool,
    own: bool,
}

struct Res {
    c: V3,
    d: f32,
    id: u32,
    v: [f32; 2],
    dbg: u32,
}

impl Ctx<'_> {
    fn idx(&self, x: i32, y: i32) -> usize {
        (y * self.w + x) as usize
    }
    fn inside(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.w && y < self.h
    }
    fn load(&self, x: i32, y: i32) -> Sample {
        let (x, y) = (x.abs(), y.abs());
        let (x, y) = (x.min(2 * self.w - 2 - x), y.min(2 * self.h - 2 - y));
        debug_assert_eq!((x + y) as u32 & 1, self.i.parity);
        self.i.current[self.idx(x, y)]
    }
    fn hist(&self) -> &HistoryRef<'_> {
        self.i.history.as_ref().expect("history when not reset")
    }

    fn taps(q: [f32; 2]) -> ([i32; 2], [f32; 4]) {
        let g = [q[0] - 0.5, q[1] - 0.5];
        let b = [g[0].floor(), g[1].floor()];
        let f = [g[0] - b[0], g[1] - b[1]];
        (
            [b[0] as i32, b[1] as i32],
            [
                (1.0 - f[0]) * (1.0 - f[1]),
                f[0] * (1.0 - f[1]),
                (1.0 - f[0]) * f[1],
                f[0] * f[1],
            ],
        )
    }

    /// Inside [lo, hi] or within the tolerance tol of either end (relative linear depth, as
    /// `depth_rel_diff`): below the span (lo - hd) / lo <= tol, above it (hd - hi) / hd <= tol,
    /// that is lo * keep <= hd and hd * keep <= hi with keep = min(1 - tol, 1), which also holds
    /// inside the span (resolve.comp's `depth_agrees`: two products, no division).
    fn depth_agrees(&self, hd: f32, lo: f32, hi: f32) -> bool {
        let keep = (1.0 - self.s.depth_tolerance).min(1.0);
        hd >= lo * keep && hd * keep <= hi
    }

    fn tap_reasons(&self, i: usize, t: &Test) -> u32 {
        let hist = self.hist();
        let mut r = 0;
        if t.ids && hist.ids[i] & ID_MASK != t.id {
            r |= DBG_REJECT_ID;
        }
        if t.depth && !self.depth_agrees(hist.depth[i], t.lo, t.hi) {
            r |= DBG_REJECT_DEPTH;
        }
        r
    }

    /// History at q for `t` when the texel containing q is valid (`fused`'s test).
    fn history_validated(&self, q: [f32; 2], t: &Test, why: &mut u32) -> Option<V3> {
        let near = [q[0].floor() as i32, q[1].floor() as i32];
        if !self.inside(near[0], near[1]) {
            return None;
        }
        let rn = self.tap_reasons(self.idx(near[0], near[1]), t);
        if rn != 0 {
            *why |= rn;
            return None;
        }
        let (_, valid) = self.history_weight(q, t, why);
        Some(self.history_resampled(q, valid))
    }

    /// The share of the bilinear footprint at q on history texels valid for `t`, and the mask of
    /// those taps (`history_weight`).
    fn history_weight(&self, q: [f32; 2], t: &Test, why: &mut u32) -> (f32, u32) {
        let (base, w) = Self::taps(q);
        let (mut ws, mut valid) = (0.0f32, 0u32);
        for k in 0..4 {
            let (tx, ty) = (base[0] + TAP[k][0], base[1] + TAP[k][1]);
            if w[k] <= 0.0 || !self.inside(tx, ty) {
                continue;
            }
            let rn = self.tap_reasons(self.idx(tx, ty), t);
            if rn == 0 {
                ws += w[k];
                valid |= 1 << k;
            } else {
                *why |= rn;
            }
        }
        (ws, valid)
    }

    /// History at q over the taps in `valid` (bilinear, renormalised), Catmull-Rom over the 12
    /// texels of the 4 x 4 window without its corners (renormalised) when all four with weight
    /// are.
    fn history_resampled(&self, q: [f32; 2], valid: u32) -> V3 {
        let (base, w) = Self::taps(q);
        let b = [base[0] as f32 + 0.5, base[1] as f32 + 0.5];
        let all_ok = (0..4).all(|k| w[k] <= 0.0 || valid & (1 << k) != 0);
        // Five bilinear taps (position in texels, weight), as resolve.comp's hist_color sampler
        // takes them.
        let taps: [([f32; 2], f32); 5] = if all_ok {
            // Catmull-Rom over the 4 x 4 window without its corners, renormalised: the inner
            // 2 x 2 in one tap, each side's pair of outer texels in one.
            let f = [q[0] - 0.5 - base[0] as f32, q[1] - 0.5 - base[1] as f32];
            let (wx, wy) = (catmull_rom(f[0]), catmull_rom(f[1]));
            let (sx, sy) = (wx[1] + wx[2], wy[1] + wy[2]);
            let c = [b[0] + wx[2] / sx, b[1] + wy[2] / sy];
            [
                (c, sx * sy),
                ([b[0] - 1.0, c[1]], wx[0] * sy),
                ([b[0] + 2.0, c[1]], wx[3] * sy),
                ([c[0], b[1] - 1.0], wy[0] * sx),
                ([c[0], b[1] + 2.0], wy[3] * sx),
            ]
        } else {
            // The valid bilinear taps, each at its texel's centre.
            let t = |k: usize| {
                let wk = if w[k] > 0.0 && valid & (1 << k) != 0 {
                    w[k]
                } else {
                    0.0
                };
                ([b[0] + TAP[k][0] as f32, b[1] + TAP[k][1] as f32], wk)
            };
            [t(0), t(1), t(2), t(3), (b, 0.0)]
        };
        let mut acc = [0.0; 3];
        let mut ws = 0.0f32;
        for (pos, wt) in taps {
            if wt != 0.0 {
                acc = add(acc, scale(self.bilinear(pos), wt));
                ws += wt;
            }
        }
        let h = div(acc, ws);
        if all_ok { h.map(|v| v.max(0.0)) } else { h }
    }

    /// The history colour filtered bilinearly at `pos` (texels, texel i's centre at i + 0.5),
    /// each texel coordinate clamped to the screen: a linear sampler with unnormalized
    /// coordinates and clamp to edge.
    fn bilinear(&self, pos: [f32; 2]) -> V3 {
        let hist = self.hist();
        let (u, v) = (pos[0] - 0.5, pos[1] - 0.5);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let texel = |dx: i32, dy: i32| {
            let x = (x0 as i32 + dx).clamp(0, self.w - 1);
            let y = (y0 as i32 + dy).clamp(0, self.h - 1);
            hist.color[self.idx(x, y)]
        };
        let lerp = |a: V3, b: V3, t: f32| add(a, scale(add(b, scale(a, -1.0)), t));
        lerp(
            lerp(texel(0, 0), texel(1, 0), fx),
            lerp(texel(0, 1), texel(1, 1), fx),
            fy,
        )
    }

    /// A rendered pixel: its sample, or with `fused` the sample blended into its history
    /// (`rendered_result` in resolve.comp).
    fn rendered(&self, x: i32, y: i32, s: Sample) -> Res {
        let mut r = Res {
            c: s.c,
            d: s.d,
            id: s.ids[0],
            v: s.v,
            dbg: DBG_RENDERED,
        };
        if !self.s.fused || self.reset {
            return r;
        }
        let hist = self.hist();
        let i = self.idx(x, y);
        let mut why = 0;
        let still = length(s.v) <= self.s.static_threshold && hist.ids[i] & ID_MOVED == 0;
        let h = if still {
            r.dbg |= DBG_STILL;
            Some(hist.color[i])
        } else {
            let q = [x as f32 + 0.5 - s.v[0], y as f32 + 0.5 - s.v[1]];
            let a = &self.s.ablation;
            let t = Test {
                id: s.ids[0],
                lo: s.d,
                hi: s.d,
                ids: a.ids,
                depth: a.depth,
            };
            self.history_validated(q, &t, &mut why)
        };
        let Some(mut h) = h else {
            r.dbg |= why;
            return r;
        };
        r.dbg |= DBG_REPROJECTED;
        let yc = to_ycocg(tonemap(s.c));
        let (mut m1, mut m2) = (yc, [yc[0] * yc[0], yc[1] * yc[1], yc[2] * yc[2]]);
        for [dx, dy] in [[-1, -1], [1, -1], [-1, 1], [1, 1]] {
            let yd = to_ycocg(tonemap(self.load(x + dx, y + dy).c));
            m1 = add(m1, yd);
            m2 = add(m2, [yd[0] * yd[0], yd[1] * yd[1], yd[2] * yd[2]]);
        }
        let mu = scale(m1, 0.2);
        let sigma = [0, 1, 2].map(|k| (m2[k] * 0.2 - mu[k] * mu[k]).max(0.0).sqrt());
        let yh = to_ycocg(tonemap(h));
        let d = [0, 1, 2].map(|k| yh[k] - mu[k]);
        let mut t = 1.0f32;
        for k in 0..3 {
            if d[k].abs() > sigma[k] {
                t = t.min(sigma[k] / d[k].abs());
            }
        }
        // Still: the history is kept unclipped (the shader says why).
        if t < 1.0 && !still {
            r.dbg |= DBG_CLAMPED;
            h = untonemap(from_ycocg(add(mu, scale(d, t))));
        }
        let t = (length(s.v) / super::FUSED_SPEED).min(1.0);
        let a = super::FUSED_ALPHA + (super::FUSED_ALPHA_MAX - super::FUSED_ALPHA) * t;
        let wc = a / (1.0 + luma(s.c).max(0.0));
        let wh = (1.0 - a) / (1.0 + luma(h).max(0.0));
        // h + (c - h) t: exactly h where c = h (the shader says why).
        r.c = [0, 1, 2].map(|k| h[k] + (s.c[k] - h[k]) * (wc / (wc + wh)));
        r
    }

    fn history_plain(&self, q: [f32; 2]) -> V3 {
        let hist = self.hist();
        let (base, w) = Self::taps(q);
        let mut acc = [0.0; 3];
        for k in 0..4 {
            let tx = (base[0] + TAP[k][0]).clamp(0, self.w - 1);
            let ty = (base[1] + TAP[k][1]).clamp(0, self.h - 1);
            acc = add(acc, scale(hist.color[self.idx(tx, ty)], w[k]));
        }
        acc
    }

    fn spatial_fill(&self, n: &[Sample; 4], ref_id: u32, use_ids: bool, own: bool) -> V3 {
        let t = n.map(|s| tonemap(s.c));
        let (mut h_ok, mut v_ok) = (true, true);
        if use_ids {
            if own {
                h_ok = n[0].ids[0] == ref_id && n[1].ids[0] == ref_id;
                v_ok = n[2].ids[0] == ref_id && n[3].ids[0] == ref_id;
            } else {
                h_ok = n[0].ids[0] == n[1].ids[0];
                v_ok = n[2].ids[0] == n[3].ids[0];
            }
        }
        let hm = scale(add(t[0], t[1]), 0.5);
        let vm = scale(add(t[2], t[3]), 0.5);
        let r = if h_ok && v_ok {
            let wh = 1.0 / (BLEND_EPS + (luma(t[0]) - luma(t[1])).abs());
            let wv = 1.0 / (BLEND_EPS + (luma(t[2]) - luma(t[3])).abs());
            div(add(scale(hm, wh), scale(vm, wv)), wh + wv)
        } else if h_ok {
            hm
        } else if v_ok {
            vm
        } else {
            let mut acc = [0.0; 3];
            let mut cnt = 0.0f32;
            for i in 0..4 {
                if n[i].ids[0] == ref_id {
                    acc = add(acc, t[i]);
                    cnt += 1.0;
                }
            }
            if cnt == 0.0 {
                acc = add(add(add(t[0], t[1]), t[2]), t[3]);
                cnt = 4.0;
            }
            div(acc, cnt)
        };
        untonemap(r)
    }

    fn clamp_to_box(&self, h: V3, n: &[Sample; 4], dbg: &mut u32) -> V3 {
        let y = to_ycocg(h);
        let mut lo = to_ycocg(n[0].c);
        let mut hi = lo;
        for s in &n[1..] {
            let q = to_ycocg(s.c);
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let yc = [0, 1, 2].map(|k| y[k].max(lo[k]).min(hi[k]));
        if yc != y {
            *dbg |= DBG_CLAMPED;
            return from_ycocg(yc);
        }
        h
    }

    fn missing(&self, x: i32, y: i32, n: &[Sample; 4]) -> Res {
        let q = [x as f32 + 0.5, y as f32 + 0.5];
        let (own_d, own_id) = match self.i.prepass {
            Some((d, ids)) if self.own => (d[self.idx(x, y)], ids[self.idx(x, y)]),
            _ => (0.0, 0),
        };
        let own = self.own;
        let a = &self.s.ablation;
        // `ours`' pair preference: exactly one opposite pair showing one object sorts its samples
        // first.
        let (hp, vp) = (n[0].ids[0] == n[1].ids[0], n[2].ids[0] == n[3].ids[0]);
        let pref = self.s.mode == ResolveMode::Ours && !own && a.ids && a.depth && hp != vp;
        let pid = if hp { n[0].ids[0] } else { n[2].ids[0] };
        let key = |s: &Sample| pref && s.ids[0] == pid;
        let mut o = [0usize, 1, 2, 3];
        for i in 1..4 {
            let k = o[i];
            let mut j = i as i32 - 1;
            while j >= 0 && (key(&n[o[j as usize]]), n[o[j as usize]].d) < (key(&n[k]), n[k].d) {
                o[(j + 1) as usize] = o[j as usize];
                j -= 1;
            }
            o[(j + 1) as usize] = k;
        }
        let near = n[o[0]];
        let ref_id = if own { own_id } else { near.ids[0] };
        let partner = if x & 1 == 0 { 1 } else { 0 };
        let mut r = Res {
            c: [0.0; 3],
            d: 0.0,
            id: 0,
            v: [0.0; 2],
            dbg: DBG_MISSING,
        };
        match self.s.mode {
            ResolveMode::Pq4k => {
                let p = n[partner];
                let avg = scale(add(add(add(n[0].c, n[1].c), n[2].c), n[3].c), 0.25);
                r.c = avg;
                r.d = p.d;
                r.id = p.ids[0];
                r.v = p.v;
                if !self.reset {
                    let tx = (q[0] - p.v[0]).floor() as i32;
                    let ty = (q[1] - p.v[1]).floor() as i32;
                    if self.inside(tx, ty) {
                        let h = self.hist().color[self.idx(tx, ty)];
                        r.dbg |= DBG_REPROJECTED;
                        if length(p.v) > self.s.motion_threshold {
                            let mut hc = h;
                            for k in 0..3 {
                                let lo = n[0].c[k].min(n[1].c[k]).min(n[2].c[k].min(n[3].c[k]));
                                let hi = n[0].c[k].max(n[1].c[k]).max(n[2].c[k].max(n[3].c[k]));
                                hc[k] = h[k].max(lo).min(hi);
                            }
                            if hc != h {
                                r.dbg |= DBG_CLAMPED;
                            }
                            r.c = add(scale(avg, 0.5), scale(hc, 0.5));
                        } else {
                            r.c = h;
                        }
                    }
                }
                if r.dbg & DBG_REPROJECTED == 0 {
                    r.dbg |= DBG_SPATIAL;
                }
            }
            ResolveMode::Intel => {
                let d = if own { own_d } else { near.d };
                r.d = d;
                r.id = ref_id;
                let ndc = [
                    q[0] / self.w as f32 * 2.0 - 1.0,
                    q[1] / self.h as f32 * 2.0 - 1.0,
                ];
                let m = &self.i.reproj;
                let v4 = [ndc[0], ndc[1], d, 1.0];
                let prev: [f32; 4] = std::array::from_fn(|row| {
                    m[row] * v4[0] + m[4 + row] * v4[1] + m[8 + row] * v4[2] + m[12 + row] * v4[3]
                });
                let mut ok = !self.reset && prev[3] > 0.0;
                let mut pq = [0.0f32; 2];
                if ok {
                    pq = [
                        (prev[0] / prev[3] * 0.5 + 0.5) * self.w as f32,
                        (prev[1] / prev[3] * 0.5 + 0.5) * self.h as f32,
                    ];
                    let (tx, ty) = (pq[0].floor() as i32, pq[1].floor() as i32);
                    ok = self.inside(tx, ty);
                    if ok
                        && depth_rel_diff(self.hist().depth[self.idx(tx, ty)], prev[2] / prev[3])
                            > self.s.depth_tolerance
                    {
                        ok = false;
                        r.dbg |= DBG_REJECT_DEPTH;
                    }
                }
                r.v = [q[0] - pq[0], q[1] - pq[1]];
                if ok {
                    r.c = self.history_plain(pq);
                    r.dbg |= DBG_REPROJECTED;
                } else {
                    let mut acc = [0.0; 3];
                    let mut ws = 0.0f32;
                    for s in n {
                        let w = 1.0 / (1.0 + luma(s.c).max(0.0));
                        acc = add(acc, scale(s.c, w));
                        ws += w;
                    }
                    r.c = div(acc, ws);
                    r.dbg |= DBG_SPATIAL;
                }
            }
            ResolveMode::Spatial => {
                r.c = self.spatial_fill(n, ref_id, a.ids, own);
                r.d = if own { own_d } else { near.d };
                r.id = ref_id;
                r.v = near.v;
                r.dbg |= DBG_SPATIAL;
            }
            ResolveMode::Temporal => {
                r.d = if own { own_d } else { near.d };
                r.id = ref_id;
                r.v = near.v;
                if self.reset {
                    r.c = self.spatial_fill(n, ref_id, true, own);
                    r.dbg |= DBG_SPATIAL;
                } else {
                    r.c = self.history_plain([q[0] - near.v[0], q[1] - near.v[1]]);
                    r.dbg |= DBG_REPROJECTED;
                }
            }
            ResolveMode::Ours => {
                let (use_ids, use_depth, use_v) = (a.ids, a.depth, a.velocity);
                // At most four candidates, on the stack (no allocation per pixel: resolve-cost counts this).
                let (mut cand, mut nc) = ([0usize; 4], 0usize);
                if own {
                    let mut best: Option<usize> = None;
                    let mut best_diff = 0.0f32;
                    for i in 0..4 {
                        let dd = (n[i].d - own_d).abs();
                        let same = n[i].ids[0] == own_id;
                        let replace = match best {
                            None => true,
                            Some(b) => {
                                let best_same = n[b].ids[0] == own_id;
                                (same && !best_same) || (same == best_same && dd < best_diff)
                            }
                        };
                        if replace {
                            best = Some(i);
                            best_diff = dd;
                        }
                    }
                    cand[nc] = best.unwrap_or(0);
                    nc += 1;
                } else if !use_ids && !use_depth {
                    cand[nc] = partner;
                    nc += 1;
                } else if !use_ids {
                    cand[nc] = o[0];
                    nc += 1;
                } else {
                    for (i, &by_depth) in o.iter().enumerate() {
                        let k = if use_depth { by_depth } else { i };
                        if !cand[..nc].iter().any(|&c| n[c].ids[0] == n[k].ids[0]) {
                            cand[nc] = k;
                            nc += 1;
                        }
                    }
                }
                // The surface a pixel takes when every hypothesis fails: the preferred pair's
                // object, else the farthest neighbour's.
                let multi = use_ids && !own;
                let fallback = if pref { o[0] } else { o[3] };
                let first = n[cand[0]];
                r.d = if own { own_d } else { first.d };
                r.id = if own { own_id } else { first.ids[0] };
                r.v = if use_v { first.v } else { [0.0; 2] };
                let mut found = None;
                let mut why = 0;
                if !self.reset && use_v && n.iter().all(|s| length(s.v) <= self.s.static_threshold)
                {
                    let i = self.idx(x, y);
                    let hid = self.hist().ids[i];
                    if hid & ID_MOVED == 0 && (!own || hid == own_id) {
                        found = Some(self.hist().color[i]);
                        r.d = self.hist().depth[i];
                        r.id = hid;
                        r.v = [0.0; 2];
                        r.dbg |= DBG_STILL;
                    }
                }
                if !self.reset && found.is_none() {
                    for &k in &cand[..nc] {
                        let s = n[k];
                        let v = if use_v { s.v } else { [0.0; 2] };
                        let id = if own { own_id } else { s.ids[0] };
                        let d = if own { own_d } else { s.d };
                        let qv = [q[0] - v[0], q[1] - v[1]];
                        let (mut lo, mut hi) = (d, d);
                        if !own && use_ids {
                            for s in n {
                                if s.ids[0] == id {
                                    lo = lo.min(s.d);
                                    hi = hi.max(s.d);
                                }
                            }
                        }
                        let t = Test {
                            id,
                            lo,
                            hi,
                            ids: use_ids,
                            depth: use_depth,
                        };
                        let (weight, valid) = self.history_weight(qv, &t, &mut why);
                        if weight > 0.5 {
                            found = Some(self.history_resampled(qv, valid));
                            r.d = d;
                            r.id = id;
                            r.v = v;
                            break;
                        }
                    }
                }
                match found {
                    Some(mut h) => {
                        r.dbg |= DBG_REPROJECTED;
                        if a.clamp && length(r.v) > self.s.static_threshold {
                            h = self.clamp_to_box(h, n, &mut r.dbg);
                            let sp = self.spatial_fill(n, r.id, use_ids, own);
                            let w = history_share(n);
                            h = [0, 1, 2].map(|k| sp[k] * (1.0 - w) + h[k] * w);
                        }
                        r.c = h;
                    }
                    None => {
                        r.dbg |= why | DBG_SPATIAL;
                        let mut fill_id = ref_id;
                        if multi && !self.reset {
                            let f = n[fallback];
                            r.id = f.ids[0];
                            r.d = f.d;
                            r.v = if use_v { f.v } else { [0.0; 2] };
                            fill_id = r.id;
                        }
                        r.c = self.spatial_fill(n, fill_id, use_ids, own);
                    }
                }
            }
        }
        r
    }
}

/// Resolves one frame on the CPU.
pub fn resolve(inputs: &Inputs, settings: &ResolveSettings) -> Output {
    let (w, h) = (inputs.width as i32, inputs.height as i32);
    let ctx = Ctx {
        i: inputs,
        s: settings,
        w,
        h,
        reset: inputs.history.is_none(),
        own: inputs.prepass.is_some() && settings.ablation.prepass,
    };
    let n = (w * h) as usize;
    let mut out = Output {
        color: vec![[0.0; 3]; n],
        depth: vec![0.0; n],
        ids: vec![0; n],
        debug: vec![0; n],
        velocity: vec![[0.0; 2]; n],
    };
    for y in 0..h {
        for x in 0..w {
            let r = if (x + y) as u32 & 1 == inputs.parity {
                ctx.rendered(x, y, inputs.current[ctx.idx(x, y)])
            } else {
                let nb = NEIGHBOUR.map(|o| ctx.load(x + o[0], y + o[1]));
                ctx.missing(x, y, &nb)
            };
            let i = ctx.idx(x, y);
            out.color[i] = r.c;
            out.depth[i] = r.d;
            let moved = length(r.v) > settings.static_threshold;
            out.ids[i] = r.id | if moved { ID_MOVED } else { 0 };
            out.debug[i] = r.dbg;
            out.velocity[i] = r.v;
        }
    }
    out
}
