//! The CPU reference of shaders/interlaced/resolve.comp, operation for operation in f32. Inputs
//! are full-resolution images; only the rows of the frame's parity are read from `current`.
//! Output colour is f32: the GPU stores it as f16 (tests/interlaced.rs says how close).

use super::resolve::InterlacedSettings;
use crate::resolve::reference::{Sample, tonemap, untonemap};
use crate::resolve::{
    DBG_CLAMPED, DBG_MISSING, DBG_REJECT_DEPTH, DBG_REJECT_ID, DBG_RENDERED, DBG_REPROJECTED,
    DBG_SPATIAL, DBG_STILL,
};

/// The previous resolved frame as stored (colour already rounded to f16).
pub struct HistoryRef<'a> {
    pub color: &'a [[f32; 3]],
    pub velocity: &'a [[f32; 2]],
    /// Reverse-Z.
    pub depth: &'a [f32],
    pub ids: &'a [[u32; 2]],
}

pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    /// The rendered rows' y mod 2.
    pub parity: u32,
    pub current: &'a [Sample],
    /// `None`: reset.
    pub history: Option<HistoryRef<'a>>,
}

#[derive(Clone, Debug, Default)]
pub struct Output {
    pub color: Vec<[f32; 3]>,
    pub velocity: Vec<[f32; 2]>,
    pub depth: Vec<f32>,
    pub ids: Vec<[u32; 2]>,
    pub debug: Vec<u32>,
}

use crate::cpu_math::{V3, catmull_rom, depth_rel_diff, from_ycocg, luma, to_ycocg};

fn speed(v: [f32; 2]) -> f32 {
    crate::cpu_math::length(v)
}

fn mad(acc: V3, w: f32, c: V3) -> V3 {
    [acc[0] + w * c[0], acc[1] + w * c[1], acc[2] + w * c[2]]
}

/// Indices into the six rendered samples around a missing pixel: the row above (x - 1, x,
/// x + 1), then the row below.
const ABOVE: usize = 1;
const BELOW: usize = 4;
const TAP: [[i32; 2]; 4] = [[0, 0], [1, 0], [0, 1], [1, 1]];

struct Res {
    c: V3,
    v: [f32; 2],
    d: f32,
    ids: [u32; 2],
    dbg: u32,
}

struct Ctx<'a> {
    i: &'a Inputs<'a>,
    s: &'a InterlacedSettings,
    w: i32,
    h: i32,
}

impl Ctx<'_> {
    fn idx(&self, x: i32, y: i32) -> usize {
        (y * self.w + x) as usize
    }
    fn inside(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.w && y < self.h
    }
    /// The sample at (x, y) reflected at the borders (rows keep their parity).
    fn load(&self, x: i32, y: i32) -> Sample {
        let (x, y) = (x.abs(), y.abs());
        let (x, y) = (x.min(2 * self.w - 2 - x), y.min(2 * self.h - 2 - y));
        debug_assert_eq!(y as u32 & 1, self.i.parity);
        self.i.current[self.idx(x, y)]
    }
    fn hist(&self) -> &HistoryRef<'_> {
        self.i.history.as_ref().expect("history when not reset")
    }

    fn depth_agrees(&self, hd: f32, lo: f32, hi: f32) -> bool {
        let tol = self.s.depth_tolerance;
        (hd >= lo && hd <= hi) || depth_rel_diff(hd, lo) <= tol || depth_rel_diff(hd, hi) <= tol
    }

    fn tap_reasons(&self, x: i32, y: i32, id: u32, lo: f32, hi: f32) -> u32 {
        let (h, t) = (self.hist(), self.idx(x, y));
        let mut r = 0;
        if self.s.ids && h.ids[t][0] != id {
            r |= DBG_REJECT_ID;
        }
        if self.s.depth && !self.depth_agrees(h.depth[t], lo, hi) {
            r |= DBG_REJECT_DEPTH;
        }
        r
    }

    /// resolve.comp's `history_validated`.
    fn history_validated(
        &self,
        q: [f32; 2],
        id: u32,
        lo: f32,
        hi: f32,
        why: &mut u32,
    ) -> Option<V3> {
        let near = [q[0].floor() as i32, q[1].floor() as i32];
        if !self.inside(near[0], near[1]) {
            return None;
        }
        let rn = self.tap_reasons(near[0], near[1], id, lo, hi);
        if rn != 0 {
            *why |= rn;
            return None;
        }
        let hist = self.hist();
        let g = [q[0] - 0.5, q[1] - 0.5];
        let b = [g[0].floor(), g[1].floor()];
        let f = [g[0] - b[0], g[1] - b[1]];
        let base = [b[0] as i32, b[1] as i32];
        let w = [
            (1.0 - f[0]) * (1.0 - f[1]),
            f[0] * (1.0 - f[1]),
            (1.0 - f[0]) * f[1],
            f[0] * f[1],
        ];
        let (mut acc, mut ws, mut all_ok) = ([0.0; 3], 0.0f32, true);
        for k in 0..4 {
            let (tx, ty) = (base[0] + TAP[k][0], base[1] + TAP[k][1]);
            if w[k] <= 0.0 {
                continue;
            }
            if self.inside(tx, ty)
                && ([tx, ty] == near || self.tap_reasons(tx, ty, id, lo, hi) == 0)
            {
                acc = mad(acc, w[k], hist.color[self.idx(tx, ty)]);
                ws += w[k];
            } else {
                all_ok = false;
            }
        }
        if !all_ok {
            return Some(acc.map(|a| a / ws));
        }
        let (wx, wy) = (catmull_rom(f[0]), catmull_rom(f[1]));
        let mut c = [0.0; 3];
        for (j, &wj) in wy.iter().enumerate() {
            let mut row = [0.0; 3];
            for (i, &wi) in wx.iter().enumerate() {
                let tx = (base[0] + i as i32 - 1).clamp(0, self.w - 1);
                let ty = (base[1] + j as i32 - 1).clamp(0, self.h - 1);
                row = mad(row, wi, hist.color[self.idx(tx, ty)]);
            }
            c = mad(c, wj, row);
        }
        Some(c.map(|v| v.max(0.0)))
    }

    /// Edge-directed line averaging (resolve.comp's `spatial_fill`).
    fn spatial_fill(&self, n: &[Sample; 6], nearest: usize) -> V3 {
        let pairs = [
            (ABOVE, BELOW),
            (ABOVE - 1, BELOW + 1),
            (ABOVE + 1, BELOW - 1),
        ];
        let count = if self.s.diagonals { 3 } else { 1 };
        let mut best: Option<(f32, V3)> = None;
        for &(a, b) in &pairs[..count] {
            if self.s.ids && n[a].ids[0] != n[b].ids[0] {
                continue;
            }
            let (ta, tb) = (tonemap(n[a].c), tonemap(n[b].c));
            let diff = (luma(ta) - luma(tb)).abs();
            if best.is_none_or(|(d, _)| diff < d) {
                best = Some((diff, [0, 1, 2].map(|k| (ta[k] + tb[k]) * 0.5)));
            }
        }
        match best {
            Some((_, mean)) => untonemap(mean),
            None => n[nearest].c,
        }
    }

    fn clamp_to_box(&self, h: V3, n: &[Sample; 6], dbg: &mut u32) -> V3 {
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
        let yc = [0, 1, 2].map(|k| {
            let margin = self.s.clamp_margin * (hi[k] - lo[k]);
            y[k].max(lo[k] - margin).min(hi[k] + margin)
        });
        if yc != y {
            *dbg |= DBG_CLAMPED;
            return from_ycocg(yc);
        }
        h
    }

    fn missing(&self, x: i32, y: i32, reset: bool) -> Res {
        let n: [Sample; 6] = std::array::from_fn(|i| {
            let (dx, dy) = (i as i32 % 3 - 1, if i < 3 { -1 } else { 1 });
            self.load(x + dx, y + dy)
        });
        let thr = self.s.static_threshold;
        let first = if n[ABOVE].d >= n[BELOW].d {
            ABOVE
        } else {
            BELOW
        };
        let second = if first == ABOVE { BELOW } else { ABOVE };
        let mut r = Res {
            c: [0.0; 3],
            v: n[first].v,
            d: n[first].d,
            ids: n[first].ids,
            dbg: DBG_MISSING,
        };
        let mut found = None;
        let mut why = 0;
        if !reset {
            let hist = self.hist();
            let i = self.idx(x, y);
            if speed(n[ABOVE].v) <= thr
                && speed(n[BELOW].v) <= thr
                && speed(hist.velocity[i]) <= thr
            {
                found = Some(hist.color[i]);
                r.d = hist.depth[i];
                r.ids = hist.ids[i];
                r.dbg |= DBG_STILL;
            }
            let mut candidates = vec![first];
            if self.s.ids && n[second].ids[0] != n[first].ids[0] {
                candidates.push(second);
            }
            for c in candidates {
                if found.is_some() {
                    break;
                }
                let id = n[c].ids[0];
                let (mut lo, mut hi) = (n[c].d, n[c].d);
                if self.s.ids && n[ABOVE].ids[0] == n[BELOW].ids[0] {
                    lo = n[ABOVE].d.min(n[BELOW].d);
                    hi = n[ABOVE].d.max(n[BELOW].d);
                }
                let q = [x as f32 + 0.5 - n[c].v[0], y as f32 + 0.5 - n[c].v[1]];
                if let Some(h) = self.history_validated(q, id, lo, hi, &mut why) {
                    found = Some(h);
                    r.v = n[c].v;
                    r.d = n[c].d;
                    r.ids = n[c].ids;
                }
            }
        }
        match found {
            Some(mut h) => {
                r.dbg |= DBG_REPROJECTED;
                if self.s.clamp && speed(r.v) > thr {
                    h = self.clamp_to_box(h, &n, &mut r.dbg);
                }
                r.c = h;
            }
            None => {
                r.dbg |= why | DBG_SPATIAL;
                r.c = self.spatial_fill(&n, first);
            }
        }
        r
    }
}

/// Resolves one frame on the CPU.
pub fn resolve(inputs: &Inputs, settings: &InterlacedSettings) -> Output {
    let (w, h) = (inputs.width as i32, inputs.height as i32);
    let ctx = Ctx {
        i: inputs,
        s: settings,
        w,
        h,
    };
    let reset = inputs.history.is_none() || !settings.history;
    let n = (w * h) as usize;
    let mut out = Output {
        color: Vec::with_capacity(n),
        velocity: Vec::with_capacity(n),
        depth: Vec::with_capacity(n),
        ids: Vec::with_capacity(n),
        debug: Vec::with_capacity(n),
    };
    for y in 0..h {
        for x in 0..w {
            let r = if y as u32 & 1 == inputs.parity {
                let s = inputs.current[ctx.idx(x, y)];
                Res {
                    c: s.c,
                    v: s.v,
                    d: s.d,
                    ids: s.ids,
                    dbg: DBG_RENDERED,
                }
            } else {
                ctx.missing(x, y, reset)
            };
            out.color.push(r.c);
            out.velocity.push(r.v);
            out.depth.push(r.d);
            out.ids.push(r.ids);
            out.debug.push(r.dbg);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(c: f32, d: f32, id: u32) -> Sample {
        Sample {
            c: [c; 3],
            v: [0.0; 2],
            d,
            ids: [id, 0],
        }
    }

    /// A 3 x 4 frame of parity 0: rows 0 and 2 rendered.
    fn frame(rows: [[Sample; 3]; 2]) -> Vec<Sample> {
        let mut v = Vec::new();
        for r in [
            rows[0],
            [Sample::default(); 3],
            rows[1],
            [Sample::default(); 3],
        ] {
            v.extend(r);
        }
        v
    }

    fn resolve_at(current: &[Sample], history: Option<HistoryRef>, x: usize, y: usize) -> Output {
        let s = InterlacedSettings::default();
        let out = resolve(
            &Inputs {
                width: 3,
                height: 4,
                parity: 0,
                current,
                history,
            },
            &s,
        );
        assert_eq!(out.debug[y * 3 + x] & DBG_MISSING, DBG_MISSING);
        out
    }

    #[test]
    fn spatial_fill_follows_the_edge_and_never_averages_across_objects() {
        // A 45-degree edge, bright where x < y: row 0 dark, row 2 bright at x = 0, 1. Pixel
        // (1, 1) is dark; the above-left/below-right pair runs along the edge and agrees.
        let (b, k) = (sample(4.0, 0.5, 1), sample(0.0, 0.5, 1));
        let cur = frame([[k, k, k], [b, b, k]]);
        let out = resolve_at(&cur, None, 1, 1);
        assert_eq!(out.color[4], [0.0; 3]);
        // The vertical pair alone blurs across the edge: the tonemapped mean of 0 and 4.
        let vertical = InterlacedSettings {
            diagonals: false,
            ..InterlacedSettings::default()
        };
        let inputs = Inputs {
            width: 3,
            height: 4,
            parity: 0,
            current: &cur,
            history: None,
        };
        let c = resolve(&inputs, &vertical).color[4][0];
        assert!((c - 0.4 / 0.6).abs() < 1e-6, "{c}");
        // Vertical pair of the same grey: its mean (through the tonemap, exact for equal values).
        let g = sample(0.25, 0.5, 1);
        let out = resolve_at(&frame([[k, g, k], [b, g, b]]), None, 1, 1);
        assert_eq!(out.color[4], [0.25; 3]);
        // Every pair crosses two objects: the nearer vertical neighbour, its depth and IDs.
        let (near, far) = (sample(2.0, 0.9, 2), sample(1.0, 0.1, 3));
        let out = resolve_at(&frame([[far, far, far], [near, near, near]]), None, 1, 1);
        assert_eq!(out.color[4], [2.0; 3]);
        assert_eq!((out.depth[4], out.ids[4]), (0.9, [2, 0]));
        assert_eq!(out.debug[4], DBG_MISSING | DBG_SPATIAL);
    }

    #[test]
    fn history_is_taken_when_still_or_validated_and_rejected_otherwise() {
        let s = sample(1.0, 0.5, 1);
        let cur = frame([[s; 3], [s; 3]]);
        let n = 12;
        let color = vec![[3.0; 3]; n];
        let velocity = vec![[0.0; 2]; n];
        let depth = vec![0.5; n];
        let ids = vec![[1, 7]; n];
        let hist = |velocity: &[[f32; 2]], ids: &[[u32; 2]], depth: &[f32]| {
            resolve_at(
                &cur,
                Some(HistoryRef {
                    color: &color,
                    velocity,
                    depth,
                    ids,
                }),
                1,
                1,
            )
        };
        // Still: history as it is (unclamped, although 3 lies outside the neighbours' 1).
        let out = hist(&velocity, &ids, &depth);
        assert_eq!(out.color[4], [3.0; 3]);
        assert_eq!(out.ids[4], [1, 7], "the history's IDs");
        assert_eq!(out.debug[4], DBG_MISSING | DBG_STILL | DBG_REPROJECTED);
        // History that moved, same object and depth: validated at the same texel (v = 0), taken.
        let moved = vec![[1.0, 0.0]; n];
        let out = hist(&moved, &ids, &depth);
        assert_eq!(out.color[4], [3.0; 3]);
        assert_eq!(out.debug[4], DBG_MISSING | DBG_REPROJECTED);
        // Another object there, or the same object 20% further: rejected, spatial fill.
        let other = vec![[2, 7]; n];
        let out = hist(&moved, &other, &depth);
        assert_eq!(out.color[4], [1.0; 3]);
        assert_eq!(out.debug[4], DBG_MISSING | DBG_SPATIAL | DBG_REJECT_ID);
        let far = vec![0.4; n];
        let out = hist(&moved, &ids, &far);
        assert_eq!(out.debug[4], DBG_MISSING | DBG_SPATIAL | DBG_REJECT_DEPTH);
    }

    #[test]
    fn moving_history_is_fetched_at_p_minus_v_and_clamped() {
        // Everything moves 1 px right: history at (0, 1), an exact texel centre, is taken, then
        // clamped to the neighbours' box (all 1.0).
        let mut s = sample(1.0, 0.5, 1);
        s.v = [1.0, 0.0];
        let cur = frame([[s; 3], [s; 3]]);
        let mut color = vec![[0.5; 3]; 12];
        color[3] = [0.75; 3];
        let (velocity, depth, ids) = (vec![[1.0, 0.0]; 12], vec![0.5; 12], vec![[1, 0]; 12]);
        let h = || {
            Some(HistoryRef {
                color: &color,
                velocity: &velocity,
                depth: &depth,
                ids: &ids,
            })
        };
        let out = resolve_at(&cur, h(), 1, 1);
        assert_eq!(out.color[4], [1.0; 3]);
        assert_eq!(out.debug[4], DBG_MISSING | DBG_REPROJECTED | DBG_CLAMPED);
        // Without the clamp, texel (0, 1) exactly.
        let s = InterlacedSettings {
            clamp: false,
            ..InterlacedSettings::default()
        };
        let inputs = Inputs {
            width: 3,
            height: 4,
            parity: 0,
            current: &cur,
            history: h(),
        };
        assert_eq!(resolve(&inputs, &s).color[4], [0.75; 3]);
    }

    #[test]
    fn the_clamp_box_is_widened_by_the_margin() {
        // Rows of grey 1 above and 2 below, all moving 1 px right; history 2.4 at (0, 1).
        let (mut a, mut b) = (sample(1.0, 0.5, 1), sample(2.0, 0.5, 1));
        (a.v, b.v) = ([1.0, 0.0], [1.0, 0.0]);
        let cur = frame([[a; 3], [b; 3]]);
        let color = vec![[2.4; 3]; 12];
        let (velocity, depth, ids) = (vec![[1.0, 0.0]; 12], vec![0.5; 12], vec![[1, 0]; 12]);
        let run = |clamp_margin: f32| {
            let s = InterlacedSettings {
                clamp_margin,
                ..InterlacedSettings::default()
            };
            let history = HistoryRef {
                color: &color,
                velocity: &velocity,
                depth: &depth,
                ids: &ids,
            };
            let inputs = Inputs {
                width: 3,
                height: 4,
                parity: 0,
                current: &cur,
                history: Some(history),
            };
            let out = resolve(&inputs, &s);
            (out.color[4][0], out.debug[4] & DBG_CLAMPED)
        };
        // The box's luma spans [1, 2]; half its extent on each side lets 2.4 through.
        assert_eq!(run(0.5), (2.4, 0));
        assert_eq!(run(0.0), (2.0, DBG_CLAMPED));
        assert_eq!(run(0.25), (2.25, DBG_CLAMPED));
    }
}
