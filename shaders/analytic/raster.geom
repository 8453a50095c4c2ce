#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`, geometry stage: reaches every pixel a triangle touches. lavapipe has no
// conservative rasterisation, so each triangle is (1) clipped to the near plane (reverse-Z:
// depth = z / w <= 1, i.e. w - z >= 0; the far plane is at infinity), (2) projected to pixels,
// (3) replaced by its Minkowski sum with the pixel square: the intersection of its bounding box
// grown by half a pixel with each edge's half-plane pushed out by the square's support along
// the edge normal, 0.5 (|nx| + |ny|), plus 1/64 px for rounding. A pixel's square meets the
// triangle exactly when its centre lies in that sum, so the hardware's centre sampling of the
// emitted polygon (at most 8 vertices) reaches every touched pixel, sub-pixel and sliver
// triangles included; the fragment stage computes the exact coverage and drops the zeros.
// The original triangle travels as flat attributes (clip positions for perspective-correct
// barycentrics, and its vertex attributes), and the near-clipped screen polygon for the areas.
#include "../inc/scene_types.glsl"

// A grown box at most this many pixels on its longer side is emitted as it is (2 triangles),
// not cut by the edges (up to 6): rasterising the few extra pixels, which the fragment stage
// drops, costs less than setting up the cut polygon's triangles (Sibenik at 160x90, most of
// whose 75k triangles are a pixel or two: frame 830 -> 767 ms; the demo at 320x180: 274 -> 238).
#define BOX_ONLY 5.0

layout(triangles) in;
layout(triangle_strip, max_vertices = 8) out;

layout(set = SET_SCENE, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };

layout(location = 0) in vec3 v_world[];
layout(location = 1) in vec3 v_normal[];
layout(location = 2) in vec2 v_uv[];
layout(location = 3) in vec4 v_clip[];
layout(location = 4) in vec4 v_prev_clip[];
layout(location = 5) flat in float v_turn[];  // forward.vert's; unused here

#include "raster_io.glsl"

vec2 to_screen(vec4 c) {
    return (c.xy / c.w * 0.5 + 0.5) * frame.output_size.xy;
}

void main() {
    // 1. Near-plane clip of the jittered clip-space triangle (Sutherland-Hodgman, one plane).
    vec4 c[3] = vec4[3](gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position);
    vec4 q[4];
    int n = 0;
    for (int i = 0; i < 3; ++i) {
        vec4 a = c[i];
        vec4 b = c[(i + 1) % 3];
        float da = a.w - a.z;
        float db = b.w - b.z;
        if (da >= 0.0) q[n++] = a;
        if ((da >= 0.0) != (db >= 0.0)) q[n++] = mix(a, b, da / (da - db));
    }
    if (n < 3) return;
    vec2 s[4];
    for (int i = 0; i < n; ++i) s[i] = to_screen(q[i]);
    // Twice the signed area: zero-area polygons cover nothing.
    float area2 = 0.0;
    for (int i = 0; i < n; ++i) {
        vec2 a = s[i];
        vec2 b = s[(i + 1) % n];
        area2 += a.x * b.y - b.x * a.y;
    }
    if (area2 == 0.0 || isnan(area2) || isinf(area2)) return;
    float o = area2 > 0.0 ? 1.0 : -1.0;

    // 2. The Minkowski sum with the pixel square: the grown box (within the screen and a pixel)
    // cut by each edge's pushed-out half-plane.
    vec2 lo = s[0];
    vec2 hi = s[0];
    for (int i = 1; i < n; ++i) {
        lo = min(lo, s[i]);
        hi = max(hi, s[i]);
    }
    const float margin = 1.0 / 64.0;
    lo = max(lo - (0.5 + margin), vec2(-1.0));
    hi = min(hi + (0.5 + margin), frame.output_size.xy + 1.0);
    if (any(greaterThanEqual(lo, hi))) return;
    vec2 poly[8];
    vec2 tmp[8];
    poly[0] = lo;
    poly[1] = vec2(hi.x, lo.y);
    poly[2] = hi;
    poly[3] = vec2(lo.x, hi.y);
    int m = 4;
    // Small boxes are kept whole (BOX_ONLY).
    bool small_box = max(hi.x - lo.x, hi.y - lo.y) <= BOX_ONLY;
    for (int e = 0; e < n && m > 0 && !small_box; ++e) {
        vec2 a = s[e];
        vec2 d = s[(e + 1) % n] - a;
        float push = (0.5 + margin) * (abs(d.x) + abs(d.y));
        // Inside: o * cross(d, p - a) + push >= 0.
        int k = 0;
        for (int i = 0; i < m; ++i) {
            vec2 p0 = poly[i];
            vec2 p1 = poly[(i + 1) % m];
            float f0 = o * (d.x * (p0.y - a.y) - d.y * (p0.x - a.x)) + push;
            float f1 = o * (d.x * (p1.y - a.y) - d.y * (p1.x - a.x)) + push;
            if (f0 >= 0.0) tmp[k++] = p0;
            if ((f0 >= 0.0) != (f1 >= 0.0) && k < 8) tmp[k++] = mix(p0, p1, f0 / (f0 - f1));
        }
        m = min(k, 8);
        for (int i = 0; i < m; ++i) poly[i] = tmp[i];
    }
    if (m < 3) return;

    // 3. Emit the convex polygon as a strip (v0, v1, v[m-1], v2, v[m-2], ...), every vertex with
    // the triangle's flat data.
    int lo_i = 1;
    int hi_i = m - 1;
    for (int j = 0; j < m; ++j) {
        int idx;
        if (j == 0) {
            idx = 0;
        } else if ((j & 1) == 1) {
            idx = lo_i++;
        } else {
            idx = hi_i--;
        }
        vec2 ndc = poly[idx] * frame.output_size.zw * 2.0 - 1.0;
        gl_Position = vec4(ndc, 0.5, 1.0);
        for (int i = 0; i < 3; ++i) {
            g_clip[i] = c[i];
            g_prev[i] = v_prev_clip[i].xyw;
            g_world[i] = v_world[i];
            g_normal[i] = v_normal[i];
        }
        g_uv01 = vec4(v_uv[0], v_uv[1]);
        g_uv2 = v_uv[2];
        g_poly01 = vec4(s[0], s[1]);
        g_poly23 = vec4(s[2], n > 3 ? s[3] : s[0]);
        g_info = uvec2(uint(n), uint(gl_PrimitiveIDIn));
        EmitVertex();
    }
    EndPrimitive();
}
