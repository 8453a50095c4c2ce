#version 460
#extension GL_GOOGLE_include_directive : require
// taau pass 3 (FSR 2's "create locks"; docs/upsampling.md; CPU reference `lock`), one render
// pixel per invocation: a thin feature is a pixel whose perceptual luma is a ridge (above or
// below every neighbour not similar to it; similar: ratio under 1.05) with no 2x2 quad around it
// of similar pixels. Its lock is set at the output pixel its (unjittered) sample falls in; the
// accumulation keeps a locked history from rectification.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_PREPARED) uniform sampler2D prepared;
layout(set = 0, binding = BINDING_NEW_LOCKS) writeonly buffer Locks { uint new_locks[]; };

#include "common.glsl"

#include "../inc/thin_feature.glsl"

// The prepared colour's luma (0 where the colour was not finite).
float luma_at(ivec2 t) { return texelFetch(prepared, clamp(t, ivec2(0), pc.sizes.zw - 1), 0).x; }

void main() {
    ivec2 i = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(i, pc.sizes.zw)) return;
    float l[9];
    for (int k = 0; k < 9; k++) l[k] = luma_at(i + OFF[k]);
    if (!thin_feature(l)) return;
    ivec2 p = ivec2(floor((vec2(i) + 0.5 - pc.jitter_ratio.xy) * pc.jitter_ratio.zw));
    p = clamp(p, ivec2(0), pc.sizes.xy - 1);
    new_locks[p.y * pc.sizes.x + p.x] = 1u;
}
