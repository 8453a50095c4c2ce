#version 460
#extension GL_GOOGLE_include_directive : require
// `deferred`'s VPL generation: VPL i is the RSM texel texels[i] (a seeded low-discrepancy pattern
// made on the host, techniques/deferred/vpl.rs), carrying that texel's flux times share = texels
// in the RSM / VPLs, so the N VPLs together carry the whole map's flux. Texels where the sun saw
// nothing, and texels whose flux is not finite (the `nan` scene's NaN albedo), give dead VPLs:
// zero flux, w = 0.
layout(local_size_x = LOCAL_SIZE_X) in;
#include "../inc/scene_types.glsl"

layout(set = 0, binding = BINDING_RSM_POSITION) uniform sampler2D rsm_position;
layout(set = 0, binding = BINDING_RSM_NORMAL) uniform sampler2D rsm_normal;
layout(set = 0, binding = BINDING_RSM_FLUX) uniform sampler2D rsm_flux;
layout(std430, set = 0, binding = BINDING_TEXELS) readonly buffer Texels { uvec2 texels[]; };
layout(std430, set = 0, binding = BINDING_VPLS) writeonly buffer Vpls { Vpl vpls[]; };

PUSH_CONSTANTS  // count; share: texels per VPL

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    ivec2 t = ivec2(texels[i]);
    vec4 p = texelFetch(rsm_position, t, 0);
    vec3 n = texelFetch(rsm_normal, t, 0).xyz;
    vec3 flux = texelFetch(rsm_flux, t, 0).rgb * pc.share;
    bool alive = p.w > 0.0 && !any(isnan(flux)) && !any(isinf(flux));
    Vpl v;
    v.position = vec4(p.xyz, alive ? 1.0 : 0.0);
    v.normal = vec4(n, 0.0);
    v.flux = vec4(alive ? flux : vec3(0.0), 0.0);
    vpls[i] = v;
}
