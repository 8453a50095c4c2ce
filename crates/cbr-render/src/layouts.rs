//! Checkerboard layouts (DESIGN.md "Techniques / checkerboard"): where each of a frame's samples
//! lives, as plain data and arithmetic, the CPU reference for shaders/inc/layout_fetch.glsl.
//!
//! A frame of parity p shades exactly the full-resolution pixels (x, y) with (x + y) mod 2 = p, at
//! their centres. The layouts store those samples differently:
//! - `masked`: a W x H target, the other parity discarded.
//! - `split`: two ceil(W/2) x ceil(H/2) layers; layer k holds, for each 2x2 quad (i, j), the shaded
//!   pixel of its row k: (2i + (p + k) mod 2, 2j + k). Rendered with a projection jitter per layer.
//! - `msaa2x`: a ceil(W/2)+1 x ceil(H/2) target with 2 samples at the standard positions
//!   (0.75, 0.75) and (0.25, 0.25): sample 0 of pixel (i, j) is full-res pixel (2i + 1 - p, 2j + 1),
//!   sample 1 is (2i - p, 2j); odd frames shift the viewport right by half a target pixel.
//!   With VK_EXT_sample_locations (`with_sample_locations`) odd frames instead move the samples to
//!   (0.25, 0.75) and (0.75, 0.25): sample 0 of pixel (i, j) is (2i, 2j + 1), sample 1 is
//!   (2i + 1, 2j); no viewport shift, no spare column.
//! - `rotated` (Decima's tangram): an L x L target whose texel (i, j) is the full-res pixel with
//!   i = (x - y - p) / 2 and j = (x + y - p) / 2, both mod L. The screen maps to a 45-degree diamond
//!   in texel space, drawn as several wrapped pieces (translations by multiples of L), each clipped
//!   to the screen rectangle. One-to-one iff L >= max(min(W, H), ceil(max(W, H) / 2)).

use cbr_gpu::Layout;

/// The smallest tangram side for which the W x H checkerboard maps one-to-one into L x L.
pub fn tangram_side(width: u32, height: u32) -> u32 {
    width.min(height).max(width.max(height).div_ceil(2))
}

/// Texel of full-res pixel (x, y) of parity p in an L x L tangram.
pub fn tangram_texel(x: i64, y: i64, parity: i64, l: i64) -> (i64, i64) {
    debug_assert_eq!((x + y - parity).rem_euclid(2), 0);
    (
        (x - y - parity).div_euclid(2).rem_euclid(l),
        (x + y - parity).div_euclid(2).rem_euclid(l),
    )
}

/// Where a layout stores one sample: texel, array layer, MSAA sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleAddr {
    pub x: u32,
    pub y: u32,
    pub layer: u32,
    pub sample: u32,
}

/// The geometry of one layout at one resolution and parity.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutPlan {
    pub layout: Layout,
    pub width: u32,
    pub height: u32,
    pub parity: u32,
    /// Size of the raster target.
    pub target: (u32, u32),
    pub layers: u32,
    pub samples: u32,
    /// Sub-pixel offset of each layer's raster, in target pixels (added to the projection).
    pub jitter: [[f32; 2]; 2],
    /// Viewport x offset in target pixels (msaa2x odd frames).
    pub viewport_x: f32,
    /// Tangram side (rotated) and the (m, n) translations of its pieces, in units of L.
    pub tangram: u32,
    pub pieces: Vec<[i32; 2]>,
    /// msaa2x with VK_EXT_sample_locations: this frame's two sample locations in [0, 1)^2.
    pub sample_locations: Option<[[f32; 2]; 2]>,
}

/// The standard 2x MSAA positions (samples 0 and 1), and the odd frames' alternative.
pub const STANDARD_2X: [[f32; 2]; 2] = [[0.75, 0.75], [0.25, 0.25]];
pub const ODD_2X: [[f32; 2]; 2] = [[0.25, 0.75], [0.75, 0.25]];

/// Texel-space (u, v) of screen point (xs, ys) in the tangram before wrapping: pixel centres map to
/// texel centres.
fn tangram_uv(xs: f64, ys: f64, parity: f64) -> (f64, f64) {
    ((xs - ys - parity + 1.0) / 2.0, (xs + ys - parity) / 2.0)
}

/// The translations (m, n) for which the screen's diamond, moved by (m L, n L), overlaps [0, L]^2
/// (separating-axis test of the diamond against the square).
fn tangram_pieces(width: u32, height: u32, parity: u32, l: u32) -> Vec<[i32; 2]> {
    let (w, h, p, lf) = (
        f64::from(width),
        f64::from(height),
        f64::from(parity),
        f64::from(l),
    );
    let corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)].map(|(x, y)| tangram_uv(x, y, p));
    let (umin, umax) = corners
        .iter()
        .fold((f64::MAX, f64::MIN), |a, c| (a.0.min(c.0), a.1.max(c.0)));
    let (vmin, vmax) = corners
        .iter()
        .fold((f64::MAX, f64::MIN), |a, c| (a.0.min(c.1), a.1.max(c.1)));
    let mut out = Vec::new();
    for m in ((-umax / lf).floor() as i32)..=((lf - umin) / lf).ceil() as i32 {
        for n in ((-vmax / lf).floor() as i32)..=((lf - vmin) / lf).ceil() as i32 {
            let (du, dv) = (f64::from(m) * lf, f64::from(n) * lf);
            let moved = corners.map(|(u, v)| (u + du, v + dv));
            let square = [(0.0, 0.0), (lf, 0.0), (lf, lf), (0.0, lf)];
            // Axes: the square's (u, v) and the diamond's edge normals (1, 1), (1, -1).
            let separated = [(1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (1.0, -1.0)]
                .iter()
                .any(|&(ax, ay)| {
                    let proj = |pts: &[(f64, f64)]| {
                        pts.iter()
                            .map(|&(u, v)| u * ax + v * ay)
                            .fold((f64::MAX, f64::MIN), |a, x| (a.0.min(x), a.1.max(x)))
                    };
                    let (a0, a1) = proj(&moved);
                    let (b0, b1) = proj(&square);
                    a1 <= b0 || b1 <= a0
                });
            if !separated {
                out.push([m, n]);
            }
        }
    }
    out
}

impl LayoutPlan {
    pub fn new(layout: Layout, width: u32, height: u32, parity: u32) -> LayoutPlan {
        let p = parity & 1;
        let (hw, hh) = (width.div_ceil(2), height.div_ceil(2));
        let mut plan = LayoutPlan {
            layout,
            width,
            height,
            parity: p,
            target: (width, height),
            layers: 1,
            samples: 1,
            jitter: [[0.0; 2]; 2],
            viewport_x: 0.0,
            tangram: 0,
            pieces: Vec::new(),
            sample_locations: None,
        };
        match layout {
            Layout::Masked => {}
            Layout::Split => {
                plan.target = (hw, hh);
                plan.layers = 2;
                // Layer k samples full-res x = 2i + (p + k) mod 2, y = 2j + k, i.e. the half-res
                // pixel centre (2i + 1, 2j + 1) moved by (a - 0.5, k - 0.5) full-res pixels; the
                // image moves the opposite way, in half-res pixels.
                for k in 0..2u32 {
                    let a = ((p + k) % 2) as f32;
                    plan.jitter[k as usize] = [-(a - 0.5) / 2.0, -(k as f32 - 0.5) / 2.0];
                }
            }
            Layout::Msaa2x => {
                // One extra column so odd frames' shifted viewport still covers x = W - 1.
                plan.target = (hw + 1, hh);
                plan.samples = 2;
                plan.viewport_x = if p == 1 { 0.5 } else { 0.0 };
            }
            Layout::Rotated => {
                let l = tangram_side(width, height);
                plan.target = (l, l);
                plan.tangram = l;
                plan.pieces = tangram_pieces(width, height, p, l);
            }
        }
        plan
    }

    /// msaa2x toggling sample locations instead of shifting the viewport (other layouts unchanged).
    pub fn with_sample_locations(mut self) -> LayoutPlan {
        if self.layout == Layout::Msaa2x {
            self.target = (self.width.div_ceil(2), self.height.div_ceil(2));
            self.viewport_x = 0.0;
            self.sample_locations = Some(if self.parity == 1 {
                ODD_2X
            } else {
                STANDARD_2X
            });
        }
        self
    }

    /// Where the sample of full-res pixel (x, y) lives, or `None` when the frame does not shade it.
    pub fn address(&self, x: u32, y: u32) -> Option<SampleAddr> {
        let p = self.parity;
        if (x + y) % 2 != p {
            return None;
        }
        Some(match self.layout {
            Layout::Masked => SampleAddr {
                x,
                y,
                layer: 0,
                sample: 0,
            },
            Layout::Split => SampleAddr {
                x: x / 2,
                y: y / 2,
                layer: y % 2,
                sample: 0,
            },
            Layout::Msaa2x => {
                // Sample 0 holds (2i + 1 - p, 2j + 1), sample 1 holds (2i - p, 2j); with the odd
                // frames' sample locations, (2i, 2j + 1) and (2i + 1, 2j).
                let odd_row = y % 2;
                let i = if self.sample_locations.is_some() && p == 1 {
                    x / 2
                } else {
                    (x + p + 1 - odd_row) / 2
                };
                SampleAddr {
                    x: i,
                    y: y / 2,
                    layer: 0,
                    sample: 1 - odd_row,
                }
            }
            Layout::Rotated => {
                let (i, j) = tangram_texel(
                    i64::from(x),
                    i64::from(y),
                    i64::from(p),
                    i64::from(self.tangram),
                );
                SampleAddr {
                    x: i as u32,
                    y: j as u32,
                    layer: 0,
                    sample: 0,
                }
            }
        })
    }

    /// Bytes of the raster targets (colour RGBA16F, velocity RG32F, IDs RG32UI, depth D32).
    pub fn target_bytes(&self) -> u64 {
        u64::from(self.target.0)
            * u64::from(self.target.1)
            * u64::from(self.layers)
            * u64::from(self.samples)
            * crate::targets::BYTES_PER_SAMPLE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn covers_each_sample_once(plan: &LayoutPlan) {
        let mut seen = HashSet::new();
        let mut n = 0u64;
        for y in 0..plan.height {
            for x in 0..plan.width {
                if let Some(a) = plan.address(x, y) {
                    assert!(
                        a.x < plan.target.0
                            && a.y < plan.target.1
                            && a.layer < plan.layers
                            && a.sample < plan.samples,
                        "{plan:?} ({x},{y}) -> {a:?}"
                    );
                    assert!(
                        seen.insert((a.x, a.y, a.layer, a.sample)),
                        "{:?} {}x{} p{}: ({x},{y}) collides at {a:?}",
                        plan.layout,
                        plan.width,
                        plan.height,
                        plan.parity
                    );
                    n += 1;
                }
            }
        }
        let expected =
            (u64::from(plan.width) * u64::from(plan.height) + u64::from(plan.parity == 0)) / 2;
        let expected = if plan.width % 2 == 1 && plan.height % 2 == 1 {
            expected
        } else {
            u64::from(plan.width) * u64::from(plan.height) / 2
        };
        assert_eq!(n, expected);
    }

    #[test]
    fn every_layout_maps_one_to_one() {
        for (w, h) in [
            (1920, 1080),
            (1280, 720),
            (640, 480),
            (2560, 1080),
            (101, 77),
            (64, 64),
            (3, 5),
            (1, 1),
            (7, 2),
            (33, 100),
        ] {
            for p in 0..2 {
                for l in Layout::ALL {
                    covers_each_sample_once(&LayoutPlan::new(l, w, h, p));
                }
            }
        }
    }

    #[test]
    fn msaa2x_sample_locations_hit_the_pixel_centres_once() {
        for (w, h) in [(1920, 1080), (101, 77), (64, 64), (3, 5), (7, 2), (33, 100)] {
            for p in 0..2 {
                let plan = LayoutPlan::new(Layout::Msaa2x, w, h, p).with_sample_locations();
                assert_eq!(
                    plan.target,
                    (w.div_ceil(2), h.div_ceil(2)),
                    "no spare column"
                );
                assert_eq!(plan.viewport_x, 0.0);
                covers_each_sample_once(&plan);
                let locs = plan.sample_locations.expect("locations");
                for y in 0..h {
                    for x in 0..w {
                        if let Some(a) = plan.address(x, y) {
                            // The sample position in full-res pixels is the pixel's centre.
                            let l = locs[a.sample as usize];
                            let sx = 2.0 * (a.x as f32 + l[0]);
                            let sy = 2.0 * (a.y as f32 + l[1]);
                            assert_eq!((sx, sy), (x as f32 + 0.5, y as f32 + 0.5), "{w}x{h} p{p}");
                        }
                    }
                }
            }
        }
        // Other layouts are left alone.
        let split = LayoutPlan::new(Layout::Split, 8, 8, 1);
        assert_eq!(split.clone().with_sample_locations(), split);
    }

    #[test]
    fn tangram_side_is_the_smallest_that_works() {
        assert_eq!(tangram_side(1920, 1080), 1080);
        assert_eq!(tangram_side(3840, 2160), 2160);
        assert_eq!(tangram_side(2560, 1080), 1280, "21:9 needs W/2");
        assert_eq!(tangram_side(1000, 1000), 1000);
        for (w, h) in [
            (1920u32, 1080u32),
            (200, 100),
            (201, 100),
            (120, 90),
            (99, 31),
            (17, 40),
        ] {
            let l = tangram_side(w, h);
            for p in 0..2 {
                let mut plan = LayoutPlan::new(Layout::Rotated, w, h, p);
                covers_each_sample_once(&plan);
                // One texel less must collide somewhere.
                plan.tangram = l - 1;
                plan.target = (l - 1, l - 1);
                let mut seen = HashSet::new();
                let collides = (0..h).any(|y| {
                    (0..w).any(|x| plan.address(x, y).is_some_and(|a| !seen.insert((a.x, a.y))))
                });
                assert!(collides, "{w}x{h}: L = {} also works", l - 1);
            }
        }
    }

    #[test]
    fn tangram_pieces_cover_the_screen() {
        // Every shaded pixel's unwrapped texel position falls in exactly one piece's square.
        for (w, h) in [(1920u32, 1080u32), (64, 36), (37, 50), (2560, 1080)] {
            for p in 0..2 {
                let plan = LayoutPlan::new(Layout::Rotated, w, h, p);
                let l = f64::from(plan.tangram);
                assert!(
                    !plan.pieces.is_empty() && plan.pieces.len() <= 8,
                    "{w}x{h}: {} pieces",
                    plan.pieces.len()
                );
                for y in (0..h).step_by(7) {
                    for x in (0..w).step_by(5) {
                        if (x + y) % 2 != p {
                            continue;
                        }
                        let (u, v) =
                            tangram_uv(f64::from(x) + 0.5, f64::from(y) + 0.5, f64::from(p));
                        let inside = plan.pieces.iter().filter(|[m, n]| {
                            let (uu, vv) = (u + f64::from(*m) * l, v + f64::from(*n) * l);
                            (0.0..l).contains(&uu) && (0.0..l).contains(&vv)
                        });
                        assert_eq!(inside.count(), 1, "{w}x{h} p{p} ({x},{y})");
                    }
                }
            }
        }
    }

    #[test]
    fn tangram_uv_puts_pixel_centres_on_texel_centres() {
        // cb_tangram_uv in layout_fetch.glsl is tangram_uv / L; with REPEAT addressing the texel
        // under pixel (x, y)'s centre must be tangram_texel(x, y).
        let (w, h) = (37, 21);
        for p in 0..2u32 {
            let l = tangram_side(w, h);
            for y in 0..h {
                for x in (0..w).filter(|x| (x + y) % 2 == p) {
                    let (u, v) = tangram_uv(f64::from(x) + 0.5, f64::from(y) + 0.5, f64::from(p));
                    assert!(
                        (u.rem_euclid(1.0) - 0.5).abs() < 1e-9
                            && (v.rem_euclid(1.0) - 0.5).abs() < 1e-9,
                        "texel centre"
                    );
                    let wrap = |c: f64| (c.floor() as i64).rem_euclid(i64::from(l));
                    assert_eq!(
                        (wrap(u), wrap(v)),
                        tangram_texel(i64::from(x), i64::from(y), i64::from(p), i64::from(l))
                    );
                }
            }
        }
    }

    #[test]
    fn memory_of_common_resolutions() {
        // Printed for docs/checkerboard-layouts.md (`cargo test -p cbr-render memory -- --nocapture`).
        for (w, h) in [(1280u32, 720u32), (1920, 1080), (2560, 1440), (3840, 2160)] {
            let native = u64::from(w) * u64::from(h) * crate::targets::BYTES_PER_SAMPLE;
            for l in Layout::ALL {
                let plan = LayoutPlan::new(l, w, h, 0);
                let used = (u64::from(w) * u64::from(h)) as f64
                    / 2.0
                    / f64::from(plan.target.0 * plan.target.1 * plan.layers * plan.samples);
                println!(
                    "{w}x{h} {:8} target {}x{}x{}x{}: {:.1} MiB ({:.2} x native), {:.0}% of samples used",
                    l.name(),
                    plan.target.0,
                    plan.target.1,
                    plan.layers,
                    plan.samples,
                    plan.target_bytes() as f64 / 1048576.0,
                    plan.target_bytes() as f64 / native as f64,
                    used * 100.0
                );
            }
        }
        assert_eq!(
            LayoutPlan::new(Layout::Rotated, 1920, 1080, 0).target,
            (1080, 1080)
        );
    }
}
