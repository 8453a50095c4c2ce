#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.gather`: the sub-images' estimates back to their pixels (the inverse of the split).
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= pc.size.x || q.y >= pc.size.y) return;
    imageStore(irradiance, q, imageLoad(s_irradiance, split_of(q)));
}
