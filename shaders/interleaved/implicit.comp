#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved:MxN:implicit`: no split. Each pixel shades, at full resolution, the VPL subset of its
// own position (x mod M, y mod N) straight from the G-buffer: the estimates the split, shade and
// gather passes produce, without moving the G-buffer into sub-images (neighbouring pixels of a
// group read different subsets). With DIRECT, the point-light subset too (shade.comp).
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
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
    vec3 spec = vec3(0.0);
    if (p.w > 0.0) {
        vec4 n = texelFetch(g_normal, q, 0);
        e = subset_irradiance(p.xyz, n.xyz, subset_of(q), pc.counts.x, pc.params.x);
#ifdef DIRECT
        subset_direct(e, spec, p.xyz, n.xyz, n.w, subset_of(q), pc.counts.yzw);
#endif
    }
    // Alpha: the seed's edge flag (2), as the gather writes it.
    float flags = 0.0;
#ifdef SEED
    if (seed_edge(q)) flags = 2.0;
#endif
    imageStore(irradiance, q, vec4(e, flags));
#ifdef DIRECT
    imageStore(specular, q, vec4(spec, 0.0));
#endif
}
