#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.gather`: the sub-images' estimates back to their pixels (the inverse of the split).
// With DEBUG the alpha channel says whether the split G-buffer gathered back the same way differs
// from the G-buffer (position and normal, bit for bit): gather(split(x)) == x at every pixel.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= pc.size.x || q.y >= pc.size.y) return;
    vec4 e = imageLoad(s_irradiance, split_of(q));
#ifdef DEBUG
    bool same = all(equal(floatBitsToUint(imageLoad(s_position, split_of(q))),
                          floatBitsToUint(texelFetch(g_position, q, 0)))) &&
                all(equal(floatBitsToUint(imageLoad(s_normal, split_of(q))),
                          floatBitsToUint(texelFetch(g_normal, q, 0))));
    e.a = same ? 0.0 : 1.0;
#endif
    imageStore(irradiance, q, e);
}
