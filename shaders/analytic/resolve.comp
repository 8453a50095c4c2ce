#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`, resolve: per pixel, the fragment list front to back. The visibility model:
// fragments sorted by depth at their shading point (nearer first; ties by object, then
// primitive, so the order never depends on the order of the atomics). A fragment whose sample
// mask lies wholly under the masks of nearer fragments of the same object is hidden: the back
// faces of a closed mesh at its silhouette, the far side of a mesh folded over itself. Every
// other fragment adds its exact coverage clamped to what nearer ones left, v = min(a, 1 - sum),
// colour += v c; the background fills the remainder. Exact for one surface over a background,
// for abutting triangles (their coverages add up to the pixel), and for an opaque surface in
// front of another object that covers the whole pixel (the clamp hands the far object exactly
// what the near one leaves); approximate where two partial surfaces overlap in one pixel
// (docs/analytic.md measures it against ssaa:32). A fragment too small to hold a mask sample
// carries a stand-in bit that neither hides nor is hidden (either would open seams in meshes).
// Lists longer than MAX_FRAGS keep the nearest MAX_FRAGS; those dropped and those that found no
// room in the pool count as overflow, and an overflowing pixel's listed surfaces are
// renormalised over their coverage instead of letting the background show through where a
// surface was lost.
#include "../inc/scene_types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = BINDING_HEADS) readonly buffer Heads { uint heads[]; };
layout(std430, set = 0, binding = BINDING_NODES) readonly buffer Nodes { uint nodes[]; };
layout(std430, set = 0, binding = BINDING_LOST) readonly buffer Lost { uint lost[]; };
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_COVERAGE, r32f) uniform writeonly image2D out_coverage;
layout(set = 0, binding = BINDING_OUT_COUNTS, rgba32ui) uniform writeonly uimage2D out_counts;
layout(push_constant) uniform Push {
    vec4 background;  // rgb
    uvec4 size;       // width, height
} pc;

#define MAX_FRAGS 16
#define END 0xFFFFFFFFu

// Counts' channels: fragments in the list, overflow (dropped + lost), flags, visible fragments.
#define FLAG_EDGE 1u      // a visible fragment covers the pixel partly, or the background shows
#define FLAG_SEED 2u      // analytic:seed: a visible fragment's shortcut area is off by > 1e-3
#define FLAG_OVERFLOW 4u

// Sort order: larger is nearer (reverse-Z depth), then the smaller object, then primitive.
bool nearer(float za, uint oa, uint pa, float zb, uint ob, uint pb) {
    return za > zb || (za == zb && (oa < ob || (oa == ob && pa < pb)));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(pc.size.x) || px.y >= int(pc.size.y)) return;
    uint pixel = uint(px.y) * pc.size.x + uint(px.x);

    uint idx[MAX_FRAGS];
    float zs[MAX_FRAGS];
    uint objs[MAX_FRAGS];
    uint prims[MAX_FRAGS];
    int count = 0;
    uint listed = 0u;
    uint dropped = 0u;
    for (uint i = heads[pixel]; i != END; i = nodes[i * NODE_WORDS]) {
        ++listed;
        float z = uintBitsToFloat(nodes[i * NODE_WORDS + 1u]);
        uint obj = nodes[i * NODE_WORDS + 5u] >> 18u;
        uint prim = nodes[i * NODE_WORDS + 6u];
        if (count == MAX_FRAGS) {
            // Full: keep the nearest; the farthest goes.
            ++dropped;
            int l = MAX_FRAGS - 1;
            if (!nearer(z, obj, prim, zs[l], objs[l], prims[l])) continue;
            --count;
        }
        int j = count;
        while (j > 0 && nearer(z, obj, prim, zs[j - 1], objs[j - 1], prims[j - 1])) {
            idx[j] = idx[j - 1];
            zs[j] = zs[j - 1];
            objs[j] = objs[j - 1];
            prims[j] = prims[j - 1];
            --j;
        }
        idx[j] = i;
        zs[j] = z;
        objs[j] = obj;
        prims[j] = prim;
        ++count;
        if (listed > 1u << 20) break;  // a cycle would be a bug; never spin forever
    }

    float sum = 0.0;
    vec3 color = vec3(0.0);
    uint flags = 0u;
    uint visible = 0u;
    for (int k = 0; k < count; ++k) {
        uint b = idx[k] * NODE_WORDS;
        uint mask = nodes[b + 3u];
        uint w5 = nodes[b + 5u];
        if (((w5 >> 17u) & 1u) == 0u) {
            // Hidden under nearer fragments of the same object?
            uint under = 0u;
            for (int m = 0; m < k; ++m) {
                uint bm = idx[m] * NODE_WORDS;
                bool stand_in = ((nodes[bm + 5u] >> 17u) & 1u) != 0u;
                if (objs[m] == objs[k] && !stand_in) under |= nodes[bm + 3u];
            }
            if ((mask & ~under) == 0u) continue;
        }
        float a = uintBitsToFloat(nodes[b + 2u]);
        if (((w5 >> 16u) & 1u) != 0u) flags |= FLAG_SEED;
        float v = min(a, 1.0 - sum);
        if (v <= 0.0) continue;
        vec3 c = vec3(unpackHalf2x16(nodes[b + 4u]), unpackHalf2x16(w5 & 0xFFFFu).x);
        color += v * c;
        sum += v;
        ++visible;
        if (a < 1.0 - 1e-6) flags |= FLAG_EDGE;
    }
    uint overflow = dropped + lost[pixel];
    if (overflow > 0u) flags |= FLAG_OVERFLOW;
    if (sum < 1.0 - 1e-6 && visible > 0u) flags |= FLAG_EDGE;
    if (overflow > 0u && sum > 0.0) {
        color /= sum;
    } else {
        color += max(1.0 - sum, 0.0) * pc.background.rgb;
    }
    imageStore(out_color, px, vec4(color, 1.0));
    imageStore(out_coverage, px, vec4(sum));
    imageStore(out_counts, px, uvec4(listed + lost[pixel], overflow, flags, visible));
}
