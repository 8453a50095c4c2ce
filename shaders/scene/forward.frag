#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_demote_to_helper_invocation : require
// Scene raster, fragment stage: alpha test, bump, lighting; writes colour, velocity and IDs.
// Discards are demotions, so the remaining lanes of a quad keep valid derivatives (the masked
// and interlaced layouts drop half of every quad). With GBUFFER (`deferred`) it stops before the
// lighting and writes the surface instead (position, shading normal, albedo): the lighting pass
// (shaders/deferred/lighting.comp) calls the same `shade` on the same bits.
#include "../inc/scene_types.glsl"

layout(set = SET_SCENE, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = SET_SCENE, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = SET_SCENE, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
// shaded_fragments: FLAG_COUNT_SHADED only; nonfinite_fragments: always (NaN/Inf containment).
layout(std430, set = SET_SCENE, binding = BINDING_COUNTER) buffer Counter {
    uint shaded_fragments;
    uint nonfinite_fragments;
};
// Per-material set; slots a material does not use hold a 1x1 white texture.
layout(set = SET_MATERIAL, binding = BINDING_ALBEDO) uniform sampler2D albedo_tex;
layout(set = SET_MATERIAL, binding = BINDING_MASK) uniform sampler2D mask_tex;
layout(set = SET_MATERIAL, binding = BINDING_BUMP) uniform sampler2D bump_tex;
PUSH_CONSTANTS

#define LIGHTS_SET SET_SCENE
#include "../inc/shading.glsl"
#include "../inc/aniso.glsl"

// msaa2x and `msaa:N:sample` shade per sample: every input is interpolated at the sample position.
#if LAYOUT == LAYOUT_MSAA2X || defined(SAMPLE_SHADING)
#define INTERP sample
#else
#define INTERP
#endif
layout(location = 0) INTERP in vec3 v_world;
layout(location = 1) INTERP in vec3 v_normal;
layout(location = 2) INTERP in vec2 v_uv;
layout(location = 3) INTERP in vec4 v_clip;
layout(location = 4) INTERP in vec4 v_prev_clip;
layout(location = 5) flat in float v_turn;  // the object's turn (forward.vert)

#ifdef EARLY_TESTS
// The G-buffer pass after its depth pre-pass (DEPTH_ONLY): the depth test is EQUAL and writes
// nothing, so testing before the shader (which the counter store below would otherwise prevent)
// only skips the fragments the late test would have thrown away, and each pixel is shaded once.
layout(early_fragment_tests) in;
#endif

#ifdef DEPTH_ONLY
// The G-buffer's depth pre-pass: the alpha test, nothing written but depth.
#elif defined(ID_ONLY)
// The native-resolution depth + ID prepass (--id-prepass): visibility only, no shading.
layout(location = 0) out uvec2 o_ids;
#elif defined(GBUFFER)
// `deferred`'s G-buffer, f32 so that the lighting pass shades exactly these inputs.
layout(location = 0) out vec4 o_position;  // xyz: camera-relative world position; w: 1
layout(location = 1) out vec4 o_normal;    // xyz: shading normal (facing the camera, bumped); w: ns
layout(location = 2) out vec4 o_albedo;    // rgb: kd x albedo texture (FLAG_DEBUG_LOD: r = LOD)
layout(location = 3) out vec2 o_velocity;
layout(location = 4) out uvec2 o_ids;      // the material is objects[x - 1].ids.y
#else
layout(location = 0) out vec4 o_color;     // HDR radiance; alpha 1 = shaded this frame
layout(location = 1) out vec2 o_velocity;  // full-res pixels moved since the previous frame (current - previous)
#ifndef NO_IDS
layout(location = 2) out uvec2 o_ids;      // x: object ID, y: primitive ID within the object
#endif
#endif

vec2 to_pixels(vec4 clip) {
    return (clip.xy / clip.w * 0.5 + 0.5) * frame.output_size.xy;
}

// Texture lookup at the layout's footprint: a LOD bias, or (LOD_GRADIENTS) derivatives turned
// into full-res screen derivatives (scaled by 2^bias). Neighbouring samples are 2 px apart in
// split/msaa2x; in the tangram a texel step is a diagonal screen step: d/du = d/dx - d/dy,
// d/dv = d/dx + d/dy. A define, not a frame flag: llvmpipe runs both sides of a branch even on a
// uniform flag, which made every tap two lookups (the G-buffer pass 22% slower on Sibenik).
bool lod_gradients() {
#ifdef LOD_GRADIENTS
    return true;
#else
    return false;
#endif
}

// d(uv)/dx and d(uv)/dy per full-res screen pixel, from the derivatives between this layout's
// neighbouring samples.
void screen_gradients(vec2 uv, out vec2 gx, out vec2 gy) {
    vec2 a = dFdx(uv);
    vec2 b = dFdy(uv);
#if LAYOUT == LAYOUT_SPLIT || LAYOUT == LAYOUT_MSAA2X
    gx = 0.5 * a;
    gy = 0.5 * b;
#elif LAYOUT == LAYOUT_ROTATED
    gx = 0.5 * (a + b);
    gy = 0.5 * (b - a);
#else
    gx = a;
    gy = b;
#endif
}

// How far the fragment has moved towards screen_jitter.w's speed, in [0, 1] (`+taa:unjitter`,
// `+taa:motionlod`):
// 0 where it is still, and everywhere without that setting (w = 0); 1 from that speed on, and
// where the speed is not finite (a vertex behind the previous camera).
float motion_share() {
    if (frame.screen_jitter.w == 0.0) return 0.0;
    float r = length(to_pixels(v_clip) - to_pixels(v_prev_clip)) * frame.screen_jitter.w;
    return (r >= 0.0 && r < 1.0) ? r : 1.0;
}

// The fragment's LOD bias: the frame's, less the part a moving fragment sheds (TAA's sharper
// bias, withdrawn linearly up to screen_jitter.w's speed; its history averages too few jittered
// samples for it). With screen_jitter.zw = 0 the bias is the frame's exactly.
//
// A turning object's fragment (v_turn: its own rotation this frame) withdraws the
// temporal technique's bias (frame.turning.x) in proportion to its turn: its shading changes every
// frame, so its history holds a frame or none, and the sharper level only aliases (the demo's
// spinning torus; docs/upsampling.md). The larger withdrawal of the two applies.
float lod_bias() {
    return frame.ambient.w - min(frame.screen_jitter.z * motion_share(), frame.turning.x * v_turn);
}

// The derivatives a, b between this layout's neighbouring samples, per output pixel (as
// screen_gradients; the native layout rendering below the output resolution, `upscale`, scaled
// by its target pixels per output pixel).
void output_derivatives(vec3 a, vec3 b, out vec3 gx, out vec3 gy) {
#if LAYOUT == LAYOUT_SPLIT || LAYOUT == LAYOUT_MSAA2X
    gx = 0.5 * a;
    gy = 0.5 * b;
#elif LAYOUT == LAYOUT_ROTATED
    gx = 0.5 * (a + b);
    gy = 0.5 * (b - a);
#else
    gx = a * (frame.viewport.x * frame.output_size.z);
    gy = b * (frame.viewport.y * frame.output_size.w);
#endif
}

// `+taa:unjitter` and `+taa:motionlod` move a moving fragment's shading inputs (UV, position,
// normal) back to the unjittered pixel centre by its share of the jitter: the projection's jitter
// puts the pixel centre on the scene point at centre - jitter, so the inputs are taken at
// + jitter, to first order through their screen derivatives. Coverage, depth, the alpha test
// and the velocity keep the jittered raster's, so edges are still anti-aliased by the jitter;
// the shading of a pixel whose history holds few frames is native's (docs/post-aa.md).
// v at the unjittered pixel centre's share r of the way: v + offset . d(v)/d(output pixel), with
// offset = r x the jitter; v itself, bit for bit, where r is 0 (still fragments, and without
// the setting).
vec3 unjittered(vec3 v, float r) {
    vec3 gx, gy;
    output_derivatives(dFdx(v), dFdy(v), gx, gy);
    vec2 o = frame.screen_jitter.xy * r;
    vec3 moved = v + gx * o.x + gy * o.y;
    return r > 0.0 ? moved : v;
}
vec2 unjittered(vec2 v, float r) {
    return unjittered(vec3(v, 0.0), r).xy;
}

// The footprint's derivatives the anisotropic lookups take: the layout's full-res screen
// derivatives, or the implicit ones, scaled by 2^bias.
void aniso_gradients(vec2 uv, out vec2 gx, out vec2 gy) {
    if (lod_gradients()) {
        screen_gradients(uv, gx, gy);
    } else {
        gx = dFdx(uv);
        gy = dFdy(uv);
    }
    float s = exp2(lod_bias());
    gx *= s;
    gy *= s;
}

vec4 tex(sampler2D t, vec2 uv) {
#ifdef ID_ONLY
    // The prepass rasterises native's grid: native's footprint, whatever the checkerboard bias.
#if MAT_ANISO > 1
    return texture_aniso_n(t, uv, dFdx(uv), dFdy(uv), MAT_ANISO);
#else
    return texture(t, uv);
#endif
#endif
#if MAT_ANISO > 1
    // The scene's `anisotropy`: up to MAT_ANISO trilinear lookups along the footprint's longer
    // side, each at its shorter side's level (inc/aniso.glsl); the bias scales the footprint.
    vec2 ax, ay;
    aniso_gradients(uv, ax, ay);
    return texture_aniso_n(t, uv, ax, ay, MAT_ANISO);
#endif
    if (!lod_gradients()) return texture(t, uv, lod_bias());
    vec2 gx, gy;
    screen_gradients(uv, gx, gy);
    // A bias on top of the full-res footprint (0 unless --lod-bias or a temporal pass asks):
    // scaling both derivatives by 2^b adds b to the isotropic LOD.
    float s = exp2(lod_bias());
    return textureGrad(t, uv, s * gx, s * gy);
}

// The level of detail `tex` selects (the isotropic formula of the Vulkan spec; with the scene's
// `anisotropy`, that of its lookups), for FLAG_DEBUG_LOD.
float lod_of(sampler2D t, vec2 uv) {
#if MAT_ANISO > 1
    vec2 ax, ay;
    aniso_gradients(uv, ax, ay);
    return aniso_lod(t, ax, ay, MAT_ANISO);
#endif
    vec2 a = dFdx(uv);
    vec2 b = dFdy(uv);
    float bias = lod_bias();
    if (lod_gradients()) screen_gradients(uv, a, b);
    vec2 size = vec2(textureSize(t, 0));
    return log2(max(length(a * size), length(b * size))) + bias;
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
    // The shading inputs, moved back to the pixel centre by a moving fragment's share of the
    // jitter under `+taa:unjitter` and `motionlod` (`unjittered`); the raster's own elsewhere.
    // A moving fragment of a material without textures is wholly centred, whatever its speed:
    // the share ramps with speed because a slow pixel's history holds jittered samples that
    // supersample its texture, and an untextured surface has nothing within the pixel for them
    // to supersample but its smooth shading, to which the jitter only adds noise (`specular`'s
    // dark floor, docs/post-aa.md).
    // A turning object is rasterised without the jitter in proportion to its turn (forward.vert):
    // its share is of the jitter it kept.
    float share = motion_share();
    if (share > 0.0 && m.tex.x < 0 && m.tex.y < 0 && m.tex.w < 0) share = 1.0;
    if (frame.screen_jitter.w != 0.0) share *= 1.0 - v_turn;
    vec2 uv = unjittered(v_uv, share);
    vec3 world = unjittered(v_world, share);
    vec3 normal = unjittered(v_normal, share);
#if LAYOUT == LAYOUT_MASKED
    if (((int(gl_FragCoord.x) + int(gl_FragCoord.y)) & 1) != int(frame.counts.w & FLAG_PARITY)) demote;
#elif LAYOUT == LAYOUT_INTERLACED
    // Rows of the other parity: every 2x2 quad keeps one row, whose derivatives stay native's.
    if ((int(gl_FragCoord.y) & 1) != int(frame.counts.w & FLAG_PARITY)) demote;
#endif
#if (MAT_FEATURES & MAT_MASK) != 0
    if (m.tex.y >= 0) {
        float a = tex(mask_tex, v_uv)[m.tex.z];
        if (a < 0.5) demote;
    }
#endif
#ifdef DEPTH_ONLY
#elif defined(ID_ONLY)
    o_ids = uvec2(o.ids.x, uint(gl_PrimitiveID));
#else
    vec3 albedo = m.kd.rgb;
#if (MAT_FEATURES & MAT_ALBEDO) != 0
    if (m.tex.x >= 0) albedo *= tex(albedo_tex, uv).rgb;
#endif
    vec3 n = normalize(normal);
    // Double-sided: OBJ winding is unreliable, so face the normal towards the camera.
    if (dot(n, -world) < 0.0) n = -n;
#if (MAT_FEATURES & MAT_BUMP) != 0
    if (m.tex.w >= 0) {
        float h = tex(bump_tex, uv).r * m.ke.w;
        n = bump(n, world, h);
    }
#endif
#ifdef GBUFFER
    o_position = vec4(world, 1.0);
    o_normal = vec4(n, m.ks.w);
    o_albedo = vec4(albedo, 1.0);
    if ((frame.counts.w & FLAG_DEBUG_LOD) != 0u) {
        o_albedo = vec4(m.tex.x >= 0 ? lod_of(albedo_tex, uv) : -100.0, 0.0, 0.0, 1.0);
    }
    o_velocity = to_pixels(v_clip) - to_pixels(v_prev_clip);
    o_ids = uvec2(o.ids.x, uint(gl_PrimitiveID));
    // Without EARLY_TESTS (bump-mapped materials after the pre-pass) this variant keeps late
    // depth tests, as the forward shader's counter stores do: on llvmpipe a lane that fails an
    // early depth test takes no part in a texture result's derivative, which the bump map takes
    // (bump_mapping_matches_native, tests/deferred.rs). The condition never holds (object IDs
    // start at 1); the store it guards keeps the late tests.
    if (o.ids.x == 0u) atomicAdd(nonfinite_fragments, 1u);
#else
    vec3 c = shade(world, n, albedo, m, frame);
    // NaN/Inf containment: a fragment whose shading is not finite is written black and counted
    // (reported per frame), so no history downstream ever holds one. Finite radiance above the
    // fp16 targets' largest value is clamped to it rather than becoming +inf there.
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
        atomicAdd(nonfinite_fragments, 1u);
    }
    o_color = vec4(min(c, vec3(65504.0)), 1.0);
    if ((frame.counts.w & FLAG_DEBUG_LOD) != 0u) {
        o_color = vec4(m.tex.x >= 0 ? lod_of(albedo_tex, uv) : -100.0, 0.0, 0.0, 1.0);
    }
    o_velocity = to_pixels(v_clip) - to_pixels(v_prev_clip);
#ifndef NO_IDS
    o_ids = uvec2(o.ids.x, uint(gl_PrimitiveID));
#endif
    // Helpers (and demoted lanes) do not count: their atomics have no effect.
    if ((frame.counts.w & FLAG_COUNT_SHADED) != 0u) atomicAdd(shaded_fragments, 1u);
#endif  // GBUFFER
#endif
}
