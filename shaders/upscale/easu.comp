#version 460
// FSR 1's EASU, edge-adaptive spatial upsampling (AMD; docs/upscale.md; CPU reference:
// crates/cbr-render/src/techniques/upscale/reference.rs), on the encoded colour (fsr1.glsl),
// linear HDR out. Per output pixel: the 12 low-resolution taps around the nearest 2x2 quad, a
// direction and an edge-ness from luma crosses around the quad's four texels, a Lanczos-2-like
// kernel rotated to that direction and stretched along the edge, the result clamped to the
// quad's range (no ringing). Depth, velocity and IDs as every upscale filter (geometry.glsl).
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform sampler2D low_color;
layout(set = 0, binding = BINDING_EASU, rgba16f) uniform writeonly image2D out_easu;

PUSH_CONSTANTS  // sizes: W, H, w, h; params: x exposure scale

#include "fsr1.glsl"
#include "geometry.glsl"

const float EASU_FLAT = 1.0 / 32768.0;  // below this squared gradient: no direction, use +x

// The taps, offsets from the quad's top-left texel f:
//     b c
//   e f g h
//   i j k l
//     n o
const ivec2 TAPS[12] = ivec2[](ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0), ivec2(0, 0),
                               ivec2(1, 0), ivec2(2, 0), ivec2(-1, 1), ivec2(0, 1),
                               ivec2(1, 1), ivec2(2, 1), ivec2(0, 2), ivec2(1, 2));

// |hi - lo| over the larger one-sided difference from c: 1 on a ramp or a step, less on a
// one-texel ridge or noise; 0 where flat.
float edgeness(float lo, float c, float hi) {
    float m = max(abs(hi - c), abs(c - lo));
    return m > 0.0 ? clamp(abs(hi - lo) / m, 0.0, 1.0) : 0.0;
}

// One "+" around a quad texel, weighted by its bilinear weight w.
void analyse(inout vec2 dir, inout float len, float w, float up, float left, float c,
             float right, float down) {
    float lx = edgeness(left, c, right);
    float ly = edgeness(up, c, down);
    dir.x += (right - left) * w;
    dir.y += (down - up) * w;
    len += (lx * lx + ly * ly) * w;
}

// Lanczos-2 as a polynomial of the squared distance: base (25/16)(2/5 x2 - 1)^2 - 9/16 times
// window (lob x2 - 1)^2.
float lanczos2_approx(float x2, float lob) {
    float wb = 0.4 * x2 - 1.0;
    float wa = lob * x2 - 1.0;
    return (25.0 / 16.0 * wb * wb - 9.0 / 16.0) * (wa * wa);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= pc.sizes.x || p.y >= pc.sizes.y) return;
    float exposure = pc.params.x;
    vec2 scale = vec2(pc.sizes.zw) / vec2(pc.sizes.xy);
    vec2 pp = (vec2(p) + 0.5) * scale - 0.5;  // low-resolution texels, centres at integers
    vec2 fp = floor(pp);
    vec2 f = pp - fp;
    ivec2 base = ivec2(fp);

    // 1. The taps, encoded, and their lumas.
    vec3 c[12];
    float l[12];
    for (int i = 0; i < 12; i++) {
        ivec2 t = clamp(base + TAPS[i], ivec2(0), pc.sizes.zw - 1);
        c[i] = fsr_encode(texelFetch(low_color, t, 0).rgb, exposure);
        l[i] = fsr_luma(c[i]);
    }

    // 2. Direction and edge-ness from the crosses around f, g, j, k.
    vec2 dir = vec2(0.0);
    float len = 0.0;
    analyse(dir, len, (1.0 - f.x) * (1.0 - f.y), l[0], l[2], l[3], l[4], l[7]);
    analyse(dir, len, f.x * (1.0 - f.y), l[1], l[3], l[4], l[5], l[8]);
    analyse(dir, len, (1.0 - f.x) * f.y, l[3], l[6], l[7], l[8], l[10]);
    analyse(dir, len, f.x * f.y, l[4], l[7], l[8], l[9], l[11]);
    float d2 = dir.x * dir.x + dir.y * dir.y;
    dir = d2 < EASU_FLAT ? vec2(1.0, 0.0) : dir * (1.0 / sqrt(d2));
    len = 0.5 * len;
    len = len * len;

    // 3. The kernel's shape: across the gradient up to 1/max(|cos|, |sin|) narrower, along
    // the edge up to 2x wider, its negative lobe weaker on edges.
    float stretch = 1.0 / max(abs(dir.x), abs(dir.y));
    vec2 len2 = vec2(1.0 + (stretch - 1.0) * len, 1.0 - 0.5 * len);
    float lob = 0.5 - 0.29 * len;
    float clp = 1.0 / lob;

    // 4. The weighted taps, clamped to the quad's range.
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
    for (int i = 0; i < 12; i++) {
        vec2 off = vec2(TAPS[i]) - f;
        float vx = (off.x * dir.x + off.y * dir.y) * len2.x;
        float vy = (off.y * dir.x - off.x * dir.y) * len2.y;
        float w = lanczos2_approx(min(vx * vx + vy * vy, clp), lob);
        acc += c[i] * w;
        wsum += w;
    }
    vec3 lo = min(min(c[3], c[4]), min(c[7], c[8]));
    vec3 hi = max(max(c[3], c[4]), max(c[7], c[8]));
    vec3 e = clamp(acc / wsum, lo, hi);
    imageStore(out_easu, p, vec4(fsr_decode(e, exposure), 1.0));
    write_geometry(p, scale);
}
