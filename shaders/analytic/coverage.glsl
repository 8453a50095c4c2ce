// Exact pixel coverage of a convex polygon (a triangle, or the quadrilateral the near plane cuts
// from one), its centroid, the seed's column shortcut and a visibility mask of MASK_SAMPLES
// (32, 64 or 128: `analytic:samples=N`) samples. Shared by
// the analytic raster (raster.frag) and the coverage test kernel (coverage_test.comp); the CPU
// f64 reference is crates/cbr-render/src/techniques/analytic/reference.rs.
//
// Everything is in pixel-local coordinates: the polygon's vertices minus the pixel's top-left
// corner, so the pixel is the unit square [0,1]^2 whatever the screen position. The subtraction of
// an integer corner from an f32 vertex is exact for |x| < 2^23 px when both are within a factor of
// two, and otherwise rounds no worse than the vertex itself is already rounded; every later
// quantity is then formed from numbers of the size of the polygon near the pixel, not of the
// screen. Where a long edge's far endpoint is large, its crossing of the pixel's sides is formed
// from a cross product evaluated with exact (Dekker) products (accurate to ~1 ulp of the result),
// never as `x0 + (y - y0) * slope` (which cancels the digits that matter).
//
// Area by edges (the winding-number form of Green's theorem): the polygon's indicator is the sum
// over its edges of +-1 where the edge crosses the horizontal ray from the point towards +x. So
//     area(P n S) = | sum_e  s_e * integral_{y in [0,1] n e} clamp(x_e(y), 0, 1) dy |,
// one term per edge that depends only on that edge and the square (s_e: +1 if the edge runs
// towards +y). The first moments (for the centroid) come the same way:
//     Mx = sum_e s_e * integral clamp(x_e)^2 / 2 dy,   My = sum_e s_e * integral y clamp(x_e) dy.
// Each edge is evaluated from its endpoints in a canonical order (lower y first), so the two
// triangles sharing an edge evaluate the same numbers: their coverages add up to the pixel to
// rounding (no conflation seam).
#ifndef ANALYTIC_COVERAGE_GLSL
#define ANALYTIC_COVERAGE_GLSL

#define MAX_POLY 4
#include "mask.glsl"

// Dekker's exact product: a * b == p + e (Veltkamp's split; no reliance on a fused multiply-add,
// which a driver may lower to a separate multiply and add).
void two_product(float a, float b, out float p, out float e) {
    precise float ca = 4097.0 * a;
    precise float ah = ca - (ca - a);
    precise float al = a - ah;
    precise float cb = 4097.0 * b;
    precise float bh = cb - (cb - b);
    precise float bl = b - bh;
    precise float pp = a * b;
    p = pp;
    precise float ee = ((ah * bh - pp) + ah * bl + al * bh) + al * bl;
    e = ee;
}

// a * b - c * d to ~1 ulp of the result: where the products cancel, their difference is exact
// (Sterbenz) and the products' rounding errors carry the digits that are left.
float diff_products(float a, float b, float c, float d) {
    float p1, e1, p2, e2;
    two_product(a, b, p1, e1);
    two_product(c, d, p2, e2);
    precise float r = (p1 - p2) + (e1 - e2);
    return r;
}

// Area and first moments of the part of the unit square left of the edge a -> b (a.y < b.y),
// within the edge's y range: x(y) clamped to [0, 1], integrated over y. Endpoints come as
// double-f32 pairs (hi, lo: the exact pixel-local coordinate is hi + lo), since a far vertex's
// local coordinate may not fit one f32 exactly.
vec3 edge_integrals(vec2 a, vec2 al, vec2 b, vec2 bl, out vec3 second) {
    second = vec3(0.0);
    precise float y0 = max(a.y, 0.0);
    precise float y1 = min(b.y, 1.0);
    if (!(y0 < y1)) return vec3(0.0);
    precise float dx = (b.x - a.x) + (bl.x - al.x);
    precise float dy = (b.y - a.y) + (bl.y - al.y);
    // x on the edge's line at the square's top (y = 0) and bottom (y = 1) when the edge crosses
    // them: x(y) = (a.x b.y - a.y b.x + y dx) / dy, the cross product to ~1 ulp plus the
    // first-order terms of the low parts.
    precise float c = diff_products(a.x, b.y, a.y, b.x)
        + ((a.x * bl.y + al.x * b.y) - (a.y * bl.x + al.y * b.x));
    precise float x0 = y0 == a.y ? a.x + al.x : c / dy;
    precise float x1 = y1 == b.y ? b.x + bl.x : (c + dx) / dy;
    precise float len = y1 - y0;
    precise float c0 = clamp(x0, 0.0, 1.0);
    precise float c1 = clamp(x1, 0.0, 1.0);
    // Up to three pieces where clamp(x) is linear: split where x crosses 0 and 1.
    float ta = 0.0;
    float tb = 0.0;
    float va = c0;
    float vb = c0;
    if (x1 != x0) {
        precise float tz = (0.0 - x0) / (x1 - x0);
        precise float to = (1.0 - x0) / (x1 - x0);
        ta = clamp(min(tz, to), 0.0, 1.0);
        tb = clamp(max(tz, to), 0.0, 1.0);
        va = ta <= 0.0 ? c0 : (ta >= 1.0 ? c1 : (tz < to ? 0.0 : 1.0));
        vb = tb <= 0.0 ? c0 : (tb >= 1.0 ? c1 : (tz < to ? 1.0 : 0.0));
    }
    float ts[4] = float[4](0.0, ta, tb, 1.0);
    float vs[4] = float[4](c0, va, vb, c1);
    precise vec3 r = vec3(0.0);
    for (int i = 0; i < 3; ++i) {
        precise float l = len * (ts[i + 1] - ts[i]);
        if (l <= 0.0) continue;
        precise float u = vs[i];
        precise float v = vs[i + 1];
        precise float ya = y0 + len * ts[i];
        precise float yb = y0 + len * ts[i + 1];
        r.x += l * (u + v) * 0.5;
        r.y += l * (u * u + u * v + v * v) * (1.0 / 6.0);
        r.z += l * (ya * (2.0 * u + v) + yb * (u + 2.0 * v)) * (1.0 / 6.0);
        // Second moments (covered_footprint; not precise, and dropped by the compiler where
        // unused): integrals of c^3 / 3, y^2 c and y c^2 / 2.
        second.x += l * (u + v) * (u * u + v * v) * (1.0 / 12.0);
        second.y += l * (ya * ya * (3.0 * u + v) + 2.0 * ya * yb * (u + v) + yb * yb * (u + 3.0 * v))
            * (1.0 / 12.0);
        second.z += l * (ya * (3.0 * u * u + 2.0 * u * v + v * v) + yb * (u * u + 2.0 * u * v + 3.0 * v * v))
            * (1.0 / 24.0);
    }
    return r;
}

struct PixelCoverage {
    float area;     // exact area of the polygon inside the pixel, [0, 1]
    vec2 mean_point;  // centroid of that part (pixel-local); the pixel centre when area is 0
    vec3 second;      // its second moments per area: mean x^2, y^2, xy (0 when area is 0)
};

// Exact coverage of the convex polygon p[0..n) (either winding), pixel-local: p is the screen
// polygon minus the pixel corner rounded to f32, lo what that rounding dropped (0 unless a vertex
// lies in a larger binade relative to the pixel than on the screen).
PixelCoverage exact_coverage(vec2 p[MAX_POLY], vec2 lo[MAX_POLY], int n) {
    precise vec3 sum = vec3(0.0);
    vec3 sum2 = vec3(0.0);
    for (int i = 0; i < n; ++i) {
        int j = (i + 1) % n;
        vec2 a = p[i];
        vec2 b = p[j];
        if (a.y == b.y && lo[i].y == lo[j].y) continue;  // horizontal edges bound no y range
        vec3 e2;
        bool up = a.y < b.y || (a.y == b.y && lo[i].y < lo[j].y);
        precise vec3 e = up ? edge_integrals(a, lo[i], b, lo[j], e2)
                            : -edge_integrals(b, lo[j], a, lo[i], e2);
        sum += e;
        sum2 += up ? e2 : -e2;
    }
    PixelCoverage c;
    c.area = min(abs(sum.x), 1.0);
    c.mean_point = vec2(0.5);
    c.second = vec3(0.0);
    if (abs(sum.x) > 0.0) {
        c.mean_point = clamp(sum.yz / sum.x, vec2(0.0), vec2(1.0));
        c.second = sum2 / sum.x;
    }
    return c;
}

// The covered part's footprint for texture filtering ("gradients of the covered part"): the
// principal axes of its second moments (pixel-local), each as long as the box of the same
// variance is wide (sqrt(12 lambda)), the longer first, as the columns. The whole pixel gives
// unit axes in no particular direction (raster.frag keeps the pixel's own footprint wherever the
// coverage is within 1e-4 of the pixel); a sliver gives a thin
// footprint along it. Bounds: the longer at least 1/16 pixel (the alpha test's point) and the
// shorter at least a quarter of the longer, which bounds texture_aniso's taps.
mat2 covered_footprint(PixelCoverage cov) {
    vec3 m = cov.second;
    vec2 mean = cov.mean_point;
    float cxx = max(m.x - mean.x * mean.x, 0.0);
    float cyy = max(m.y - mean.y * mean.y, 0.0);
    float cxy = m.z - mean.x * mean.y;
    float h = 0.5 * (cxx + cyy);
    float d = sqrt(0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy);
    float l1 = h + d;
    float l2 = max(h - d, 0.0);
    // The eigenvector of l1: (l1 - cyy, cxy), or (cxy, l1 - cxx) where that one vanishes.
    vec2 e1 = vec2(l1 - cyy, cxy);
    if (dot(e1, e1) < 1e-12) e1 = vec2(cxy, l1 - cxx);
    e1 = dot(e1, e1) < 1e-12 ? vec2(1.0, 0.0) : normalize(e1);
    float w1 = max(sqrt(12.0 * l1), 1.0 / 16.0);
    float w2 = max(sqrt(12.0 * l2), 0.25 * w1);
    return mat2(e1 * w1, vec2(-e1.y, e1.x) * w2);
}

// Screen polygon -> pixel-local hi + lo pairs (Knuth's TwoSum: hi + lo == v - corner exactly).
void to_local(vec2 screen[MAX_POLY], vec2 corner, out vec2 p[MAX_POLY], out vec2 lo[MAX_POLY]) {
    for (int i = 0; i < MAX_POLY; ++i) {
        precise vec2 v = screen[i];
        precise vec2 s = v - corner;
        precise vec2 bb = s - v;
        precise vec2 err = (v - (s - bb)) + (-corner - bb);
        p[i] = s;
        lo[i] = err;
    }
}

// The seed's shortcut (analytic:seed): the polygon's vertical extent on the pixel column's
// centre line, clipped to the pixel (exact when every edge crossing the column crosses one pixel
// of it); columns holding a vertex take the supersampled mask instead, as the seed prescribes
// for "the triangle's vertex pixels".
float seed_coverage(vec2 p[MAX_POLY], int n, Mask mask) {
    float ylo = 1e30;
    float yhi = -1e30;
    bool vertex_column = false;
    for (int i = 0; i < n; ++i) {
        vec2 a = p[i];
        vec2 b = p[(i + 1) % n];
        if (a.x >= 0.0 && a.x <= 1.0) vertex_column = true;
        if ((a.x - 0.5) * (b.x - 0.5) > 0.0 || a.x == b.x) continue;
        float y = a.y + (0.5 - a.x) * (b.y - a.y) / (b.x - a.x);
        ylo = min(ylo, y);
        yhi = max(yhi, y);
    }
    if (vertex_column) return float(mask_count(mask)) / float(MASK_SAMPLES);
    return max(min(yhi, 1.0) - max(ylo, 0.0), 0.0);
}

// The visibility mask's sample k: a rank-1 lattice (every row and column of an N x N grid holds
// one sample, N = MASK_SAMPLES), so near-horizontal and near-vertical edges still sweep through
// samples one by one. Generator MASK_GEN (mask.glsl).
vec2 mask_sample(int k) {
    return (vec2(float(k), float((k * MASK_GEN) & (MASK_SAMPLES - 1))) + 0.5) / float(MASK_SAMPLES);
}

// Which of the mask samples lie in the polygon. A sample exactly on an edge goes to the polygon
// on the positive side of the edge in its canonical direction (lower y, then lower x, first), so
// of two polygons sharing an edge exactly one takes it, whatever their windings. `orient` is the
// sign of the polygon's signed area (the sum of the area integrals before abs).
// Edge i's function in canonical form, e(q) = ex q.x - ey q.y + c (c to ~1 ulp), and the sign
// `side` of e on the polygon's inside: the same numbers for the two polygons sharing the edge.
struct CanonicalEdge {
    float ex;
    float ey;
    float c;
    float side;
};

CanonicalEdge canonical_edge(vec2 p[MAX_POLY], int n, int i, float orient) {
    vec2 a = p[i];
    vec2 b = p[(i + 1) % n];
    bool canonical = a.y < b.y || (a.y == b.y && a.x < b.x);
    vec2 lo = canonical ? a : b;
    vec2 hi = canonical ? b : a;
    CanonicalEdge e;
    e.ex = hi.y - lo.y;
    e.ey = hi.x - lo.x;
    e.c = diff_products(e.ey, lo.y, e.ex, lo.x);
    // A polygon of positive orientation traversing the edge canonically lies where e < 0.
    e.side = (canonical ? -1.0 : 1.0) * orient;
    return e;
}

bool on_inside(CanonicalEdge e, vec2 q) {
    precise float v = e.ex * q.x - e.ey * q.y + e.c;
    return v * e.side > 0.0 || (v == 0.0 && e.side > 0.0);
}

bool inside(vec2 p[MAX_POLY], int n, float orient, vec2 q) {
    for (int i = 0; i < n; ++i) {
        if (!on_inside(canonical_edge(p, n, i, orient), q)) return false;
    }
    return true;
}

// The signed area's sign of a polygon (its winding in the area integrals' convention).
float orientation(vec2 p[MAX_POLY], int n) {
    precise float s = 0.0;
    for (int i = 0; i < n; ++i) {
        vec2 a = p[i];
        vec2 b = p[(i + 1) % n];
        s += diff_products(a.x, b.y, b.x, a.y);
    }
    return s < 0.0 ? -1.0 : 1.0;
}

// Sample k lies at x = (k + 1/2) / N: the samples in the polygon's x extent are a run of
// consecutive k, and only those are tested (a fifth of a pixel wide, a fifth of the samples),
// with a sample's margin on each side. A sample outside the extent is outside the polygon; only
// a sliver so thin that rounding puts a sample beyond its tip on the inside of both its long
// edges could tell otherwise.
Mask sample_mask(vec2 p[MAX_POLY], int n, float orient) {
    CanonicalEdge e[MAX_POLY];
    float xmin = 1e30;
    float xmax = -1e30;
    for (int i = 0; i < n; ++i) {
        e[i] = canonical_edge(p, n, i, orient);
        xmin = min(xmin, p[i].x);
        xmax = max(xmax, p[i].x);
    }
    const float N = float(MASK_SAMPLES);
    // NaN is tested before the clamp, which need not pass it through.
    float lo = floor(xmin * N - 0.5) - 1.0;
    float hi = ceil(xmax * N - 0.5) + 1.0;
    int k0 = isnan(lo) ? 0 : int(clamp(lo, 0.0, N - 1.0));
    int k1 = isnan(hi) ? MASK_SAMPLES - 1 : int(clamp(hi, 0.0, N - 1.0));
    Mask m = Mask(0u);
    for (int k = k0; k <= k1; ++k) {
        vec2 q = mask_sample(k);
        bool in_all = true;
        for (int i = 0; i < n; ++i) in_all = in_all && on_inside(e[i], q);
        if (in_all) m |= mask_bit(k);
    }
    return m;
}

// A covered part too small to hold a sample still needs one bit for the visibility test: the
// sample nearest its centroid (the lowest k among equally near ones). Sample k lies at x = (k +
// 1/2) / N, so the search runs outwards from q's column and stops where the columns alone are
// farther than the nearest sample found: the same sample as a scan of all N.
Mask nearest_sample_bit(vec2 q) {
    const float N = float(MASK_SAMPLES);
    int c = isnan(q.x) ? 0 : int(clamp(floor(q.x * N), 0.0, N - 1.0));
    int best = c;
    vec2 d0 = mask_sample(c) - q;
    float bd = dot(d0, d0);
    for (int i = 1; i < MASK_SAMPLES; ++i) {
        bool any_near = false;
        for (int side = 0; side < 2; ++side) {
            int k = side == 0 ? c - i : c + i;
            if (k < 0 || k >= MASK_SAMPLES) continue;
            vec2 d = mask_sample(k) - q;
            if (d.x * d.x > bd) continue;
            any_near = true;
            float dd = dot(d, d);
            if (dd < bd || (dd == bd && k < best)) {
                bd = dd;
                best = k;
            }
        }
        if (!any_near) break;
    }
    return mask_bit(best);
}

#endif
