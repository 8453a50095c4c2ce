#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`: puts the albedo jobs in order of material for the albedo pass (albedo.comp), which
// runs once per material over that material's jobs alone. BIN_PLAN (one invocation): each
// material's offset (the running sum of the counts the raster pass made) and its dispatch.
// Otherwise (one invocation per job, the raster pass's rows): each job's index at its material's
// place; the order within a material depends on the atomics, but each job writes only its own
// slot or record, so the frame does not.
#include "albedo_job.glsl"

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(std430, set = 0, binding = BINDING_ALBEDO_BINS) buffer AlbedoBins { AlbedoBin albedo_bins[]; };
#ifndef BIN_PLAN
layout(std430, set = 0, binding = BINDING_ALBEDO_JOBS) readonly buffer AlbedoJobs { AlbedoJob albedo_jobs[]; };
layout(std430, set = 0, binding = BINDING_ALBEDO_COUNT) readonly buffer AlbedoCounts { AlbedoCount albedo_count; };
layout(std430, set = 0, binding = BINDING_ALBEDO_ORDER) writeonly buffer AlbedoOrder { uint albedo_order[]; };
#endif

void main() {
#ifdef BIN_PLAN
    if (gl_GlobalInvocationID.x != 0u) return;
    uint offset = 0u;
    for (uint m = 0u; m < uint(albedo_bins.length()); ++m) {
        uint n = albedo_bins[m].count;
        albedo_bins[m].offset = offset;
        albedo_bins[m].cursor = 0u;
        albedo_bins[m].groups_x = (n + 63u) / 64u;
        albedo_bins[m].groups_y = 1u;
        albedo_bins[m].groups_z = 1u;
        offset += n;
    }
#else
    uint i = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u + gl_GlobalInvocationID.x;
    if (i >= min(albedo_count.count, uint(albedo_jobs.length()))) return;
    uint m = albedo_jobs[i].material;
    uint k = atomicAdd(albedo_bins[m].cursor, 1u);
    albedo_order[albedo_bins[m].offset + k] = i;
#endif
}
