// `analytic`: a fragment beyond its pixel's K nearest that is not hidden (raster.frag records it,
// tail.comp lights it and adds it to the pixel's tail sums): 9 + MASK_WORDS words, 36 + 4
// MASK_WORDS bytes (std430, no padding). The buffer's length sets the capacity; the count may run past it (the technique then
// grows the buffer and renders the frame again: crates/cbr-render/src/techniques/analytic,
// tail_record_bytes). Needs surface.glsl (the octahedral normal) and mask.glsl.
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
    uint mask;       // the covered part's sample mask (its first word)
    uint material;   // material index | TAIL_FACING_AWAY
    uint world_x;    // camera-relative shading point, f32 bits
    uint world_y;
    uint world_z;
    uint normal;     // shading normal, octahedral, 2 x snorm16
    uint albedo_rg;  // albedo, 3 x f16
    uint albedo_b;
#if MASK_WORDS > 1
    uint mask_hi[MASK_WORDS - 1];  // the mask's other words
#endif
};

TailRecord make_tail_record(uint pixel, float coverage, Mask mask, uint material, bool facing_away,
                            vec3 world, vec3 normal, vec3 albedo) {
    uvec3 w = floatBitsToUint(world);
    TailRecord t;
    t.pixel = pixel;
    t.coverage = floatBitsToUint(coverage);
    t.mask = mask_word(mask, 0);
    t.material = material | (facing_away ? TAIL_FACING_AWAY : 0u);
    t.world_x = w.x;
    t.world_y = w.y;
    t.world_z = w.z;
    t.normal = packSnorm2x16(oct_encode(normal));
    t.albedo_rg = packHalf2x16(albedo.rg);
    t.albedo_b = packHalf2x16(vec2(albedo.b, 0.0));
#if MASK_WORDS > 1
    for (int i = 1; i < MASK_WORDS; ++i) t.mask_hi[i - 1] = mask_word(mask, i);
#endif
    return t;
}

Mask tail_record_mask(TailRecord t) {
    Mask m = Mask(t.mask);
#if MASK_WORDS > 1
    for (int i = 1; i < MASK_WORDS; ++i) m[i] = t.mask_hi[i - 1];
#endif
    return m;
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
