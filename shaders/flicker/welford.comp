#version 460
// `flicker`: one step of Welford's running mean and variance of each pixel's luminance
// (crates/cbr-render/src/techniques/flicker.rs). History texel: (frames, mean, M2, unused).
// A luminance that is not finite leaves the history as it was: NaN and Inf never enter it.

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform sampler2D color;
layout(set = 0, binding = BINDING_HIST, rgba32f) uniform readonly image2D hist;
layout(set = 0, binding = BINDING_OUT_HIST, rgba32f) uniform writeonly image2D out_hist;
PUSH_CONSTANTS

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size))) {
        return;
    }
    vec4 h = pc.reset != 0u ? vec4(0.0) : imageLoad(hist, p);
    float y = dot(texelFetch(color, p, 0).rgb, vec3(0.2126, 0.7152, 0.0722));
    if (!isnan(y) && !isinf(y)) {
        float n = h.x + 1.0;
        float d = y - h.y;
        float mean = h.y + d / n;
        h = vec4(n, mean, h.z + d * (y - mean), 0.0);
    }
    imageStore(out_hist, p, h);
}
