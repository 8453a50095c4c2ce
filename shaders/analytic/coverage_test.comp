#version 460
#extension GL_GOOGLE_include_directive : require
// Test kernel: coverage.glsl on listed (polygon, pixel) cases, for the comparison with the f64
// reference (crates/cbr-render/tests/analytic.rs). Polygons are in screen pixels, as the raster
// passes them; the pixel-local subtraction is the fragment stage's.
#include "coverage.glsl"

layout(local_size_x = 64) in;

struct Case {
    vec4 p01;    // vertices 0 and 1, screen pixels
    vec4 p23;    // vertices 2 and 3 (3: a quadrilateral only)
    ivec4 info;  // vertex count, pixel x, pixel y, 0
};
struct Result {
    vec4 area_centroid_seed;  // exact area, centroid (pixel-local), seed area
    uvec4 mask;               // the sample mask's words (MASK_WORDS of them; 0 beyond)
    uvec4 info;               // the nearest sample to the centroid, centre inside, 0, 0
};
layout(std430, set = 0, binding = 0) readonly buffer Cases { Case cases[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Results { Result results[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Case c = cases[i];
    vec2 corner = vec2(c.info.yz);
    vec2 screen[MAX_POLY] = vec2[MAX_POLY](c.p01.xy, c.p01.zw, c.p23.xy, c.p23.zw);
    vec2 p[MAX_POLY];
    vec2 lo[MAX_POLY];
    to_local(screen, corner, p, lo);
    int n = c.info.x;
    PixelCoverage cov = exact_coverage(p, lo, n);
    float o = orientation(p, n);
    Mask mask = sample_mask(p, n, o);
    results[i].area_centroid_seed = vec4(cov.area, cov.mean_point, seed_coverage(p, n, mask));
    uvec4 words = uvec4(0u);
    for (int w = 0; w < MASK_WORDS; ++w) words[w] = mask_word(mask, w);
    results[i].mask = words;
    Mask nearest = nearest_sample_bit(cov.mean_point);
    int nearest_index = mask_pop(nearest);
    results[i].info = uvec4(uint(nearest_index), inside(p, n, o, vec2(0.5)) ? 1u : 0u, 0u, 0u);
}
