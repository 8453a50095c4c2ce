#version 460
#extension GL_GOOGLE_include_directive : require
// `deferred`'s lighting pass: per pixel, the G-buffer's surface (written by the forward fragment
// shader with GBUFFER: the same position, shading normal and albedo bits it would shade) through
// the forward pass's `shade` (shaders/inc/shading.glsl), then the extra point lights
// (`points=N`) through the same light term, then the one-bounce indirect light of the VPLs
// (`vpls=N`): albedo x their summed irradiance (with INTERLEAVED, `interleaved`'s filtered
// estimate instead: shaders/interleaved/filter.glsl; with DIRECT the point lights' too, the pass
// then shading the directional lights only). NaN/Inf shading is written black and
// counted, as the forward pass does; background pixels get the background radiance.
layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;
#include "../inc/scene_types.glsl"

layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = BINDING_LIGHTS) readonly buffer Lights { LightData lights[]; };
layout(std430, set = 0, binding = BINDING_POINTS) readonly buffer Points { LightData points[]; };
layout(std430, set = 0, binding = BINDING_VPLS) readonly buffer Vpls { Vpl vpls[]; };
layout(std430, set = 0, binding = BINDING_COUNTER) buffer Counter {
    uint shaded_fragments;
    uint nonfinite_fragments;
};
layout(set = 0, binding = BINDING_POSITION) uniform sampler2D g_position;
layout(set = 0, binding = BINDING_NORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = BINDING_ALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = BINDING_IDS) uniform usampler2D g_ids;
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;

// background.rgb: radiance where nothing was drawn; counts: x extra point lights, y VPLs, zw
// width, height; params.x: the VPL clamp c in 1/max(d^2, c) (m^2).
PUSH_CONSTANTS

#include "../inc/shading.glsl"
#ifdef INTERLEAVED
#include "../interleaved/filter.glsl"
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(pc.counts.z) || px.y >= int(pc.counts.w)) return;
#if defined(INTERLEAVED) && defined(DEBUG)
    imageStore(debug_bits, px, uvec4(0u));
#endif
    uint object = texelFetch(g_ids, px, 0).x;
    if (object == 0u) {
        imageStore(out_color, px, vec4(pc.background.rgb, 1.0));
        return;
    }
    vec3 p = texelFetch(g_position, px, 0).xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 albedo = texelFetch(g_albedo, px, 0).rgb;
    if ((frame.counts.w & FLAG_DEBUG_LOD) != 0u) {
        imageStore(out_color, px, vec4(albedo.r, 0.0, 0.0, 1.0));
        return;
    }
    MaterialData m = materials[objects[object - 1u].ids.y];
#ifdef DIRECT
    // `interleaved:...:direct`: the point lights come filtered with the VPLs, below.
    vec3 c = shade_lights(p, n, albedo, m, frame, frame.counts.x);
#else
    vec3 c = shade(p, n, albedo, m, frame);
    vec3 v = normalize(-p);
    for (uint i = 0u; i < pc.counts.x; ++i) add_light(c, p, n, v, albedo, m, points[i]);
#endif
    if (pc.counts.y > 0u) {
#ifdef INTERLEAVED
        // `interleaved`: the filtered sub-image estimates, then (as below) times albedo; with
        // DIRECT the point lights' diffuse term is in them, and their specular term comes apart.
        uint bits;
        vec3 spec;
        c += albedo * interleaved_irradiance(px, object, p, n, m.ks.w, bits, spec);
#ifdef DIRECT
        c += m.ks.rgb * spec;
#endif
#ifdef DEBUG
        if ((int(texelFetch(g_irradiance, px, 0).a) & 1) != 0) bits |= DBG_ROUNDTRIP;
        imageStore(debug_bits, px, uvec4(bits));
#endif
#else
        vec3 e = vec3(0.0);
        for (uint i = 0u; i < pc.counts.y; ++i) e += vpl_irradiance(p, n, vpls[i], pc.params.x);
        c += albedo * e;
#endif
    }
    // NaN/Inf containment and the fp16 clamp, as in shaders/scene/forward.frag.
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
        atomicAdd(nonfinite_fragments, 1u);
    }
    imageStore(out_color, px, vec4(min(c, vec3(65504.0)), 1.0));
    if ((frame.counts.w & FLAG_COUNT_SHADED) != 0u) atomicAdd(shaded_fragments, 1u);
}
