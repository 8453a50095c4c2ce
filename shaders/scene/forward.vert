#version 460
#extension GL_GOOGLE_include_directive : require
// Scene raster, vertex stage: vertices pulled from a storage buffer (8 floats each).
#include "../inc/scene_types.glsl"

layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_VERTICES) readonly buffer Vertices { float vdata[]; };
layout(push_constant) uniform Push { uint object_index; } pc;

layout(location = 0) out vec3 v_world;   // camera-relative world position
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_uv;
layout(location = 3) out vec4 v_clip;       // unjittered, this frame
layout(location = 4) out vec4 v_prev_clip;  // previous frame

void main() {
    uint b = uint(gl_VertexIndex) * 8u;
    vec4 local = vec4(vdata[b], vdata[b + 1], vdata[b + 2], 1.0);
    vec3 n = vec3(vdata[b + 3], vdata[b + 4], vdata[b + 5]);
    ObjectData o = objects[pc.object_index];
    v_world = (o.world_from_local * local).xyz;
    v_normal = mat3(o.normal_from_local) * n;
    v_uv = vec2(vdata[b + 6], vdata[b + 7]);
    v_clip = o.clip_from_local * local;
    v_prev_clip = o.prev_clip_from_local * local;
    vec4 pos = v_clip;
    // A jitter of j pixels moves NDC by 2j / size.
    pos.xy += frame.jitter.xy * 2.0 * frame.viewport.zw * pos.w;
    gl_Position = pos;
}
