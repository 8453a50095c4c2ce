// Material evaluation and Lambert + Blinn-Phong lighting, shared by the scene passes.
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "scene_types.glsl"

// Smooth window that takes a point light to zero at its range (1 well inside it).
float range_window(float dist, float range) {
    if (range <= 0.0) return 1.0;
    float r = dist / range;
    float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
    return w * w;
}

// Outgoing radiance towards the camera at camera-relative position p with normal n (facing the
// camera). Lambert without 1/pi: a white surface facing a light of irradiance E returns E.
// Blinn-Phong specular (n.h)^ns, unnormalised, masked by n.l > 0.
vec3 shade(vec3 p, vec3 n, vec3 albedo, MaterialData m, FrameConstants frame) {
    vec3 v = normalize(-p);
    vec3 radiance = m.ke.rgb + frame.ambient.rgb * albedo;
    uint count = frame.counts.x + frame.counts.y;
    for (uint i = 0u; i < count; ++i) {
        LightData light = lights[i];
        vec3 l;
        vec3 irradiance = light.color.rgb;
        if (light.position.w == 0.0) {
            l = -normalize(light.position.xyz);
        } else {
            vec3 d = light.position.xyz - p;
            float dist2 = max(dot(d, d), 1e-8);
            float dist = sqrt(dist2);
            l = d / dist;
            irradiance *= range_window(dist, light.color.w) / dist2;
        }
        float ndl = dot(n, l);
        if (ndl <= 0.0) continue;
        vec3 h = normalize(l + v);
        float spec = m.ks.w > 0.0 ? pow(max(dot(n, h), 0.0), m.ks.w) : 0.0;
        radiance += (albedo * ndl + m.ks.rgb * spec * ndl) * irradiance;
    }
    return radiance;
}
#endif
