#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.fallback` (one invocation per pair: its subset's irradiance at its pixel, times
// M N) and, with FINISH, `interleaved.finish` (one per entry: the found sum plus its pairs in slot
// order, the mean, times albedo, onto its colour; NaN/Inf black and counted, as lighting.comp).
// fallback_list.glsl has the lists.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"

#ifndef FINISH
layout(set = 0, binding = BINDING_POSITION) uniform sampler2D g_position;
layout(set = 0, binding = BINDING_NORMAL) uniform sampler2D g_normal;
#else
layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_COUNTER) buffer Counter {
    uint shaded_fragments;
    uint nonfinite_fragments;
};
layout(set = 0, binding = BINDING_ALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
#endif

// lighting.comp's: counts.y VPLs; params.x the clamp.
PUSH_CONSTANTS

#include "../inc/shading.glsl"
#include "subsets.glsl"
#include "fallback_list.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
#ifndef FINISH
    if (i >= min(f_pairs, f_pair_cap)) return;
    uint pair = f_pair[i];
    ivec2 px = pair_pixel(pair);
    vec3 p = texelFetch(g_position, px, 0).xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 e = subset_irradiance(p, n, pair_subset(pair), pc.counts.y, pc.params.x);
    f_result[3u * i] = e.x;
    f_result[3u * i + 1u] = e.y;
    f_result[3u * i + 2u] = e.z;
#else
    if (i >= min(f_entries, f_entry_cap)) return;
    FallbackEntry en = f_entry[i];
    ivec2 px = ivec2(int(en.meta.x & 0xffffu), int(en.meta.x >> 16));
    vec3 sum = en.sum.xyz;
    for (uint j = en.meta.y; j < en.meta.y + en.meta.z; ++j) {
        sum += vec3(f_result[3u * j], f_result[3u * j + 1u], f_result[3u * j + 2u]);
    }
    vec3 albedo = texelFetch(g_albedo, px, 0).rgb;
    vec3 c = en.color.xyz;
    c += albedo * (sum / float(SUBSETS));
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
        atomicAdd(nonfinite_fragments, 1u);
    }
    imageStore(out_color, px, vec4(min(c, vec3(65504.0)), 1.0));
    if ((frame.counts.w & FLAG_COUNT_SHADED) != 0u) atomicAdd(shaded_fragments, 1u);
#endif
}
