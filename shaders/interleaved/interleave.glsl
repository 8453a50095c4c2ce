// `interleaved`'s split layout, shared by split.comp, shade.comp and gather.comp: the W x H
// G-buffer becomes M x N sub-images of Ws x Hs = ceil(W/M) x ceil(H/N), side by side; sub-image
// (i, j) holds the pixels (x, y) with x mod M = i, y mod N = j, so neighbouring texels of a
// sub-image are M (N) pixels apart on screen (Segovia et al. 2006's "split" of the G-buffer).
// The mosaic (M Ws x N Hs texels) is stored row by row in storage buffers of vec4, one per
// quantity (split.rs, `Storage`). Each pass binds only what it uses (split.rs: its declaration),
// so each binding is declared where its BINDING_* define exists.
#ifdef BINDING_POSITION
layout(set = 0, binding = BINDING_POSITION) uniform sampler2D g_position;
#endif
#ifdef BINDING_NORMAL
layout(set = 0, binding = BINDING_NORMAL) uniform sampler2D g_normal;
#endif
#ifdef BINDING_SPLIT_POSITION
layout(std430, set = 0, binding = BINDING_SPLIT_POSITION) buffer SplitPosition { vec4 s_position[]; };
#endif
#ifdef BINDING_SPLIT_NORMAL
layout(std430, set = 0, binding = BINDING_SPLIT_NORMAL) buffer SplitNormal { vec4 s_normal[]; };
#endif
#ifdef BINDING_SPLIT_IRRADIANCE
layout(std430, set = 0, binding = BINDING_SPLIT_IRRADIANCE) buffer SplitIrradiance { vec4 s_irradiance[]; };
#endif
// `direct`: the scene's lights (directional first, then its point lights) and the extra point
// lights (`points=N`), whose point lights the sub-images shade in subsets too; the specular
// estimates beside the diffuse ones (the split mosaic's and the gathered).
// (The VPLs, the scene's lights and the extra point lights: inc/light_buffers.glsl.)
#include "../inc/light_buffers.glsl"
#ifdef BINDING_SPLIT_SPECULAR
layout(std430, set = 0, binding = BINDING_SPLIT_SPECULAR) buffer SplitSpecular { vec4 s_specular[]; };
#endif
// The full-resolution estimates: an image, as the lighting pass's filter reads them at
// data-dependent pixels, which llvmpipe's texel fetches gather faster than buffer loads.
#ifdef BINDING_IRRADIANCE
layout(set = 0, binding = BINDING_IRRADIANCE, rgba32f) uniform image2D irradiance;
#endif
#ifdef BINDING_SPECULAR
layout(set = 0, binding = BINDING_SPECULAR, rgba32f) uniform image2D specular;
#endif

// size: W, H, Ws, Hs; counts.x: VPLs (`direct`: y directional lights, z the scene's point
// lights, w extra ones); params.x: the VPL clamp c (m^2).
PUSH_CONSTANTS

// The word of split texel s in the mosaic's buffers.
uint word_of(ivec2 s) {
    return uint(s.y * (TILE_M * pc.size.z) + s.x);
}

// Whether pixel q lies on the screen.
bool on_screen(ivec2 q) {
    return q.x >= 0 && q.y >= 0 && q.x < pc.size.x && q.y < pc.size.y;
}

// The mosaic word of pixel (t M + i, y): texel t of row y / N of sub-image (i, y mod N). The split
// and the gather walk the screen this way, invocation (t, y) taking i = 0 .. M-1: per step a SIMD
// group's lanes touch consecutive texels of one sub-image row, and every divisor is a constant.
uint row_word(int t, int y, int i) {
    return word_of(ivec2(i * pc.size.z + t, (y % TILE_N) * pc.size.w + y / TILE_N));
}
