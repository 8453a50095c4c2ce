// Anisotropic texture filtering in the shader, shared by the scene pass (forward.frag, with the
// scene's `anisotropy` setting) and `analytic` (analytic/texture.glsl). Explicit gradients only,
// so it runs in any stage.
//
// The pixel's footprint in the texture is the parallelogram spanned by the UV map's screen
// derivatives gx, gy; isotropic trilinear filtering takes the mip level of its longer side and
// blurs the shorter direction too (the receding floor's checks). So the footprint is cut along
// its longer side into n = ceil(long / short) pieces (at most max_taps), each filtered at the
// shorter side's level, and their mean taken: a box filter along the long side, as the
// supersampled reference integrates it. The same lookups on every device: the sampler's own
// anisotropy is not used (Mesa 22.3's llvmpipe reports `samplerAnisotropy` but filters
// isotropically, and each vendor's hardware filter differs).
#ifndef INC_ANISO_GLSL
#define INC_ANISO_GLSL

// The footprint's sides gx, gy in texels of level 0.
vec2 footprint_texels(sampler2D t, vec2 gx, vec2 gy) {
    vec2 size = vec2(textureSize(t, 0));
    return vec2(length(gx * size), length(gy * size));
}

// Lookups along the longer side: one per unit of the footprint's aspect ratio, 1 to max_taps
// (1 where the ratio is not a number).
int aniso_taps(vec2 l, int max_taps) {
    float ratio = max(l.x, l.y) / max(min(l.x, l.y), 1e-6);
    return isnan(ratio) ? 1 : int(clamp(ceil(ratio), 1.0, float(max_taps)));
}

vec4 texture_aniso_n(sampler2D t, vec2 uv, vec2 gx, vec2 gy, int max_taps) {
    vec2 l = footprint_texels(t, gx, gy);
    vec2 major = l.x >= l.y ? gx : gy;
    vec2 minor = l.x >= l.y ? gy : gx;
    int n = aniso_taps(l, max_taps);
    if (n == 1) return textureGrad(t, uv, gx, gy);
    vec2 step_uv = major / float(n);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < n; ++i) {
        sum += textureGrad(t, uv + step_uv * (float(i) + 0.5 - 0.5 * float(n)), step_uv, minor);
    }
    return sum / float(n);
}

// The mip level texture_aniso_n's lookups take (before the sampler's clamp to the levels there
// are): the isotropic formula of the Vulkan spec over (major / n, minor).
float aniso_lod(sampler2D t, vec2 gx, vec2 gy, int max_taps) {
    vec2 l = footprint_texels(t, gx, gy);
    int n = aniso_taps(l, max_taps);
    return log2(max(max(l.x, l.y) / float(n), min(l.x, l.y)));
}

#endif
