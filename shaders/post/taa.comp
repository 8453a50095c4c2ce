#version 460
#extension GL_GOOGLE_include_directive : require
// `+taa`: temporal anti-aliasing as a post pass (docs/post-aa.md). One pixel per invocation.
// The CPU reference is crates/cbr-render/src/post/taa.rs (`reference`): keep the two in step,
// operation for operation.
//
// MODE 0 (`+taa`, after Karis 2014): 3x3 closest-depth velocity dilation, history by
// Catmull-Rom mixed with Lanczos-3 over 6x6 texels (HISTORY 2, in the proportion `sharp`; 1:
// Karis' 5-tap Catmull-Rom in Jimenez's bilinear form; 0: bilinear), YCoCg variance clipping
// (Salvi) of the history towards the
// neighbourhood mean, luminance-weighted blend; plus the object-ID and depth disocclusion tests of
// the checkerboard resolve. MODE 1 (`+taa:inside`, Pedersen 2016): 3x3 closest-depth dilation,
// bilinear history, rounded 3x3 min-max box with YCoCg chroma shrink, clip towards the clamped
// neighbourhood mean, feedback from the unbiased luminance difference.
//
// Colours are compared in "perceptual" space: exposure-scaled, Reinhard-tonemapped on luminance,
// YCoCg. History and output are linear HDR. A non-finite current sample never enters the history.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_CUR) uniform sampler2D cur;
layout(set = 0, binding = BINDING_VELOCITY) uniform sampler2D velocity;
#if !PACKED
layout(set = 0, binding = BINDING_DEPTH) uniform sampler2D depth;
#endif
layout(set = 0, binding = BINDING_IDS) uniform usampler2D ids;
layout(set = 0, binding = BINDING_HIST) uniform sampler2D hist;  // bilinear, clamped
layout(set = 0, binding = BINDING_HIST_GEOM) uniform usampler2D hist_geom;
layout(set = 0, binding = BINDING_OUT_HIST, rgba16f) uniform writeonly image2D out_hist;
layout(set = 0, binding = BINDING_OUT_GEOM, rg32ui) uniform writeonly uimage2D out_geom;
// The still pixels' jitter cycle (F_CYCLE): rgb the mean of this cycle's samples so far, a their
// count k (0: none); and the range of their perceptual luma, xy of the last complete cycle
// (x > y: none), zw of this one.
layout(set = 0, binding = BINDING_CYCLE) uniform sampler2D hist_cycle;
layout(set = 0, binding = BINDING_RANGE) uniform sampler2D hist_range;
layout(set = 0, binding = BINDING_OUT_CYCLE, rgba32f) uniform writeonly image2D out_cycle;
layout(set = 0, binding = BINDING_OUT_RANGE, rgba16f) uniform writeonly image2D out_range;
// Each object's turn this frame, by object ID (F_REACTIVE; gpu_scene.rs `object_turns`).
layout(set = 0, binding = BINDING_TURNS) readonly buffer Turns { float turns[]; };

// F_RESET, F_DILATION, F_CLIP, F_IDS, F_DEPTH, F_MEAN (blend weight 1 / (n + 1): the
// running mean), F_FILTER (reconstruct the current sample at the pixel centre, Karis' filter),
// F_COUNT (the current-frame weight is at least 1 / (m + 1), m the frames the pixel's history
// holds), F_LUMA (Karis' luminance weights in the blend), F_CYCLE (a still pixel shows the mean
// of its last complete jitter cycle), F_CENTRED (a reset frame is rendered unjittered),
// F_INTERIOR, F_LOCK, F_SHED (below), F_SURFACE (a surface keeps its own velocity): the flag
// bits, and MOVED / ID_MASK (the geometry the technique gives) and HIST_ID_MASK / COUNT_SHIFT / COUNT_MAX (history
// geometry: x = object ID | count << COUNT_SHIFT | MOVED where the pixel moved more than the
// still threshold), are defines from crates/cbr-render/src/post/taa.rs.

// size: W, H (of the output and the geometry), 0, 0; flags: x: F_*, y: n (frames accumulated
// since the reset), z: the jitter cycle's length L; params: alpha (current-frame weight), gamma,
// depth tolerance, exposure scale; feedback_still: INSIDE feedback min, max, still threshold
// (pixels), the cycle's change tolerance (perceptual luma); speed_jitter:
// x: current-frame weight at and above speed y (pixels per frame; 0: off), zw: the jitter;
// interior: x the speed at which a moving interior's weight reaches 1 (F_INTERIOR), y the
// history kernel's Lanczos-3 share (HISTORY 2; `sharp`).
PUSH_CONSTANTS

bool has(uint f) { return (pc.flags.x & f) != 0u; }

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
float luma(vec3 c) { return dot(c, LUMA); }

#include "../inc/perceptual.glsl"
#include "../inc/plane.glsl"
#include "../inc/thin_feature.glsl"
#include "../inc/lanczos3.glsl"

// Linear HDR -> perceptual YCoCg at the frame's exposure, and back (taau's space too).
vec3 to_p(vec3 c) { return perceptual(c, pc.params.w); }
vec3 from_p(vec3 y) { return linear_from_perceptual(y, pc.params.w); }

// The geometry texel's reverse-Z depth and object ID (PACKED: the checkerboard resolve's history
// geometry, (object ID | moved bit, depth bits), in the IDs image).
#if PACKED
float geom_depth(ivec2 t) { return uintBitsToFloat(texelFetch(ids, t, 0).y); }
uint geom_id(ivec2 t) { return texelFetch(ids, t, 0).x & ID_MASK; }
#else
float geom_depth(ivec2 t) { return texelFetch(depth, t, 0).r; }
uint geom_id(ivec2 t) { return texelFetch(ids, t, 0).x; }
#endif

ivec2 clamp_px(ivec2 q) { return clamp(q, ivec2(0), pc.size.xy - 1); }

// |a - b| / max(a, b) of linear depths from reverse-Z (the resolve's `depth_rel_diff`).
float depth_rel_diff(float a, float b) {
    float m = max(a, b);
    return m > 0.0 ? abs(a - b) / m : 0.0;
}

// Catmull-Rom weights of the taps at -1, 0, 1, 2 for fractional position f.
vec4 catmull_rom(float f) {
    float f2 = f * f;
    float f3 = f2 * f;
    return vec4(-0.5 * f3 + f2 - 0.5 * f, 1.5 * f3 - 2.5 * f2 + 1.0,
                -1.5 * f3 + 2.0 * f2 + 0.5 * f, 0.5 * f3 - 0.5 * f2);
}

// History at continuous pixel position q: Catmull-Rom in 5 bilinear taps (the 4x4 footprint less
// its corners, the middle 2x2 in one tap), renormalised over the taps' weights.
vec3 history_catmull(vec2 q) {
    vec2 g = q - 0.5;
    vec2 b = floor(g);
    vec2 f = g - b;
    vec4 wx = catmull_rom(f.x);
    vec4 wy = catmull_rom(f.y);
    vec2 w12 = vec2(wx.y + wx.z, wy.y + wy.z);
    // Tap k of -1..2 is centred at b + k + 0.5; the middle pair in one bilinear tap between them.
    vec2 c12 = b + 0.5 + vec2(wx.z, wy.z) / w12;
    vec2 c0 = b - 0.5;
    vec2 c3 = b + 2.5;
    vec2 inv = 1.0 / vec2(pc.size.xy);
    float w[5] = float[5](w12.x * wy.x, wx.x * w12.y, w12.x * w12.y, wx.w * w12.y, w12.x * wy.w);
    vec2 at[5] = vec2[5](vec2(c12.x, c0.y), vec2(c0.x, c12.y), c12, vec2(c3.x, c12.y),
                         vec2(c12.x, c3.y));
    vec3 acc = vec3(0.0);
    float ws = 0.0;
    for (int k = 0; k < 5; k++) {
        acc += w[k] * textureLod(hist, at[k] * inv, 0.0).rgb;
        ws += w[k];
    }
    return max(acc / ws, vec3(0.0));
}

// History at continuous pixel position q, HISTORY 2: (1 - s) Catmull-Rom (its 4x4 weights, padded
// to the 6x6) + s Lanczos-3 (renormalised) over the 6x6 texels around q, one sum, clamped at 0;
// exact at rest (f = 0). The history is resampled at every reprojection and the blur compounds
// over the frames it holds: Lanczos-3 keeps more of the detail, but alone it kept more of a
// view-dependent highlight's lag too (`specular`), so it is mixed (`sharp`; docs/post-aa.md has
// the sweep). One sum of texel reads: the 5-tap Catmull-Rom's bilinear taps beside the 36 reads
// cost 184 ms a frame at 1280x720 on lavapipe, this 141.
vec3 history_mixed(vec2 q, float s) {
    vec2 g = q - 0.5;
    vec2 bf = floor(g);
    vec2 f = g - bf;
    ivec2 b = ivec2(bf);
    float lx[6], ly[6];
    lanczos3_weights(f.x, lx);
    lanczos3_weights(f.y, ly);
    vec4 cx4 = catmull_rom(f.x), cy4 = catmull_rom(f.y);
    float cx[6] = float[6](0.0, cx4.x, cx4.y, cx4.z, cx4.w, 0.0);
    float cy[6] = float[6](0.0, cy4.x, cy4.y, cy4.z, cy4.w, 0.0);
    float lsx = 0.0, lsy = 0.0;
    for (int k = 0; k < 6; k++) {
        lsx += lx[k];
        lsy += ly[k];
    }
    float ls = s / (lsx * lsy);
    vec3 acc = vec3(0.0);
    for (int y = 0; y < 6; y++) {
        for (int x = 0; x < 6; x++) {
            float w = (1.0 - s) * cx[x] * cy[y] + ls * lx[x] * ly[y];
            acc += w * texelFetch(hist, clamp_px(b + ivec2(x - 2, y - 2)), 0).rgb;
        }
    }
    return max(acc, vec3(0.0));
}

vec3 history_bilinear(vec2 q) { return textureLod(hist, q / vec2(pc.size.xy), 0.0).rgb; }

const ivec2 OFF[9] = ivec2[9](ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0), ivec2(0, 0),
                              ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size.xy))) return;

    // The current 3x3 neighbourhood; non-finite samples take no part.
    vec3 c[9];
    bool ok[9];
    vec3 sum = vec3(0.0);
    float n_ok = 0.0;
    for (int k = 0; k < 9; k++) {
        c[k] = texelFetch(cur, clamp_px(p + OFF[k]), 0).rgb;
        ok[k] = finite3(c[k]);
        if (ok[k]) {
            sum += c[k];
            n_ok += 1.0;
        }
    }
    // A non-finite centre is replaced by the mean of the finite neighbours (0 when none).
    vec3 c0 = ok[4] ? c[4] : (n_ok > 0.0 ? sum / n_ok : vec3(0.0));
    vec3 cf = c0;
    if (has(F_FILTER) || has(F_ADAPTIVE)) {
        // The current frame at the pixel centre: the 3x3's samples (at offset o - jitter from
        // it) weighted by a Gaussian fit of Blackman-Harris (Karis 2014), exp(-2.29 d^2).
        vec3 acc = vec3(0.0);
        float ws = 0.0;
        for (int k = 0; k < 9; k++) {
            if (!ok[k]) continue;
            vec2 d = vec2(OFF[k]) - pc.speed_jitter.zw;
            float w = exp(-2.29 * dot(d, d));
            acc += w * c[k];
            ws += w;
        }
        if (ws > 0.0) cf = acc / ws;
    }
    // F_FILTER: always the reconstruction; F_ADAPTIVE: the reconstruction in the proportion the
    // current frame weighs in the output (below).
    if (has(F_FILTER)) c0 = cf;
    vec3 y0 = to_p(c0);
    // The 3x3 in the perceptual space (a non-finite sample as the centre's replacement): what
    // the lock test, the variance box and INSIDE's box read.
    vec3 yk[9];
    for (int k = 0; k < 9; k++) yk[k] = ok[k] ? to_p(c[k]) : y0;

    // Geometry: the nearest (largest reverse-Z) texel of the 3x3 gives the velocity (dilation);
    // the neighbourhood's object IDs and depth span validate the history.
    float d_best = -1.0;
    ivec2 g_best = p;
    float lo = 1e30, hi = -1e30;
    uint nid[9];
    float nd[9];
    for (int k = 0; k < 9; k++) {
        ivec2 t = clamp_px(p + OFF[k]);
        float d = geom_depth(t);
        nid[k] = geom_id(t);
        nd[k] = d;
        lo = min(lo, d);
        hi = max(hi, d);
        if (d > d_best) {
            d_best = d;
            g_best = t;
        }
    }
    // The 3x3's reverse-Z depth is one plane, within the depth tolerance (inc/plane.glsl).
    bool plane = depth_plane(nd, pc.params.z);
    // Dilation takes the nearest texel's velocity, so that a silhouette's pixels move with the
    // object in front; on a surface (the 3x3 one plane, F_SURFACE) the pixel keeps its own: the
    // nearest texel of a receding floor is the one below, whose velocity differs by the
    // perspective's gradient, and each frame's history was fetched that far off (a lag that the
    // exponential window accumulates; `specular`'s dark floor, docs/post-aa.md).
    bool dilate = has(F_DILATION) && !(has(F_SURFACE) && plane);
    vec2 v = texelFetch(velocity, dilate ? g_best : p, 0).xy;
    vec2 q = vec2(p) + 0.5 - v;

    bool use = !has(F_RESET) && all(greaterThanEqual(q, vec2(0.0))) &&
               all(lessThan(q, vec2(pc.size.xy)));
    // Still: this pixel and its history texel did not move (the checkerboard resolve's rule):
    // nothing can have been disoccluded, and the tests would only reject jittered sub-pixel
    // features (a wire that one jitter sees and the next misses).
    bool moving = length(v) > pc.feedback_still.z;
    uvec2 g = uvec2(0u);
    if (use) g = texelFetch(hist_geom, ivec2(floor(q)), 0).xy;
    bool still = !moving && (g.x & MOVED) == 0u;
    // The jitter cycle of a still pixel (F_CYCLE): its jittered samples repeat every L frames
    // while nothing changes, so a sample outside the luma range of the last complete cycle (by
    // more than the tolerance) means the content changed (a shadow moved over it, a light
    // changed): its history is rejected, as a disoccluded pixel's is, and its cycle restarts.
    vec4 cyc = vec4(0.0);
    vec4 rng = vec4(1.0, 0.0, 1.0, 0.0);
    bool cycling = false;
    bool complete = false;  // the last cycle is complete: rng.xy is its range
#if MODE == 0
    if (has(F_CYCLE) && use && still) {
        ivec2 t = ivec2(floor(q));
        cyc = texelFetch(hist_cycle, t, 0);
        rng = texelFetch(hist_range, t, 0);
        complete = rng.x <= rng.y;
        float tol = pc.feedback_still.w;
        bool changed = complete && (y0.x < rng.x - tol || y0.x > rng.y + tol);
        use = !changed;
        cycling = !changed;
    }
#endif
    // F_LOCK: a thin feature's lock (FSR 2's locks, for `+taa`). A moving pixel keeps its
    // lock's life in the cycle image's x (it has no cycle); the history texel's is read where
    // that texel moved. A lock lives L frames (the jitter cycle), renewed wherever this frame's
    // sample is a thin feature. It holds on a surface only (the 3x3 one plane: a decal, a far
    // stripe, a texture's line, which move with the surface, so their history reprojects
    // exactly; not a silhouette, whose history slides over what is behind it): there the history
    // is kept from rectification in the lock's proportion and from the ID test (a sub-pixel
    // feature that this frame's jitter missed is not disoccluded; the depth test still applies),
    // and the pixel is no interior (but see F_SHED).
    float life = 0.0;
#if MODE == 0
    if (has(F_LOCK)) {
        if (use && (g.x & MOVED) != 0u)
            life = max(texelFetch(hist_cycle, ivec2(floor(q)), 0).x - 1.0 / float(pc.flags.z), 0.0);
        float yl[9];
        for (int k = 0; k < 9; k++) yl[k] = yk[k].x;
        if (thin_feature(yl)) life = 1.0;
    }
#endif
    float lock_hold = plane ? life : 0.0;
    bool locked = lock_hold > 0.0;
    // The history's object is one of the 3x3's.
    bool seen = false;
    for (int k = 0; k < 9; k++) seen = seen || nid[k] == (g.x & HIST_ID_MASK);
    if (use && !still && (has(F_IDS) || has(F_DEPTH))) {
        if (has(F_IDS) && !locked) use = use && seen;
        if (has(F_DEPTH)) {
            float hd = uintBitsToFloat(g.y);
            use = use && ((hd >= lo && hd <= hi) || depth_rel_diff(hd, lo) <= pc.params.z ||
                          depth_rel_diff(hd, hi) <= pc.params.z);
        }
    }
    vec3 h = vec3(0.0);
    if (use) {
#if HISTORY == 2
        h = history_mixed(q, pc.interior.y);
#elif HISTORY == 1
        h = history_catmull(q);
#else
        h = history_bilinear(q);
#endif
        use = finite3(h);
    }
    cycling = cycling && use;

    // A pixel without history is this frame alone: with F_ADAPTIVE, its reconstruction at the
    // pixel centre rather than one jittered point sample.
    vec3 result = has(F_ADAPTIVE) ? cf : c0;
    // Frames the output holds: 1 (this one) unless a history is blended in.
    uint count = 1u;
    if (use) {
        count = min(((g.x >> COUNT_SHIFT) & COUNT_MAX) + 1u, COUNT_MAX);
#if MODE == 0
        // Still pixels (this one and its history texel did not move) keep their history
        // unclipped: the jitter alone changes their 3x3, and clipping towards a box that moves
        // with the jitter phase is not a contraction, so a static scene never settled (tens of
        // fp16 ulps of flicker after hundreds of frames; tests/stability.rs, drift). Without it
        // the history is the running average of the jittered samples and converges.
        if (has(F_CLIP) && !still) {
            // Variance box (mean +- gamma sigma) of the finite neighbours in perceptual YCoCg.
            vec3 m1 = vec3(0.0), m2 = vec3(0.0);
            for (int k = 0; k < 9; k++) {
                m1 += yk[k];
                m2 += yk[k] * yk[k];
            }
            vec3 mu = m1 / 9.0;
            vec3 sigma = sqrt(max(m2 / 9.0 - mu * mu, vec3(0.0)));
            // A history inside the box is kept bit for bit (the round trip through the
            // perceptual space is not exact).
            vec3 yp = to_p(h);
            vec3 box_lo = mu - pc.params.y * sigma, box_hi = mu + pc.params.y * sigma;
            if (any(lessThan(yp, box_lo)) || any(greaterThan(yp, box_hi)))
                h = from_p(mix(clip_towards(mu, yp, box_lo, box_hi), yp, lock_hold));
        }
        if (has(F_MEAN)) {
            float w = 1.0 / float(pc.flags.y + 1u);
            result = mix(h, c0, w);
        } else {
            // Each reprojection resamples the history and softens it: the faster the pixel moves,
            // the more the current frame weighs (alpha rises linearly to speed.x at speed.y px).
            float a = pc.params.x;
            // F_INTERIOR (`motionlod`, or `interior` with `unjitter`): a moving pixel away from
            // edges was shaded at the pixel centre by the scene pass, so its current sample is the technique's own
            // and the history only softens it: its weight rises to 1, not to amax. Edges keep
            // amax: there the history is what anti-aliases them. An edge: the 3x3 shows another
            // object, or its depth is not one plane (`plane` above); so is a locked pixel. Its
            // sample is sharper than native's where the LOD bias stays (`unjitter:interior`), so its
            // lock keeps the history that averages it; with the bias shed (F_SHED, `motionlod`)
            // the sample is native's own, and only a lock on a history of an object the 3x3 does
            // not show (a sub-pixel feature this frame missed) keeps it. An interior's weight
            // reaches 1 at interior.x (`ispeed`), an edge's amax at `speed`.
            float amax = pc.speed_jitter.x;
            float ramp = pc.speed_jitter.y;
            if (has(F_INTERIOR)) {
                bool edge = !plane || (locked && (!seen || !has(F_SHED)));
                for (int k = 0; k < 9; k++) edge = edge || nid[k] != nid[4];
                if (!edge) {
                    amax = 1.0;
                    ramp = pc.interior.x;
                }
            }
            if (pc.speed_jitter.y > 0.0) a = mix(a, amax, min(length(v) / ramp, 1.0));
            // F_REACTIVE (FSR 2's reactive mask from the scene's own motion, as `taau`'s): a
            // turning object's shading changes every frame (its normals turn with it), however
            // slowly its pixel moves (near its axis), and its history only lags; its current
            // weight goes on to 1 by its turn (the demo's spinning torus; docs/post-aa.md). So
            // does a history that shows a turning object, whatever this pixel shows: where the
            // object has just uncovered the background the ID test keeps its history (the object
            // is in the 3x3), the clip towards a box that holds its colours too keeps some of
            // it, and the moving demo showed trails of the torus on the sky.
            if (has(F_REACTIVE)) {
                uint hid = g.x & HIST_ID_MASK;
                float turn = nid[4] < uint(turns.length()) ? turns[nid[4]] : 0.0;
                turn = max(turn, hid < uint(turns.length()) ? turns[hid] : 0.0);
                a = mix(a, 1.0, turn);
            }
            // A history of m frames (m + 1 = count) takes the current frame with weight at least
            // 1 / (m + 1): the running mean until the exponential window 1 / alpha is full, after
            // a reset and after every rejection (a disoccluded pixel converges as fast as a
            // fresh frame, instead of keeping its first sample at weight (1 - alpha)^k).
            if (has(F_COUNT)) a = max(a, 1.0 / float(count));
            // In a running mean of `count` frames this sample is 1 / count of the output: it is
            // reconstructed at the pixel centre in that proportion (a fresh pixel: the filtered
            // 3x3; a converged one: the jittered point sample that the accumulation box-filters).
            vec3 cc = has(F_ADAPTIVE) ? mix(c0, cf, 1.0 / float(count)) : c0;
            float wc = a, wh = 1.0 - a;
            if (has(F_LUMA)) {
                wc /= 1.0 + luma(cc * pc.params.w);
                wh /= 1.0 + luma(h * pc.params.w);
            }
            // h + (cc - h) t is h itself where cc = h; (wc cc + wh h) / (wc + wh) is not, and the
            // RGBA16F store kept the difference: specular's constant dark sky ended an f16 ulp
            // off its colour (FLIP 0.0023 there against native's 0).
            result = h + (cc - h) * (wc / (wc + wh));
        }
#else
        // INSIDE: rounded min-max (the 3x3 box averaged with the cross's), chroma shrunk around
        // the centre's, history clipped towards the clamped mean, unbiased-luminance feedback.
        vec3 mn = vec3(1e30), mx = vec3(-1e30), avg = vec3(0.0);
        vec3 mn5 = vec3(1e30), mx5 = vec3(-1e30), avg5 = vec3(0.0);
        for (int k = 0; k < 9; k++) {
            vec3 y = yk[k];
            mn = min(mn, y);
            mx = max(mx, y);
            avg += y;
            if (k == 1 || k == 3 || k == 4 || k == 5 || k == 7) {
                mn5 = min(mn5, y);
                mx5 = max(mx5, y);
                avg5 += y;
            }
        }
        mn = 0.5 * (mn + mn5);
        mx = 0.5 * (mx + mx5);
        avg = 0.5 * (avg / 9.0 + avg5 / 5.0);
        float ext = 0.125 * (mx.x - mn.x);
        mn.yz = y0.yz - ext;
        mx.yz = y0.yz + ext;
        avg.yz = y0.yz;
        vec3 yh = to_p(h);
        if (has(F_CLIP)) yh = clip_towards(clamp(avg, mn, mx), yh, mn, mx);
        float l0 = y0.x, l1 = yh.x;
        float diff = abs(l0 - l1) / max(l0, max(l1, 0.2));
        float wgt = (1.0 - diff) * (1.0 - diff);
        float feedback = mix(pc.feedback_still.x, pc.feedback_still.y, wgt);
        result = from_p(mix(y0, yh, feedback));
#endif
    }
    // The cycle's state (F_CYCLE): a moving pixel has none; a still pixel whose cycle did not go
    // on (reset, rejected, changed, its history texel moved) starts one with this sample; one
    // that goes on adds the sample to the cycle's mean and range. When the cycle is complete (L
    // samples, each jitter phase once) its mean is the output and the range the one later
    // samples are tested against; until the next is complete the output stays that mean. A
    // static still pixel therefore shows the mean of its L jittered samples, bit for bit the same
    // every frame (no flicker); a change the range test misses is gone within two cycles.
    vec4 cyc_out = vec4(0.0);
    vec4 rng_out = vec4(1.0, 0.0, 1.0, 0.0);
#if MODE == 0
    // F_CENTRED: a reset frame was rendered unjittered (the renderer's centred reset): it is no
    // phase of the cycle, which starts with the next frame.
    if (has(F_CYCLE) && !moving && !(has(F_RESET) && has(F_CENTRED))) {
        float l = y0.x;
        // The mean the last complete cycle left in the history, shown until the next one is.
        bool hold = cycling && complete;
        if (cycling && cyc.w > 0.0) {
            float k = cyc.w + 1.0;
            vec3 m = cyc.rgb + (c0 - cyc.rgb) / k;
            vec2 cur = vec2(min(rng.z, l), max(rng.w, l));
            if (k >= float(pc.flags.z)) {
                result = m;
                rng_out = vec4(cur, 1.0, 0.0);
            } else {
                if (hold) result = texelFetch(hist, ivec2(floor(q)), 0).rgb;
                cyc_out = vec4(m, k);
                rng_out = vec4(rng.xy, cur);
            }
        } else {
            // The first sample of a cycle; one that follows a complete cycle keeps its range.
            if (hold) result = texelFetch(hist, ivec2(floor(q)), 0).rgb;
            cyc_out = vec4(c0, 1.0);
            rng_out = vec4(hold ? rng.xy : vec2(1.0, 0.0), l, l);
        }
    }
    // A moving pixel has no cycle: its image keeps the lock's life (F_LOCK).
    if (moving) cyc_out = vec4(life, 0.0, 0.0, 0.0);
#endif
    imageStore(out_cycle, p, cyc_out);
    imageStore(out_range, p, rng_out);
    imageStore(out_hist, p, vec4(result, 1.0));
    uint gx = (nid[4] & HIST_ID_MASK) | (count << COUNT_SHIFT) | (moving ? MOVED : 0u);
    imageStore(out_geom, p, uvec4(gx, floatBitsToUint(geom_depth(p)), 0u, 0u));
}
