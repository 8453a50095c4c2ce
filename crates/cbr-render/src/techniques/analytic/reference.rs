//! The CPU reference of `analytic`, in f64 and by a different method than the shader: clip the
//! polygon to the pixel square (Sutherland-Hodgman) and take the clipped polygon's area and
//! centroid (shoelace), where the shader integrates edge by edge. Also the seed's column shortcut
//! and the N-sample mask (32, 64, 128) with the shader's tie rule.

/// A polygon's vertices in screen pixels (y down).
pub type Poly = Vec<[f64; 2]>;

/// Clips `poly` to the half-plane `keep(p) >= 0` given as `a x + b y + c >= 0`.
fn clip(poly: &[[f64; 2]], a: f64, b: f64, c: f64) -> Poly {
    let f = |p: [f64; 2]| a * p[0] + b * p[1] + c;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fp, fq) = (f(p), f(q));
        if fp >= 0.0 {
            out.push(p);
        }
        if (fp >= 0.0) != (fq >= 0.0) {
            let t = fp / (fp - fq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    out
}

/// Signed area (shoelace; positive for the shader's positive orientation) and centroid.
pub fn area_centroid(poly: &[[f64; 2]]) -> (f64, [f64; 2]) {
    let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let cross = p[0] * q[1] - q[0] * p[1];
        a2 += cross;
        cx += (p[0] + q[0]) * cross;
        cy += (p[1] + q[1]) * cross;
    }
    if a2 == 0.0 {
        return (0.0, [f64::NAN; 2]);
    }
    (a2 / 2.0, [cx / (3.0 * a2), cy / (3.0 * a2)])
}

/// The part of `poly` inside pixel (x, y)'s square.
pub fn clip_to_pixel(poly: &[[f64; 2]], x: i64, y: i64) -> Poly {
    let (x, y) = (x as f64, y as f64);
    let p = clip(poly, 1.0, 0.0, -x);
    let p = clip(&p, -1.0, 0.0, x + 1.0);
    let p = clip(&p, 0.0, 1.0, -y);
    clip(&p, 0.0, -1.0, y + 1.0)
}

/// Exact area of pixel (x, y) covered by the convex polygon, and the covered part's centroid in
/// pixel-local coordinates (`None` when nothing is covered).
pub fn coverage(poly: &[[f64; 2]], x: i64, y: i64) -> (f64, Option<[f64; 2]>) {
    let c = clip_to_pixel(poly, x, y);
    if c.len() < 3 {
        return (0.0, None);
    }
    let (a, cen) = area_centroid(&c);
    if a == 0.0 {
        return (0.0, None);
    }
    (a.abs(), Some([cen[0] - x as f64, cen[1] - y as f64]))
}

/// The rank-1 lattice's generator of an N-sample mask (shaders/analytic/mask.glsl, which takes
/// it as the define MASK_GEN): of the odd generators, the one with the least RMS error of the
/// sample share against the exact area over random half-planes crossing the pixel (13 for 32
/// samples, kept from before; docs/analytic.md, The mask's sample count).
pub fn mask_generator(samples: u32) -> u32 {
    match samples {
        32 => 13,
        64 => 19,
        128 => 47,
        _ => panic!("no {samples}-sample mask (32, 64 or 128)"),
    }
}

/// Sample `k` of the N-sample visibility mask, pixel-local (coverage.glsl's `mask_sample`).
pub fn mask_sample_of(k: u32, samples: u32) -> [f64; 2] {
    let n = f64::from(samples);
    [
        (f64::from(k) + 0.5) / n,
        (f64::from((k * mask_generator(samples)) & (samples - 1)) + 0.5) / n,
    ]
}

/// Sample `k` of the 32-sample visibility mask.
pub fn mask_sample(k: u32) -> [f64; 2] {
    mask_sample_of(k, 32)
}

/// Whether pixel-local point `q` is in the polygon (pixel-local too), with the shader's rule for
/// points on an edge.
pub fn inside(poly: &[[f64; 2]], q: [f64; 2]) -> bool {
    let (a2, _) = area_centroid(poly);
    let orient = if a2 < 0.0 { -1.0 } else { 1.0 };
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let canonical = a[1] < b[1] || (a[1] == b[1] && a[0] < b[0]);
        let (lo, hi) = if canonical { (a, b) } else { (b, a) };
        let e = (hi[1] - lo[1]) * (q[0] - lo[0]) - (hi[0] - lo[0]) * (q[1] - lo[1]);
        let side = if canonical { -orient } else { orient };
        if e * side < 0.0 || (e == 0.0 && side < 0.0) {
            return false;
        }
    }
    true
}

/// The N-sample mask of pixel (x, y), sample k in bit k.
pub fn sample_mask_of(poly: &[[f64; 2]], x: i64, y: i64, samples: u32) -> u128 {
    let local: Poly = poly
        .iter()
        .map(|p| [p[0] - x as f64, p[1] - y as f64])
        .collect();
    (0..samples)
        .filter(|&k| inside(&local, mask_sample_of(k, samples)))
        .fold(0, |m, k| m | 1 << k)
}

/// The 32-sample mask of pixel (x, y).
pub fn sample_mask(poly: &[[f64; 2]], x: i64, y: i64) -> u32 {
    sample_mask_of(poly, x, y, 32) as u32
}

/// The seed's shortcut for pixel (x, y): the polygon's vertical extent on the column's centre line
/// clipped to the pixel, or the mask's fraction where the column holds a vertex.
pub fn seed_coverage(poly: &[[f64; 2]], x: i64, y: i64) -> f64 {
    seed_coverage_of(poly, x, y, 32)
}

/// The same with an N-sample mask in the vertex columns.
pub fn seed_coverage_of(poly: &[[f64; 2]], x: i64, y: i64, samples: u32) -> f64 {
    let (xf, yf) = (x as f64, y as f64);
    let cx = xf + 0.5;
    if poly.iter().any(|p| p[0] >= xf && p[0] <= xf + 1.0) {
        return f64::from(sample_mask_of(poly, x, y, samples).count_ones()) / f64::from(samples);
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a[0] - cx) * (b[0] - cx) > 0.0 || a[0] == b[0] {
            continue;
        }
        let yy = a[1] + (cx - a[0]) * (b[1] - a[1]) / (b[0] - a[0]);
        lo = lo.min(yy);
        hi = hi.max(yy);
    }
    (hi.min(yf + 1.0) - lo.max(yf)).max(0.0)
}

/// The pixels a polygon's bounding box touches (inclusive), clamped to `limit` pixels per side
/// around the box's corner for huge polygons.
pub fn bbox_pixels(poly: &[[f64; 2]]) -> (i64, i64, i64, i64) {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in poly {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    (
        x0.floor() as i64,
        y0.floor() as i64,
        x1.floor() as i64,
        y1.floor() as i64,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn areas_of_known_shapes() {
        // A pixel inside a big triangle: 1; a small triangle inside a pixel: its area.
        let big = vec![[-10.0, -10.0], [30.0, -10.0], [-10.0, 30.0]];
        assert_eq!(coverage(&big, 2, 3).0, 1.0);
        let small = vec![[2.25, 3.25], [2.75, 3.25], [2.25, 3.75]];
        assert!((coverage(&small, 2, 3).0 - 0.125).abs() < 1e-15);
        // Half a pixel, cut on its diagonal; the centroid of that half.
        let half = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let (a, c) = coverage(&half, 0, 0);
        assert!((a - 0.5).abs() < 1e-15);
        let c = c.unwrap();
        assert!((c[0] - 1.0 / 3.0).abs() < 1e-15 && (c[1] - 1.0 / 3.0).abs() < 1e-15);
        // Areas over every pixel add up to the polygon's area.
        let tri = vec![[0.3, 0.7], [7.9, 2.2], [3.1, 6.6]];
        let (x0, y0, x1, y1) = bbox_pixels(&tri);
        let mut sum = 0.0;
        for y in y0..=y1 {
            for x in x0..=x1 {
                sum += coverage(&tri, x, y).0;
            }
        }
        assert!((sum - area_centroid(&tri).0.abs()).abs() < 1e-12, "{sum}");
    }

    #[test]
    fn the_seed_is_exact_for_shallow_edges_and_not_for_steep_ones() {
        // A shallow edge (slope 0.2) across columns without vertices: exact in the columns where
        // the edge stays within one pixel; off where it crosses a row boundary inside the column.
        let shallow = vec![[-10.0, 0.3], [20.0, 6.3], [-10.0, 20.0]];
        for x in 0..8i64 {
            let yl = 0.3 + (x as f64 + 10.0) * 0.2;
            if yl.floor() != (yl + 0.2).floor() {
                let off = (0..8)
                    .map(|y| (seed_coverage(&shallow, x, y) - coverage(&shallow, x, y).0).abs())
                    .fold(0.0, f64::max);
                assert!(off > 1e-4, "column {x}: {off}");
                continue;
            }
            for y in 0..4 {
                let e = coverage(&shallow, x, y).0;
                assert!((seed_coverage(&shallow, x, y) - e).abs() < 1e-12, "{x} {y}");
            }
        }
        // A steep edge (slope 3) crosses several pixels of a column: the shortcut is off.
        let steep = vec![[0.2, -10.0], [10.2, 20.0], [-20.0, 20.0]];
        let worst = (0..8)
            .flat_map(|y| (0..8).map(move |x| (x, y)))
            .map(|(x, y)| (seed_coverage(&steep, x, y) - coverage(&steep, x, y).0).abs())
            .fold(0.0, f64::max);
        assert!(worst > 0.05, "{worst}");
    }

    #[test]
    fn shared_edges_give_each_sample_to_one_side() {
        // Two triangles of a quad, the diagonal through sample positions; both windings.
        let a = vec![[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let b = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        let b_rev = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0]];
        for other in [&b, &b_rev] {
            let (ma, mb) = (sample_mask(&a, 0, 0), sample_mask(other, 0, 0));
            assert_eq!(ma & mb, 0);
            assert_eq!(ma | mb, u32::MAX);
        }
    }
}

/// A surface for [`visible_areas`]: a convex polygon (screen pixels) and its depth as an affine
/// function of the screen point, `depth(x, y) = d[0] + d[1] x + d[2] y`, nearer larger (1 / w, or
/// reverse-Z depth: both are affine in the screen for a planar polygon).
#[derive(Clone, Debug)]
pub struct Surface {
    pub poly: Poly,
    pub depth: [f64; 3],
}

impl Surface {
    fn depth_at(&self, p: [f64; 2]) -> f64 {
        self.depth[0] + self.depth[1] * p[0] + self.depth[2] * p[1]
    }
}

/// A line `y = m x + q` over a range of x.
#[derive(Clone, Copy)]
struct Line {
    m: f64,
    q: f64,
    x0: f64,
    x1: f64,
}

impl Line {
    fn at(&self, x: f64) -> f64 {
        self.m * x + self.q
    }
}

/// Exact visibility in pixel (x, y) (the `analytic:exact` model, after Auzinger, Wimmer & Jeschke
/// 2013's fragment-against-fragment clipping, as a CPU reference): the area of the pixel square
/// where each surface is the nearest one, overlaps and intersections included. By slabs: every
/// x where two boundaries (the polygons' edges, the lines where two surfaces' depths are equal,
/// the square's sides) cross, or a vertex lies, cuts the square into vertical slabs in which the
/// boundaries do not cross; within a slab, each band between consecutive boundaries has one
/// owner (the nearest surface holding the band's midpoint) and is a trapezoid.
pub fn visible_areas(surfaces: &[Surface], x: i64, y: i64) -> Vec<f64> {
    let (px, py) = (x as f64, y as f64);
    let clipped: Vec<Poly> = surfaces
        .iter()
        .map(|s| clip_to_pixel(&s.poly, x, y))
        .collect();
    let mut lines = vec![
        Line {
            m: 0.0,
            q: py,
            x0: px,
            x1: px + 1.0,
        },
        Line {
            m: 0.0,
            q: py + 1.0,
            x0: px,
            x1: px + 1.0,
        },
    ];
    let mut xs = vec![px, px + 1.0];
    for c in clipped.iter().filter(|c| c.len() >= 3) {
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            xs.push(a[0]);
            if (b[0] - a[0]).abs() > 1e-12 {
                let m = (b[1] - a[1]) / (b[0] - a[0]);
                lines.push(Line {
                    m,
                    q: a[1] - m * a[0],
                    x0: a[0].min(b[0]),
                    x1: a[0].max(b[0]),
                });
            }
        }
    }
    for i in 0..surfaces.len() {
        for j in i + 1..surfaces.len() {
            let d: Vec<f64> = (0..3)
                .map(|k| surfaces[i].depth[k] - surfaces[j].depth[k])
                .collect();
            if d[2].abs() > 1e-14 {
                lines.push(Line {
                    m: -d[1] / d[2],
                    q: -d[0] / d[2],
                    x0: px,
                    x1: px + 1.0,
                });
            } else if d[1].abs() > 1e-14 {
                xs.push(-d[0] / d[1]);
            }
        }
    }
    for (i, a) in lines.iter().enumerate() {
        for b in &lines[i + 1..] {
            if (a.m - b.m).abs() > 1e-14 {
                let xc = (b.q - a.q) / (a.m - b.m);
                if xc >= a.x0.max(b.x0) && xc <= a.x1.min(b.x1) {
                    xs.push(xc);
                }
            }
        }
    }
    xs.retain(|&v| v >= px && v <= px + 1.0);
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
    let mut areas = vec![0.0; surfaces.len()];
    for w in xs.windows(2) {
        let (xa, xb) = (w[0], w[1]);
        if xb - xa < 1e-13 {
            continue;
        }
        let xm = 0.5 * (xa + xb);
        let mut band: Vec<&Line> = lines
            .iter()
            .filter(|l| l.x0 <= xa + 1e-12 && l.x1 >= xb - 1e-12)
            .filter(|l| (py..=py + 1.0).contains(&l.at(xm)))
            .collect();
        band.sort_by(|a, b| a.at(xm).total_cmp(&b.at(xm)));
        for pair in band.windows(2) {
            let (lo, hi) = (pair[0], pair[1]);
            let mid = [xm, 0.5 * (lo.at(xm) + hi.at(xm))];
            let owner = (0..surfaces.len())
                .filter(|&k| clipped[k].len() >= 3 && inside(&clipped[k], mid))
                .max_by(|&a, &b| {
                    surfaces[a]
                        .depth_at(mid)
                        .total_cmp(&surfaces[b].depth_at(mid))
                });
            if let Some(k) = owner {
                let h = 0.5 * ((hi.at(xa) - lo.at(xa)) + (hi.at(xb) - lo.at(xb)));
                areas[k] += h.max(0.0) * (xb - xa);
            }
        }
    }
    areas
}

#[cfg(test)]
mod visibility_tests {
    use super::*;

    fn square(x0: f64, y0: f64, x1: f64, y1: f64, depth: [f64; 3]) -> Surface {
        Surface {
            poly: vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
            depth,
        }
    }

    fn check(s: &[Surface], want: &[f64]) {
        let a = visible_areas(s, 0, 0);
        assert!(
            a.iter().zip(want).all(|(a, w)| (a - w).abs() < 1e-12),
            "{a:?} vs {want:?}"
        );
    }

    #[test]
    fn visible_areas_of_overlaps_and_intersections() {
        // A near square over the left 0.3 of the pixel, a far one over its left 0.7: the far
        // one shows on 0.4.
        check(
            &[
                square(0.0, 0.0, 0.3, 1.0, [2.0, 0.0, 0.0]),
                square(0.0, 0.0, 0.7, 1.0, [1.0, 0.0, 0.0]),
            ],
            &[0.3, 0.4],
        );
        // Two full-pixel planes crossing on the line x + y = 1 (depth equal there): each owns
        // the triangle where it is nearer, 1/2 each.
        check(
            &[
                square(-1.0, -1.0, 2.0, 2.0, [1.0, 1.0, 1.0]),
                square(-1.0, -1.0, 2.0, 2.0, [3.0, -1.0, -1.0]),
            ],
            &[0.5, 0.5],
        );
        // Crossing on x = 0.25 (a vertical depth line), the second nearer left of it.
        check(
            &[
                square(-1.0, -1.0, 2.0, 2.0, [0.0, 4.0, 0.0]),
                square(-1.0, -1.0, 2.0, 2.0, [1.0, 0.0, 0.0]),
            ],
            &[0.75, 0.25],
        );
        // A triangle in front of a square that covers half the pixel: the triangle 1/2; the
        // square's part right of x + y = 1: 1/2 - (the triangle's part of it, 1/8) = 3/8.
        check(
            &[
                Surface {
                    poly: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                    depth: [5.0, 0.0, 0.0],
                },
                square(0.5, 0.0, 1.0, 1.0, [1.0, 0.0, 0.0]),
            ],
            &[0.5, 0.375],
        );
    }
}
