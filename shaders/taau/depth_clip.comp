#version 460
#extension GL_GOOGLE_include_directive : require
// taau pass 2 (FSR 2's "depth clip"; docs/upsampling.md; CPU reference `depth_clip`), one render
// pixel per invocation: how far the history at the pixel's previous position shows another,
// nearer surface (a disocclusion: 1 drops the history). The reconstructed previous depth is read
// bilinearly at the previous position; each texel holding a surface nearer than the pixel's by
// more than the tolerance (relative, in linear depth) keeps sep / diff of its weight. Off screen
// last frame: 1. Nothing drawn here (depth 0): 0.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_DILATED) uniform sampler2D dilated;
layout(set = 0, binding = BINDING_RECON) readonly buffer Recon { uint recon[]; };
layout(set = 0, binding = BINDING_DISOCCLUSION, r32f) uniform writeonly image2D disocclusion;

#include "common.glsl"

void main() {
    ivec2 i = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = pc.sizes.zw;
    if (!inside(i, size)) return;
    vec4 g = texelFetch(dilated, i, 0);
    float d = g.z;
    float dis = 0.0;
    if (d > 0.0) {
        vec2 q = vec2(i) + 0.5 - g.xy;
        if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, vec2(size)))) {
            dis = 1.0;
        } else {
            vec2 gq = q - 0.5;
            ivec2 b = ivec2(floor(gq));
            vec2 f = gq - vec2(b);
            float keep = 0.0, ws = 0.0;
            for (int k = 0; k < 4; k++) {
                ivec2 o = ivec2(k & 1, k >> 1);
                ivec2 t = b + o;
                float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
                if (!inside(t, size) || w <= 0.0) continue;
                float pd = uintBitsToFloat(recon[t.y * size.x + t.x]);
                float kept = 1.0;
                if (pd > d) {
                    // Linear depths 1 / d and 1 / pd (the near plane cancels in the ratio).
                    float z = 1.0 / d;
                    float diff = z - 1.0 / pd;
                    float sep = pc.params.y * z;
                    if (diff > sep) kept = sep / diff;
                }
                keep += w * kept;
                ws += w;
            }
            dis = ws > 0.0 ? 1.0 - keep / ws : 0.0;
        }
    }
    imageStore(disocclusion, i, vec4(dis));
}
