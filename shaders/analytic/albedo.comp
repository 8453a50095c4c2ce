#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`, the albedo pass: the textured fragments' albedo lookups that the raster pass left
// as jobs (albedo_job.glsl), one invocation each, on a dense list: the albedo texture filtered
// over the covered part's footprint (texture_box, or texture_aniso with `analytic:aniso`) times
// the material's kd, into the kept fragment's slot (its colour, keeping the flags the raster pass
// wrote) or the tail record; and, for a slot, the albedo grid's cells the raster pass asked for
// (surface.glsl's pack_cells). The same arithmetic as the lookups had in the raster pass.
// lavapipe indexes no sampler array non-uniformly, so the pass runs once per textured material
// with that material's set bound, over that material's jobs (albedo_bin.comp sorts them by
// material first: run over every job, each dispatch found a few of its own in most SIMD groups
// and ran the loops for all the lanes).
#include "../inc/scene_types.glsl"
#include "surface.glsl"
#include "mask.glsl"
#include "tail_record.glsl"
#include "albedo_job.glsl"

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(std430, set = 0, binding = BINDING_ALBEDO_JOBS) readonly buffer AlbedoJobs { AlbedoJob albedo_jobs[]; };
layout(std430, set = 0, binding = BINDING_ALBEDO_BINS) readonly buffer AlbedoBins { AlbedoBin albedo_bins[]; };
layout(std430, set = 0, binding = BINDING_ALBEDO_ORDER) readonly buffer AlbedoOrder { uint albedo_order[]; };
layout(std430, set = 0, binding = BINDING_COLORS) buffer Colors { uvec2 colors[]; };
layout(std430, set = 0, binding = BINDING_CELLS) writeonly buffer Cells { uvec2 cells[]; };
layout(std430, set = 0, binding = BINDING_CELLS_HI) writeonly buffer CellsHi { uvec2 cells_hi[]; };
layout(std430, set = 0, binding = BINDING_TAIL_RECORDS) buffer TailRecords { TailRecord tail_records[]; };
// The scene's buffers (the LOD bias, the materials' kd) and the material's albedo texture.
layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(set = 0, binding = BINDING_ALBEDO_TEXTURE) uniform sampler2D albedo_tex;
// pc.material (passes.rs's AlbedoPush).
PUSH_CONSTANTS

#include "texture.glsl"

void main() {
    // This material's jobs, in the order albedo_bin.comp put them in.
    AlbedoBin bin = albedo_bins[pc.material];
    if (gl_GlobalInvocationID.x >= bin.count) return;
    AlbedoJob j = albedo_jobs[albedo_order[bin.offset + gl_GlobalInvocationID.x]];
    vec3 albedo = materials[j.material].kd.rgb;
#ifdef TEXTURE_BOX
    albedo *= texture_box(albedo_tex, j.uv, j.fx, j.fy, (j.info & JOB_BOXED) != 0u).rgb;
#else
    albedo *= texture_aniso(albedo_tex, j.uv, j.fx, j.fy).rgb;
#endif
    if ((j.target & JOB_TAIL) != 0u) {
        uint t = j.target & ~JOB_TAIL;
        tail_records[t].albedo_rg = packHalf2x16(albedo.rg);
        tail_records[t].albedo_b = packHalf2x16(vec2(albedo.b, 0.0));
        return;
    }
    uvec2 c = colors[j.target];
    colors[j.target] = uvec2(packHalf2x16(albedo.rg),
                             (packHalf2x16(vec2(albedo.b, 0.0)) & 0xFFFFu) | (c.y & 0xFFFF0000u));
    // The cells (raster.frag's gate): a quarter of the pixel's footprint centred in each.
    float cell_luma[CELLS];
    for (int k = 0; k < CELLS; ++k) cell_luma[k] = 1.0;
    float lod_scale = exp2(frame.ambient.w);
    vec2 gx = j.dx * lod_scale;
    vec2 gy = j.dy * lod_scale;
    uint bits = j.info & ((1u << uint(CELLS)) - 1u);
    while (bits != 0u) {
        int k = findLSB(bits);
        bits &= bits - 1u;
        vec2 d = (vec2(float(k % CELLS_SIDE), float(k / CELLS_SIDE)) + 0.5) / float(CELLS_SIDE)
            - j.mean_point;
        const float side = 1.0 / float(CELLS_SIDE);
        cell_luma[k] = albedo_luma(texture_aniso_n(albedo_tex, j.uv + j.dx * d.x + j.dy * d.y,
                                                   side * gx, side * gy, CELL_ANISO).rgb);
    }
    uvec4 packed_cells = pack_cells(cell_luma);
    cells[j.target] = packed_cells.xy;
    cells_hi[j.target] = packed_cells.zw;
}
