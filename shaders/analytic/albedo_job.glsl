// `analytic`: a textured fragment's albedo lookups, deferred from the raster pass (raster.frag)
// to the albedo pass (albedo.comp). In the raster pass a SIMD group holding one kept fragment ran
// the texture's loops for all its lanes, most of them pixels the fragment's triangle does not
// touch (docs/analytic.md, Measurements: 30% of Sibenik's frame at 160x90); the albedo pass runs
// them on a dense list. 16 words, 64 bytes (std430). The buffer's length is the capacity; the
// count may run past it (the technique then grows the buffer and renders the frame again, as for
// the tail records: crates/cbr-render/src/techniques/analytic, ALBEDO_JOB_BYTES).
#ifndef ALBEDO_JOB_GLSL
#define ALBEDO_JOB_GLSL
#define JOB_TAIL 0x80000000u  // target: a tail record's index (else a slot's)
#define JOB_BOXED 0x10000u    // info: texture_box's box (else its anisotropic lookups)

// The jobs' count and the albedo pass's dispatch (a VkDispatchIndirectCommand from word 1), rows
// of TAIL_ROW_GROUPS groups of 64 as the tail pass's (tail_record.glsl's TailCount).
struct AlbedoCount {
    uint count;
    uint groups_x;
    uint groups_y;
    uint groups_z;
};

// Per material, its jobs' place in the order (albedo_bin.comp): how many, where they start,
// the scatter's cursor, and the albedo pass's dispatch for that material (a
// VkDispatchIndirectCommand at word 4: ceil(count / 64) groups).
struct AlbedoBin {
    uint count;
    uint offset;
    uint cursor;
    uint pad;
    uint groups_x;
    uint groups_y;
    uint groups_z;
    uint pad2;
};

struct AlbedoJob {
    vec2 uv;          // the UV at the shading point
    vec2 fx;          // the footprint the albedo is filtered over (the covered part's)
    vec2 fy;
    vec2 dx;          // the UV map's change over one pixel step (the cells' offsets and size)
    vec2 dy;
    vec2 mean_point;  // the shading point in the pixel, [0, 1]^2
    uint target;      // the slot's index, or the tail record's | JOB_TAIL
    uint material;
    uint info;        // the grid's cells to look up (CELLS bits) | JOB_BOXED
    uint pad;
};
#endif
