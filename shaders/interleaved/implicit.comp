#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved:MxN:implicit`: no split. Each pixel shades, at full resolution, the VPL subset of its
// own position (x mod M, y mod N) straight from the G-buffer: the estimates the split, shade and
// gather passes produce, without moving the G-buffer into sub-images (neighbouring pixels of a
// group read different subsets).
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
#define VPLS_ONLY
#include "../inc/shading.glsl"
#include "subsets.glsl"
#ifdef SEED
#include "seed_edges.glsl"
#endif

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= pc.size.x || q.y >= pc.size.y) return;
    vec4 p = texelFetch(g_position, q, 0);
    vec3 e = vec3(0.0);
    if (p.w > 0.0) {
        e = subset_irradiance(p.xyz, texelFetch(g_normal, q, 0).xyz, subset_of(q), pc.counts.x,
                              pc.params.x);
    }
    // Alpha: the seed's edge flag (2), as the gather writes it.
    float flags = 0.0;
#ifdef SEED
    if (seed_edge(q)) flags = 2.0;
#endif
    imageStore(irradiance, q, vec4(e, flags));
}
