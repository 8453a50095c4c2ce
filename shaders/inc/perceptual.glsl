// The perceptual space temporal passes compare and blend colours in (taau; +taa's to_p/from_p
// are the same maps): exposure-scaled, Reinhard on Rec. 709 luminance, then YCoCg. CPU:
// crates/cbr-render/src/cpu_math.rs (`perceptual`, `linear_from_perceptual`, `clip_towards`).
#ifndef CBR_PERCEPTUAL_GLSL
#define CBR_PERCEPTUAL_GLSL

const vec3 LUMA_709 = vec3(0.2126, 0.7152, 0.0722);

vec3 perceptual(vec3 c, float exposure) {
    vec3 x = c * exposure;
    vec3 t = x / (1.0 + max(dot(x, LUMA_709), 0.0));
    return vec3(0.25 * t.r + 0.5 * t.g + 0.25 * t.b, 0.5 * t.r - 0.5 * t.b,
                -0.25 * t.r + 0.5 * t.g - 0.25 * t.b);
}

// Clipping in YCoCg can leave the RGB gamut: negative components are clamped to 0.
vec3 linear_from_perceptual(vec3 y, float exposure) {
    vec3 t = max(vec3(y.x + y.y - y.z, y.x + y.z, y.x - y.y - y.z), vec3(0.0));
    return t / max(1.0 - dot(t, LUMA_709), 1e-3) / exposure;
}

bool finite3(vec3 c) { return !any(isnan(c)) && !any(isinf(c)); }

// Moves h towards p until it lies in the box [lo, hi] (p inside the box).
vec3 clip_towards(vec3 p, vec3 h, vec3 lo, vec3 hi) {
    vec3 r = h - p;
    float t = 1.0;
    for (int i = 0; i < 3; i++) {
        if (r[i] > 1e-7) t = min(t, (hi[i] - p[i]) / r[i]);
        else if (r[i] < -1e-7) t = min(t, (lo[i] - p[i]) / r[i]);
    }
    return p + r * max(t, 0.0);
}

#endif
