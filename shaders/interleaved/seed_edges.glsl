// The seed's edge detection (its EdgeDetectionPass; seed_blur.comp and, for the debug view, the
// lighting pass): a pixel is an edge when a 4-neighbour on the screen has no surface, a normal
// more than ~25 degrees off (dot < 0.9), or a distance from the camera more than 2% off: depth and
// normal, as the seed's, with the thresholds of `ours` (filter.glsl) so that the two compare.
// Needs g_position, g_normal (camera-relative position, w > 0 where a surface was drawn) and
// on_screen().
#ifndef SEED_EDGES_GLSL
#define SEED_EDGES_GLSL
bool seed_edge(ivec2 px) {
    vec4 p = texelFetch(g_position, px, 0);
    if (p.w <= 0.0) return true;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    float d = length(p.xyz);
    const ivec2 around[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
    for (int k = 0; k < 4; ++k) {
        ivec2 q = px + around[k];
        if (!on_screen(q)) continue;
        vec4 pq = texelFetch(g_position, q, 0);
        if (pq.w <= 0.0) return true;
        if (dot(n, texelFetch(g_normal, q, 0).xyz) < 0.9) return true;
        if (abs(length(pq.xyz) - d) > 0.02 * d) return true;
    }
    return false;
}
#endif
