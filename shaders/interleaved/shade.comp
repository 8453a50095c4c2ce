#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.shade`: sub-image k = j M + i shades its texels with VPL subset k only, times M N
// (subsets.glsl): the irradiance estimate that the gather puts back at each pixel and the
// lighting pass filters. Texels without a surface (background, past the edge) get 0.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
#define VPLS_ONLY
#include "../inc/shading.glsl"
#include "subsets.glsl"

void main() {
    ivec2 s = ivec2(gl_GlobalInvocationID.xy);
    if (s.x >= TILE_M * pc.size.z || s.y >= TILE_N * pc.size.w) return;
    uint w = word_of(s);
    vec4 p = s_position[w];
    vec3 e = vec3(0.0);
    if (p.w > 0.0) {
        uint k = subset_of(pixel_of(s));
        e = subset_irradiance(p.xyz, s_normal[w].xyz, k, pc.counts.x, pc.params.x);
    }
    s_irradiance[w] = vec4(e, 0.0);
}
