#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
// `deferred`'s lighting pass: per pixel, the G-buffer's surface (written by the forward fragment
// shader with GBUFFER: the same position, shading normal and albedo bits it would shade) through
// the forward pass's `shade` (shaders/inc/shading.glsl), then the extra point lights
// (`points=N`) through the same light term, then the one-bounce indirect light of the VPLs
// (`vpls=N`): albedo x their summed irradiance (with INTERLEAVED, `interleaved`'s filtered
// estimate instead: shaders/interleaved/filter.glsl; with DIRECT the point lights' too, the pass
// then shading the directional lights only). NaN/Inf shading is written black and
// counted, as the forward pass does; background pixels get the background radiance.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"

layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = BINDING_COUNTER) buffer Counter {
    uint shaded_fragments;
    uint nonfinite_fragments;
};
layout(set = 0, binding = BINDING_POSITION) uniform sampler2D g_position;
layout(set = 0, binding = BINDING_NORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = BINDING_ALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = BINDING_IDS) uniform usampler2D g_ids;
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;

// background.rgb: radiance where nothing was drawn; counts: x extra point lights, y VPLs, zw
// width, height; params.x: the VPL clamp c in 1/max(d^2, c) (m^2).
PUSH_CONSTANTS

// PARTS (`interleaved:...:parts=P`, a timing attribution; the frame is then not the technique's):
// 0 everything; 1 the G-buffer's fetches, emission, ambient and the directional lights; 2 and the
// per-pixel point lights; 3 and the filter without `ours`' fallback (filter.glsl).
#ifndef PARTS
#define PARTS 0
#endif
// CULL_LIGHTS 0 (`cull=0`): every point light at every pixel (the same frame, for timing).
#ifndef CULL_LIGHTS
#define CULL_LIGHTS 1
#endif

#include "../inc/shading.glsl"

// Whether point light `light` may reach p: a range of 0 or less has no window (every distance);
// else p lies within 1.01 times the range. Beyond the range shading.glsl's window is 0, so the
// light's term (add_light) adds exactly 0 there: a light that reaches no pixel of a SIMD group is
// skipped by the whole group, and every pixel's sum is the same. The two loops in main() advance
// past such lights with the test alone (each lane the same index, the vote the same in every
// lane, so they leave together), where a skipped iteration of a plain loop would run the light
// term anyway on hardware that runs both sides of a branch, as llvmpipe does.
bool reaches(vec3 p, LightData light) {
    float r = light.color.w;
    if (r <= 0.0) return true;
    vec3 d = light.position.xyz - p;
    return dot(d, d) < 1.0201 * (r * r);
}
#ifdef INTERLEAVED
#include "../interleaved/filter.glsl"
#endif
#ifdef FALLBACK_PAIRS
#include "../interleaved/fallback_list.glsl"

// `fallback=pairs`: lists pixel px (colour c before the VPL term, found sum `sum`, `missing` its
// missing window slots, none where it needs no fallback) and its missing slots' subsets for the
// fallback passes; false where it needs none or the lists are full (the caller then shades them
// inline). Every active lane of the SIMD group calls it: the group takes its pairs and entries
// with one atomic each (a subgroup scan gives each lane its place), so that the lists cost a few
// atomics a group, not five a pixel. A lane whose pairs straddle the pairs' capacity fills the
// slots below it with its first pair, so that every pair below min(pairs, capacity), the
// fallback pass's range, is a real one (the straddling pixel itself takes the inline loop).
bool defer_fallback(ivec2 px, vec3 c, uvec2 missing, vec3 sum) {
    uint count = uint(bitCount(missing.x) + bitCount(missing.y));
    uint total = subgroupAdd(count);
    if (total == 0u) return false;
    uint base = 0u;
    if (subgroupElect()) {
        base = atomicAdd(f_pairs, total);
        uint end = min(base + total, f_pair_cap);
        if (end > base) atomicMax(f_pair_groups[0], (end + FALLBACK_GROUP - 1u) / FALLBACK_GROUP);
    }
    uint first = subgroupBroadcastFirst(base) + subgroupExclusiveAdd(count);
    bool fits = count > 0u && first + count <= f_pair_cap;
    uint j = first;
    while (missing.x != 0u || missing.y != 0u) {
        uint word = missing.x != 0u ? 0u : 1u;
        uint t = uint(findLSB(missing[word]));
        missing[word] &= ~(1u << t);
        t += 32u * word;
        ivec2 o = ivec2(int(t % uint(TILE_M)) - (TILE_M - 1) / 2,
                        int(t / uint(TILE_M)) - (TILE_N - 1) / 2);
        uint pair = pack_pair(px, subset_of(px + o));
        if (fits) {
            f_pair[j] = pair;
        } else if (j == first) {
            // Straddling the capacity: fill up to it with this (real) pair.
            for (uint k = first; k < f_pair_cap; ++k) f_pair[k] = pair;
        }
        j += 1u;
    }
    uint entries = subgroupAdd(fits ? 1u : 0u);
    if (entries == 0u) return false;
    uint e0 = 0u;
    if (subgroupElect()) {
        e0 = atomicAdd(f_entries, entries);
        uint end = min(e0 + entries, f_entry_cap);
        if (end > e0) atomicMax(f_entry_groups[0], (end + FALLBACK_GROUP - 1u) / FALLBACK_GROUP);
    }
    uint e = subgroupBroadcastFirst(e0) + subgroupExclusiveAdd(fits ? 1u : 0u);
    if (!fits || e >= f_entry_cap) return false;
    f_entry[e] = FallbackEntry(uvec4(uint(px.x) | (uint(px.y) << 16), first, count, 0u),
                               vec4(c, 0.0), vec4(sum, 0.0));
    return true;
}
#endif

// The point lights START <= i < END of ARRAY (element i - FIRST) added to c at p, each skipped
// where no lane of the SIMD group is within its reach (`reaches`).
#define POINT_LIGHTS(ARRAY, FIRST, START, END)                                                   \
    for (uint i = (START); true; ++i) {                                                          \
        while (CULL_LIGHTS != 0 && i < (END) && !subgroupAny(reaches(p, ARRAY[i - (FIRST)]))) ++i; \
        if (i >= (END)) break;                                                                   \
        add_light(c, p, n, v, albedo, m, ARRAY[i - (FIRST)]);                                    \
    }

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
#ifdef INTERLEAVED
    window_load();
#endif
    if (px.x >= int(pc.counts.z) || px.y >= int(pc.counts.w)) return;
#if defined(INTERLEAVED) && defined(DEBUG)
    imageStore(debug_bits, px, uvec4(0u));
#endif
    uint object = texelFetch(g_ids, px, 0).x;
    if (object == 0u) {
        imageStore(out_color, px, vec4(pc.background.rgb, 1.0));
        return;
    }
    vec3 p = texelFetch(g_position, px, 0).xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 albedo = texelFetch(g_albedo, px, 0).rgb;
    if ((frame.counts.w & FLAG_DEBUG_LOD) != 0u) {
        imageStore(out_color, px, vec4(albedo.r, 0.0, 0.0, 1.0));
        return;
    }
    MaterialData m = materials[objects[object - 1u].ids.y];
    // Emission, ambient and the directional lights (the scene's lights come directional first).
    vec3 c = shade_lights(p, n, albedo, m, frame, frame.counts.x);
#if !defined(DIRECT) && PARTS != 1
    // The scene's point lights, then the extra ones (`points=N`), in shade()'s order, each skipped
    // where no pixel of the SIMD group is within its reach (below); with `interleaved:...:direct`
    // they come filtered with the VPLs instead.
    // Each list in two loops, its uniform part's and the rest's (light_buffers.glsl).
    vec3 v = normalize(-p);
    uint end = frame.counts.x + frame.counts.y;
    POINT_LIGHTS(lights, 0u, frame.counts.x, min(end, UNIFORM_LIGHTS))
    POINT_LIGHTS(more_lights, UNIFORM_LIGHTS, max(frame.counts.x, UNIFORM_LIGHTS), end)
    POINT_LIGHTS(points, 0u, 0u, min(pc.counts.x, UNIFORM_LIGHTS))
    POINT_LIGHTS(more_points, UNIFORM_LIGHTS, UNIFORM_LIGHTS, pc.counts.x)
#endif
    if (pc.counts.y > 0u && (PARTS == 0 || PARTS == 3)) {
#ifdef INTERLEAVED
        // `interleaved`: the filtered sub-image estimates, then (as below) times albedo; with
        // DIRECT the point lights' diffuse term is in them, and their specular term comes apart.
        uint bits;
        vec3 spec;
        vec3 irradiance = interleaved_irradiance(px, object, p, n, m.ks.w, bits, spec);
#ifdef FALLBACK_PAIRS
        // Every lane takes part in the lists' scans (defer_fallback), those without a fallback
        // with nothing to list.
        bool listed = defer_fallback(px, c, g_pending, g_pending_sum);
        if (g_pending != uvec2(0u)) {
            if (listed) {
                // interleaved.finish writes the pixel.
#ifdef DEBUG
                if ((int(texelFetch(g_irradiance, px, 0).a) & 1) != 0) bits |= DBG_ROUNDTRIP;
                imageStore(debug_bits, px, uvec4(bits));
#endif
                return;
            }
            irradiance = shade_missing(px, p, n, m.ks.w, g_pending, g_pending_sum, vec3(0.0), spec);
        }
#endif
        c += albedo * irradiance;
#ifdef DIRECT
        c += m.ks.rgb * spec;
#endif
#ifdef DEBUG
        if ((int(texelFetch(g_irradiance, px, 0).a) & 1) != 0) bits |= DBG_ROUNDTRIP;
        imageStore(debug_bits, px, uvec4(bits));
#endif
#else
        vec3 e = vec3(0.0);
        for (uint i = 0u; i < min(pc.counts.y, UNIFORM_VPLS); ++i) {
            e += vpl_irradiance(p, n, vpls[i], pc.params.x);
        }
        for (uint i = UNIFORM_VPLS; i < pc.counts.y; ++i) {
            e += vpl_irradiance(p, n, more_vpls[i - UNIFORM_VPLS], pc.params.x);
        }
        c += albedo * e;
#endif
    }
    // NaN/Inf containment and the fp16 clamp, as in shaders/scene/forward.frag.
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
        atomicAdd(nonfinite_fragments, 1u);
    }
    imageStore(out_color, px, vec4(min(c, vec3(65504.0)), 1.0));
    if ((frame.counts.w & FLAG_COUNT_SHADED) != 0u) atomicAdd(shaded_fragments, 1u);
}
