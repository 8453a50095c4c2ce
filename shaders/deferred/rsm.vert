#version 460
#extension GL_GOOGLE_include_directive : require
// `deferred`'s reflective shadow map (Dachsbacher & Stamminger 2005), vertex stage: the scene seen
// from the sun, an orthographic projection along the first directional light framing the scene.
#include "../inc/scene_types.glsl"
#include "rsm.glsl"

layout(std430, set = SET_SCENE, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = SET_SCENE, binding = BINDING_VERTICES) readonly buffer Vertices { float vdata[]; };

layout(location = 0) out vec3 v_world;  // camera-relative world position
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_uv;

void main() {
    uint b = uint(gl_VertexIndex) * 8u;
    vec4 local = vec4(vdata[b], vdata[b + 1], vdata[b + 2], 1.0);
    vec3 n = vec3(vdata[b + 3], vdata[b + 4], vdata[b + 5]);
    ObjectData o = objects[pc.object_index];
    v_world = (o.world_from_local * local).xyz;
    v_normal = mat3(o.normal_from_local) * n;
    v_uv = vec2(vdata[b + 6], vdata[b + 7]);
    gl_Position = pc.clip_from_world * vec4(v_world, 1.0);
}
