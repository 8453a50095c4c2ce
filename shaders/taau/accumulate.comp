#version 460
#extension GL_GOOGLE_include_directive : require
// taau pass 4 (FSR 2's "reproject and accumulate"; docs/upsampling.md; CPU reference
// `accumulate`), one output pixel per invocation, in the perceptual space (inc/perceptual.glsl):
//
// 1. The current frame at the output pixel's centre: the 3x3 render samples around it, each at
//    its unjittered position i + 1/2 - jitter, weighted by the kernel at the distance times the
//    kernel bias (Lanczos-2 and Catmull-Rom: the ratio W / w capped at 1.99, so the kernel spans
//    about 2 output pixels; falling to 1, the widest, where the history is dropped and as the
//    pixel's speed nears the moving cap's), clamped to
//    the samples' range (deringing). The sample weight is the kernel's weight of the nearest
//    sample: 1 on the pixel centre, less farther off.
// 2. The history at p + 1/2 - velocity (the dilated velocity of the render pixel under p, scaled
//    to output pixels), 6x6 separable Lanczos-3 (HISTORY_LOBES 3; 4x4 Lanczos-2 with 2, as FSR
//    2), 4x4 Catmull-Rom or 2x2 bilinear, deringed by its 2x2; its weight and the lock from the
//    nearest of that 2x2. Dropped on reset, off screen, in proportion to the disocclusion (the
//    depth clip), or where it is another object moving differently (the object test, below).
// 3. Locks: a lock decays by 1 / phases per frame, is renewed where the lock pass found a thin
//    feature this frame, and dies with a disocclusion over 1/2.
// 4. Rectification, unless the pixel is still (no motion, no disocclusion, not the background
//    of a turning camera; then the history is
//    the running mean of the jittered samples and converges): the history clipped towards the
//    mean into mean +- gamma sigma of the 3x3 samples, each weighted exp(-2.3 d^2) by its
//    distance d (render pixels) from the output pixel (FSR 2's rectification box), then mixed back towards the unclipped
//    history by the lock's strength.
// 5. Luminance stability: where the current luma's change reverses the previous frame's
//    (oscillation), the sample weight drops by half of min / max of the two changes.
// 6. Accumulation: history weight capped at mix(accum still, accum moving, min(speed / SPEED,
//    1)) (1 - turn), turn the pixel's object's own rotation (REACTIVE); out = (H h + w c) /
//    (H + w); the weight stored is H + w.
// NaN and Inf never enter the history: non-finite samples take no part, a non-finite history is
// dropped.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_PREPARED) uniform sampler2D prepared;
layout(set = 0, binding = BINDING_DILATED) uniform sampler2D dilated;
#ifdef BINDING_DISOCCLUSION
layout(set = 0, binding = BINDING_DISOCCLUSION) uniform sampler2D disocclusion;
#endif
#ifdef BINDING_NEW_LOCKS
layout(set = 0, binding = BINDING_NEW_LOCKS) readonly buffer Locks { uint new_locks[]; };
#endif
#if REACTIVE
// Each object's turn this frame, by object ID (TaauPasses::set_turns).
layout(set = 0, binding = BINDING_TURNS) readonly buffer Turns { float turns[]; };
#endif
layout(set = 0, binding = BINDING_HIST) uniform sampler2D hist;
layout(set = 0, binding = BINDING_HIST_AUX) uniform sampler2D hist_aux;
layout(set = 0, binding = BINDING_OUT_HIST, rgba32f) uniform writeonly image2D out_hist;
layout(set = 0, binding = BINDING_OUT_AUX, rgba32f) uniform writeonly image2D out_aux;
layout(set = 0, binding = BINDING_ACCUMULATED, rgba16f) uniform writeonly image2D accumulated;
#ifdef BINDING_DEBUG
layout(set = 0, binding = BINDING_DEBUG, rgba32f) uniform writeonly image2D debug;
#endif

#include "common.glsl"
#include "../inc/perceptual.glsl"
#include "../upscale/geometry.glsl"

// The kernel at squared distance x2 (already scaled): KERNEL 0 tent (radius 1), 1 Catmull-Rom,
// 2 Lanczos-2, sinc(x) sinc(x / 2), as a degree-9 polynomial in u = x2 / 2 - 1 (a Chebyshev fit
// on [0, 4], within 5e-7 of the sines in f32; the reference's `lanczos2_poly`). The sines cost
// 15-20% of this pass on lavapipe. (FSR 2's own polynomial is off by up to 0.049: on the
// moving demo it raised FLIP by 2.4%; docs/upsampling.md.)
float kernel_weight_sq(float x2) {
#if KERNEL == 0
    return max(1.0 - sqrt(x2), 0.0);
#elif KERNEL == 1
    float x = sqrt(x2);
    if (x < 1.0) return (1.5 * x - 2.5) * x2 + 1.0;
    if (x < 2.0) return ((-0.5 * x + 2.5) * x - 4.0) * x + 2.0;
    return 0.0;
#else
    if (x2 >= 4.0) return 0.0;
    float u = 0.5 * x2 - 1.0;
    float r = -0.00023376644821837544;
    r = r * u + 0.0018180252518504858;
    r = r * u - 0.010657694190740585;
    r = r * u + 0.0487825907766819;
    r = r * u - 0.1603366583585739;
    r = r * u + 0.3473505973815918;
    r = r * u - 0.4245021343231201;
    r = r * u + 0.1797589808702469;
    r = r * u + 0.0957302525639534;
    return r * u - 0.0777103453874588;
#endif
}

const float STILL = 1.0 / 64.0;
// The history aux's w: this pixel's nearest sample's object ID (modulo 2^18) << SPEED_BITS |
// its own speed in SPEED_STEP output pixels a frame (up to SPEED_MAX), an integer exact in f32.
const uint SPEED_BITS = 6u, SPEED_MASK = 63u, ID_MASK = 0x3ffffu;
const float SPEED_STEP = 0.25, SPEED_MAX = 15.75;
const float BOX_CURVE = 2.3;

// The history's kernel: Lanczos-3 (inc/lanczos3.glsl) keeps more detail than FSR 2's Lanczos-2
// (the moving demo 1.044x -> 1.021x `native`'s FLIP; `lobes=2` is FSR 2's; docs/upsampling.md).
#include "../inc/lanczos3.glsl"

vec4 hist_texel(ivec2 t) { return texelFetch(hist, clamp(t, ivec2(0), pc.sizes.xy - 1), 0); }

// The history at continuous output position b + 1/2 + f (b the texel below and left of it, f
// in [0, 1)): its colour (deringed by its 2x2), and in w the weight of the texel `nearest`, one
// of the inner 2x2, from one pass over the taps.
vec4 history_at(ivec2 b, vec2 f, ivec2 nearest) {
    vec3 mn = vec3(1e30), mx = vec3(-1e30);
    float hw = 0.0;
#if KERNEL == 0
    const int LO = 0, HI = 1;
    vec2 wx = vec2(1.0 - f.x, f.x), wy = vec2(1.0 - f.y, f.y);
#elif KERNEL == 2 && HISTORY_LOBES == 3
    const int LO = -2, HI = 3;
    float wx[6], wy[6];
    lanczos3_weights(f.x, wx);
    lanczos3_weights(f.y, wy);
#else
    const int LO = -1, HI = 2;
    float wx[4], wy[4];
    for (int k = 0; k < 4; k++) {
        float dx = float(k - 1) - f.x, dy = float(k - 1) - f.y;
        wx[k] = kernel_weight_sq(dx * dx);
        wy[k] = kernel_weight_sq(dy * dy);
    }
#endif
    vec3 acc = vec3(0.0);
    float ws = 0.0;
    for (int y = LO; y <= HI; y++) {
        for (int x = LO; x <= HI; x++) {
            ivec2 o = ivec2(x, y);
            vec4 t = hist_texel(b + o);
            float w = wx[x - LO] * wy[y - LO];
            acc += w * t.rgb;
            ws += w;
            if (x >= 0 && x <= 1 && y >= 0 && y <= 1) {
                mn = min(mn, t.rgb);
                mx = max(mx, t.rgb);
                if (b + o == nearest) hw = t.w;
            }
        }
    }
    return vec4(clamp(acc / ws, mn, mx), hw);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 out_size = pc.sizes.xy, size = pc.sizes.zw;
    if (!inside(p, out_size)) return;
    vec2 ratio = pc.jitter_ratio.zw, jit = pc.jitter_ratio.xy;
    float e = pc.params.x;
    vec2 src = (vec2(p) + 0.5) / ratio;
    ivec2 under = clamp(ivec2(floor(src)), ivec2(0), size - 1);
    vec4 g = texelFetch(dilated, under, 0);
    vec2 v = g.xy * ratio;
    float speed = length(v);
    // How far the pixel is towards SPEED (accum.z): the history's cap and the kernel follow it.
    float moving = min(speed / pc.accum.z, 1.0);
#ifdef BINDING_DISOCCLUSION
    float dis = texelFetch(disocclusion, under, 0).r;
#else
    float dis = 0.0;
#endif

    // 2. The history (step 1 needs to know whether there is one).
    vec2 q = vec2(p) + 0.5 - v;
    bool use = (pc.flags.x & F_RESET) == 0u && all(greaterThanEqual(q, vec2(0.0))) &&
               all(lessThan(q, vec2(out_size)));
    vec3 h = vec3(0.0);
    float hw = 0.0;
    vec4 aux = vec4(0.0);
    if (use) {
        vec2 gq = q - 0.5;
        ivec2 b = ivec2(floor(gq));
        vec2 f = gq - vec2(b);
        ivec2 nearest = b + ivec2(step(vec2(0.5), f));
        vec4 hc = history_at(b, f, nearest);
        h = hc.rgb;
        hw = hc.w;
        aux = texelFetch(hist_aux, clamp(nearest, ivec2(0), out_size - 1), 0);
        use = finite3(h) && finite3(aux.xyz) && !isnan(hw) && !isinf(hw);
    }
    // The object test (OBJECT_TEST; `without-ids` leaves it out): a history texel of another
    // object than this pixel's nearest sample, moving at least SPEED (accum.z) output pixels a
    // frame faster or slower than that sample's own velocity, is a disocclusion. FSR 2's depth
    // clip sees only the surfaces this frame shows: a torus that spun its face away leaves
    // nothing in the reconstructed depth, and its colour stayed on the wall or sky behind it
    // under the box (a brick wall's is wide) and the locks. The ID alone is the checkerboard
    // resolve's and `+taa`'s test; the speed keeps a sub-pixel wire that this frame's jitter
    // missed (its history moves as the sky around it does) (docs/upsampling.md).
    ivec2 c0 = clamp(ivec2(floor(src + jit)), ivec2(0), size - 1);
    uint raw_id = texelFetch(low_ids, c0, 0).x;
    uint own_id = raw_id & ID_MASK;
    float own_speed = min(length(texelFetch(low_velocity, c0, 0).xy * ratio), SPEED_MAX);
#if OBJECT_TEST
    if (use) {
        uint code = uint(aux.w);
        if ((code >> SPEED_BITS) != own_id &&
            abs(float(code & SPEED_MASK) * SPEED_STEP - own_speed) >= pc.accum.z)
            dis = 1.0;
    }
#endif
    float keep = use ? 1.0 - dis : 0.0;

    // 1. The current frame at the pixel centre. The kernel narrows (bias up to params.w) only as
    // far as a long history will average what it aliases: where the history is dropped, and as
    // the pixel's speed nears accum.z (SPEED, the moving cap's: the history holds a frame or two),
    // it widens back to 1, the render grid's own Lanczos (the moving demo 1.094x -> 1.054x
    // `native`'s FLIP; docs/upsampling.md).
#if KERNEL == 0
    float bias = 1.0;
#else
    float bias = mix(1.0, pc.params.w, keep * (1.0 - moving));
#endif
    vec3 acc = vec3(0.0), m1 = vec3(0.0), m2 = vec3(0.0);
    vec3 mn = vec3(1e30), mx = vec3(-1e30);
    float wsum = 0.0, count = 0.0, ws = 0.0;
    vec3 nearest = vec3(0.0);
    for (int k = 0; k < 9; k++) {
        ivec2 t = c0 + OFF[k];
        if (!inside(t, size)) continue;
        vec4 pre = texelFetch(prepared, t, 0);
        if (pre.w == 0.0) continue;
        vec3 y = pre.xyz;
        vec2 d = vec2(t) + 0.5 - jit - src;
#if KERNEL == 0
        float w = max(1.0 - abs(d.x), 0.0) * max(1.0 - abs(d.y), 0.0);
#else
        float w = kernel_weight_sq(dot(d, d) * bias * bias);
#endif
        acc += w * y;
        wsum += w;
        // The rectification box's moments, each sample weighted by its distance (FSR 2's
        // exp(-2.3 d^2), d in render pixels): the box is the output pixel's, not the 3x3's.
        float b = exp(-BOX_CURVE * dot(d, d));
        m1 += b * y;
        m2 += b * y * y;
        mn = min(mn, y);
        mx = max(mx, y);
        count += b;
        if (k == 4) {
            ws = max(w, 0.0);
            nearest = y;
        }
    }
    vec3 cur = wsum > 1e-4 ? clamp(acc / wsum, mn, mx) : nearest;

    // 3. Locks.
    float life = use ? max(aux.x - pc.accum.w, 0.0) : 0.0;
#ifdef BINDING_NEW_LOCKS
    if (new_locks[p.y * out_size.x + p.x] != 0u) life = 1.0;
    if (dis > 0.5) life = 0.0;
#else
    life = 0.0;
#endif

    float change = 0.0;
    vec3 result = cur;
    float weight = ws;
    if (use) {
        // 4. Rectification.
        // The background (its 3x3 all of it: dilated depth 0) has no velocity written; when the
        // camera turned (F_BACKGROUND) it moved, and its history is rectified too (a torus that
        // spun off the sky left its colour there, and the sky's 3x3 never showed it).
        bool still = speed <= STILL && dis == 0.0 &&
                     !((pc.flags.x & F_BACKGROUND) != 0u && g.z == 0.0);
        if (!still && count > 0.0) {
            vec3 mu = m1 / count;
            vec3 sigma = sqrt(max(m2 / count - mu * mu, vec3(0.0)));
            vec3 clipped = clip_towards(mu, h, mu - pc.params.z * sigma, mu + pc.params.z * sigma);
            h = mix(clipped, h, life);
        }
        // 5. Luminance stability.
        change = cur.x - aux.y;
#if STABILITY
        if (change * aux.z < 0.0) {
            float a = abs(change), b = abs(aux.z);
            ws *= 1.0 - 0.5 * min(a, b) / max(a, b);
        }
#endif
        // 6. Accumulation.
        // FSR 2's reactive mask, from the scene's own motion (REACTIVE): a turning object's
        // shading changes every frame (its normals turn with it), however slowly its pixel
        // moves (near its axis), and its history only lags: it keeps (1 - turn) of the cap
        // (the demo's spinning torus).
#if REACTIVE
        float turn = raw_id < uint(turns.length()) ? turns[raw_id] : 0.0;
#else
        float turn = 0.0;
#endif
        float cap = mix(pc.accum.x, pc.accum.y, moving) * (1.0 - turn);
        float hk = min(hw * keep, cap);
        float total = hk + ws;
        if (total > 0.0) result = (hk * h + ws * cur) / total;
        weight = total;
    }
    imageStore(out_hist, p, vec4(result, weight));
    uint remembered = (own_id << SPEED_BITS) | uint(own_speed / SPEED_STEP + 0.5);
    imageStore(out_aux, p, vec4(life, cur.x, change, float(remembered)));
    imageStore(accumulated, p, vec4(linear_from_perceptual(result, e), 1.0));
#ifdef BINDING_DEBUG
    imageStore(debug, p, vec4(dis, life, ws, weight));
#endif
    write_geometry(p, 1.0 / ratio);
}
