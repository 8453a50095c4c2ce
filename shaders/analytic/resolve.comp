#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`, resolve: per pixel, its K nearest fragments front to back. The visibility model:
// fragments sorted by depth at the pixel centre (nearer first; ties by object, then primitive,
// so the order never depends on the order of the atomics). A fragment whose sample
// mask lies wholly under the masks of nearer fragments of the same object is hidden: the back
// faces of a closed mesh at its silhouette, the far side of a mesh folded over itself. Every
// other fragment adds its exact coverage clamped to what nearer ones left, v = min(a, 1 - sum),
// colour += v c; the background fills the remainder. Exact for one surface over a background,
// for abutting triangles (their coverages add up to the pixel), and for an opaque surface in
// front of another object that covers the whole pixel (the clamp hands the far object exactly
// what the near one leaves); approximate where two partial surfaces overlap in one pixel
// (docs/analytic.md measures it against ssaa:32). A fragment too small to hold a mask sample
// carries a stand-in bit that neither hides nor is hidden (either would open seams in meshes).
// Only the K nearest fragments of a pixel are kept (the select pass); those beyond count as
// overflow and are merged into one tail fragment (coverage-weighted mean colour, summed
// coverage) composited after the K, so no surface is dropped, only its order within the tail.
#extension GL_ARB_gpu_shader_int64 : require
#define EMPTY_KEY 0xFFFFFFFFFFFFFFFFul  // a slot no fragment took
#include "../inc/scene_types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = BINDING_KEYS) readonly buffer Keys { uint64_t keys[]; };
layout(std430, set = 0, binding = BINDING_SLOTS) readonly buffer Slots { uvec2 slots[]; };
layout(std430, set = 0, binding = BINDING_COLORS) readonly buffer Colors { uvec2 colors[]; };
layout(std430, set = 0, binding = BINDING_COUNTS) readonly buffer Counts { uint counts[]; };
layout(std430, set = 0, binding = BINDING_TAIL) readonly buffer Tail { uint64_t tail[]; };
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_COVERAGE, r32f) uniform writeonly image2D out_coverage;
layout(set = 0, binding = BINDING_OUT_COUNTS, rgba32ui) uniform writeonly uimage2D out_counts;
layout(push_constant) uniform Push {
    vec4 background;  // rgb
    uvec4 size;       // width, height
} pc;

// Counts' channels: fragments that touched the pixel, overflow (beyond the K nearest), flags,
// visible fragments.
#define FLAG_EDGE 1u      // a visible fragment covers the pixel partly, or the background shows
#define FLAG_SEED 2u      // analytic:seed: a visible fragment's shortcut area is off by > 1e-3
#define FLAG_OVERFLOW 4u
#define FLAG_NONFINITE 8u  // a kept fragment's shading was not finite (dropped)

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(pc.size.x) || px.y >= int(pc.size.y)) return;
    uint pixel = uint(px.y) * pc.size.x + uint(px.x);
    uint base = pixel * uint(K_SLOTS);

    // The slots hold the K nearest keys in order (the select pass's insertion).
    uint objs[K_SLOTS];
    int count = 0;
    for (int k = 0; k < K_SLOTS; ++k) {
        uint64_t key = keys[base + uint(k)];
        if (key == EMPTY_KEY) break;
        objs[k] = uint(key & 0xFFFFFFFFul) >> 20u;
        ++count;
    }

    float sum = 0.0;
    vec3 color = vec3(0.0);
    uint flags = 0u;
    uint visible = 0u;
    for (int k = 0; k < count; ++k) {
        uvec2 sl = slots[base + uint(k)];
        uvec2 cl = colors[base + uint(k)];
        uvec4 s = uvec4(sl, cl);
        uint mask = s.y;
        uint fflags = s.w >> 16u;
        if ((fflags & 2u) == 0u) {
            // Hidden under nearer fragments of the same object?
            uint under = 0u;
            for (int m = 0; m < k; ++m) {
                bool stand_in = ((colors[base + uint(m)].y >> 17u) & 1u) != 0u;
                if (objs[m] == objs[k] && !stand_in) under |= slots[base + uint(m)].y;
            }
            if ((mask & ~under) == 0u) continue;
        }
        float a = uintBitsToFloat(s.x);
        if ((fflags & 1u) != 0u) flags |= FLAG_SEED;
        if ((fflags & 4u) != 0u) flags |= FLAG_NONFINITE;
        float v = min(a, 1.0 - sum);
        if (v <= 0.0) continue;
        vec3 c = vec3(unpackHalf2x16(s.z), unpackHalf2x16(s.w & 0xFFFFu).x);
        color += v * c;
        sum += v;
        ++visible;
        if (a < 1.0 - 1e-6) flags |= FLAG_EDGE;
    }
    uint seen = counts[pixel];
    uint overflow = seen - uint(count);
    if (overflow > 0u) flags |= FLAG_OVERFLOW;
    if (sum < 1.0 - 1e-6 && visible > 0u) flags |= FLAG_EDGE;
    if (overflow > 0u && sum < 1.0) {
        // The fragments beyond the K nearest, merged into one (their coverage-weighted mean
        // colour, their summed coverage), fill what the nearest left, as one more fragment.
        uint t = pixel * 4u;
        const float unit = 1.0 / 16777216.0;
        float ta = float(tail[t + 3u]) * unit;
        if (ta > 0.0) {
            vec3 tc = vec3(float(tail[t]), float(tail[t + 1u]), float(tail[t + 2u])) * unit / ta;
            float v = min(ta, 1.0 - sum);
            color += v * tc;
            sum += v;
        }
    }
    color += max(1.0 - sum, 0.0) * pc.background.rgb;
    imageStore(out_color, px, vec4(color, 1.0));
    imageStore(out_coverage, px, vec4(sum));
    imageStore(out_counts, px, uvec4(seen, overflow, flags, visible));
}
