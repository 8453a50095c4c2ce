// `analytic`: the albedo texture's filters, shared by the raster pass (raster.frag: the alpha
// test's lookups) and the albedo pass (albedo.comp: the kept and recorded fragments' albedo and
// their cells). Explicit gradients only, so they run in any stage.
#ifndef ANALYTIC_TEXTURE_GLSL
#define ANALYTIC_TEXTURE_GLSL

#include "../inc/aniso.glsl"

// texture_aniso_n (inc/aniso.glsl) with up to MAX_ANISO lookups.
#define MAX_ANISO 16
// The albedo grid's cells (below): at most this many lookups each.
#define CELL_ANISO 4

vec4 texture_aniso(sampler2D t, vec2 uv, vec2 gx, vec2 gy) {
    return texture_aniso_n(t, uv, gx, gy, MAX_ANISO);
}

// TEXTURE_BOX (the default; `analytic:aniso` leaves it out): the albedo's footprint integrated as
// a box, by the midpoint rule
// over a grid of cells, each looked up (trilinear) over its own cell: BOX_CELLS cells across the
// footprint's shorter side (or across each texel where it is under one texel), as many along the
// longer side as keep the cells about square, at most 16 along it and BOX_MAX_TAPS in all. A single trilinear lookup at the footprint's level filters
// with a tent two of that level's texels wide, twice the pixel: on textures minified several
// levels (Šibenik's stone at 320x180) it blurs what the supersampled reference keeps
// (docs/analytic.md, The texture's box). Only for a fragment covering at least BOX_MIN_AREA of
// its pixel (`boxed`): the smaller ones weigh little in the pixel and cost the most lookups (a
// sliver's footprint is long and thin), and take texture_aniso's lookups.
#define BOX_CELLS 3.0
#define BOX_MAX_TAPS 16
#define BOX_MIN_AREA 0.25
vec4 texture_box(sampler2D t, vec2 uv, vec2 gx, vec2 gy, bool boxed) {
    vec2 l = footprint_texels(t, gx, gy);
    float lx = l.x;
    float ly = l.y;
    // Lengths that are not finite take texture_aniso's own guard (min and max need not pass NaN).
    if (isnan(lx) || isnan(ly) || isinf(lx) || isinf(ly)) return texture_aniso(t, uv, gx, gy);
    float unit = max(min(lx, ly), 1.0);
    // Cells along the longer side first: beyond BOX_MAX_TAPS the shorter side has fewer cells,
    // down to one (then the lookups are texture_aniso's, finer along the longer side).
    bool x_long = lx >= ly;
    int n_long = int(clamp(ceil(BOX_CELLS * max(lx, ly) / unit), 1.0, 16.0));
    int n_short = int(clamp(ceil(BOX_CELLS * min(lx, ly) / unit), 1.0, BOX_CELLS));
    n_short = clamp(BOX_MAX_TAPS / n_long, 1, n_short);
    if (!boxed) {
        // texture_aniso's lookups (one per unit of the footprint's aspect ratio along its longer
        // side, at most MAX_ANISO) through the same loop: a SIMD group holding fragments of both
        // kinds runs one loop, not both functions (Sibenik at 160x90: the raster pass 550-564
        // -> 528-548 ms).
        n_long = aniso_taps(l, MAX_ANISO);
        n_short = 1;
    }
    int nx = x_long ? n_long : n_short;
    int ny = x_long ? n_short : n_long;
    vec4 sum = vec4(0.0);
    for (int i = 0; i < nx; ++i) {
        for (int j = 0; j < ny; ++j) {
            vec2 o = vec2((float(i) + 0.5) / float(nx) - 0.5, (float(j) + 0.5) / float(ny) - 0.5);
            sum += textureGrad(t, uv + gx * o.x + gy * o.y, gx / float(nx), gy / float(ny));
        }
    }
    return sum / float(nx * ny);
}

#endif
