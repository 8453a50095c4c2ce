#version 460
// `ssaa:N`: adds one sub-pixel sample's raster (colour and IDs at native resolution) into the
// fp32 accumulation (MODE_ACCUMULATE), or divides the sum by the sample count into the RGBA16F
// output (MODE_RESOLVE). Coverage: aux.x = the first sample's object ID; aux.y = samples on
// geometry, bit 31 set once a sample shows another object ID than the first (an edge pixel).
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform sampler2D color;
layout(set = 0, binding = BINDING_IDS) uniform usampler2D ids;
layout(set = 0, binding = BINDING_ACCUM, rgba32f) uniform image2D accum;
layout(set = 0, binding = BINDING_AUX, rg32ui) uniform uimage2D aux;
layout(set = 0, binding = BINDING_OUT, rgba16f) uniform writeonly image2D outc;
// size_sample_mode: x, y: size; z: the sample's index (0 starts the sum); w: 0 accumulate,
// 1 resolve. samples.x: the number of samples. EDGE: a define from crates/cbr-render/src/techniques/ssaa.rs.
PUSH_CONSTANTS

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size_sample_mode.xy))) return;
    if (pc.size_sample_mode.w == 1) {
        // Division, not a multiply by the reciprocal: ssaa:1 must equal native bit for bit, and
        // x / 1 is exact.
        imageStore(outc, p, imageLoad(accum, p) / pc.samples.x);
        return;
    }
    vec4 c = texelFetch(color, p, 0);
    uint id = texelFetch(ids, p, 0).x;
    uint hit = id != 0u ? 1u : 0u;
    if (pc.size_sample_mode.z == 0) {
        imageStore(accum, p, c);
        imageStore(aux, p, uvec4(id, hit, 0u, 0u));
    } else {
        imageStore(accum, p, imageLoad(accum, p) + c);
        uvec2 a = imageLoad(aux, p).xy;
        uint edge = (a.y & EDGE) | (id != a.x ? EDGE : 0u);
        imageStore(aux, p, uvec4(a.x, ((a.y & ~EDGE) + hit) | edge, 0u, 0u));
    }
}
