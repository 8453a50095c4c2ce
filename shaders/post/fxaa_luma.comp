#version 460
// `+fxaa`, first pass: display-space luma of every pixel, once (shaders/post/fxaa.comp reads it
// for every tap). Same function as the CPU reference's `luma` (crates/cbr-render/src/post/fxaa.rs).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = BINDING_SRC) uniform sampler2D src;
layout(set = 0, binding = BINDING_LUMA_OUT, r32f) uniform writeonly image2D luma_out;
layout(push_constant) uniform Push { ivec4 size; vec4 params; } pc;  // params.w: 2^exposure

#include "fxaa_luma.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, pc.size.xy))) return;
    imageStore(luma_out, p, vec4(luma(texelFetch(src, p, 0).rgb, pc.params.w)));
}
