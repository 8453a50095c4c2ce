#version 460
#extension GL_GOOGLE_include_directive : require
// `--resolve none`: the raw checkerboard frame at full resolution, read through the layout fetch
// include. Missing pixels: colour (0,0,0,0), depth 0 (infinitely far), IDs 0, mask 0.
#include "../inc/layout_fetch.glsl"

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_COLOR) uniform CB_SAMPLER color_tex;
layout(set = 0, binding = BINDING_VELOCITY) uniform CB_SAMPLER velocity_tex;
layout(set = 0, binding = BINDING_IDS) uniform CB_USAMPLER ids_tex;
layout(set = 0, binding = BINDING_DEPTH) uniform CB_SAMPLER depth_tex;

struct Pixel {
    vec4 color;
    vec4 velocity_depth_mask;  // xy: velocity, z: reverse-Z depth, w: 1 if shaded this frame
    uvec4 ids;                 // xy: object, primitive
};
layout(std430, set = 0, binding = BINDING_OUT) writeonly buffer Out { Pixel pixels[]; };

PUSH_CONSTANTS  // size_parity_side: W, H, parity, tangram L

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = pc.size_parity_side.xy;
    if (p.x >= size.x || p.y >= size.y) return;
    ivec4 a = cb_address(p, pc.size_parity_side.z, pc.size_parity_side.w);
    Pixel px;
    if (a.x < 0) {
        px.color = vec4(0.0);
        px.velocity_depth_mask = vec4(0.0);
        px.ids = uvec4(0u);
    } else {
        // Every sample of this parity is rendered, the sky included (its clear colour).
        px.color = vec4(cb_fetch(color_tex, a).rgb, 1.0);
        px.velocity_depth_mask = vec4(cb_fetch(velocity_tex, a).xy, cb_fetch(depth_tex, a).x, 1.0);
        px.ids = uvec4(cb_fetch(ids_tex, a).xy, 0u, 0u);
    }
    pixels[p.y * size.x + p.x] = px;
}
