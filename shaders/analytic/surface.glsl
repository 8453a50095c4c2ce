// `analytic`: what a kept fragment's light needs, left in its slot by the raster pass
// (raster.frag) for the resolve (resolve.comp, which lights the fragments it composites): the
// albedo in the colour's place (3 x f16) and, in `surfaces`, the shading normal
// (octahedral, 2 x snorm16: within about 3e-5 radians) and the shading point in the pixel
// (2 x unorm16: within 1e-5 pixel). The point's position is then that of the slot's depth plane
// there, unprojected.
#ifndef SURFACE_GLSL
#define SURFACE_GLSL

// Luminance of an albedo (Rec. 709 weights), for the quadrants' relative albedo.
float albedo_luma(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// The albedo grid: a kept fragment's albedo luminance in each cell of a CELLS_SIDE x CELLS_SIDE
// grid over its pixel, by which the resolve takes the albedo of the part that shows when other
// fragments hide the rest (resolve.comp's shown_albedo). 16 cells of 8 bits, relative to the
// largest and square-root encoded (a dark cell beside a white one is kept within about 1% of
// its value), in a uvec4; all cells equal (255) means one albedo over the pixel.
#define CELLS_SIDE 4
#define CELLS (CELLS_SIDE * CELLS_SIDE)

// The cell of pixel-local point q.
int cell_of(vec2 q) {
    ivec2 c = clamp(ivec2(q * float(CELLS_SIDE)), ivec2(0), ivec2(CELLS_SIDE - 1));
    return c.x + CELLS_SIDE * c.y;
}

uvec4 pack_cells(float luma[CELLS]) {
    float top = 0.0;
    for (int i = 0; i < CELLS; ++i) top = max(top, luma[i]);
    uvec4 packed = uvec4(0u);
    for (int i = 0; i < CELLS; ++i) {
        float v = top > 0.0 && !isinf(top) ? sqrt(clamp(luma[i] / top, 0.0, 1.0)) : 1.0;
        packed[i >> 2] |= uint(round(v * 255.0)) << (8u * uint(i & 3));
    }
    return packed;
}

float unpack_cell(uvec4 packed, int i) {
    float v = float((packed[i >> 2] >> (8u * uint(i & 3))) & 0xFFu) / 255.0;
    return v * v;
}

// Octahedral encoding of a unit vector (Meyer et al. 2010) into [-1, 1]^2, and back.
vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.xy;
    if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return e;
}

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

uvec2 pack_surface(vec3 normal, vec2 point) {
    return uvec2(packSnorm2x16(oct_encode(normal)), packUnorm2x16(point));
}

void unpack_surface(uvec2 s, out vec3 normal, out vec2 point) {
    normal = oct_decode(unpackSnorm2x16(s.x));
    point = unpackUnorm2x16(s.y);
}
#endif
