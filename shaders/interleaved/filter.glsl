// `interleaved`'s filter, in the lighting pass (deferred/lighting.comp with INTERLEAVED): the
// VPLs' irradiance at pixel p from the gathered sub-image estimates of the M x N window around p,
// offsets -(M-1)/2 .. M/2 (and likewise for N): one pixel of each subset. FILTER 0: p's own
// estimate (no filter); 1: the window's mean; 2 (ours): the window's mean where a neighbour that
// is not on p's surface (another object, a normal more than ~25 degrees off, or off p's tangent
// plane by more than 2% of p's distance) is replaced by its subset shaded at p itself. On a
// smooth surface that is the box; at an edge, p shades the subsets its surface lacks (DESIGN.md);
// where every neighbour is rejected, p gets every VPL, the reference.
layout(set = 0, binding = BINDING_IRRADIANCE) uniform sampler2D g_irradiance;

#define SAME_NORMAL_COS 0.9
#define PLANE_TOLERANCE 0.02

#include "../interleaved/subsets.glsl"

bool on_screen(ivec2 q) {
    return q.x >= 0 && q.y >= 0 && q.x < int(pc.counts.z) && q.y < int(pc.counts.w);
}

bool same_surface(ivec2 q, uint object, vec3 p, vec3 n) {
    if (texelFetch(g_ids, q, 0).x != object) return false;
    vec3 nq = texelFetch(g_normal, q, 0).xyz;
    vec3 pq = texelFetch(g_position, q, 0).xyz;
    return dot(n, nq) >= SAME_NORMAL_COS && abs(dot(n, pq - p)) <= PLANE_TOLERANCE * length(p);
}

vec3 interleaved_irradiance(ivec2 px, uint object, vec3 p, vec3 n) {
#if FILTER == 0
    return texelFetch(g_irradiance, px, 0).rgb;
#else
    vec3 sum = vec3(0.0);
    for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
        for (int ox = -(TILE_M - 1) / 2; ox <= TILE_M / 2; ++ox) {
            ivec2 q = px + ivec2(ox, oy);
            bool use = on_screen(q);
#if FILTER == 2
            use = use && same_surface(q, object, p, n);
#endif
            if (use) {
                sum += texelFetch(g_irradiance, q, 0).rgb;
            } else {
                sum += subset_irradiance(p, n, subset_of(q), pc.counts.y, pc.params.x);
            }
        }
    }
    return sum / float(SUBSETS);
#endif
}
