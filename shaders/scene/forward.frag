#version 460
#extension GL_GOOGLE_include_directive : require
// Scene raster, fragment stage: alpha test, bump, lighting; writes colour, velocity and IDs.
#include "../inc/scene_types.glsl"

layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = BINDING_LIGHTS) readonly buffer Lights { LightData lights[]; };
// Per-material set; slots a material does not use hold a 1x1 white texture.
layout(set = 1, binding = BINDING_ALBEDO) uniform sampler2D albedo_tex;
layout(set = 1, binding = BINDING_MASK) uniform sampler2D mask_tex;
layout(set = 1, binding = BINDING_BUMP) uniform sampler2D bump_tex;
layout(push_constant) uniform Push { uint object_index; } pc;

#include "../inc/shading.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_uv;
layout(location = 3) in vec4 v_clip;
layout(location = 4) in vec4 v_prev_clip;

layout(location = 0) out vec4 o_color;     // HDR radiance; alpha 1 = shaded this frame
layout(location = 1) out vec2 o_velocity;  // pixels moved since the previous frame (current - previous)
layout(location = 2) out uvec2 o_ids;      // x: object ID, y: primitive ID within the object

vec2 to_pixels(vec4 clip) {
    return (clip.xy / clip.w * 0.5 + 0.5) * frame.viewport.xy;
}

// Bump mapping from a height map without tangents (Mikkelsen 2010, screen-space derivatives).
vec3 bump(vec3 n, vec3 p, float height) {
    vec3 dpdx = dFdx(p);
    vec3 dpdy = dFdy(p);
    float dhdx = dFdx(height);
    float dhdy = dFdy(height);
    vec3 r1 = cross(dpdy, n);
    vec3 r2 = cross(n, dpdx);
    float det = dot(dpdx, r1);
    if (abs(det) < 1e-20) return n;
    vec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
    return normalize(abs(det) * n - grad);
}

void main() {
    ObjectData o = objects[pc.object_index];
    MaterialData m = materials[o.ids.y];
    float bias = frame.ambient.w;
    vec3 albedo = m.kd.rgb;
    if (m.tex.x >= 0) albedo *= texture(albedo_tex, v_uv, bias).rgb;
    if (m.tex.y >= 0) {
        float a = texture(mask_tex, v_uv, bias)[m.tex.z];
        if (a < 0.5) discard;
    }
    vec3 n = normalize(v_normal);
    // Double-sided: OBJ winding is unreliable, so face the normal towards the camera.
    if (dot(n, -v_world) < 0.0) n = -n;
    if (m.tex.w >= 0) {
        float h = texture(bump_tex, v_uv, bias).r * m.ke.w;
        n = bump(n, v_world, h);
    }
    o_color = vec4(shade(v_world, n, albedo, m, frame), 1.0);
    o_velocity = to_pixels(v_clip) - to_pixels(v_prev_clip);
    o_ids = uvec2(o.ids.x, uint(gl_PrimitiveID));
}
