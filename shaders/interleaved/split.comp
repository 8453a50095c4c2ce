#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.split`: the G-buffer's position and normal into the M x N sub-images. One invocation
// per M x N block of pixels (block (bx, by) of Ws x Hs): it reads the block's rows, contiguous on
// the screen, and writes pixel (bx M + i, by N + j) to split texel (i Ws + bx, j Hs + by), so the
// lanes of a group write contiguous texels of each sub-image. (One invocation per split texel
// reads pixels M apart, and the rest of each line it touches only much later.) Pixels past the
// screen's edge hold nothing (w = 0).
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    ivec2 b = ivec2(gl_GlobalInvocationID.xy);
    if (b.x >= pc.size.z || b.y >= pc.size.w) return;
    for (int j = 0; j < TILE_N; ++j) {
        for (int i = 0; i < TILE_M; ++i) {
            ivec2 q = b * ivec2(TILE_M, TILE_N) + ivec2(i, j);
            ivec2 s = ivec2(i, j) * pc.size.zw + b;
            bool on = q.x < pc.size.x && q.y < pc.size.y;
            imageStore(s_position, s, on ? texelFetch(g_position, q, 0) : vec4(0.0));
            imageStore(s_normal, s, on ? texelFetch(g_normal, q, 0) : vec4(0.0));
        }
    }
}
