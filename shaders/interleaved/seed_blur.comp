#version 460
#extension GL_GOOGLE_include_directive : require
// `interleaved:MxN:seed`: the seed's filter (Segovia et al. 2006 as the seed reproduces it), one
// direction per dispatch: HORIZONTAL reads the gathered estimates and writes seed_tmp, otherwise it
// reads seed_tmp and writes seed_out, which the lighting pass reads. Edge pixels (seed_edges.glsl)
// keep their own subset's estimate (the seed's noisy edge lines) and are skipped as taps, as are
// pixels without a surface; the others take a Gaussian over offsets -(P-1) .. P-1 along the
// direction (P = M, then N), sigma P / 2, weights renormalised over the taps used. The alpha
// channel carries the gather's flags of the pixel through both directions: the round trip (1)
// and the seed's edge test (2), computed once per pixel by the gather (or implicit) pass.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"
#include "interleave.glsl"

#ifdef BINDING_SEED_TMP
layout(set = 0, binding = BINDING_SEED_TMP, rgba32f) uniform image2D seed_tmp;
#endif
#ifdef BINDING_SEED_OUT
layout(set = 0, binding = BINDING_SEED_OUT, rgba32f) uniform image2D seed_out;
#endif
// DIRECT: the specular estimates, blurred with the same taps and weights.
#ifdef BINDING_SEED_TMP_SPECULAR
layout(set = 0, binding = BINDING_SEED_TMP_SPECULAR, rgba32f) uniform image2D seed_tmp_spec;
#endif
#ifdef BINDING_SEED_OUT_SPECULAR
layout(set = 0, binding = BINDING_SEED_OUT_SPECULAR, rgba32f) uniform image2D seed_out_spec;
#endif


#ifdef HORIZONTAL
#define PERIOD TILE_M
#define STEP ivec2(1, 0)
vec4 load(ivec2 q) { return imageLoad(irradiance, q); }
void store(ivec2 q, vec4 v) { imageStore(seed_tmp, q, v); }
#ifdef DIRECT
vec3 load_spec(ivec2 q) { return imageLoad(specular, q).rgb; }
void store_spec(ivec2 q, vec3 v) { imageStore(seed_tmp_spec, q, vec4(v, 0.0)); }
#endif
#else
#define PERIOD TILE_N
#define STEP ivec2(0, 1)
vec4 load(ivec2 q) { return imageLoad(seed_tmp, q); }
void store(ivec2 q, vec4 v) { imageStore(seed_out, q, v); }
#ifdef DIRECT
vec3 load_spec(ivec2 q) { return imageLoad(seed_tmp_spec, q).rgb; }
void store_spec(ivec2 q, vec3 v) { imageStore(seed_out_spec, q, vec4(v, 0.0)); }
#endif
#endif

bool edge(vec4 v) { return (int(v.a) & 2) != 0; }

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (!on_screen(px)) return;
    vec4 own = load(px);
    if (edge(own)) {
        store(px, own);
#ifdef DIRECT
        store_spec(px, load_spec(px));
#endif
        return;
    }
    float sigma = 0.5 * float(PERIOD);
    vec3 sum = vec3(0.0);
    vec3 sum_spec = vec3(0.0);
    float weights = 0.0;
    for (int d = -(PERIOD - 1); d <= PERIOD - 1; ++d) {
        ivec2 q = px + d * STEP;
        if (!on_screen(q)) continue;
        vec4 v = load(q);
        if (edge(v)) continue;
        float w = exp(-float(d * d) / (2.0 * sigma * sigma));
        sum += w * v.rgb;
#ifdef DIRECT
        sum_spec += w * load_spec(q);
#endif
        weights += w;
    }
    store(px, vec4(sum / weights, own.a));
#ifdef DIRECT
    store_spec(px, sum_spec / weights);
#endif
}
