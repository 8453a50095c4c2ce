#version 460
// `+fxaa`: FXAA 3.11 quality (Lottes 2011), presets 12, 29, 39 as step tables in the push
// constants. Luma in display space (exposure, Narkowicz ACES fit, sRGB OETF, Rec. 601 weights);
// the blend mixes linear HDR colour. Filtered taps are bilinear by hand from texel fetches with
// clamp-to-edge addressing, so the CPU reference (crates/cbr-render/src/post/fxaa.rs) matches it
// within float rounding; the steps below follow it one for one.
// Display luma comes from the first pass (fxaa_luma.comp), read once per tap.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_SRC) uniform sampler2D src;
layout(set = 0, binding = BINDING_OUT, rgba16f) uniform writeonly image2D dst;
layout(set = 0, binding = BINDING_LUMA) uniform sampler2D luma_in;
// size_steps: W, H, number of steps, 0; params: edge threshold, minimum edge threshold,
// sub-pixel quality, 2^exposure; steps[MAX_STEPS]
PUSH_CONSTANTS

vec4 texel(ivec2 p) {
    return texelFetch(src, clamp(p, ivec2(0), pc.size_steps.xy - 1), 0);
}

float luma_texel(ivec2 p) {
    return texelFetch(luma_in, clamp(p, ivec2(0), pc.size_steps.xy - 1), 0).r;
}

// Bilinear at `pos` (texel units, centres at +0.5).
float luma_at(vec2 pos) {
    vec2 q = pos - 0.5;
    vec2 q0 = floor(q);
    vec2 f = q - q0;
    ivec2 i = ivec2(q0);
    float a = luma_texel(i), b = luma_texel(i + ivec2(1, 0));
    float c = luma_texel(i + ivec2(0, 1)), d = luma_texel(i + ivec2(1, 1));
    float top = a + (b - a) * f.x;
    float bottom = c + (d - c) * f.x;
    return top + (bottom - top) * f.y;
}

vec4 rgba_at(vec2 pos) {
    vec2 q = pos - 0.5;
    vec2 q0 = floor(q);
    vec2 f = q - q0;
    ivec2 i = ivec2(q0);
    vec4 a = texel(i), b = texel(i + ivec2(1, 0)), c = texel(i + ivec2(0, 1)), d = texel(i + ivec2(1, 1));
    vec4 top = a + (b - a) * f.x;
    vec4 bottom = c + (d - c) * f.x;
    return top + (bottom - top) * f.y;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size_steps.xy))) return;
    vec4 m = texel(p);
    vec2 pos_m = vec2(p) + 0.5;
    float luma_m = luma_texel(p);
    float luma_n = luma_texel(p + ivec2(0, -1)), luma_s = luma_texel(p + ivec2(0, 1));
    float luma_w = luma_texel(p + ivec2(-1, 0)), luma_e = luma_texel(p + ivec2(1, 0));

    // 1. Local contrast: skip pixels without an edge.
    float range_max = max(max(max(max(luma_m, luma_n), luma_s), luma_w), luma_e);
    float range_min = min(min(min(min(luma_m, luma_n), luma_s), luma_w), luma_e);
    float range = range_max - range_min;
    if (range < max(pc.params.y, range_max * pc.params.x)) {
        imageStore(dst, p, m);
        return;
    }

    // 2. Edge orientation from second differences over the 3x3 neighbourhood.
    float luma_nw = luma_texel(p + ivec2(-1, -1)), luma_ne = luma_texel(p + ivec2(1, -1));
    float luma_sw = luma_texel(p + ivec2(-1, 1)), luma_se = luma_texel(p + ivec2(1, 1));
    float edge_horz = abs(-2.0 * luma_w + luma_nw + luma_sw)
        + 2.0 * abs(-2.0 * luma_m + luma_n + luma_s)
        + abs(-2.0 * luma_e + luma_ne + luma_se);
    float edge_vert = abs(-2.0 * luma_s + luma_sw + luma_se)
        + 2.0 * abs(-2.0 * luma_m + luma_w + luma_e)
        + abs(-2.0 * luma_n + luma_nw + luma_ne);
    bool horz_span = edge_horz >= edge_vert;

    // 3. Sub-pixel aliasing: the 3x3 low-pass against the centre, relative to the range.
    float subpix_a = 2.0 * (luma_n + luma_s + luma_w + luma_e) + (luma_nw + luma_ne + luma_sw + luma_se);
    float subpix_c = clamp(abs(subpix_a / 12.0 - luma_m) / range, 0.0, 1.0);
    float subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    float subpix_h = subpix_f * subpix_f * pc.params.z;
    if (!horz_span) {
        luma_n = luma_w;
        luma_s = luma_e;
    }

    // 4. The side of the edge: the neighbour pair with the steeper gradient.
    float gradient_n = luma_n - luma_m, gradient_s = luma_s - luma_m;
    bool pair_n = abs(gradient_n) >= abs(gradient_s);
    float gradient = max(abs(gradient_n), abs(gradient_s));
    float length_sign = pair_n ? -1.0 : 1.0;
    float luma_nn = pair_n ? luma_n + luma_m : luma_s + luma_m;

    // 5. Search along the edge both ways, half a pixel towards that side.
    int axis = horz_span ? 0 : 1;
    int perp = 1 - axis;
    vec2 pos_b = pos_m;
    pos_b[perp] += 0.5 * length_sign;
    vec2 pos_n = pos_b, pos_p = pos_b;
    pos_n[axis] -= pc.steps[0];
    pos_p[axis] += pc.steps[0];
    float gradient_scaled = gradient * 0.25;
    float luma_mm = luma_m - luma_nn * 0.5;
    float end_n = luma_at(pos_n) - luma_nn * 0.5;
    float end_p = luma_at(pos_p) - luma_nn * 0.5;
    bool done_n = abs(end_n) >= gradient_scaled;
    bool done_p = abs(end_p) >= gradient_scaled;
    // FXAA 3.11's nesting: after evaluating at step k, each unfinished end moves by step k + 1;
    // the last move is not evaluated.
    int n = pc.size_steps.z;
    for (int k = 1; k < n; k++) {
        if (!done_n) pos_n[axis] -= pc.steps[k];
        if (!done_p) pos_p[axis] += pc.steps[k];
        if ((done_n && done_p) || k + 1 == n) break;
        if (!done_n) {
            end_n = luma_at(pos_n) - luma_nn * 0.5;
            done_n = abs(end_n) >= gradient_scaled;
        }
        if (!done_p) {
            end_p = luma_at(pos_p) - luma_nn * 0.5;
            done_p = abs(end_p) >= gradient_scaled;
        }
    }

    // 6. The nearer end decides; its luma must cross the centre's for the span to be good.
    float dst_n = pos_m[axis] - pos_n[axis];
    float dst_p = pos_p[axis] - pos_m[axis];
    bool m_lt_zero = luma_mm < 0.0;
    bool good_span = dst_n < dst_p ? (end_n < 0.0) != m_lt_zero : (end_p < 0.0) != m_lt_zero;
    float pixel_offset = -min(dst_n, dst_p) / (dst_n + dst_p) + 0.5;
    float offset = max(good_span ? pixel_offset : 0.0, subpix_h);
    vec2 pos = pos_m;
    pos[perp] += offset * length_sign;
    vec4 o = rgba_at(pos);
    imageStore(dst, p, vec4(o.rgb, m.a));
}
