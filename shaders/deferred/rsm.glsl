// The reflective shadow map pass's push constants (crates/cbr-render/src/techniques/deferred/rsm.rs
// mirrors them as `RsmPush`).
layout(push_constant) uniform Push {
    mat4 clip_from_world;  // camera-relative world -> the sun's orthographic clip space
    vec4 sun;              // xyz: the sun's unit direction of travel; w: one texel's area (m^2)
    uint object_index;
} pc;
