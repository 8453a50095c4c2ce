// Layout-independent access to a checkerboard frame's samples (LAYOUT define, values in
// scene_types.glsl). The CPU reference is crates/cbr-render/src/layouts.rs (LayoutPlan::address).
//
//   ivec4 a = cb_address(p, parity, tangram_side);  // (x, y, layer, sample), or -1 if p is missing
//   vec4 c = cb_fetch(color_tex, a);                 // textures declared as CB_SAMPLER / CB_USAMPLER
#ifndef LAYOUT_FETCH_GLSL
#define LAYOUT_FETCH_GLSL
#include "scene_types.glsl"

#if LAYOUT == LAYOUT_SPLIT
#define CB_SAMPLER sampler2DArray
#define CB_USAMPLER usampler2DArray
#define cb_fetch(t, a) texelFetch(t, ivec3((a).xy, (a).z), 0)
#elif LAYOUT == LAYOUT_MSAA2X
#define CB_SAMPLER sampler2DMS
#define CB_USAMPLER usampler2DMS
#define cb_fetch(t, a) texelFetch(t, (a).xy, (a).w)
#else
#define CB_SAMPLER sampler2D
#define CB_USAMPLER usampler2D
#define cb_fetch(t, a) texelFetch(t, (a).xy, 0)
#endif

// Where the sample of full-resolution pixel p lives in this frame's raster targets.
ivec4 cb_address(ivec2 p, int parity, int tangram_side) {
    if (((p.x + p.y) & 1) != parity) return ivec4(-1);
#if LAYOUT == LAYOUT_SPLIT
    // Layer k holds the shaded pixel of row k of each 2x2 quad.
    return ivec4(p / 2, p.y & 1, 0);
#elif LAYOUT == LAYOUT_MSAA2X
    // Sample 0 of target pixel (i, j) is (2i + 1 - parity, 2j + 1); sample 1 is (2i - parity, 2j).
    // MSAA_LOCATIONS (VK_EXT_sample_locations): odd frames' samples are (2i, 2j + 1), (2i + 1, 2j).
    int odd = p.y & 1;
#if defined(MSAA_LOCATIONS) && MSAA_LOCATIONS
    if (parity == 1) return ivec4(p.x / 2, p.y / 2, 0, 1 - odd);
#endif
    return ivec4((p.x + parity + 1 - odd) / 2, p.y / 2, 0, 1 - odd);
#elif LAYOUT == LAYOUT_ROTATED
    // Tangram texel (i, j) = ((x - y - parity) / 2, (x + y - parity) / 2) mod L; both divisions
    // are exact (the numerators are even). For p on the W x H screen and L = tangram_side(W, H)
    // (L >= max(W, H) / 2 and L >= min(W, H)), i lies in [-L, L) and j in [0, 2L), so one
    // conditional add or subtract is the modulo: integer division has no SIMD instruction on
    // x86, and llvmpipe would run one scalar division per lane and per modulo. The halving is an
    // arithmetic shift: equal to the division on even numerators, negative ones included, where
    // a signed division by 2 costs a GPU its sign fix-up (ACO, docs/gpu-isa.md).
    int l = tangram_side;
    int i = (p.x - p.y - parity) >> 1;
    int j = (p.x + p.y - parity) >> 1;
    return ivec4(i < 0 ? i + l : i, j >= l ? j - l : j, 0, 0);
#else
    return ivec4(p, 0, 0);
#endif
}

// Rotated layout: the texture coordinate of continuous screen position s (pixels, y down) in the
// tangram, for a sampler with REPEAT addressing (the wrap does the unwrapping of the pieces).
// Pixel centres land on texel centres, so bilinear filtering interpolates on the diamond lattice:
// half-way between two horizontally adjacent pixels it averages the two diagonal neighbours.
vec2 cb_tangram_uv(vec2 s, int parity, int tangram_side) {
    float p = float(parity);
    return vec2(s.x - s.y - p + 1.0, s.x + s.y - p) * 0.5 / float(tangram_side);
}

#endif
