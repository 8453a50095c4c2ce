// The full-resolution depth, velocity and IDs of every upscale filter (upscale.comp,
// easu.comp): the nearest low-resolution sample; velocity rescaled to full-resolution pixels.
// Needs PUSH_CONSTANTS' sizes (W, H, w, h) declared first.

layout(set = 0, binding = BINDING_VELOCITY) uniform sampler2D low_velocity;
layout(set = 0, binding = BINDING_IDS) uniform usampler2D low_ids;
layout(set = 0, binding = BINDING_DEPTH) uniform sampler2D low_depth;
layout(set = 0, binding = BINDING_OUT_VELOCITY, rg32f) uniform writeonly image2D out_velocity;
layout(set = 0, binding = BINDING_OUT_IDS, rg32ui) uniform writeonly uimage2D out_ids;
layout(set = 0, binding = BINDING_OUT_DEPTH, r32f) uniform writeonly image2D out_depth;

// `scale`: low / full resolution per axis.
void write_geometry(ivec2 p, vec2 scale) {
    vec2 q = (vec2(p) + 0.5) * scale;
    ivec2 n = clamp(ivec2(floor(q)), ivec2(0), pc.sizes.zw - 1);
    imageStore(out_velocity, p, vec4(texelFetch(low_velocity, n, 0).xy / scale, 0.0, 0.0));
    imageStore(out_ids, p, texelFetch(low_ids, n, 0));
    imageStore(out_depth, p, vec4(texelFetch(low_depth, n, 0).x));
}
