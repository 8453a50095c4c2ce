#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_demote_to_helper_invocation : require
// `deferred`'s reflective shadow map, fragment stage: per texel the first surface the sun meets,
// its normal turned towards the sun (double-sided, as the forward pass turns it to the camera),
// and the flux it reflects: albedo x the sun's irradiance x the texel's area (the area across the
// beam, whatever the surface's slope). Alpha-tested like the forward pass; no bump mapping.
#include "../inc/scene_types.glsl"
#include "rsm.glsl"

layout(std430, set = SET_SCENE, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = SET_SCENE, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
#define LIGHTS_SET SET_SCENE
#include "../inc/light_buffers.glsl"
layout(set = SET_MATERIAL, binding = BINDING_ALBEDO) uniform sampler2D albedo_tex;
layout(set = SET_MATERIAL, binding = BINDING_MASK) uniform sampler2D mask_tex;

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_uv;

layout(location = 0) out vec4 o_position;  // xyz: camera-relative world position; w: 1 (0: empty)
layout(location = 1) out vec4 o_normal;    // xyz: unit normal facing the sun
layout(location = 2) out vec4 o_flux;      // rgb: reflected flux of the texel

void main() {
    MaterialData m = materials[objects[pc.object_index].ids.y];
    if (m.tex.y >= 0 && texture(mask_tex, v_uv)[m.tex.z] < 0.5) demote;
    vec3 albedo = m.kd.rgb;
    if (m.tex.x >= 0) albedo *= texture(albedo_tex, v_uv).rgb;
    vec3 n = normalize(v_normal);
    if (dot(n, pc.sun.xyz) > 0.0) n = -n;
    o_position = vec4(v_world, 1.0);
    o_normal = vec4(n, 0.0);
    // The sun is lights[0]: directional lights come first.
    o_flux = vec4(albedo * lights[0].color.rgb * pc.sun.w, 0.0);
}
