#version 460
#extension GL_GOOGLE_include_directive : require
// Scene raster, vertex stage: vertices pulled from a storage buffer (8 floats each), placed in
// the raster target of the layout (LAYOUT define).
#include "../inc/scene_types.glsl"
#if LAYOUT == LAYOUT_SPLIT
#extension GL_ARB_shader_viewport_layer_array : require
#endif

layout(set = SET_SCENE, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = SET_SCENE, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = SET_SCENE, binding = BINDING_VERTICES) readonly buffer Vertices { float vdata[]; };
PUSH_CONSTANTS

layout(location = 0) out vec3 v_world;   // camera-relative world position
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_uv;
layout(location = 3) out vec4 v_clip;       // unjittered screen clip position, this frame
layout(location = 4) out vec4 v_prev_clip;  // previous frame
// The object's turn (ObjectData.ids.z; 0 where no reactive rule applies), as a flat varying: the
// fragment shader's helper lanes (a quad's uncovered pixels, which its derivatives read) get it
// too, where their own load of the objects buffer reads 0 on llvmpipe, and a turning object's
// texture derivatives came out mixed (docs/post-aa.md).
layout(location = 5) flat out float v_turn;

// Layouts whose targets extend past the screen (odd sizes, msaa2x's spare column, the tangram's
// wrapped pieces) clip exactly to the screen rectangle.
#if LAYOUT == LAYOUT_SPLIT || LAYOUT == LAYOUT_MSAA2X || LAYOUT == LAYOUT_ROTATED
#define CLIP_TO_SCREEN 1
out float gl_ClipDistance[4];
#endif

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
    v_turn = uintBitsToFloat(o.ids.z);
    vec4 pos = v_clip;
    // The projection's jitter (`--jitter`, TAA): j output pixels move NDC by 2j / size, before any
    // layout's mapping, so every layout and the ID prepass see the same jittered scene. Under
    // `+taa`'s `unjitter` (screen_jitter.w != 0) a turning object (ObjectData.ids.z) is
    // rasterised without it in proportion to its turn: its history is cut by its turn (the
    // reactive rule), and a single jittered sample is a worse estimate of its pixel than the
    // centred one (`native`'s) at its edges as inside (the moving demo's torus; docs/post-aa.md).
    float kept = frame.screen_jitter.w != 0.0 ? 1.0 - v_turn : 1.0;
    pos.xy += frame.screen_jitter.xy * kept * 2.0 * frame.output_size.zw * pos.w;
#ifdef CLIP_TO_SCREEN
    gl_ClipDistance[0] = pos.x + pos.w;
    gl_ClipDistance[1] = pos.w - pos.x;
    gl_ClipDistance[2] = pos.y + pos.w;
    gl_ClipDistance[3] = pos.w - pos.y;
#endif
#if LAYOUT == LAYOUT_SPLIT || LAYOUT == LAYOUT_MSAA2X
    // The target is ceil(W/2) (+1) x ceil(H/2) pixels; scale clip space so that full-res pixel X
    // lands at X / 2 whatever the rounding.
    vec2 half_scale = 0.5 * frame.output_size.xy * frame.viewport.zw;
    pos.xy = (pos.xy + pos.w) * half_scale - pos.w;
#endif
#if LAYOUT == LAYOUT_SPLIT
    // One instance per layer; each layer samples its pixel of every 2x2 quad through a jitter.
    gl_Layer = gl_InstanceIndex;
    vec2 jitter = gl_InstanceIndex == 0 ? frame.jitter.xy : frame.jitter.zw;
    pos.xy += jitter * 2.0 * frame.viewport.zw * pos.w;
#elif LAYOUT == LAYOUT_ROTATED
    // Map screen pixels (x_s, y_s) to tangram texels u = (x_s - y_s - p + 1) / 2 + m L,
    // v = (x_s + y_s - p) / 2 + n L (all times w: the map is linear in homogeneous coordinates),
    // one instance per wrapped piece (m, n).
    float p = float(frame.counts.w & FLAG_PARITY);
    float l = float(frame.tangram.x);
    vec2 piece = vec2(frame.pieces[gl_InstanceIndex].xy);
    float xs = 0.5 * frame.output_size.x * (pos.x + pos.w);
    float ys = 0.5 * frame.output_size.y * (pos.y + pos.w);
    float u = 0.5 * (xs - ys + (1.0 - p) * pos.w) + piece.x * l * pos.w;
    float v = 0.5 * (xs + ys - p * pos.w) + piece.y * l * pos.w;
    pos.x = 2.0 * u / l - pos.w;
    pos.y = 2.0 * v / l - pos.w;
#elif !defined(ID_ONLY)
    // A jitter of j pixels moves NDC by 2j / size. (The ID prepass runs at native resolution with
    // the checkerboard pass's constants: no jitter.)
    pos.xy += frame.jitter.xy * 2.0 * frame.viewport.zw * pos.w;
#endif
    gl_Position = pos;
}
