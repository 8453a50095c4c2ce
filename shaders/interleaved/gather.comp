#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved.gather`: the sub-images' estimates back to their pixels (the inverse of the split);
// with DIRECT the specular estimates too. With BOX_ROWS (`box`) each pixel's window row summed
// instead (below).
// The alpha channel holds flags (as a float): 1 with DEBUG where the split G-buffer gathered back the
// same way differs from the G-buffer (position and normal, bit for bit: gather(split(x)) == x at
// every pixel), + 2 with SEED where the pixel is an edge by the seed's test (seed_edges.glsl), which
// the seed's blur then reads once per tap.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"
#ifdef SEED
#include "seed_edges.glsl"
#endif

// DEBUG: 1 where split texel s does not hold pixel q's position and normal bit for bit, else 0.
float roundtrip_flag(ivec2 q, uint s) {
#ifdef DEBUG
    bool same = all(equal(floatBitsToUint(s_position[s]),
                          floatBitsToUint(texelFetch(g_position, q, 0)))) &&
                all(equal(floatBitsToUint(s_normal[s]),
                          floatBitsToUint(texelFetch(g_normal, q, 0))));
    return same ? 0.0 : 1.0;
#else
    return 0.0;
#endif
}

// Pixel q's estimate from split texel s, with its flags.
void gather(ivec2 q, uint s) {
    vec4 e = s_irradiance[s];
    e.a = roundtrip_flag(q, s);
#ifdef SEED
    if (seed_edge(q)) e.a += 2.0;
#endif
    imageStore(irradiance, q, e);
#ifdef DIRECT
    imageStore(specular, q, s_specular[s]);
#endif
}

#ifdef BOX_ROWS
// `box` (BOX_ROWS): pixel (x, y) gets the sum of the estimates of the on-screen pixels of its
// window's row, x - (M-1)/2 .. x + M/2, in that order; the lighting pass then adds the window's
// rows (filter.glsl). Invocation (t, y) reads the 2M - 1 texels its M pixels' rows span.
const int ROW_LO = -(TILE_M - 1) / 2;
const int SPAN = 2 * TILE_M - 1;

void main() {
    int t = int(gl_GlobalInvocationID.x);
    int y = int(gl_GlobalInvocationID.y);
    if (t >= pc.size.z || y >= pc.size.y) return;
    vec3 e[SPAN];
#ifdef DIRECT
    vec3 sp[SPAN];
#endif
    for (int j = 0; j < SPAN; ++j) {
        int x = t * TILE_M + ROW_LO + j;
        bool on = x >= 0 && x < pc.size.x;
        int xc = clamp(x, 0, pc.size.x - 1);  // an address inside the mosaic for every lane
        int tc = xc / TILE_M;
        uint s = row_word(tc, y, xc - tc * TILE_M);
        e[j] = on ? s_irradiance[s].rgb : vec3(0.0);
#ifdef DIRECT
        sp[j] = on ? s_specular[s].rgb : vec3(0.0);
#endif
    }
    for (int i = 0; i < TILE_M; ++i) {
        ivec2 q = ivec2(t * TILE_M + i, y);
        if (q.x >= pc.size.x) continue;
        vec3 sum = vec3(0.0);
#ifdef DIRECT
        vec3 sum_spec = vec3(0.0);
#endif
        for (int o = 0; o < TILE_M; ++o) {
            sum += e[i + o];
#ifdef DIRECT
            sum_spec += sp[i + o];
#endif
        }
        imageStore(irradiance, q, vec4(sum, roundtrip_flag(q, row_word(t, y, i))));
#ifdef DIRECT
        imageStore(specular, q, vec4(sum_spec, 0.0));
#endif
    }
}
#else
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
#endif
