//! `+fxaa[:12|29|39]`: FXAA 3.11, quality presets 12, 29 (default) and 39 (Lottes 2011), with
//! the published defaults as settings: edge threshold 0.166, minimum edge threshold 0.0833,
//! sub-pixel quality 0.75 (`+fxaa:29:0.125:0.0625:1.0` sets all three).
//!
//! Luma is taken in display space: the colour through the display transform cbr's PNGs and
//! metrics use (scene exposure, Narkowicz ACES fit, clamp, sRGB OETF), then Rec. 601 weights,
//! as FXAA expects perceptual luma, computed once per pixel by a first pass into an R32F image
//! (shaders/post/fxaa_luma.comp). The blend itself mixes the linear HDR colour. Every
//! filtered lookup (FXAA's bilinear taps) is done by hand from texel fetches, in the shader and
//! in [`reference`] alike, so the two agree within float rounding whatever a device's filtering
//! precision; addressing clamps to the edge. shaders/post/fxaa.comp.

use cbr_gpu::{Cmd, Image, Profiler, Result, vk};

use super::{PostBuildCtx, PostFrame, PostPass, PostRegistration};
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::targets::COLOR_FORMAT;

pub const REGISTRATION: PostRegistration = PostRegistration {
    name: "fxaa",
    grammar: "fxaa[:12|29|39[:EDGE[:EDGE_MIN[:SUBPIX]]]]",
    about: "FXAA 3.11 quality presets 12, 29 (default), 39; luma in display space",
    check: |p| FxaaConfig::parse(p).map(|_| ()),
    geometry: false,
    estimate: |ctx, _| crate::pass::estimate(&resources(ctx.width, ctx.height), "fxaa"),
    passes: |p, _| {
        FxaaConfig::parse(p)?;
        Ok(decls().to_vec())
    },
    build: |ctx, p| {
        let c = FxaaConfig::parse(p).map_err(|e| super::refused("fxaa", p, e))?;
        Ok(Box::new(Fxaa::new(ctx, c)?))
    },
};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FxaaConfig {
    pub preset: u32,
    /// Minimum local contrast, relative to the local maximum luma, to process a pixel.
    pub edge_threshold: f32,
    /// Contrast below which dark pixels are skipped.
    pub edge_threshold_min: f32,
    /// Amount of sub-pixel aliasing removal.
    pub subpix: f32,
}

impl FxaaConfig {
    pub fn parse(params: &[&str]) -> std::result::Result<FxaaConfig, String> {
        let mut c = FxaaConfig {
            preset: 29,
            edge_threshold: 0.166,
            edge_threshold_min: 0.0833,
            subpix: 0.75,
        };
        if let Some(p) = params.first() {
            c.preset = match *p {
                "12" | "29" | "39" => p.parse().map_err(|_| "unreachable".to_string())?,
                _ => return Err(format!("fxaa preset `{p}` (12, 29 or 39)")),
            };
        }
        let num = |i: usize, name: &str, lo: f32, hi: f32| -> std::result::Result<_, String> {
            match params.get(i) {
                None => Ok(None),
                Some(v) => match v.parse::<f32>() {
                    Ok(x) if (lo..=hi).contains(&x) => Ok(Some(x)),
                    _ => Err(format!("fxaa {name} `{v}` (a number from {lo} to {hi})")),
                },
            }
        };
        c.edge_threshold = num(1, "edge threshold", 0.0, 1.0)?.unwrap_or(c.edge_threshold);
        c.edge_threshold_min =
            num(2, "minimum edge threshold", 0.0, 1.0)?.unwrap_or(c.edge_threshold_min);
        c.subpix = num(3, "sub-pixel quality", 0.0, 1.0)?.unwrap_or(c.subpix);
        if let Some(extra) = params.get(4) {
            return Err(format!(
                "`{extra}`: fxaa takes a preset and three thresholds"
            ));
        }
        Ok(c)
    }

    /// The edge-search step lengths of the preset (FXAA 3.11's FXAA_QUALITY__P0..P11).
    pub fn steps(&self) -> &'static [f32] {
        match self.preset {
            12 => &[1.0, 1.5, 2.0, 4.0, 12.0],
            39 => &[1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0],
            _ => &[1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0],
        }
    }
}

pub const MAX_STEPS: usize = 12;

crate::push_constants! {
    /// The luma pass's.
    struct LumaPush {
        /// W, H, 0, 0.
        size: [i32; 4],
        /// .w: the exposure scale (2^stops).
        params: [f32; 4],
    }
}

crate::push_constants! {
    struct Push {
        /// W, H, number of steps, 0.
        size_steps: [i32; 4],
        /// Edge threshold, minimum threshold, sub-pixel quality, exposure scale (2^stops).
        params: [f32; 4],
        steps: [f32; MAX_STEPS] as array,
    }
}

/// The luma pass (shaders/post/fxaa_luma.comp: display luma once per pixel), then FXAA
/// (shaders/post/fxaa.comp).
pub fn decls() -> [ComputeDecl; 2] {
    [
        ComputeDecl::new("fxaa.luma", "post/fxaa_luma.comp")
            .bind(Binding::sampled("src"))
            .bind(Binding::image("luma", Use::Write))
            .push::<LumaPush>(),
        ComputeDecl::new("fxaa", "post/fxaa.comp")
            .define("MAX_STEPS", MAX_STEPS)
            .bind(Binding::sampled("src"))
            .bind(Binding::image("out", Use::Write))
            .bind(Binding::sampled("luma"))
            .push::<Push>(),
    ]
}

fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::image("out", COLOR_FORMAT, w, h),
        ResourceDecl::image("luma", vk::Format::R32_SFLOAT, w, h),
    ]
}

pub struct Fxaa {
    luma_pass: ComputePass,
    pass: ComputePass,
    res: Resources,
    size: (u32, u32),
    push: Push,
    luma_push: LumaPush,
}

impl Fxaa {
    fn new(ctx: &PostBuildCtx, c: FxaaConfig) -> Result<Fxaa> {
        let [luma, fxaa] = decls();
        let mut steps = [0.0; MAX_STEPS];
        steps[..c.steps().len()].copy_from_slice(c.steps());
        let push = Push {
            size_steps: [
                ctx.width as i32,
                ctx.height as i32,
                c.steps().len() as i32,
                0,
            ],
            params: [
                c.edge_threshold,
                c.edge_threshold_min,
                c.subpix,
                ctx.exposure_stops.exp2(),
            ],
            steps,
        };
        Ok(Fxaa {
            luma_pass: luma.build(ctx.gpu, ctx.shaders)?,
            pass: fxaa.build(ctx.gpu, ctx.shaders)?,
            res: Resources::new(ctx.gpu, "fxaa", &resources(ctx.width, ctx.height))?,
            size: (ctx.width, ctx.height),
            luma_push: LumaPush {
                size: [push.size_steps[0], push.size_steps[1], 0, 0],
                params: push.params,
            },
            push,
        })
    }
}

impl PostPass for Fxaa {
    fn record(
        &mut self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        _frame: &PostFrame,
        input: &Image,
    ) -> Result<()> {
        let binds = Binds::of(&self.res).image("src", input);
        self.luma_pass
            .dispatch_2d(cmd, profiler, &binds, &self.luma_push, self.size)?;
        self.pass
            .dispatch_2d(cmd, profiler, &binds, &self.push, self.size)
    }

    fn output(&self, _frame: u32) -> Result<&Image> {
        self.res.image("out")
    }
}

// ---- The CPU reference ----------------------------------------------------------------------

/// Display-space luma of linear HDR RGB: exposure, Narkowicz ACES fit, sRGB OETF, Rec. 601.
pub fn luma(rgb: [f32; 3], exposure_scale: f32) -> f32 {
    let d = |x: f32| {
        let x = (x * exposure_scale).max(0.0);
        let t = ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
        if t <= 0.003_130_8 {
            12.92 * t
        } else {
            1.055 * t.powf(1.0 / 2.4) - 0.055
        }
    };
    0.299 * d(rgb[0]) + 0.587 * d(rgb[1]) + 0.114 * d(rgb[2])
}

struct Img<'a> {
    w: usize,
    h: usize,
    rgba: &'a [f32],
    luma: Vec<f32>,
}

impl Img<'_> {
    fn texel(&self, x: i64, y: i64) -> usize {
        let x = x.clamp(0, self.w as i64 - 1) as usize;
        let y = y.clamp(0, self.h as i64 - 1) as usize;
        y * self.w + x
    }

    /// Bilinear weights and corners of position `p` (texel units, centres at +0.5).
    fn taps(&self, p: [f32; 2]) -> ([usize; 4], [f32; 2]) {
        let (x, y) = (p[0] - 0.5, p[1] - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        (
            [
                self.texel(x0, y0),
                self.texel(x0 + 1, y0),
                self.texel(x0, y0 + 1),
                self.texel(x0 + 1, y0 + 1),
            ],
            [fx, fy],
        )
    }

    fn luma_at(&self, p: [f32; 2]) -> f32 {
        let ([a, b, c, d], [fx, fy]) = self.taps(p);
        let l = &self.luma;
        let top = l[a] + (l[b] - l[a]) * fx;
        let bottom = l[c] + (l[d] - l[c]) * fx;
        top + (bottom - top) * fy
    }

    fn rgba_at(&self, p: [f32; 2]) -> [f32; 4] {
        let ([a, b, c, d], [fx, fy]) = self.taps(p);
        std::array::from_fn(|k| {
            let v = |i: usize| self.rgba[4 * i + k];
            let top = v(a) + (v(b) - v(a)) * fx;
            let bottom = v(c) + (v(d) - v(c)) * fx;
            top + (bottom - top) * fy
        })
    }
}

/// FXAA 3.11 quality of one RGBA image (rows top to bottom), alpha passed through.
pub fn reference(
    w: usize,
    h: usize,
    rgba: &[f32],
    c: &FxaaConfig,
    exposure_scale: f32,
) -> Vec<f32> {
    let luma: Vec<f32> = rgba
        .chunks_exact(4)
        .map(|p| luma([p[0], p[1], p[2]], exposure_scale))
        .collect();
    let img = Img { w, h, rgba, luma };
    let mut out = vec![0.0; rgba.len()];
    for y in 0..h {
        for x in 0..w {
            let o = 4 * (y * w + x);
            let mut exact = Ties {
                eps: 0.0,
                mask: 0,
                n: 0,
            };
            out[o..o + 4].copy_from_slice(&pixel(&img, x as i64, y as i64, c, &mut exact));
        }
    }
    out
}

/// Every output [`reference`] could give at pixel (x, y) if decisions that tie within
/// `eps` (relative) went the other way, the exact one first. FXAA takes `>=`/`<` decisions
/// between lumas that tie exactly on flat colours (e.g. a search end at exactly a quarter of the
/// gradient); a shader's rounding (pow, fused multiply-adds) decides those, so tests accept any
/// variant. At most 6 ties per pixel are explored (64 variants).
#[allow(clippy::too_many_arguments)]
pub fn reference_variants(
    w: usize,
    h: usize,
    rgba: &[f32],
    c: &FxaaConfig,
    exposure_scale: f32,
    x: usize,
    y: usize,
    eps: f32,
) -> Vec<[f32; 4]> {
    let luma: Vec<f32> = rgba
        .chunks_exact(4)
        .map(|p| luma([p[0], p[1], p[2]], exposure_scale))
        .collect();
    let img = Img { w, h, rgba, luma };
    let mut out = Vec::new();
    let mut ties = Ties { eps, mask: 0, n: 0 };
    out.push(pixel(&img, x as i64, y as i64, c, &mut ties));
    let found = ties.n.min(6);
    for mask in 1..(1u32 << found) {
        let mut t = Ties { eps, mask, n: 0 };
        out.push(pixel(&img, x as i64, y as i64, c, &mut t));
    }
    out
}

/// Decisions that may go either way when their sides tie within `eps`: bit k of `mask` flips
/// the k-th tie met.
struct Ties {
    eps: f32,
    mask: u32,
    n: u32,
}

impl Ties {
    /// `a >= b`, flipped at a tie whose bit is set.
    fn ge(&mut self, a: f32, b: f32) -> bool {
        let r = a >= b;
        if self.eps > 0.0 && (a - b).abs() <= self.eps * a.abs().max(b.abs()) {
            let flip = self.n < 32 && (self.mask >> self.n) & 1 == 1;
            self.n += 1;
            return r != flip;
        }
        r
    }

    fn lt(&mut self, a: f32, b: f32) -> bool {
        !self.ge(a, b)
    }

    /// `v < 0`, a tie when |v| is within `eps` of `scale`.
    fn neg(&mut self, v: f32, scale: f32) -> bool {
        let r = v < 0.0;
        if self.eps > 0.0 && v.abs() <= self.eps * scale {
            let flip = self.n < 32 && (self.mask >> self.n) & 1 == 1;
            self.n += 1;
            return r != flip;
        }
        r
    }
}

fn pixel(img: &Img, x: i64, y: i64, c: &FxaaConfig, t: &mut Ties) -> [f32; 4] {
    let l = |dx: i64, dy: i64| img.luma[img.texel(x + dx, y + dy)];
    let pos_m = [x as f32 + 0.5, y as f32 + 0.5];
    let luma_m = l(0, 0);
    let (mut luma_n, mut luma_s) = (l(0, -1), l(0, 1));
    let (luma_w, luma_e) = (l(-1, 0), l(1, 0));
    // Local contrast: skip pixels without an edge.
    let range_max = luma_m.max(luma_n).max(luma_s).max(luma_w).max(luma_e);
    let range_min = luma_m.min(luma_n).min(luma_s).min(luma_w).min(luma_e);
    let range = range_max - range_min;
    let m = img.rgba[4 * img.texel(x, y)..][..4]
        .try_into()
        .unwrap_or([0.0; 4]);
    if t.lt(
        range,
        c.edge_threshold_min.max(range_max * c.edge_threshold),
    ) {
        return m;
    }
    let (luma_nw, luma_ne, luma_sw, luma_se) = (l(-1, -1), l(1, -1), l(-1, 1), l(1, 1));
    // Edge orientation from second differences over the 3x3 neighbourhood.
    let edge_horz = (-2.0 * luma_w + luma_nw + luma_sw).abs()
        + 2.0 * (-2.0 * luma_m + luma_n + luma_s).abs()
        + (-2.0 * luma_e + luma_ne + luma_se).abs();
    let edge_vert = (-2.0 * luma_s + luma_sw + luma_se).abs()
        + 2.0 * (-2.0 * luma_m + luma_w + luma_e).abs()
        + (-2.0 * luma_n + luma_nw + luma_ne).abs();
    let horz_span = t.ge(edge_horz, edge_vert);
    // Sub-pixel aliasing amount: the 3x3 low-pass against the centre, relative to the range.
    let subpix_a =
        2.0 * (luma_n + luma_s + luma_w + luma_e) + (luma_nw + luma_ne + luma_sw + luma_se);
    let subpix_c = ((subpix_a / 12.0 - luma_m).abs() / range).clamp(0.0, 1.0);
    let subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    let subpix_h = subpix_f * subpix_f * c.subpix;
    if !horz_span {
        (luma_n, luma_s) = (luma_w, luma_e);
    }
    // Which side of the edge: the neighbour pair with the steeper gradient.
    let (gradient_n, gradient_s) = (luma_n - luma_m, luma_s - luma_m);
    let pair_n = t.ge(gradient_n.abs(), gradient_s.abs());
    let gradient = gradient_n.abs().max(gradient_s.abs());
    let length_sign = if pair_n { -1.0 } else { 1.0 };
    let luma_nn = if pair_n {
        luma_n + luma_m
    } else {
        luma_s + luma_m
    };
    // Search along the edge, half a pixel towards the chosen side, both ways.
    let (axis, perp) = if horz_span { (0, 1) } else { (1, 0) };
    let mut pos_b = pos_m;
    pos_b[perp] += 0.5 * length_sign;
    let steps = c.steps();
    let (mut pos_n, mut pos_p) = (pos_b, pos_b);
    pos_n[axis] -= steps[0];
    pos_p[axis] += steps[0];
    let gradient_scaled = gradient * 0.25;
    let luma_mm = luma_m - luma_nn * 0.5;
    let mut end_n = img.luma_at(pos_n) - luma_nn * 0.5;
    let mut end_p = img.luma_at(pos_p) - luma_nn * 0.5;
    let mut done_n = t.ge(end_n.abs(), gradient_scaled);
    let mut done_p = t.ge(end_p.abs(), gradient_scaled);
    // FXAA 3.11's nesting: after evaluating at step k, each unfinished end moves by step k + 1;
    // the last move (by the final step) is not evaluated.
    for k in 1..steps.len() {
        if !done_n {
            pos_n[axis] -= steps[k];
        }
        if !done_p {
            pos_p[axis] += steps[k];
        }
        if (done_n && done_p) || k + 1 == steps.len() {
            break;
        }
        if !done_n {
            end_n = img.luma_at(pos_n) - luma_nn * 0.5;
            done_n = t.ge(end_n.abs(), gradient_scaled);
        }
        if !done_p {
            end_p = img.luma_at(pos_p) - luma_nn * 0.5;
            done_p = t.ge(end_p.abs(), gradient_scaled);
        }
    }
    // The nearer end decides; its luma must cross the centre's for the span to be good.
    let dst_n = pos_m[axis] - pos_n[axis];
    let dst_p = pos_p[axis] - pos_m[axis];
    // Signs tie relative to the gradient's size.
    let m_lt_zero = t.neg(luma_mm, gradient);
    let good_span = if t.lt(dst_n, dst_p) {
        t.neg(end_n, gradient) != m_lt_zero
    } else {
        t.neg(end_p, gradient) != m_lt_zero
    };
    let pixel_offset = -dst_n.min(dst_p) / (dst_n + dst_p) + 0.5;
    let offset = if good_span { pixel_offset } else { 0.0 }.max(subpix_h);
    let mut pos = pos_m;
    pos[perp] += offset * length_sign;
    let mut out = img.rgba_at(pos);
    out[3] = m[3];
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(preset: &str) -> FxaaConfig {
        FxaaConfig::parse(&[preset]).expect("preset")
    }

    #[test]
    fn flat_images_are_unchanged() {
        let img: Vec<f32> = [0.3, 0.5, 0.7, 1.0].repeat(8 * 6);
        for p in ["12", "29", "39"] {
            assert_eq!(reference(8, 6, &img, &cfg(p), 1.0), img);
        }
    }

    /// A hard vertical edge blends across it, over (at most) the preset's search span, and
    /// leaves pixels away from the edge alone.
    #[test]
    fn a_hard_vertical_edge_is_blended() {
        let (w, h) = (16, 16);
        let img: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let v = if i % w < 8 { 0.0 } else { 1.0 };
                [v, v, v, 1.0]
            })
            .collect();
        let out = reference(w, h, &img, &cfg("29"), 1.0);
        let at = |x: usize, y: usize| out[4 * (y * w + x)];
        for y in 0..h {
            assert_eq!(at(0, y), 0.0);
            assert_eq!(at(15, y), 1.0);
            // A straight edge along the whole column: an infinitely long span, so the offset
            // comes from the sub-pixel term alone: both sides move towards the other.
            assert!(at(7, y) > 0.0 && at(7, y) < 0.5, "{}", at(7, y));
            assert!(at(8, y) < 1.0 && at(8, y) > 0.5, "{}", at(8, y));
        }
    }

    #[test]
    fn a_one_pixel_line_is_softened() {
        let (w, h) = (16, 16);
        let img: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let v = if i / w == 8 { 1.0 } else { 0.0 };
                [v, v, v, 1.0]
            })
            .collect();
        let out = reference(w, h, &img, &cfg("29"), 1.0);
        let at = |x: usize, y: usize| out[4 * (y * w + x)];
        for x in 2..14 {
            assert!(at(x, 8) < 1.0, "line pixel darker: {}", at(x, 8));
            assert!(at(x, 7) > 0.0 || at(x, 9) > 0.0, "light spreads");
        }
    }

    #[test]
    fn a_stair_step_edge_searches_its_span() {
        // A shallow edge: 1 pixel up every 6 columns. Pixels along a step get offsets that
        // grow towards the step's end, so neighbouring pixels of one row differ.
        let (w, h) = (24, 12);
        let img: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                let v = if y >= 4 + x / 6 { 1.0 } else { 0.0 };
                [v, v, v, 1.0]
            })
            .collect();
        let out = reference(w, h, &img, &cfg("39"), 1.0);
        let row: Vec<f32> = (6..12).map(|x| out[4 * (5 * w + x)]).collect();
        let distinct = row
            .windows(2)
            .filter(|p| (p[0] - p[1]).abs() > 1e-3)
            .count();
        assert!(distinct >= 3, "offsets vary along the span: {row:?}");
        assert!(FxaaConfig::parse(&["30"]).is_err() && FxaaConfig::parse(&["29", "2"]).is_err());
    }
}
