#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// The checkerboard resolve (docs/resolve.md). One output pixel per invocation (MAPPING 0) or one
// 2x2 quad per invocation (MAPPING 1); both call the same per-pixel functions with the same
// inputs, so they write identical images. The CPU reference is crates/cbr-render/src/resolve/
// reference.rs: keep the two in step, operation for operation.
//
// Defines: LAYOUT (the raster layout, read through layout_fetch.glsl), MODE, MAPPING, FP16 (colour arithmetic in float16), OUT_FORMAT (rgba16f or rgba32f), DEBUG
// (write the debug bits), OUT_VELOCITY (write the velocity used: debug, `+taa`), BINDING_* (crates/cbr-render/src/resolve/mod.rs).
#if FP16
#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require
#define real float16_t
#define real3 f16vec3
#else
#define real float
#define real3 vec3
#endif
#include "../inc/layout_fetch.glsl"

// Defines from crates/cbr-render/src/resolve/mod.rs (`decl`): MODE_* (the modes), F_* (the
// push-constant flags: F_RESET no usable history; F_NO_VELOCITY, F_NO_DEPTH, F_NO_IDS,
// F_NO_CLAMP the ablations of `ours`; F_PREPASS the native-resolution depth + ID prepass is bound
// and used), DBG_* (the debug bits, one R32UI per pixel; DBG_STILL: `ours` took the history at p
// as it is in a still neighbourhood), ID_MOVED (history IDs carry it where the pixel moved more
// than the static threshold) and ID_MASK; LOCAL_SIZE_X/Y (the workgroup side, 8 or 16).

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform CB_SAMPLER cur_color;
layout(set = 0, binding = BINDING_VELOCITY) uniform CB_SAMPLER cur_velocity;
layout(set = 0, binding = BINDING_IDS) uniform CB_USAMPLER cur_ids;
layout(set = 0, binding = BINDING_DEPTH) uniform CB_SAMPLER cur_depth;
layout(set = 0, binding = BINDING_HIST_COLOR) uniform sampler2D hist_color;
// History geometry, one texel per pixel: x = object ID (| ID_MOVED), y = reverse-Z depth bits.
layout(set = 0, binding = BINDING_HIST_GEOM) uniform usampler2D hist_geom;
layout(set = 0, binding = BINDING_PRE_DEPTH) uniform sampler2D pre_depth;
layout(set = 0, binding = BINDING_PRE_IDS) uniform usampler2D pre_ids;
layout(set = 0, binding = BINDING_OUT_COLOR, OUT_FORMAT) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_GEOM, rg32ui) uniform writeonly uimage2D out_geom;
#if DEBUG
layout(set = 0, binding = BINDING_DEBUG_BITS, r32ui) uniform writeonly uimage2D out_debug;
#endif
#if OUT_VELOCITY
layout(set = 0, binding = BINDING_DEBUG_VELOCITY, rg32f) uniform writeonly image2D out_velocity;
#endif

// size_parity_side: W, H, parity, tangram side; flags.x: F_* flags; params: x depth tolerance,
// y static threshold (px), z pq4k motion threshold (px), w 0; reproj (intel): previous clip from
// current (NDC x, NDC y, depth, 1).
PUSH_CONSTANTS

ivec2 size() { return pc.size_parity_side.xy; }
vec2 inv_size() { return pc.inv_size.xy; }
// Every flag but F_RESET is fixed for the pass's lifetime and compiled in (STATIC_FLAGS, the same
// bits the push constant carries), so the paths a configuration does not use are not in its
// pipeline: on a SIMD machine that predicates branches they would cost even when no lane takes
// them.
bool has(uint f) { return f == F_RESET ? (pc.flags.x & f) != 0u : (uint(STATIC_FLAGS) & f) != 0u; }

struct Sample {
    real3 c;
    vec2 v;
    float d;     // reverse-Z depth (0 = infinitely far)
    uvec2 ids;   // object, primitive
};

// Reflect coordinates at the screen border: keeps (x + y) mod 2, so a missing pixel's
// neighbours outside the screen are rendered samples inside it. Needs W, H >= 2.
ivec2 mirror(ivec2 q) {
    ivec2 s = size();
    q = abs(q);
    return min(q, 2 * s - 2 - q);
}

// One coordinate reflected as mirror() does, for a coordinate at most one step off [0, n).
int mirror1(int x, int n) {
    x = abs(x);
    return min(x, 2 * n - 2 - x);
}

// The sample at q, a pixel on the screen (no reflection).
Sample load_on_screen(ivec2 q) {
    ivec4 a = cb_address(q, pc.size_parity_side.z, pc.size_parity_side.w);
    Sample s;
    s.c = real3(cb_fetch(cur_color, a).rgb);
    s.v = cb_fetch(cur_velocity, a).xy;
    s.d = cb_fetch(cur_depth, a).x;
    s.ids = cb_fetch(cur_ids, a).xy;
    return s;
}
Sample load_sample(ivec2 q) { return load_on_screen(mirror(q)); }
// The sample one step from p, a pixel on the screen, along x (`horizontal`) or y: only that
// coordinate can leave the screen, so only it is reflected (the same pixel as mirror()).
Sample load_step(ivec2 p, int step, bool horizontal) {
    ivec2 q = p;
    if (horizontal) q.x = mirror1(p.x + step, size().x);
    else q.y = mirror1(p.y + step, size().y);
    return load_on_screen(q);
}

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
real luma(real3 c) { return dot(c, real3(LUMA)); }
// Reinhard on luminance: averages of HDR colours taken here do not let one bright sample win.
real3 tonemap(real3 c) { return c / (real(1.0) + max(luma(c), real(0.0))); }
real3 untonemap(real3 t) { return t / max(real(1.0) - luma(t), real(1e-3)); }

real3 to_ycocg(real3 c) {
    return real3(real(0.25) * c.r + real(0.5) * c.g + real(0.25) * c.b,
                 real(0.5) * c.r - real(0.5) * c.b,
                 real(-0.25) * c.r + real(0.5) * c.g - real(0.25) * c.b);
}
real3 from_ycocg(real3 y) { return real3(y.x + y.y - y.z, y.x + y.z, y.x - y.y - y.z); }

// |z1 - z2| / max(z1, z2) of the linear depths z = near / d, computed from reverse-Z d.
float depth_rel_diff(float a, float b) {
    float m = max(a, b);
    return m > 0.0 ? abs(a - b) / m : 0.0;
}

bool inside(ivec2 t) { return all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, size())); }

// Bilinear taps around continuous pixel position q (pixel centres at integer + 0.5).
void bilinear_taps(vec2 q, out ivec2 base, out float w[4]) {
    vec2 g = q - 0.5;
    vec2 b = floor(g);
    vec2 f = g - b;
    base = ivec2(b);
    w[0] = (1.0 - f.x) * (1.0 - f.y);
    w[1] = f.x * (1.0 - f.y);
    w[2] = (1.0 - f.x) * f.y;
    w[3] = f.x * f.y;
}
const ivec2 TAP[4] = ivec2[4](ivec2(0, 0), ivec2(1, 0), ivec2(0, 1), ivec2(1, 1));

// Whether history depth hd shows the surface whose samples around the pixel span reverse-Z
// depths [lo, hi]: inside the span, or within the relative tolerance tol of either end
// (|z1 - z2| / max(z1, z2) of the linear depths z = near / d). Below the span that is
// (lo - hd) / lo <= tol, above it (hd - hi) / hd <= tol, so with keep = 1 - tol:
// lo * keep <= hd and hd * keep <= hi, which also holds inside the span. Two products, no
// division (an fp32 division is a reciprocal and a product on a GPU, with the driver's
// precision); keep is at most 1, so a negative tolerance leaves the span alone.
// keep = min(1 - tol, 1), computed on the CPU (ResolveSettings::params).
float depth_keep() { return pc.params.w; }
bool depth_agrees(float hd, float lo, float hi) {
    float keep = depth_keep();
    bool above_lo = hd >= lo * keep;
    bool below_hi = hd * keep <= hi;
    return above_lo && below_hi;
}

// Catmull-Rom weights of the taps at -1, 0, 1, 2 for fractional position f.
vec4 catmull_rom(float f) {
    float f2 = f * f;
    float f3 = f2 * f;
    return vec4(-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0,
                -1.5 * f3 + 2.0 * f2 + 0.5 * f, 0.5 * f3 - 0.5 * f2);
}

// Why history geometry g does not show object `id` at reverse-Z depths [lo, hi] (0: it does).
uint geom_reasons(uvec2 g, uint id, float lo, float hi, bool use_ids, bool use_depth) {
    uint r = 0u;
    if (use_ids && (g.x & ID_MASK) != id) r |= DBG_REJECT_ID;
    if (use_depth && !depth_agrees(uintBitsToFloat(g.y), lo, hi)) r |= DBG_REJECT_DEPTH;
    return r;
}
uint tap_reasons(ivec2 t, uint id, float lo, float hi, bool use_ids, bool use_depth) {
    return geom_reasons(texelFetch(hist_geom, t, 0).xy, id, lo, hi, use_ids, use_depth);
}

// The share of the bilinear footprint at q on history texels showing object `id` at reverse-Z
// depths [lo, hi] (off-screen taps count as invalid). `ours` accepts a hypothesis when more than
// half of it is valid: the footprint locates an edge of the object to a fraction of a texel,
// where the texel containing q alone (`fused`'s test) is off by up to half a texel. `valid`
// gets bit k for each valid tap k (TAP order), for history_resampled; `g0` the geometry of tap 0
// (the texel containing q when q is a texel centre; zero if that tap has no weight or lies off
// the screen).
float history_weight(vec2 q, uint id, float lo, float hi, bool use_ids, bool use_depth,
                     out bvec4 valid, inout uint why, out uvec2 g0) {
    ivec2 base;
    float w[4];
    bilinear_taps(q, base, w);
    // The footprint's 2 x 2 texels in two gathers (IDs, depth bits), at the point between their
    // centres: a coordinate half a texel from any centre, which the normalisation's rounding
    // cannot move to another footprint. Gather order: (0,1), (1,1), (1,0), (0,0).
    vec2 uv = (floor(q - 0.5) + 1.0) * inv_size();
    uvec4 gi = textureGather(hist_geom, uv, 0);
    uvec4 gd = textureGather(hist_geom, uv, 1);
    uvec2 gt[4] = uvec2[4](uvec2(gi.w, gd.w), uvec2(gi.z, gd.z), uvec2(gi.x, gd.x),
                           uvec2(gi.y, gd.y));
    // Which taps lie on the screen: tap x is base.x or base.x + 1, each tested as unsigned.
    bool x0 = uint(base.x) < uint(size().x);
    bool x1 = uint(base.x + 1) < uint(size().x);
    bool y0 = uint(base.y) < uint(size().y);
    bool y1 = uint(base.y + 1) < uint(size().y);
    bool on[4] = bool[4](x0 && y0, x1 && y0, x0 && y1, x1 && y1);
    float keep = depth_keep();
    float lo_keep = lo * keep;
    float ws = 0.0;
    g0 = w[0] > 0.0 && on[0] ? gt[0] : uvec2(0u);
    // Every tap is tested without a branch (each part a select): a SIMD machine runs the four
    // taps once whatever its lanes' verdicts. A tap without weight adds nothing to the sum
    // whatever its verdict, so it is not tested for weight here; `valid` may then hold such a
    // tap, which history_resampled, the only reader, ignores. The reasons are only kept for the
    // debug bits (of taps with weight, on the screen).
    for (int k = 0; k < 4; k++) {
        bool id_ok = (gt[k].x & ID_MASK) == id;
        id_ok = id_ok || !use_ids;
        float hd = uintBitsToFloat(gt[k].y);
        bool above_lo = hd >= lo_keep;
        bool below_hi = hd * keep <= hi;
        bool depth_ok = above_lo && below_hi;
        depth_ok = depth_ok || !use_depth;
        bool ok = on[k] && id_ok;
        ok = ok && depth_ok;
        ws += ok ? w[k] : 0.0;
        valid[k] = ok;
#if DEBUG
        uint rn = (id_ok ? 0u : DBG_REJECT_ID) | (depth_ok ? 0u : DBG_REJECT_DEPTH);
        why |= w[k] > 0.0 && on[k] ? rn : 0u;
#endif
    }
    return ws;
}

// History at q once accepted: bilinear over the valid taps (history_weight's `valid`),
// renormalised; with `exact`, the texel q lies in, as it is (the still rule). Kept apart from the
// test so that `ours` tests its candidates first and resamples once, for the winner: on a SIMD
// machine a resample inside the candidates' tests runs for every candidate on which any lane
// stops.
//
// hist_color's sampler is bilinear, clamp to edge, in texel units (resolve/mod.rs), and every case
// is five taps of it, each at a per-lane position with a per-lane weight, so that a SIMD machine
// that predicates (llvmpipe runs both sides of every `if`, and every texel read is a call there)
// makes five calls for whatever mix of cases its lanes hold:
// - all four bilinear taps valid: Catmull-Rom over the 4 x 4 texels around q without the four
//   corners (products of two negative lobes, at most 0.0055 each), the other 12 renormalised, as
//   5 bilinear taps: the inner 2 x 2 in one tap at the ratio of its weights, and each pair of
//   outer texels on one side in one tap (the Catmull-Rom's inner weights are positive, so every
//   pair's ratio lies in [0, 1]). Outer texels are clamped to the screen and not validated; the
//   neighbourhood clamp bounds any overshoot. It keeps the history sharp where bilinear would
//   soften it at every reprojection.
// - some taps invalid: the valid ones, each a tap at its texel's centre (a bilinear tap there is
//   that texel exactly: its fractions are 0).
// - `exact`: one tap at the centre of the texel q lies in.
real3 history_resampled(vec2 q, bvec4 valid, bool exact) {
    ivec2 base;
    float w[4];
    bilinear_taps(q, base, w);
    vec2 b = vec2(base) + 0.5;  // tap 0's texel centre
    // `exact` is the bilinear case with tap 0 alone valid: q is then a texel centre (the still
    // rule's v = 0), so tap 0 has weight 1 and the others 0.
    bool all_ok = !exact;
    for (int k = 0; k < 4; k++) all_ok = all_ok && (w[k] <= 0.0 || valid[k]);
    vec2 pos[5];
    float wt[5];
    // A branch, not a select of both cases' positions and weights: a SIMD vector whose lanes
    // agree runs one case.
    [[dont_flatten]] if (all_ok) {
        vec2 f = (q - 0.5) - vec2(base);
        vec4 wx = catmull_rom(f.x);
        vec4 wy = catmull_rom(f.y);
        float sx = wx.y + wx.z;
        float sy = wy.y + wy.z;
        vec2 c = b + vec2(wx.z / sx, wy.z / sy);
        pos[0] = c;
        wt[0] = sx * sy;
        pos[1] = vec2(b.x - 1.0, c.y);
        wt[1] = wx.x * sy;
        pos[2] = vec2(b.x + 2.0, c.y);
        wt[2] = wx.w * sy;
        pos[3] = vec2(c.x, b.y - 1.0);
        wt[3] = wy.x * sx;
        pos[4] = vec2(c.x, b.y + 2.0);
        wt[4] = wy.w * sx;
    } else {
        for (int k = 0; k < 4; k++) {
            pos[k] = b + vec2(TAP[k]);
            wt[k] = w[k] > 0.0 && valid[k] ? w[k] : 0.0;
        }
        pos[4] = b;
        wt[4] = 0.0;
    }
    real3 acc = real3(0.0);
    float ws = 0.0;
    for (int k = 0; k < 5; k++) {
        real3 t = real3(textureLod(hist_color, pos[k], 0.0).rgb);
        if (wt[k] != 0.0) {
            acc += real(wt[k]) * t;
            ws += wt[k];
        }
    }
    real3 h = acc / real(ws);
    return all_ok ? max(h, real3(0.0)) : h;
}

// History at q validated against object `id` and reverse-Z depths [lo, hi] (`fused`): the texel
// containing q must be valid (the reprojected point lands on the surface), then
// history_resampled(). That texel is one of the bilinear taps, always with weight at least 1/4,
// so history_weight's mask holds its verdict; only a rejection reads its reasons.
bool history_validated(vec2 q, uint id, float lo, float hi, bool use_ids, bool use_depth,
                       out real3 h, inout uint why) {
    h = real3(0.0);
    ivec2 near = ivec2(floor(q));
    if (!inside(near)) return false;
    bvec4 valid;
    uint tap_why = 0u;
    uvec2 g0;
    history_weight(q, id, lo, hi, use_ids, use_depth, valid, tap_why, g0);
    ivec2 k = near - ivec2(floor(q - 0.5));
    if (!valid[k.x + 2 * k.y]) {
        why |= tap_reasons(near, id, lo, hi, use_ids, use_depth);
        return false;
    }
    h = history_resampled(q, valid, false);
    return true;
}

// History at q, bilinear, taps clamped to the screen, no validation.
real3 history_plain(vec2 q) {
    ivec2 base;
    float w[4];
    bilinear_taps(q, base, w);
    real3 acc = real3(0.0);
    for (int k = 0; k < 4; k++) {
        ivec2 t = clamp(base + TAP[k], ivec2(0), size() - 1);
        acc += real(w[k]) * real3(texelFetch(hist_color, t, 0).rgb);
    }
    return acc;
}

// Neighbours: 0 left, 1 right, 2 up, 3 down. Ordered by depth, nearest (largest reverse-Z)
// first, ties in neighbour order; with `pref`, the samples showing object `pid` before all others
// (`ours`' pair preference, below). The order is kept as its six pairwise verdicts (Order.bij: i
// comes before j), not as a sorted copy: the neighbour of rank k is picked where it is needed
// (`ranked`), so only the ranks a pixel uses cost selections, and on a GPU the verdicts and ranks
// are lane masks (scalar instructions). Each comparison is one unsigned compare of a key: the
// depth's bits (a depth is in [0, 1], below 2^30 as bits, ordered as the floats; the sign masked
// off, so -0 is 0) shifted left by 2 over 3 - the neighbour index. A total order, so the same as
// the stable sort it replaces. Without `by_depth`, neighbour order.
struct Order {
    bool b01, b02, b03, b12, b13, b23;  // bij: neighbour i comes before neighbour j
};
bool key_before(uint ki, bool pi, uint kj, bool pj) { return pi != pj ? pi : ki > kj; }
Order neighbour_order(Sample n[4], bool pref, uint pid, bool by_depth) {
    Order o = Order(true, true, true, true, true, true);
    if (by_depth) {
        uint key[4];
        bool pr[4];
        for (int i = 0; i < 4; i++) {
            key[i] = ((floatBitsToUint(n[i].d) & 0x7fffffffu) << 2) | uint(3 - i);
            pr[i] = pref && n[i].ids.x == pid;
        }
        o.b01 = key_before(key[0], pr[0], key[1], pr[1]);
        o.b02 = key_before(key[0], pr[0], key[2], pr[2]);
        o.b03 = key_before(key[0], pr[0], key[3], pr[3]);
        o.b12 = key_before(key[1], pr[1], key[2], pr[2]);
        o.b13 = key_before(key[1], pr[1], key[3], pr[3]);
        o.b23 = key_before(key[2], pr[2], key[3], pr[3]);
    }
    return o;
}

// Which of the other three neighbours come before neighbour i (i a constant).
bvec3 before_it(Order o, int i) {
    if (i == 0) return bvec3(!o.b01, !o.b02, !o.b03);
    if (i == 1) return bvec3(o.b01, !o.b12, !o.b13);
    if (i == 2) return bvec3(o.b02, o.b12, !o.b23);
    return bvec3(o.b03, o.b13, o.b23);
}

// Whether neighbour i has rank k: exactly k of the other three come before it.
bool has_rank(Order o, int i, int k) {
    bvec3 e = before_it(o, i);
    if (k == 0) return !any(e);
    if (k == 3) return all(e);
    if (k == 1) return e.x ? !e.y && !e.z : e.y != e.z;
    return e.x ? e.y != e.z : e.y && e.z;
}

// The neighbour of rank k (colour and primitive ID not carried: the resolve reads only the
// velocity, depth and object ID of a ranked sample).
Sample ranked(Sample n[4], Order o, int k) {
    Sample s;
    s.c = real3(0.0);
    s.v = n[3].v;
    s.d = n[3].d;
    s.ids = uvec2(n[3].ids.x, 0u);
    if (has_rank(o, 2, k)) {
        s.v = n[2].v;
        s.d = n[2].d;
        s.ids.x = n[2].ids.x;
    }
    if (has_rank(o, 1, k)) {
        s.v = n[1].v;
        s.d = n[1].d;
        s.ids.x = n[1].ids.x;
    }
    if (has_rank(o, 0, k)) {
        s.v = n[0].v;
        s.d = n[0].d;
        s.ids.x = n[0].ids.x;
    }
    return s;
}

// Whether neighbour i shows an object a neighbour before it shows.
bool repeats(Sample n[4], Order o, int i) {
    bvec3 e = before_it(o, i);
    int j0 = i == 0 ? 1 : 0;
    int j1 = i <= 1 ? 2 : 1;
    int j2 = i <= 2 ? 3 : 2;
    uint id = n[i].ids.x;
    bool r0 = e.x && n[j0].ids.x == id;
    bool r1 = e.y && n[j1].ids.x == id;
    bool r2 = e.z && n[j2].ids.x == id;
    return r0 || r1 || r2;
}

// Whether the neighbour of rank k shows an object a neighbour of lower rank shows.
bool rank_repeats(Sample n[4], Order o, int k) {
    bool r0 = has_rank(o, 0, k) && repeats(n, o, 0);
    bool r1 = has_rank(o, 1, k) && repeats(n, o, 1);
    bool r2 = has_rank(o, 2, k) && repeats(n, o, 2);
    bool r3 = has_rank(o, 3, k) && repeats(n, o, 3);
    return r0 || r1 || r2 || r3;
}

// Weights of the differential blend: 1 / (BLEND_EPS + luminance difference of the pair), in
// tonemapped units (0..1). 1/64 bounds the weight ratio, keeps fp16 stable (exact in f16).
#define BLEND_EPS 0.015625

// The differential blend of the vertical and horizontal pairs in tonemapped space; pairs that
// cross an object-ID edge (or do not show `ref_id`, with the prepass) are rejected.
// The neighbours' colours tonemapped, and their luminances: computed once per pixel for
// spatial_fill and history_share (divisions are dear on a CPU's vector units).
void toned(Sample n[4], out real3 t[4], out real l[4]) {
    for (int i = 0; i < 4; i++) {
        t[i] = tonemap(n[i].c);
        l[i] = luma(t[i]);
    }
}

real3 spatial_fill(Sample n[4], real3 t[4], real l[4], uint ref_id, bool use_ids, bool own) {
    bool h_ok = true;
    bool v_ok = true;
    if (use_ids) {
        if (own) {
            h_ok = n[0].ids.x == ref_id && n[1].ids.x == ref_id;
            v_ok = n[2].ids.x == ref_id && n[3].ids.x == ref_id;
        } else {
            h_ok = n[0].ids.x == n[1].ids.x;
            v_ok = n[2].ids.x == n[3].ids.x;
        }
    }
    real3 hm = (t[0] + t[1]) * real(0.5);
    real3 vm = (t[2] + t[3]) * real(0.5);
    real3 r;
    if (h_ok && v_ok) {
        real wh = real(1.0) / (real(BLEND_EPS) + abs(l[0] - l[1]));
        real wv = real(1.0) / (real(BLEND_EPS) + abs(l[2] - l[3]));
        r = (wh * hm + wv * vm) / (wh + wv);
    } else if (h_ok) {
        r = hm;
    } else if (v_ok) {
        r = vm;
    } else {
        real3 acc = real3(0.0);
        real cnt = real(0.0);
        for (int i = 0; i < 4; i++) {
            if (n[i].ids.x == ref_id) {
                acc += t[i];
                cnt += real(1.0);
            }
        }
        if (cnt == real(0.0)) {
            acc = t[0] + t[1] + t[2] + t[3];
            cnt = real(4.0);
        }
        r = acc / cnt;
    }
    return untonemap(r);
}

// The history's share in `ours`' moving blend, from the tonemapped luminance differences of the
// two opposite pairs: HISTORY_WEIGHT, up to HISTORY_WEIGHT_DETAIL where both pairs differ (detail
// or a corner: the spatial estimate guesses), down to 0 where one differs much more than the
// other (an edge through p: the differential blend follows it, while the resampled history is
// the softer and the likelier to be off by a fraction of a pixel there).
real history_share(real l[4]) {
    real dh = abs(l[0] - l[1]);
    real dv = abs(l[2] - l[3]);
    real lo = min(dh, dv);
    real detail = clamp(lo / real(DETAIL_CONTRAST), real(0.0), real(1.0));
    real edge = clamp((max(dh, dv) - lo) / real(EDGE_CONTRAST), real(0.0), real(1.0));
    real w = real(HISTORY_WEIGHT) + real(HISTORY_WEIGHT_DETAIL - HISTORY_WEIGHT) * detail
        - real(HISTORY_WEIGHT) * edge;
    return clamp(w, real(0.0), real(1.0));
}

// The same-quad horizontal neighbour (x xor 1): rendered whenever the pixel is missing.
int quad_partner(ivec2 p) { return (p.x & 1) == 0 ? 1 : 0; }

struct Result {
    real3 c;
    float d;
    uint id;
    vec2 v;
    uint dbg;
};

real3 clamp_to_box(real3 h, Sample n[4], inout uint dbg) {
    real3 y = to_ycocg(h);
    real3 lo = to_ycocg(n[0].c);
    real3 hi = lo;
    for (int i = 1; i < 4; i++) {
        real3 q = to_ycocg(n[i].c);
        lo = min(lo, q);
        hi = max(hi, q);
    }
    real3 yc = clamp(y, lo, hi);
    if (any(notEqual(yc, y))) {
        dbg |= DBG_CLAMPED;
        return from_ycocg(yc);
    }
    return h;
}

// `ours`' test of candidate ck (a neighbour's surface; with the prepass the pixel's own, moving
// as ck): more than half of the bilinear footprint at q - v on history texels showing its object
// at a depth inside the span of the neighbours showing it (or within the tolerance). On success
// the result takes its depth, ID and velocity and `valid` the footprint's valid taps; `why`
// collects the reasons of rejected taps either way.
bool try_candidate(vec2 q, Sample ck, Sample n[4], bool own, uint own_id, float own_d, bool multi,
                   bool use_ids, bool use_depth, bool use_v, inout Result r, inout bvec4 valid,
                   inout uint why) {
    vec2 v = use_v ? ck.v : vec2(0.0);
    uint id = own ? own_id : ck.ids.x;
    float d = own ? own_d : ck.d;
    // The depth span of the neighbours showing this object (with the prepass, the pixel's own
    // depth).
    float lo = d;
    float hi = d;
    if (multi) {
        // A neighbour showing another object contributes d itself, which the span holds.
        for (int i = 0; i < 4; i++) {
            float di = n[i].ids.x == id ? n[i].d : d;
            lo = min(lo, di);
            hi = max(hi, di);
        }
    }
    bvec4 tap_valid;
    uvec2 g0;
    float wsum = history_weight(q - v, id, lo, hi, use_ids, use_depth, tap_valid, why, g0);
    if (wsum > 0.5) {
        r.d = d;
        r.id = id;
        r.v = v;
        valid = tap_valid;
        return true;
    }
    return false;
}

Result resolve_missing(ivec2 p, Sample n[4]) {
    Result r;
    r.dbg = DBG_MISSING;
    vec2 q = vec2(p) + 0.5;
    bool reset = has(F_RESET);
    bool own = has(F_PREPASS);
    float own_d = 0.0;
    uint own_id = 0u;
    if (own) {
        own_d = texelFetch(pre_depth, p, 0).x;
        own_id = texelFetch(pre_ids, p, 0).x;
    }
    // `ours` with every neighbour's object and depth known: when exactly one of the two opposite
    // pairs (left and right; up and down) shows a single object, p lies between those two
    // samples, most likely on that object whatever the depths, so its samples sort first.
    bool pref = false;
    uint pid = 0u;
#if MODE == MODE_OURS
    if (!own && !has(F_NO_IDS) && !has(F_NO_DEPTH)) {
        bool hp = n[0].ids.x == n[1].ids.x;
        bool vp = n[2].ids.x == n[3].ids.x;
        pref = hp != vp;
        pid = hp ? n[0].ids.x : n[2].ids.x;
    }
#endif
    Order bef = neighbour_order(n, pref, pid, true);
    Sample near = ranked(n, bef, 0);
    uint ref_id = own ? own_id : near.ids.x;
#if MODE == MODE_PQ4K
    Sample partner = n[quad_partner(p)];
    real3 avg = (n[0].c + n[1].c + n[2].c + n[3].c) * real(0.25);
    r.c = avg;
    r.d = partner.d;
    r.id = partner.ids.x;
    r.v = partner.v;
    if (!reset) {
        ivec2 t = ivec2(floor(q - partner.v));
        if (inside(t)) {
            real3 h = real3(texelFetch(hist_color, t, 0).rgb);
            r.dbg |= DBG_REPROJECTED;
            if (length(partner.v) > pc.params.z) {
                real3 lo = min(min(n[0].c, n[1].c), min(n[2].c, n[3].c));
                real3 hi = max(max(n[0].c, n[1].c), max(n[2].c, n[3].c));
                real3 hc = clamp(h, lo, hi);
                if (any(notEqual(hc, h))) r.dbg |= DBG_CLAMPED;
                r.c = avg * real(0.5) + hc * real(0.5);
            } else {
                r.c = h;
            }
        }
    }
    if ((r.dbg & DBG_REPROJECTED) == 0u) r.dbg |= DBG_SPATIAL;
#elif MODE == MODE_INTEL
    float d = own ? own_d : near.d;
    r.d = d;
    r.id = ref_id;
    vec2 ndc = q / vec2(size()) * 2.0 - 1.0;
    vec4 prev = pc.reproj * vec4(ndc, d, 1.0);
    bool ok = !reset && prev.w > 0.0;
    vec2 pq = vec2(0.0);
    if (ok) {
        pq = (prev.xy / prev.w * 0.5 + 0.5) * vec2(size());
        ivec2 t = ivec2(floor(pq));
        ok = inside(t);
        if (ok && depth_rel_diff(uintBitsToFloat(texelFetch(hist_geom, t, 0).y), prev.z / prev.w) > pc.params.x) {
            ok = false;
            r.dbg |= DBG_REJECT_DEPTH;
        }
    }
    r.v = q - pq;
    if (ok) {
        r.c = history_plain(pq);
        r.dbg |= DBG_REPROJECTED;
    } else {
        real3 acc = real3(0.0);
        real ws = real(0.0);
        for (int i = 0; i < 4; i++) {
            real w = real(1.0) / (real(1.0) + max(luma(n[i].c), real(0.0)));
            acc += w * n[i].c;
            ws += w;
        }
        r.c = acc / ws;
        r.dbg |= DBG_SPATIAL;
    }
#elif MODE == MODE_SPATIAL
    real3 t[4];
    real l[4];
    toned(n, t, l);
    r.c = spatial_fill(n, t, l, ref_id, !has(F_NO_IDS), own);
    r.d = own ? own_d : near.d;
    r.id = ref_id;
    r.v = near.v;
    r.dbg |= DBG_SPATIAL;
#elif MODE == MODE_TEMPORAL
    r.d = own ? own_d : near.d;
    r.id = ref_id;
    r.v = near.v;
    if (reset) {
        real3 t[4];
        real l[4];
        toned(n, t, l);
        r.c = spatial_fill(n, t, l, ref_id, true, own);
        r.dbg |= DBG_SPATIAL;
    } else {
        r.c = history_plain(q - near.v);
        r.dbg |= DBG_REPROJECTED;
    }
#else  // MODE_OURS
    bool use_ids = !has(F_NO_IDS);
    bool use_depth = !has(F_NO_DEPTH);
    bool use_v = !has(F_NO_VELOCITY);
    // Hypotheses: the surfaces the neighbours show, nearest first, one per object ID (with the
    // prepass: the pixel's own surface, moving as its nearest-in-depth neighbour of that ID).
    // Without depth they come in neighbour order; without IDs and depth, only the quad partner.
    // c: the candidates in order; with IDs and without the prepass every distinct object
    // among them is tried, else only c[0].
    // cbef: the candidates' order (ranked(n, cbef, k) is c[k]).
    Order cbef = neighbour_order(n, pref, pid, use_depth);
    Sample c0 = ranked(n, cbef, 0);
    bool multi = use_ids && !own;
    // The surface a pixel takes when every hypothesis fails: the preferred pair's object, else
    // the farthest neighbour's (the nearer surfaces' histories would have been valid had they
    // covered p: a failure is a disocclusion).
    Sample fb = pref ? near : ranked(n, bef, 3);
    if (own) {
        Sample best = n[0];
        float best_diff = abs(n[0].d - own_d);
        for (int i = 1; i < 4; i++) {
            float dd = abs(n[i].d - own_d);
            bool same = n[i].ids.x == own_id;
            bool best_same = best.ids.x == own_id;
            if ((same && !best_same) || (same == best_same && dd < best_diff)) {
                best = n[i];
                best_diff = dd;
            }
        }
        c0 = best;
    } else if (!use_ids && !use_depth) {
        c0 = quad_partner(p) == 1 ? n[1] : n[0];
    }
    r.d = own ? own_d : c0.d;
    r.id = own ? own_id : c0.ids.x;
    r.v = use_v ? c0.v : vec2(0.0);
    bool found = false;
    uint why = 0u;
    real3 h = real3(0.0);
    // The hypotheses, in order, each tested only where every earlier one failed:
    // - First, where the neighbourhood is still (every neighbour below the static threshold): the
    //   history at p, if it did not move either (with the prepass: if it shows the pixel's own
    //   object). Nothing can have covered or uncovered p, so its history stands as it is. This
    //   keeps thin features that no neighbour shows; a disoccluded pixel's history moved, so it is
    //   not taken. One geometry fetch at p (the footprint at p's centre is that texel alone).
    // - Then the candidates: the first with more than half of its bilinear footprint at q - v
    //   valid wins. Candidates showing an object an earlier candidate already showed are skipped.
    // The winner's history is resampled once, afterwards. Written as a fixed sequence of `if`s
    // (at most the still hypothesis and 4 candidates), not a loop over a per-lane index: each
    // candidate's fields are then registers, not a per-lane selection among the four, and a GPU
    // skips a block no lane of its wave takes, as it leaves a loop no lane continues (AMD's
    // compiler also counts a loop's body 8 times in its estimates: docs/resolve.md, "GCN ISA").
    // llvmpipe does not skip an `if` (its lanes are masks): there every candidate's gathers run,
    // where the loop ran only the iterations some lane of a vector needed (the cost on lavapipe
    // rose by about a fifth; same section).
    bool still = false;
    if (!reset && use_v) {
        still = true;
        for (int i = 0; i < 4; i++) still = still && length(n[i].v) <= pc.params.y;
    }
    bool covered = false;
    bool still_won = false;
    bvec4 win_valid = bvec4(false);
    if (still) {
        uvec2 g0 = texelFetch(hist_geom, p, 0).xy;
        if ((g0.x & ID_MOVED) == 0u && (!own || g0.x == own_id)) {
            covered = true;
            still_won = true;
            r.d = uintBitsToFloat(g0.y);
            r.id = g0.x;
            r.v = vec2(0.0);
            r.dbg |= DBG_STILL;
            win_valid = bvec4(true, false, false, false);
        }
    }
    if (!reset && !covered) {
        covered = try_candidate(q, c0, n, own, own_id, own_d, multi, use_ids, use_depth, use_v,
                                r, win_valid, why);
        if (multi && !covered) {
            // The later candidates, each picked (and checked for a repeated object) only here.
            if (!rank_repeats(n, cbef, 1))
                covered = try_candidate(q, ranked(n, cbef, 1), n, own, own_id, own_d, multi,
                                        use_ids, use_depth, use_v, r, win_valid, why);
            if (!covered) {
                if (!rank_repeats(n, cbef, 2))
                    covered = try_candidate(q, ranked(n, cbef, 2), n, own, own_id, own_d, multi,
                                            use_ids, use_depth, use_v, r, win_valid, why);
                if (!covered && !rank_repeats(n, cbef, 3))
                    covered = try_candidate(q, ranked(n, cbef, 3), n, own, own_id, own_d, multi,
                                            use_ids, use_depth, use_v, r, win_valid, why);
            }
        }
    }
    if (covered) {
        found = true;
        h = history_resampled(q - r.v, win_valid, still_won);
    }
    // Moving: clamp to the neighbourhood, then blend with the spatial estimate, the history
    // weighted by history_share (resolve/mod.rs's constants; pq4k takes its 4-neighbour mean half
    // and half):
    // resampled history alone is softer and noisier than fresh neighbours. Without history, the
    // spatial estimate alone, of `fb`'s surface when every hypothesis failed. Computed once.
    bool blend = found && !has(F_NO_CLAMP) && length(r.v) > pc.params.y;
    if (!found && multi && !reset) {
        r.id = fb.ids.x;
        r.d = fb.d;
        r.v = use_v ? fb.v : vec2(0.0);
    }
    real3 sp = real3(0.0);
    real share = real(0.0);
    if (!found || blend) {
        // Only here: a pixel that takes its history as it is needs no neighbour tonemapped.
        real3 t[4];
        real l[4];
        toned(n, t, l);
        sp = spatial_fill(n, t, l, found || (multi && !reset) ? r.id : ref_id, use_ids, own);
        share = history_share(l);
    }
    if (found) {
        r.dbg |= DBG_REPROJECTED;
        if (blend) {
            h = clamp_to_box(h, n, r.dbg);
            h = mix(sp, h, share);
        }
        r.c = h;
    } else {
        r.dbg |= why | DBG_SPATIAL;
        r.c = sp;
    }
#endif
    return r;
}

void write_result(ivec2 p, Result r) {
    imageStore(out_color, p, vec4(vec3(r.c), 1.0));
    uint id = r.id | (length(r.v) > pc.params.y ? ID_MOVED : 0u);
    imageStore(out_geom, p, uvec4(id, floatBitsToUint(r.d), 0u, 0u));
#if DEBUG
    imageStore(out_debug, p, uvec4(r.dbg));
#endif
#if OUT_VELOCITY
    imageStore(out_velocity, p, vec4(r.v, 0.0, 0.0));
#endif
}

Result pass_through(Sample s) {
    Result r;
    r.c = s.c;
    r.d = s.d;
    r.id = s.ids.x;
    r.v = s.v;
    r.dbg = DBG_RENDERED;
    return r;
}


#if FUSED
const ivec2 DIAGONAL[4] = ivec2[4](ivec2(-1, -1), ivec2(1, -1), ivec2(-1, 1), ivec2(1, 1));

// `fused` (checkerboard and TAA in one history): a rendered pixel blends its fresh (jittered)
// sample into its own history: taken as it is where pixel and history texel are still, else
// reprojected and validated against the sample's object and depth like a missing pixel's and
// then clipped towards the mean of the variance box (mean +- sigma, tonemapped YCoCg) of the
// sample and its four diagonal neighbours (rendered this frame too); then blended with a luminance-weighted
// weight FUSED_ALPHA for the sample (rising with speed).
Result rendered_result(ivec2 p, Sample s) {
    Result r = pass_through(s);
    if (has(F_RESET)) return r;
    real3 h = real3(0.0);
    bool found = false;
    uint why = 0u;
    bool still = length(s.v) <= pc.params.y && (texelFetch(hist_geom, p, 0).x & ID_MOVED) == 0u;
    if (still) {
        h = real3(texelFetch(hist_color, p, 0).rgb);
        found = true;
        r.dbg |= DBG_STILL;
    } else {
        found = history_validated(vec2(p) + 0.5 - s.v, s.ids.x, s.d, s.d, !has(F_NO_IDS),
                                  !has(F_NO_DEPTH), h, why);
    }
    if (!found) {
        r.dbg |= why;
        return r;
    }
    r.dbg |= DBG_REPROJECTED;
    real3 y = to_ycocg(tonemap(s.c));
    real3 m1 = y;
    real3 m2 = y * y;
    for (int i = 0; i < 4; i++) {
        real3 yd = to_ycocg(tonemap(load_sample(p + DIAGONAL[i]).c));
        m1 += yd;
        m2 += yd * yd;
    }
    real3 mu = m1 * real(0.2);
    real3 sigma = sqrt(max(m2 * real(0.2) - mu * mu, real3(0.0)));
    real3 yh = to_ycocg(tonemap(h));
    // Clip towards mu into [mu - sigma, mu + sigma].
    real3 d = yh - mu;
    real t = real(1.0);
    for (int i = 0; i < 3; i++) {
        if (abs(d[i]) > sigma[i]) t = min(t, sigma[i] / abs(d[i]));
    }
    // Still (pixel and history texel did not move): the history is kept unclipped. Only the
    // jitter changes the box there, and clipping towards a box that moves with the jitter phase
    // is not a contraction: a static scene never settled (hundreds of fp16 ulps of flicker;
    // tests/stability.rs, drift). Unclipped, the history is the running average and converges.
    if (t < real(1.0) && !still) {
        r.dbg |= DBG_CLAMPED;
        h = untonemap(from_ycocg(mu + d * t));
    }
    // The sample's weight rises with speed like `+taa`'s (FUSED_ALPHA_MAX at FUSED_SPEED px).
    real a = real(mix(FUSED_ALPHA, FUSED_ALPHA_MAX, min(length(s.v) / FUSED_SPEED, 1.0)));
    real wc = a / (real(1.0) + max(luma(s.c), real(0.0)));
    real wh = (real(1.0) - a) / (real(1.0) + max(luma(h), real(0.0)));
    // The weighted mean (wc c + wh h) / (wc + wh) as h + (c - h) t: exactly h where c = h, where
    // the quotient form is off in the last bits and the RGBA16F history keeps them (`+taa`'s
    // blend, docs/post-aa.md: every hard case's FLIP fell with the change).
    r.c = h + (s.c - h) * (wc / (wc + wh));
    return r;
}
#else
Result rendered_result(ivec2 p, Sample s) { return pass_through(s); }
#endif

bool rendered(ivec2 p) { return ((p.x + p.y) & 1) == pc.size_parity_side.z; }

#if MAPPING == 0
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size().x || p.y >= size().y) return;
    if (rendered(p)) {
        write_result(p, rendered_result(p, load_on_screen(p)));
        return;
    }
    Sample n[4];
    n[0] = load_step(p, -1, true);
    n[1] = load_step(p, 1, true);
    n[2] = load_step(p, -1, false);
    n[3] = load_step(p, 1, false);
    write_result(p, resolve_missing(p, n));
}
#else
// Missing pixel p of a quad, whose rendered samples h_in (its horizontal neighbour) and v_in
// (its vertical one) are loaded: only the two neighbours outside the quad are loaded. Written
// without a per-lane choice between loaded and loading: a SIMD machine that predicates would
// otherwise run all four loads.
void resolve_in_quad(ivec2 p, Sample h_in, Sample v_in) {
    if (!inside(p)) return;
    // In the quad's right column the outer horizontal neighbour is to the right, else to the
    // left; likewise the bottom row and the vertical one.
    bool right = (p.x & 1) == 1;
    bool below = (p.y & 1) == 1;
    Sample h_out = load_step(p, right ? 1 : -1, true);
    Sample v_out = load_step(p, below ? 1 : -1, false);
    Sample n[4];
    n[0] = right ? h_in : h_out;
    n[1] = right ? h_out : h_in;
    n[2] = below ? v_in : v_out;
    n[3] = below ? v_out : v_in;
    write_result(p, resolve_missing(p, n));
}

// One 2x2 quad: its two rendered samples are loaded once and serve as two of the four
// neighbours of each of its two missing pixels: 6 sample loads instead of 10.
void main() {
    ivec2 base = 2 * ivec2(gl_GlobalInvocationID.xy);
    if (base.x >= size().x || base.y >= size().y) return;
    int parity = pc.size_parity_side.z;
    // Rendered: (0,0),(1,1) for parity 0; (1,0),(0,1) for parity 1. Missing: the other two.
    ivec2 ra = base + (parity == 0 ? ivec2(0, 0) : ivec2(1, 0));
    ivec2 rb = base + (parity == 0 ? ivec2(1, 1) : ivec2(0, 1));
    ivec2 ma = base + (parity == 0 ? ivec2(1, 0) : ivec2(0, 0));
    ivec2 mb = base + (parity == 0 ? ivec2(0, 1) : ivec2(1, 1));
    // rb may lie outside an odd-sized screen; mirror() makes its load the reflected sample,
    // which is exactly what a missing pixel's neighbour load would read there.
    Sample sa = load_sample(ra);
    Sample sb = load_sample(rb);
    if (inside(ra)) write_result(ra, rendered_result(ra, sa));
    if (inside(rb)) write_result(rb, rendered_result(rb, sb));
    // A missing pixel's horizontal neighbour inside the quad is sa for ma and sb for mb, its
    // vertical one the other (both parities). Two calls, not a loop over the two pixels: llvmpipe
    // tests a loop's exit only at the end of an iteration, so a `for` over them ran a third
    // iteration, the whole missing-pixel path with no lane active (docs/resolve.md).
    resolve_in_quad(ma, sa, sb);
    resolve_in_quad(mb, sb, sa);
}
#endif
