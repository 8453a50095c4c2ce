#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.gather`: the sub-images' estimates back to their pixels (the inverse of the split);
// with DIRECT the specular estimates too.
// The alpha channel holds flags (as a float): 1 with DEBUG where the split G-buffer gathered back the
// same way differs from the G-buffer (position and normal, bit for bit: gather(split(x)) == x at
// every pixel), + 2 with SEED where the pixel is an edge by the seed's test (seed_edges.glsl), which
// the seed's blur then reads once per tap.
layout(local_size_x = 64, local_size_y = 1) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
#ifdef SEED
#include "seed_edges.glsl"
#endif

// Pixel q's estimate from split texel s, with its flags.
void gather(ivec2 q, uint s) {
    vec4 e = s_irradiance[s];
    e.a = 0.0;
#ifdef DEBUG
    bool same = all(equal(floatBitsToUint(s_position[s]),
                          floatBitsToUint(texelFetch(g_position, q, 0)))) &&
                all(equal(floatBitsToUint(s_normal[s]),
                          floatBitsToUint(texelFetch(g_normal, q, 0))));
    e.a = same ? 0.0 : 1.0;
#endif
#ifdef SEED
    if (seed_edge(q)) e.a += 2.0;
#endif
    imageStore(irradiance, q, e);
#ifdef DIRECT
    imageStore(specular, q, s_specular[s]);
#endif
}

void main() {
    // Invocation (t, y): pixels (t M + i, y), i = 0 .. M-1, from their texels (row_word).
    int t = int(gl_GlobalInvocationID.x);
    int y = int(gl_GlobalInvocationID.y);
    if (t >= pc.size.z || y >= pc.size.y) return;
    for (int i = 0; i < TILE_M; ++i) {
        ivec2 q = ivec2(t * TILE_M + i, y);
        if (q.x < pc.size.x) gather(q, row_word(t, y, i));
    }
}
