// `analytic`: a fragment beyond its pixel's K nearest that is not hidden (raster.frag records it,
// tail.comp lights it and adds it to the pixel's tail sums): 10 words, 40 bytes (std430, no
// padding). The buffer's length sets the capacity; the count may run past it (the technique then
// grows the buffer and renders the frame again: crates/cbr-render/src/techniques/analytic,
// TAIL_RECORD_BYTES). Needs surface.glsl (the octahedral normal).
#ifndef TAIL_RECORD_GLSL
#define TAIL_RECORD_GLSL
#define TAIL_FACING_AWAY 0x80000000u

// The records' count and the tail pass's dispatch (a VkDispatchIndirectCommand from word 1): rows
// of TAIL_ROW_GROUPS groups of 64 invocations (x, set by the host each frame with y = 0, z = 1),
// y counting the rows begun by the records the buffer holds. The raster pass adds a row when it
// writes a record at the start of one, so the pass runs ceil(held / (64 TAIL_ROW_GROUPS)) rows,
// not the buffer's capacity. TAIL_ROW_GROUPS: a define (crates/cbr-render's analytic module).
struct TailCount {
    uint count;     // records counted, some past the buffer's capacity when it overflows
    uint groups_x;  // TAIL_ROW_GROUPS
    uint groups_y;  // rows
    uint groups_z;  // 1
};

struct TailRecord {
    uint pixel;
    uint coverage;   // f32 bits
    uint mask;       // the covered part's sample mask
    uint material;   // material index | TAIL_FACING_AWAY
    uint world_x;    // camera-relative shading point, f32 bits
    uint world_y;
    uint world_z;
    uint normal;     // shading normal, octahedral, 2 x snorm16
    uint albedo_rg;  // albedo, 3 x f16
    uint albedo_b;
};

TailRecord make_tail_record(uint pixel, float coverage, uint mask, uint material, bool facing_away,
                            vec3 world, vec3 normal, vec3 albedo) {
    uvec3 w = floatBitsToUint(world);
    return TailRecord(pixel, floatBitsToUint(coverage), mask,
                      material | (facing_away ? TAIL_FACING_AWAY : 0u), w.x, w.y, w.z,
                      packSnorm2x16(oct_encode(normal)), packHalf2x16(albedo.rg),
                      packHalf2x16(vec2(albedo.b, 0.0)));
}

void read_tail_record(TailRecord t, out float coverage, out uint material, out bool facing_away,
                      out vec3 world, out vec3 normal, out vec3 albedo) {
    coverage = uintBitsToFloat(t.coverage);
    material = t.material & ~TAIL_FACING_AWAY;
    facing_away = (t.material & TAIL_FACING_AWAY) != 0u;
    world = uintBitsToFloat(uvec3(t.world_x, t.world_y, t.world_z));
    normal = oct_decode(unpackSnorm2x16(t.normal));
    albedo = vec3(unpackHalf2x16(t.albedo_rg), unpackHalf2x16(t.albedo_b).x);
}
#endif
