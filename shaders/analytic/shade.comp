#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_gpu_shader_int64 : require
// `analytic.shade`: the light of the kept fragments, per pixel and kept slot. The raster pass
// (raster.frag) left in each slot the fragment's albedo (in the colour's place), shading normal
// and shading point (the covered part's centroid: surface.glsl); the point's camera-relative
// position is the slot's depth plane there, unprojected (pc.world_from_clip, the inverse of the
// camera's unjittered camera-relative projection, made in f64 on the CPU; the jitter is taken
// off first). Then shading.glsl's `shade`, as the raster pass shades the tails, and the colour
// is written over the albedo. A non-finite colour is dropped as the raster pass drops it:
// colour and coverage 0, flagged (holes: it wins no samples in the resolve).
#define EMPTY_KEY 0xFFFFFFFFFFFFFFFFul
#include "../inc/scene_types.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = BINDING_LIGHTS) readonly buffer Lights { LightData lights[]; };
layout(std430, set = 1, binding = BINDING_KEYS) readonly buffer Keys { uint64_t keys[]; };
layout(std430, set = 1, binding = BINDING_SLOTS) buffer Slots { uvec2 slots[]; };
layout(std430, set = 1, binding = BINDING_COLORS) buffer Colors { uvec2 colors[]; };
layout(std430, set = 1, binding = BINDING_PLANES) readonly buffer Planes { vec2 planes[]; };
layout(std430, set = 1, binding = BINDING_PLANES_Y) readonly buffer PlanesY { float planes_y[]; };
layout(std430, set = 1, binding = BINDING_SURFACES) readonly buffer Surfaces { uvec2 surfaces[]; };
layout(push_constant) uniform Push { mat4 world_from_clip; } pc;

#include "../inc/shading.glsl"
#include "surface.glsl"

// A fragment's own flags (raster.frag, resolve.comp).
#define FRAG_HOLES 2u
#define FRAG_NONFINITE 4u

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(frame.output_size.x) || px.y >= int(frame.output_size.y)) return;
    uint base = (uint(px.y) * uint(frame.output_size.x) + uint(px.x)) * uint(K_SLOTS);
    // The projection's jitter in NDC (forward.vert adds it to the clip positions).
    vec2 jitter = frame.screen_jitter.xy * 2.0 * frame.output_size.zw;
    for (int k = 0; k < K_SLOTS; ++k) {
        uint s = base + uint(k);
        uint64_t key = keys[s];
        if (key == EMPTY_KEY) break;
        uvec2 col = colors[s];
        if (((col.y >> 16u) & FRAG_NONFINITE) != 0u) continue;
        vec3 albedo = vec3(unpackHalf2x16(col.x), unpackHalf2x16(col.y).x);
        vec3 nrm;
        vec2 point;
        unpack_surface(surfaces[s], nrm, point);
        vec2 plane = planes[s];
        float z = plane.x + plane.y * (point.x - 0.5) + planes_y[s] * (point.y - 0.5);
        vec2 ndc = (vec2(px) + point) * frame.output_size.zw * 2.0 - 1.0 - jitter;
        vec4 h = pc.world_from_clip * vec4(ndc, z, 1.0);
        vec3 world = h.xyz / h.w;
        uint object = uint(key & 0xFFFFFFFFul) >> 20u;
        MaterialData mat = materials[objects[object - 1u].ids.y];
        vec3 color = shade(world, nrm, albedo, mat, frame);
        uint flags = 0u;
        if (any(isnan(color)) || any(isinf(color))) {
            color = vec3(0.0);
            flags = FRAG_HOLES | FRAG_NONFINITE;
            slots[s].x = floatBitsToUint(0.0);
        }
        colors[s] = uvec2(packHalf2x16(color.rg),
                          (packHalf2x16(vec2(color.b, 0.0)) & 0xFFFFu) | (col.y & 0xFFFF0000u)
                          | (flags << 16u));
    }
}
