#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.split`: the G-buffer's position and normal into the M x N sub-images. Invocation
// (t, y), y over the screen's rows padded to N Hs: pixels (t M + i, y), i = 0 .. M-1, to texel t of
// row y / N of sub-images (i, y mod N). A SIMD group's lanes then write consecutive texels of one
// sub-image row per step, and no lane divides by the sub-image's size (constant divisors only: a
// per-lane integer division is a scalar loop on a CPU device). Texels of pixels past the screen's
// edge hold nothing (w = 0).
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    int t = int(gl_GlobalInvocationID.x);
    int y = int(gl_GlobalInvocationID.y);
    if (t >= pc.size.z || y >= TILE_N * pc.size.w) return;
    for (int i = 0; i < TILE_M; ++i) {
        ivec2 q = ivec2(t * TILE_M + i, y);
        bool on = q.x < pc.size.x && q.y < pc.size.y;
        uint w = row_word(t, y, i);
        s_position[w] = on ? texelFetch(g_position, q, 0) : vec4(0.0);
        s_normal[w] = on ? texelFetch(g_normal, q, 0) : vec4(0.0);
    }
}
