#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.split`: the G-buffer's position and normal into the M x N sub-images (a scatter:
// each pixel of the screen padded to the mosaic's size, M Ws x N Hs, writes its split texel; the
// padding's texels, past the screen's edge, hold nothing: w = 0). One invocation per pixel rather
// than per split texel: the pixel's split texel divides by the constants M and N, where a texel's
// pixel divides by the sub-image's size, a per-lane integer division on a CPU device.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= TILE_M * pc.size.z || q.y >= TILE_N * pc.size.w) return;
    uint s = word_of(split_of(q));
    bool on = q.x < pc.size.x && q.y < pc.size.y;
    s_position[s] = on ? texelFetch(g_position, q, 0) : vec4(0.0);
    s_normal[s] = on ? texelFetch(g_normal, q, 0) : vec4(0.0);
}
