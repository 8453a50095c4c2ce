#version 460
#extension GL_GOOGLE_include_directive : require
// taau pass 1 (FSR 2's "reconstruct and dilate"; docs/upsampling.md; CPU reference `dilate` in
// crates/cbr-render/src/techniques/taau/reference.rs), one render pixel per invocation: the
// velocity and depth of the nearest (largest reverse-Z) texel of the 3x3 (SURFACE_VELOCITY: the
// pixel's own velocity where the 3x3 is one plane, as `+taa`'s), and, with the depth
// clip, the reconstructed previous depth: the dilated depth scattered (atomic max: the nearest
// wins, in any order) into those of the 2x2 texels around where the pixel was last frame whose
// bilinear weight there exceeds 0.05; and the
// prepared colour the later passes read (FSR 2 prepares it in its depth-clip pass): the
// perceptual colour (inc/perceptual.glsl), w 1, or 0 where the colour is not finite.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(set = 0, binding = BINDING_DEPTH) uniform sampler2D depth;
layout(set = 0, binding = BINDING_VELOCITY) uniform sampler2D velocity;
layout(set = 0, binding = BINDING_COLOR) uniform sampler2D color;
layout(set = 0, binding = BINDING_DILATED, rgba32f) uniform writeonly image2D dilated;
layout(set = 0, binding = BINDING_PREPARED, rgba32f) uniform writeonly image2D prepared;
#ifdef BINDING_RECON
layout(set = 0, binding = BINDING_RECON) buffer Recon { uint recon[]; };
#endif

#include "common.glsl"

const float RECON_WEIGHT = 0.05;
#include "../inc/perceptual.glsl"
#include "../inc/plane.glsl"

void main() {
    ivec2 i = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = pc.sizes.zw;
    if (!inside(i, size)) return;
    float best = -1.0;
    ivec2 at = i;
    float nd[9];
    for (int k = 0; k < 9; k++) {
        ivec2 t = clamp(i + OFF[k], ivec2(0), size - 1);
        float d = texelFetch(depth, t, 0).r;
        nd[k] = d;
        if (d > best) {
            best = d;
            at = t;
        }
    }
#if SURFACE_VELOCITY
    // A surface (the 3x3 one plane within the depth tolerance, inc/plane.glsl) keeps its own
    // velocity: dilation is for silhouettes, and a receding floor's nearest texel, the one
    // below, moves faster; the history was fetched that far off every frame. The depth stays
    // the nearest (the depth clip's).
    if (depth_plane(nd, pc.params.y)) at = i;
#endif
    vec2 v = texelFetch(velocity, at, 0).xy;
    imageStore(dilated, i, vec4(v, best, 0.0));
    vec3 c = texelFetch(color, i, 0).rgb;
    imageStore(prepared, i, finite3(c) ? vec4(perceptual(c, pc.params.x), 1.0) : vec4(0.0));
#ifdef BINDING_RECON
    vec2 g = vec2(i) + 0.5 - v - 0.5;
    ivec2 b = ivec2(floor(g));
    vec2 f = g - vec2(b);
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 t = b + o;
        // Only the texels the bilinear read gives weight (FSR 2's threshold 0.05): a still
        // pixel lands on its own texel alone, not on its neighbours'.
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        if (inside(t, size) && w > RECON_WEIGHT) atomicMax(recon[t.y * size.x + t.x], floatBitsToUint(best));
    }
#endif
}
