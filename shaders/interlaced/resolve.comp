#version 460
// The `interlaced` resolve (docs/interlaced.md): rows of the frame's parity were rendered, the
// others are reconstructed from the previous resolved frame (velocity-reprojected, validated by
// object ID and depth like the checkerboard resolve) or, where history fails, from the rows
// above and below (edge-directed line averaging). Two output pixels per invocation, one rendered
// and one missing (main, below). The CPU
// reference is crates/cbr-render/src/techniques/interlaced/reference.rs: keep the two in step,
// operation for operation.
//
// Defines: DEBUG (write the debug bits), BINDING_* (crates/cbr-render/src/techniques/interlaced/
// resolve.rs).

// Defines from crates/cbr-render/src/techniques/interlaced/resolve.rs (`decl`): the push-constant
// flags F_RESET (no usable history: first frame, camera cut, `without-history`), F_NO_DEPTH,
// F_NO_IDS, F_NO_CLAMP, F_NO_DIAGONALS (ablations); the debug bits DBG_* (one R32UI per pixel),
// the checkerboard resolve's values, so `cbr render` writes the same debug views.

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

// This frame's raster (full resolution; only rows of the frame's parity are read).
layout(set = 0, binding = BINDING_COLOR) uniform sampler2D cur_color;
layout(set = 0, binding = BINDING_VELOCITY) uniform sampler2D cur_velocity;
layout(set = 0, binding = BINDING_IDS) uniform usampler2D cur_ids;
layout(set = 0, binding = BINDING_DEPTH) uniform sampler2D cur_depth;
// The previous frame's resolved colour and geometry (the other slot).
layout(set = 0, binding = BINDING_HIST_COLOR) uniform sampler2D hist_color;
layout(set = 0, binding = BINDING_HIST_VELOCITY) uniform sampler2D hist_velocity;
layout(set = 0, binding = BINDING_HIST_IDS) uniform usampler2D hist_ids;
layout(set = 0, binding = BINDING_HIST_DEPTH) uniform sampler2D hist_depth;
// This frame's resolved colour and geometry (this slot).
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_VELOCITY, rg32f) uniform writeonly image2D out_velocity;
layout(set = 0, binding = BINDING_OUT_IDS, rg32ui) uniform writeonly uimage2D out_ids;
layout(set = 0, binding = BINDING_OUT_DEPTH, r32f) uniform writeonly image2D out_depth;
#if DEBUG
layout(set = 0, binding = BINDING_DEBUG_BITS, r32ui) uniform writeonly uimage2D out_debug;
#endif

// size_parity: W, H, parity (the rendered rows' y mod 2), 0; flags.x: F_* flags; params: x depth
// tolerance, y static threshold (px), z clamp margin, w 0.
PUSH_CONSTANTS

ivec2 size() { return pc.size_parity.xy; }
bool has(uint f) { return (pc.flags.x & f) != 0u; }

struct Sample {
    vec3 c;
    vec2 v;
    float d;    // reverse-Z depth (0 = infinitely far)
    uvec2 ids;  // object, primitive
};

// Reflect coordinates at the screen border: y - 1 and y + 1 of a missing row stay rendered rows
// (reflection keeps y mod 2). Needs W, H >= 2.
ivec2 mirror(ivec2 q) {
    ivec2 s = size();
    q = abs(q);
    return min(q, 2 * s - 2 - q);
}

Sample load_sample(ivec2 q) {
    q = mirror(q);
    Sample s;
    s.c = texelFetch(cur_color, q, 0).rgb;
    s.v = texelFetch(cur_velocity, q, 0).xy;
    s.d = texelFetch(cur_depth, q, 0).x;
    s.ids = texelFetch(cur_ids, q, 0).xy;
    return s;
}

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
float luma(vec3 c) { return c.r * LUMA.r + c.g * LUMA.g + c.b * LUMA.b; }
// Reinhard on luminance: means of HDR colours taken here do not let one bright sample win.
vec3 tonemap(vec3 c) { return c / (1.0 + max(luma(c), 0.0)); }
vec3 untonemap(vec3 t) { return t / max(1.0 - luma(t), 1e-3); }

vec3 to_ycocg(vec3 c) {
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b,
                -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}
vec3 from_ycocg(vec3 y) { return vec3(y.x + y.y - y.z, y.x + y.z, y.x - y.y - y.z); }

// |z1 - z2| / max(z1, z2) of the linear depths z = near / d, computed from reverse-Z d.
float depth_rel_diff(float a, float b) {
    float m = max(a, b);
    return m > 0.0 ? abs(a - b) / m : 0.0;
}

// Whether history depth hd shows the surface whose samples around the pixel span reverse-Z
// depths [lo, hi]: inside the span, or within the relative tolerance of either end.
bool depth_agrees(float hd, float lo, float hi) {
    return (hd >= lo && hd <= hi) || depth_rel_diff(hd, lo) <= pc.params.x ||
           depth_rel_diff(hd, hi) <= pc.params.x;
}

bool inside(ivec2 t) { return all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, size())); }

float speed(vec2 v) { return sqrt(v.x * v.x + v.y * v.y); }

// Why history texel t does not show object `id` at reverse-Z depths [lo, hi] (0: it does).
uint tap_reasons(ivec2 t, uint id, float lo, float hi) {
    uint r = 0u;
    if (!has(F_NO_IDS) && texelFetch(hist_ids, t, 0).x != id) r |= DBG_REJECT_ID;
    if (!has(F_NO_DEPTH) && !depth_agrees(texelFetch(hist_depth, t, 0).x, lo, hi)) {
        r |= DBG_REJECT_DEPTH;
    }
    return r;
}

// Catmull-Rom weights of the taps at -1, 0, 1, 2 for fractional position f (0, 1, 0, 0 at 0).
vec4 catmull_rom(float f) {
    float f2 = f * f;
    float f3 = f2 * f;
    return vec4(-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0,
                -1.5 * f3 + 2.0 * f2 + 0.5 * f, 0.5 * f3 - 0.5 * f2);
}

const ivec2 TAP[4] = ivec2[4](ivec2(0, 0), ivec2(1, 0), ivec2(0, 1), ivec2(1, 1));

// History at continuous position q (pixel centres at integer + 0.5) validated against object
// `id` at depths [lo, hi]: the texel containing q must be valid, then bilinear over the valid
// taps (renormalised), or Catmull-Rom over the 4 x 4 texels around q when all four bilinear
// taps are valid (outer taps clamped to the screen, not validated). At a texel centre both
// return that texel exactly.
bool history_validated(vec2 q, uint id, float lo, float hi, out vec3 h, inout uint why) {
    h = vec3(0.0);
    ivec2 near = ivec2(floor(q));
    if (!inside(near)) return false;
    uint rn = tap_reasons(near, id, lo, hi);
    if (rn != 0u) {
        why |= rn;
        return false;
    }
    vec2 g = q - 0.5;
    vec2 b = floor(g);
    vec2 f = g - b;
    ivec2 base = ivec2(b);
    float w[4] = float[4]((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y,
                          f.x * f.y);
    vec3 acc = vec3(0.0);
    float ws = 0.0;
    bool all_ok = true;
    for (int k = 0; k < 4; k++) {
        ivec2 t = base + TAP[k];
        if (w[k] <= 0.0) continue;
        if (inside(t) && (t == near || tap_reasons(t, id, lo, hi) == 0u)) {
            acc += w[k] * texelFetch(hist_color, t, 0).rgb;
            ws += w[k];
        } else {
            all_ok = false;
        }
    }
    h = acc / ws;
    if (all_ok) {
        vec4 wx = catmull_rom(f.x);
        vec4 wy = catmull_rom(f.y);
        vec3 c = vec3(0.0);
        for (int j = 0; j < 4; j++) {
            vec3 row = vec3(0.0);
            for (int i = 0; i < 4; i++) {
                ivec2 t = clamp(base + ivec2(i - 1, j - 1), ivec2(0), size() - 1);
                row += wx[i] * texelFetch(hist_color, t, 0).rgb;
            }
            c += wy[j] * row;
        }
        h = max(c, vec3(0.0));
    }
    return true;
}

// The rendered samples around a missing pixel: the row above (x - 1, x, x + 1), then the row
// below (x - 1, x, x + 1).
#define ABOVE 1
#define BELOW 4

// Edge-directed line averaging (the deinterlacers' ELA): of the pairs through p (above-left with
// below-right, above with below, above-right with below-left), the one whose two samples differ
// least in tonemapped luminance, ties to the vertical pair, then the first diagonal; a pair whose
// samples show different objects is no candidate. Its mean in tonemapped space; with no candidate,
// the nearer vertical neighbour `nearest`.
vec3 spatial_fill(Sample n[6], int nearest) {
    int pairs[6] = int[6](ABOVE, BELOW, ABOVE - 1, BELOW + 1, ABOVE + 1, BELOW - 1);
    int count = has(F_NO_DIAGONALS) ? 1 : 3;
    int best = -1;
    float best_diff = 0.0;
    vec3 best_mean = vec3(0.0);
    for (int k = 0; k < count; k++) {
        Sample s = n[pairs[2 * k]];
        Sample t = n[pairs[2 * k + 1]];
        if (!has(F_NO_IDS) && s.ids.x != t.ids.x) continue;
        vec3 ts = tonemap(s.c);
        vec3 tt = tonemap(t.c);
        float diff = abs(luma(ts) - luma(tt));
        if (best < 0 || diff < best_diff) {
            best = k;
            best_diff = diff;
            best_mean = (ts + tt) * 0.5;
        }
    }
    return best < 0 ? n[nearest].c : untonemap(best_mean);
}

// Clamps h to the YCoCg min/max box of the six rendered samples around the pixel, widened on
// each side by a fraction (params.z) of its extent: the rows above and below do not hold the
// missing row's own content (thin horizontal features, steep vertical gradients), so their box
// alone is too tight (docs/interlaced.md: measured).
vec3 clamp_to_box(vec3 h, Sample n[6], inout uint dbg) {
    vec3 y = to_ycocg(h);
    vec3 lo = to_ycocg(n[0].c);
    vec3 hi = lo;
    for (int i = 1; i < 6; i++) {
        vec3 q = to_ycocg(n[i].c);
        lo = min(lo, q);
        hi = max(hi, q);
    }
    vec3 margin = pc.params.z * (hi - lo);
    vec3 yc = clamp(y, lo - margin, hi + margin);
    if (any(notEqual(yc, y))) {
        dbg |= DBG_CLAMPED;
        return from_ycocg(yc);
    }
    return h;
}

struct Result {
    vec3 c;
    vec2 v;
    float d;
    uvec2 ids;
    uint dbg;
};

Result resolve_missing(ivec2 p) {
    Sample n[6];
    for (int i = 0; i < 3; i++) {
        n[i] = load_sample(p + ivec2(i - 1, -1));
        n[3 + i] = load_sample(p + ivec2(i - 1, 1));
    }
    float thr = pc.params.y;
    // Candidates: the nearer vertical neighbour (larger reverse-Z, ties to the one above), then
    // the other if it shows another object; each brings its own velocity.
    int first = n[ABOVE].d >= n[BELOW].d ? ABOVE : BELOW;
    int second = first == ABOVE ? BELOW : ABOVE;
    Result r;
    r.dbg = DBG_MISSING;
    r.v = n[first].v;
    r.d = n[first].d;
    r.ids = n[first].ids;
    bool found = false;
    uint why = 0u;
    vec3 h = vec3(0.0);
    if (!has(F_RESET)) {
        // Still: both neighbours and the history pixel itself (rendered there last frame) moved
        // less than the threshold: nothing can have covered or uncovered p, its history stands
        // as it is, with its depth and IDs. This keeps rows no neighbour shows (thin horizontal
        // features) and makes a static scene exact.
        if (speed(n[ABOVE].v) <= thr && speed(n[BELOW].v) <= thr &&
            speed(texelFetch(hist_velocity, p, 0).xy) <= thr) {
            found = true;
            h = texelFetch(hist_color, p, 0).rgb;
            r.d = texelFetch(hist_depth, p, 0).x;
            r.ids = texelFetch(hist_ids, p, 0).xy;
            r.dbg |= DBG_STILL;
        }
        // The candidates in one loop whose exit test is the body's last statement: llvmpipe
        // checks whether any lane goes on only at the end of an iteration, and runs the body of
        // an `if` whatever its lanes take, so a test at the top ran one more iteration, every
        // fetch in it, with no lane active (docs/resolve.md). A pixel the still rule took
        // skips the body; one whose second candidate shows the first one's object stops after
        // the first; none goes past the second.
        bool one = has(F_NO_IDS) || n[second].ids.x == n[first].ids.x;
        for (int k = 0; k < 2; k++) {
            int c = k == 0 ? first : second;
            uint id = n[c].ids.x;
            // The depth span of the vertical neighbours showing this object.
            float lo = n[c].d;
            float hi = n[c].d;
            if (!has(F_NO_IDS) && n[ABOVE].ids.x == n[BELOW].ids.x) {
                lo = min(n[ABOVE].d, n[BELOW].d);
                hi = max(n[ABOVE].d, n[BELOW].d);
            }
            if (!found && history_validated(vec2(p) + 0.5 - n[c].v, id, lo, hi, h, why)) {
                found = true;
                r.v = n[c].v;
                r.d = n[c].d;
                r.ids = n[c].ids;
            }
            if (found || one || k == 1) break;
        }
    }
    if (found) {
        r.dbg |= DBG_REPROJECTED;
        if (!has(F_NO_CLAMP) && speed(r.v) > thr) h = clamp_to_box(h, n, r.dbg);
        r.c = h;
    } else {
        r.dbg |= why | DBG_SPATIAL;
        r.c = spatial_fill(n, first);
    }
    return r;
}

void write_result(ivec2 p, Result r) {
    imageStore(out_color, p, vec4(r.c, 1.0));
    imageStore(out_velocity, p, vec4(r.v, 0.0, 0.0));
    imageStore(out_ids, p, uvec4(r.ids, 0u, 0u));
    imageStore(out_depth, p, vec4(r.d, 0.0, 0.0, 0.0));
#if DEBUG
    imageStore(out_debug, p, uvec4(r.dbg));
#endif
}

// Invocation (x, j): the pixels of column x in rows 2j and 2j + 1, one rendered and one missing.
// Every lane then has a missing pixel to resolve: with one pixel per invocation an 8-wide lane
// group is one row, all rendered or all missing, and on a SIMD machine that runs the body of an
// `if` whatever its lanes take (llvmpipe) the rendered rows' groups paid for the missing path too.
void main() {
    ivec2 p0 = ivec2(gl_GlobalInvocationID.x, 2 * int(gl_GlobalInvocationID.y));
    if (p0.x >= size().x || p0.y >= size().y) return;
    ivec2 pr = p0 + ivec2(0, pc.size_parity.z);      // the pair's rendered row
    ivec2 pm = p0 + ivec2(0, 1 - pc.size_parity.z);  // and its missing one
    if (pr.y < size().y) {
        Sample s = load_sample(pr);
        Result r;
        r.c = s.c;
        r.v = s.v;
        r.d = s.d;
        r.ids = s.ids;
        r.dbg = DBG_RENDERED;
        write_result(pr, r);
    }
    if (pm.y < size().y) write_result(pm, resolve_missing(pm));
}
