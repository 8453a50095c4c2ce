#version 460
// The `upscale` baseline: a frame rendered at SCALE W x SCALE H (default SCALE 1/sqrt(2): the
// checkerboard's pixel count) brought to W x H. FILTER 0: bilinear; 1: bicubic (Catmull-Rom,
// 4x4 taps, negative lobes' undershoot clamped at 0). Depth, velocity and IDs take the nearest
// low-resolution sample, velocity rescaled (geometry.glsl). Taps clamp to the image edge.
// FSR 1 (`upscale:fsr1`) is easu.comp then rcas.comp.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform sampler2D low_color;
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;

PUSH_CONSTANTS  // sizes: W, H, w, h (params: FSR 1's)

#include "geometry.glsl"

vec3 texel(ivec2 t) {
    ivec2 lo = pc.sizes.zw;
    return texelFetch(low_color, clamp(t, ivec2(0), lo - 1), 0).rgb;
}

// Catmull-Rom weights for fractional position f.
vec4 catmull_rom(float f) {
    float f2 = f * f;
    float f3 = f2 * f;
    return vec4(-0.5 * f3 + f2 - 0.5 * f,
                1.5 * f3 - 2.5 * f2 + 1.0,
                -1.5 * f3 + 2.0 * f2 + 0.5 * f,
                0.5 * f3 - 0.5 * f2);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= pc.sizes.x || p.y >= pc.sizes.y) return;
    vec2 scale = vec2(pc.sizes.zw) / vec2(pc.sizes.xy);
    vec2 q = (vec2(p) + 0.5) * scale;  // in low-resolution pixels
    vec2 g = q - 0.5;
    ivec2 b = ivec2(floor(g));
    vec2 f = g - floor(g);
    vec3 c;
#if FILTER == 0
    c = mix(mix(texel(b), texel(b + ivec2(1, 0)), f.x),
            mix(texel(b + ivec2(0, 1)), texel(b + ivec2(1, 1)), f.x), f.y);
#else
    vec4 wx = catmull_rom(f.x);
    vec4 wy = catmull_rom(f.y);
    c = vec3(0.0);
    for (int j = 0; j < 4; j++) {
        vec3 row = vec3(0.0);
        for (int i = 0; i < 4; i++) row += wx[i] * texel(b + ivec2(i - 1, j - 1));
        c += wy[j] * row;
    }
    c = max(c, vec3(0.0));
#endif
    imageStore(out_color, p, vec4(c, 1.0));
    write_geometry(p, scale);
}
