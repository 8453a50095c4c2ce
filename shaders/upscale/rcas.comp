#version 460
// FSR 1's RCAS, robust contrast-adaptive sharpening (AMD; docs/upscale.md; CPU reference:
// crates/cbr-render/src/techniques/upscale/reference.rs) of EASU's output, on the encoded
// colour (fsr1.glsl), linear HDR out. A 5-tap cross b (up), d (left), e, f (right), h (down):
// out = (e + lobe (b + d + f + h)) / (1 + 4 lobe), the lobe (negative) the largest that keeps
// each channel inside [0, 1] given the cross's minimum and maximum (centre included), capped at
// 1/4 - 1/16, times 2^-sharpness. Edges clamp. No denoise variant.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_RCAS_IN) uniform sampler2D rcas_in;  // EASU's output, taau's accumulation
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;

PUSH_CONSTANTS  // sizes: W, H, w, h; params: x exposure scale, y 2^-sharpness

#include "fsr1.glsl"

const float RCAS_LIMIT = 0.25 - 1.0 / 16.0;
const float RCAS_EPS = 1.0 / 65536.0;  // guards the limits' divisions

vec3 at(ivec2 q) {
    q = clamp(q, ivec2(0), pc.sizes.xy - 1);
    return fsr_encode(texelFetch(rcas_in, q, 0).rgb, pc.params.x);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= pc.sizes.x || p.y >= pc.sizes.y) return;
    vec3 b = at(p + ivec2(0, -1));
    vec3 d = at(p + ivec2(-1, 0));
    vec3 e = at(p);
    vec3 f = at(p + ivec2(1, 0));
    vec3 h = at(p + ivec2(0, 1));
    vec3 mn4 = min(min(b, d), min(f, h));
    vec3 mx4 = max(max(b, d), max(f, h));
    // The lobe at which a channel would reach 0, and the one at which it would reach 1.
    vec3 hit_min = min(mn4, e) / max(4.0 * mx4, vec3(RCAS_EPS));
    vec3 hit_max = (1.0 - max(mx4, e)) / min(4.0 * mn4 - 4.0, vec3(-RCAS_EPS));
    vec3 lobes = max(-hit_min, hit_max);
    float lobe = max(-RCAS_LIMIT, min(fsr_max3(lobes), 0.0)) * pc.params.y;
    vec3 o = (lobe * (b + d + f + h) + e) / (4.0 * lobe + 1.0);
    imageStore(out_color, p, vec4(fsr_decode(o, pc.params.x), 1.0));
}
