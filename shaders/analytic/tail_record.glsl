// `analytic`: a fragment beyond its pixel's K nearest that is not hidden (raster.frag records it,
// tail.comp lights it and adds it to the pixel's tail sums). TAIL_RECORD_WORDS words:
//   0 pixel, 1 coverage (f32 bits), 2 sample mask, 3 material index | facing away << 31,
//   4-6 camera-relative shading point (f32), 7 shading normal (octahedral, 2 x snorm16),
//   8-9 albedo (3 x f16).
// The buffer's length sets the capacity; the count may run past it (the technique then grows
// the buffer and renders the frame again: crates/cbr-render/src/techniques/analytic).
#ifndef TAIL_RECORD_GLSL
#define TAIL_RECORD_GLSL
#define TAIL_RECORD_WORDS 10u
#define TAIL_FACING_AWAY 0x80000000u

#endif
