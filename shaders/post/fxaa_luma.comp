#version 460
// `+fxaa`, first pass: display-space luma of every pixel, once (shaders/post/fxaa.comp reads it
// for every tap). Same function as the CPU reference's `luma` (crates/cbr-render/src/post/fxaa.rs).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_SRC) uniform sampler2D src;
layout(set = 0, binding = BINDING_LUMA, r32f) uniform writeonly image2D luma_out;
PUSH_CONSTANTS  // size; params.w: 2^exposure

#include "fxaa_luma.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size.xy))) return;
    imageStore(luma_out, p, vec4(luma(texelFetch(src, p, 0).rgb, pc.params.w)));
}
