// `interleaved`'s light subsets: subset k of the M x N (TILE_M x TILE_N) sub-images is the k-th
// contiguous block of count / (M N) VPLs (count is a multiple of M N). The VPLs are the seeded
// Halton (2, 3) points in order, and any block of consecutive Halton points is stratified over the
// whole map (64 consecutive indices take every residue mod 64: one point in each 1/64 column), so
// each subset spreads over the whole map. (A stride, every (M N)-th VPL from the k-th, is not:
// indices equal mod 16 share the first four binary digits of their base-2 radical inverse, so such
// a subset lies in one 1/16 strip of the map; crates/cbr-render/src/techniques/interleaved/mod.rs,
// `subset_range`, and its test.) Its irradiance times M N estimates that of all the VPLs. Needs
// `vpls` and shading.glsl's vpl_irradiance.
//
// With DIRECT (`direct`) the point lights are shaded in subsets too: the scene's point lights
// (lights[dirs + j], j < scene) then the extra ones (points[j - scene]), light j in subset
// j mod (M N) (a stride: the lights are random, not a low-discrepancy pattern, and any count
// works), times M N; their diffuse term n.l E joins the VPLs' irradiance and their specular term
// (n.h)^ns n.l E is estimated apart (shading.glsl, add_light_terms). Needs `lights` and `points`.
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
    uint size = count / SUBSETS;
    vec3 e = vec3(0.0);
    // The uniform part, then the rest (inc/light_buffers.glsl).
    uint end = (k + 1u) * size;
    for (uint i = k * size; i < min(end, UNIFORM_VPLS); ++i) {
        e += vpl_irradiance(p, n, vpls[i], clamp_d2);
    }
    for (uint i = max(k * size, UNIFORM_VPLS); i < end; ++i) {
        e += vpl_irradiance(p, n, more_vpls[i - UNIFORM_VPLS], clamp_d2);
    }
    return e * float(SUBSETS);
}

#ifdef DIRECT
// Adds subset k of the point lights, times M N, to `diffuse` and `specular` at p (normal n,
// specular exponent ns) seen from the camera at the origin; `counts`: directional lights, the
// scene's point lights, extra point lights.
void subset_direct(inout vec3 diffuse, inout vec3 specular, vec3 p, vec3 n, float ns, uint k,
                   uvec3 counts) {
    vec3 v = normalize(-p);
    vec3 d = vec3(0.0);
    vec3 s = vec3(0.0);
    // Two loops over the one sequence j = k, k + M N, ...: the scene's lights, then the extra
    // ones from the first such j past them (one loop with an if/else would evaluate both light
    // terms for every light on SIMD hardware that runs both sides of a branch, as llvmpipe does).
    // Each list's uniform part, then its rest (inc/light_buffers.glsl).
    uint j = k;
    for (; j < counts.y && counts.x + j < UNIFORM_LIGHTS; j += SUBSETS) {
        add_light_terms(d, s, p, n, v, ns, lights[counts.x + j]);
    }
    for (; j < counts.y; j += SUBSETS) {
        add_light_terms(d, s, p, n, v, ns, more_lights[counts.x + j - UNIFORM_LIGHTS]);
    }
    for (; j < counts.y + counts.z && j - counts.y < UNIFORM_LIGHTS; j += SUBSETS) {
        add_light_terms(d, s, p, n, v, ns, points[j - counts.y]);
    }
    for (; j < counts.y + counts.z; j += SUBSETS) {
        add_light_terms(d, s, p, n, v, ns, more_points[j - counts.y - UNIFORM_LIGHTS]);
    }
    diffuse += d * float(SUBSETS);
    specular += s * float(SUBSETS);
}
#endif
#endif
