#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.split`: the G-buffer's position and normal into the M x N sub-images (a gather: each
// split texel reads its pixel). Texels past the screen's edge hold nothing (w = 0).
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    ivec2 s = ivec2(gl_GlobalInvocationID.xy);
    if (s.x >= TILE_M * pc.size.z || s.y >= TILE_N * pc.size.w) return;
    ivec2 q = pixel_of(s);
    bool on = q.x < pc.size.x && q.y < pc.size.y;
    imageStore(s_position, s, on ? texelFetch(g_position, q, 0) : vec4(0.0));
    imageStore(s_normal, s, on ? texelFetch(g_normal, q, 0) : vec4(0.0));
}
