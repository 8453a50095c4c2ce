#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.shade`: sub-image k = j M + i shades its texels with VPL subset k only, times M N
// (subsets.glsl): the irradiance estimate that the gather puts back at each pixel and the
// lighting pass filters; with DIRECT also point-light subset k, its diffuse term into the same
// estimate and its specular term into s_specular (the split normal's w is the specular exponent,
// written by the G-buffer pass). Texels without a surface (background, past the edge) get 0.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
#include "../inc/shading.glsl"
#include "subsets.glsl"

// Workgroup z is the sub-image k = j M + i, (x, y) its texel: the subset is known without a
// per-lane division of the mosaic position by the sub-image's size, which a CPU device runs as a
// scalar loop.
void main() {
    uint k = gl_WorkGroupID.z;
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    if (t.x >= pc.size.z || t.y >= pc.size.w) return;
    ivec2 s = ivec2(int(k) % TILE_M, int(k) / TILE_M) * pc.size.zw + t;
    uint w = word_of(s);
    vec4 p = s_position[w];
    vec3 e = vec3(0.0);
    vec3 spec = vec3(0.0);
    if (p.w > 0.0) {
        vec4 n = s_normal[w];
        e = subset_irradiance(p.xyz, n.xyz, k, pc.counts.x, pc.params.x);
#ifdef DIRECT
        subset_direct(e, spec, p.xyz, n.xyz, n.w, k, pc.counts.yzw);
#endif
    }
    s_irradiance[w] = vec4(e, 0.0);
#ifdef DIRECT
    s_specular[w] = vec4(spec, 0.0);
#endif
}
