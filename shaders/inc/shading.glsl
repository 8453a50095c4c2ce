// Material evaluation and Lambert + Blinn-Phong lighting, shared by the scene passes (forward)
// and the deferred lighting pass: one light term, one loop.
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "scene_types.glsl"
// The light buffers the pass binds (`shade_lights` and `shade` read the scene's `lights`).
#include "light_buffers.glsl"

// Smooth window that takes a point light to zero at its range (1 well inside it).
float range_window(float dist, float range) {
    if (range <= 0.0) return 1.0;
    float r = dist / range;
    float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
    return w * w;
}

// The irradiance `light` delivers at p on a surface facing it, and the unit direction l towards it.
vec3 incident(vec3 p, LightData light, out vec3 l) {
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
    return irradiance;
}

// The factors of `light`'s term at p (normal n, unit direction v to the camera, specular exponent
// ns <= 0: none): false where it does not reach the surface's front (n.l <= 0); else n.l, the
// Blinn-Phong (n.h)^ns and the irradiance E facing it.
bool light_factors(vec3 p, vec3 n, vec3 v, float ns, LightData light, out float ndl,
                   out float spec, out vec3 irradiance) {
    vec3 l;
    irradiance = incident(p, light, l);
    ndl = dot(n, l);
    spec = 0.0;
    if (ndl <= 0.0) return false;
    vec3 h = normalize(l + v);
    spec = ns > 0.0 ? pow(max(dot(n, h), 0.0), ns) : 0.0;
    return true;
}

// Adds what `light` reflects towards the camera (unit direction v from p) to `radiance`: Lambert
// without 1/pi (a white surface facing a light of irradiance E returns E) plus Blinn-Phong
// specular (n.h)^ns, unnormalised, both masked by n.l > 0.
void add_light(inout vec3 radiance, vec3 p, vec3 n, vec3 v, vec3 albedo, MaterialData m,
               LightData light) {
    float ndl, spec;
    vec3 irradiance;
    if (!light_factors(p, n, v, m.ks.w, light, ndl, spec, irradiance)) return;
    radiance += (albedo * ndl + m.ks.rgb * spec * ndl) * irradiance;
}

// add_light's two terms before the material's colours (`interleaved:...:direct`, which filters
// them apart): adds n.l E to `diffuse` and (n.h)^ns n.l E to `specular`, so that
// albedo diffuse + ks specular is add_light's radiance.
void add_light_terms(inout vec3 diffuse, inout vec3 specular, vec3 p, vec3 n, vec3 v, float ns,
                     LightData light) {
    float ndl, spec;
    vec3 irradiance;
    if (!light_factors(p, n, v, ns, light, ndl, spec, irradiance)) return;
    diffuse += ndl * irradiance;
    specular += spec * ndl * irradiance;
}

// Emission, ambient and the first `count` lights of the scene's `lights` buffer (directional
// first) reflected towards the camera at camera-relative position p with normal n (facing the
// camera).
#ifdef BINDING_LIGHTS
vec3 shade_lights(vec3 p, vec3 n, vec3 albedo, MaterialData m, FrameConstants frame, uint count) {
    vec3 v = normalize(-p);
    vec3 radiance = m.ke.rgb + frame.ambient.rgb * albedo;
    // The uniform part, then the rest (light_buffers.glsl).
    for (uint i = 0u; i < min(count, UNIFORM_LIGHTS); ++i) {
        add_light(radiance, p, n, v, albedo, m, lights[i]);
    }
    for (uint i = UNIFORM_LIGHTS; i < count; ++i) {
        add_light(radiance, p, n, v, albedo, m, more_lights[i - UNIFORM_LIGHTS]);
    }
    return radiance;
}

// Outgoing radiance towards the camera: emission, ambient, and every light of the scene.
vec3 shade(vec3 p, vec3 n, vec3 albedo, MaterialData m, FrameConstants frame) {
    return shade_lights(p, n, albedo, m, frame, frame.counts.x + frame.counts.y);
}
#endif

// Irradiance at p (normal n) from one virtual point light (Dachsbacher & Stamminger 2005):
// flux * max(0, n_vpl.(p - x)) * max(0, n.(x - p)) / (pi * d^2 * max(d^2, clamp_d2)), d = |p - x|:
// the VPL radiates flux * cos / pi per steradian, and 1/max(d^2, clamp_d2) instead of 1/d^2 keeps
// it finite near the VPL (the clamp's bias is docs/interleaved.md's). clamp_d2 > 0. Dead VPLs
// (nothing in their RSM texel) have zero flux.
vec3 vpl_irradiance(vec3 p, vec3 n, Vpl vpl, float clamp_d2) {
    vec3 d = p - vpl.position.xyz;
    float d2 = dot(d, d);
    float cosines = max(dot(vpl.normal.xyz, d), 0.0) * max(-dot(n, d), 0.0);
    // cosines <= d^2, so the guard against d2 == 0 only matters where cosines is 0 too.
    return vpl.flux.rgb * (cosines / (3.14159265358979 * max(d2, 1e-30) * max(d2, clamp_d2)));
}
#endif
