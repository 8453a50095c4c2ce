// `interleaved`'s light subsets: subset k of the M x N (TILE_M x TILE_N) sub-images is every VPL i
// with i mod (M N) = k, a stride through the seeded Halton pattern, itself spread over the whole
// map. Its irradiance times M N estimates that of all the VPLs (N is a multiple of M N). Needs
// `vpls` and shading.glsl's vpl_irradiance.
#ifndef SUBSETS_GLSL
#define SUBSETS_GLSL

const uint SUBSETS = uint(TILE_M * TILE_N);

// The subset sub-image (i, j) shades, and the one pixel (x, y) belongs to: i = x mod M,
// j = y mod N, k = j M + i (negative coordinates wrap the same way).
uint subset_of(ivec2 q) {
    ivec2 r = ivec2(((q.x % TILE_M) + TILE_M) % TILE_M, ((q.y % TILE_N) + TILE_N) % TILE_N);
    return uint(r.y * TILE_M + r.x);
}

vec3 subset_irradiance(vec3 p, vec3 n, uint k, uint count, float clamp_d2) {
    vec3 e = vec3(0.0);
    for (uint i = k; i < count; i += SUBSETS) e += vpl_irradiance(p, n, vpls[i], clamp_d2);
    return e * float(SUBSETS);
}
#endif
