#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_gpu_shader_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
// `analytic`, the tail pass: lights the fragments beyond their pixel's K nearest that the raster
// pass recorded (tail_record.glsl: the ones no occluder hides) and adds each to its pixel's tail,
// facing the camera or away, as the fixed-point sums (2^-24 units) of coverage x colour and of
// coverage, and the union of the sample masks. Integer sums: the result does not depend on the
// order the raster pass recorded them in. A fragment whose light is not finite is left out, as
// the resolve drops such a kept fragment.
// One invocation per record: a dense list, where the raster pass's SIMD groups were mostly
// pixels the fragment's triangle does not touch (docs/analytic.md, Shading).
#include "../inc/scene_types.glsl"
#include "surface.glsl"
#include "mask.glsl"
#include "tail_record.glsl"

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(std430, set = 0, binding = BINDING_TAIL_RECORDS) readonly buffer TailRecords { TailRecord tail_records[]; };
layout(std430, set = 0, binding = BINDING_TAIL_COUNT) readonly buffer TailCounts { TailCount tail_count; };
// Per pixel, two tails (facing the camera, facing away), 4 sums each; and their masks' unions
// (MASK_WORDS words each).
layout(std430, set = 0, binding = BINDING_TAIL) buffer Tail { uint64_t tail[]; };
layout(std430, set = 0, binding = BINDING_TAIL_BACK) buffer TailBack { uint64_t tail_back[]; };
layout(std430, set = 0, binding = BINDING_TAIL_MASKS) buffer TailMasks { uint tail_masks[]; };
// The scene's buffers, for the lighting.
layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };

#include "../inc/shading.glsl"

void main() {
    // Rows of TAIL_ROW_GROUPS groups of 64 (tail_record.glsl's TailCount), as many as the records
    // held begin; the last row's invocations past the count return.
    uint i = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u + gl_GlobalInvocationID.x;
    if (i >= min(tail_count.count, uint(tail_records.length()))) return;
    TailRecord rec = tail_records[i];
    uint pixel = rec.pixel;
    Mask mask = tail_record_mask(rec);
    float coverage;
    uint material;
    bool facing_away;
    vec3 world, nrm, albedo;
    read_tail_record(rec, coverage, material, facing_away, world, nrm, albedo);
    vec3 color = shade(world, nrm, albedo, materials[material], frame);
    if (any(isnan(color)) || any(isinf(color))) return;

    const float unit = 16777216.0;  // 2^24
    vec3 ac = clamp(color, 0.0, 65504.0) * coverage * unit;
    uint t = pixel * 4u;
#define ADD_TAIL(buf)                                       \
    atomicAdd(buf[t], uint64_t(ac.r));                      \
    atomicAdd(buf[t + 1u], uint64_t(ac.g));                 \
    atomicAdd(buf[t + 2u], uint64_t(ac.b));                 \
    atomicAdd(buf[t + 3u], uint64_t(coverage * unit))
    if (facing_away) {
        ADD_TAIL(tail_back);
    } else {
        ADD_TAIL(tail);
    }
#undef ADD_TAIL
    uint m = (pixel * 2u + (facing_away ? 1u : 0u)) * uint(MASK_WORDS);
    for (int w = 0; w < MASK_WORDS; ++w) {
        uint bits = mask_word(mask, w);
        if (bits != 0u) atomicOr(tail_masks[m + uint(w)], bits);
    }
}
