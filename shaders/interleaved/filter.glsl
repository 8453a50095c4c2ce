// `interleaved`'s filter, in the lighting pass (deferred/lighting.comp with INTERLEAVED): the VPLs'
// irradiance at pixel p from the gathered sub-image estimates. The M x N window around p, offsets
// -(M-1)/2 .. M/2 (and likewise for N), holds one pixel of each subset.
//   FILTER 0 (`none`) and 3 (`seed`: the image bound here is already the seed's blur,
//     seed_blur.comp): p's own texel.
//   FILTER 1 (`box`): the mean of the window's on-screen pixels (near the screen's edge fewer
//     than M N: each estimates all the VPLs); with BOX_ROWS (the split passes) the gather has
//     summed each pixel's window row, and the window takes one tap per row.
//   FILTER 2 (`ours`): for each subset, the window's pixel holding it if it lies on p's surface
//     (same object, normals' dot at least SAME_NORMAL_COS, `normal=C`, default 0.9: ~25
//     degrees; on p's tangent plane within PLANE_TOLERANCE, `plane=T`, default 2%, of p's
//     distance; both defines set by the host, crates/cbr-render's interleaved module),
//     with SEARCH 1 else the nearest pixel holding it one period (M or N pixels) further that does;
//     when at least ENOUGH subsets were found (`enough=K`), their mean; otherwise every subset
//     with no such pixel is shaded at p itself (ENOUGH = M N, the default: always). Every subset
//     counts once, so on a smooth surface it is the box, and at an edge p never mixes in another
//     surface's light; only where its surface holds no pixel of a subset nearby (thin features)
//     does p pay for that subset. With EXACT_EDGES R > 0 (`exact-edges=R`), a pixel with a pixel
//     off its surface within R (the square of side 2R+1) shades every subset at p; with
//     BAND_OBJECTS (`band=object`) only a pixel of another object or the background makes it;
//     with BAND_CONTRAST T as well (`band=albedo:contrast=T`) only such a pixel whose tone
//     (band_tone_fetch: the luminance of its albedo, or of the background's radiance) differs
//     from p's by at least T of the brighter of the two (band_contrast); with BAND_DEPTH too
//     (`band=depth`) the background, or such a pixel whose distance from the camera differs from
//     p's by at least T of the farther; with BAND_SIDE 1 (`side=near`) only where p is the nearer
//     of the two (the background counting as farther), 2 (`side=far`) only the farther.
// With DIRECT (`direct`) the specular estimates of the point lights go through the same filter
// with the same choices (the same pixels, weights and fallback subsets), into `specular`.
layout(set = 0, binding = BINDING_IRRADIANCE) uniform sampler2D g_irradiance;
layout(set = 0, binding = BINDING_SPECULAR) uniform sampler2D g_specular;
#ifdef DEBUG
// Per pixel (docs/interleaved.md, debug views): bits 0-5 the pixel's subset, bit 6 edge (the
// window holds a pixel not on p's surface; `seed`: the seed's edge test), bits 8-14 the subsets
// p shaded itself, bit 16 where gather(split(G-buffer)) differs from the G-buffer.
layout(set = 0, binding = BINDING_DEBUG_BITS, r32ui) uniform writeonly uimage2D debug_bits;
#endif

const uint DBG_EDGE = 1u << 6;
const uint DBG_FALLBACK_SHIFT = 8u;
const uint DBG_ROUNDTRIP = 1u << 16;

#include "../interleaved/subsets.glsl"

bool on_screen(ivec2 q) {
    return q.x >= 0 && q.y >= 0 && q.x < int(pc.counts.z) && q.y < int(pc.counts.w);
}

#ifdef BAND_CONTRAST
// `band=albedo`'s tone of on-screen pixel q showing object `id`: the luminance (Rec. 709
// weights) of its albedo, or of the background's radiance where nothing is drawn (id 0).
float band_tone_fetch(ivec2 q, uint id) {
    vec3 a = id == 0u ? pc.background.rgb : texelFetch(g_albedo, q, 0).rgb;
    return dot(a, vec3(0.2126, 0.7152, 0.0722));
}

// Whether tones (or distances) a and b differ by at least BAND_CONTRAST of the larger (two
// blacks never: the host sets BAND_CONTRAST above 0).
bool band_contrast(float a, float b) {
    return abs(a - b) >= BAND_CONTRAST * max(a, b);
}
#endif

// WINDOW_TILE (`ours`; `window=fetch` turns it off): the workgroup's pixels and the apron their
// windows (`search`'s candidates and `exact-edges`' squares) reach are fetched once into shared
// memory (window_load, at the start of the pass, before any invocation returns), and the filter
// reads them there: each texel is fetched once per workgroup instead of once per window that
// holds it (16 for 4x4). The same bits, so the same frame. `search=1`'s candidates lie at most
// one period from p (`candidate`: o -/+ P on the other side of p, or +-P for o = 0).
#if defined(WINDOW_TILE) && FILTER == 2
const int APRON_X0 = max(max((TILE_M - 1) / 2, SEARCH * TILE_M), EXACT_EDGES);
const int APRON_X1 = max(max(TILE_M / 2, SEARCH * TILE_M), EXACT_EDGES);
const int APRON_Y0 = max(max((TILE_N - 1) / 2, SEARCH * TILE_N), EXACT_EDGES);
const int APRON_Y1 = max(max(TILE_N / 2, SEARCH * TILE_N), EXACT_EDGES);
const int WIN_W = LOCAL_SIZE_X + APRON_X0 + APRON_X1;
const int WIN_H = LOCAL_SIZE_Y + APRON_Y0 + APRON_Y1;
shared uint w_ids[WIN_W * WIN_H];
shared vec3 w_position[WIN_W * WIN_H];
shared vec3 w_normal[WIN_W * WIN_H];
shared vec3 w_irradiance[WIN_W * WIN_H];
#ifdef DIRECT
shared vec3 w_specular[WIN_W * WIN_H];
#endif
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
shared float w_tone[WIN_W * WIN_H];
#endif

ivec2 window_origin() {
    return ivec2(gl_WorkGroupID.xy) * ivec2(LOCAL_SIZE_X, LOCAL_SIZE_Y) - ivec2(APRON_X0, APRON_Y0);
}

// Every invocation of the workgroup, before any returns: the tile into shared memory, then a
// barrier. Texels off the screen get object 0 (never on a surface; the filter tests on_screen
// first anyway).
void window_load() {
    ivec2 origin = window_origin();
    for (uint t = gl_LocalInvocationIndex; t < uint(WIN_W * WIN_H);
         t += uint(LOCAL_SIZE_X * LOCAL_SIZE_Y)) {
        ivec2 q = origin + ivec2(int(t) % WIN_W, int(t) / WIN_W);
        uint id = 0u;
        vec3 pq = vec3(0.0), nq = vec3(0.0), eq = vec3(0.0), sq = vec3(0.0);
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
        float tq = 0.0;
#endif
        if (on_screen(q)) {
            id = texelFetch(g_ids, q, 0).x;
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
            tq = band_tone_fetch(q, id);
#endif
            pq = texelFetch(g_position, q, 0).xyz;
            nq = texelFetch(g_normal, q, 0).xyz;
            eq = texelFetch(g_irradiance, q, 0).rgb;
#ifdef DIRECT
            sq = texelFetch(g_specular, q, 0).rgb;
#endif
        }
        w_ids[t] = id;
        w_position[t] = pq;
        w_normal[t] = nq;
        w_irradiance[t] = eq;
#ifdef DIRECT
        w_specular[t] = sq;
#endif
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
        w_tone[t] = tq;
#endif
    }
    barrier();
}

int window_index(ivec2 q) {
    ivec2 l = q - window_origin();
    return l.y * WIN_W + l.x;
}
uint window_id(ivec2 q) { return w_ids[window_index(q)]; }
vec3 window_position(ivec2 q) { return w_position[window_index(q)]; }
vec3 window_normal(ivec2 q) { return w_normal[window_index(q)]; }
vec3 window_irradiance(ivec2 q) { return w_irradiance[window_index(q)]; }
#ifdef DIRECT
vec3 window_specular(ivec2 q) { return w_specular[window_index(q)]; }
#endif
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
float window_tone(ivec2 q) { return w_tone[window_index(q)]; }
#endif
#else
void window_load() {}
uint window_id(ivec2 q) { return texelFetch(g_ids, q, 0).x; }
vec3 window_position(ivec2 q) { return texelFetch(g_position, q, 0).xyz; }
vec3 window_normal(ivec2 q) { return texelFetch(g_normal, q, 0).xyz; }
vec3 window_irradiance(ivec2 q) { return texelFetch(g_irradiance, q, 0).rgb; }
#ifdef DIRECT
vec3 window_specular(ivec2 q) { return texelFetch(g_specular, q, 0).rgb; }
#endif
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
float window_tone(ivec2 q) { return band_tone_fetch(q, texelFetch(g_ids, q, 0).x); }
#endif
#endif

bool same_surface(ivec2 q, uint object, vec3 p, vec3 n) {
    if (window_id(q) != object) return false;
    vec3 nq = window_normal(q);
    vec3 pq = window_position(q);
    return dot(n, nq) >= SAME_NORMAL_COS && abs(dot(n, pq - p)) <= PLANE_TOLERANCE * length(p);
}

#if FILTER == 3
#include "../interleaved/seed_edges.glsl"
#endif

// Candidate i (0, 1, 2) along one axis for the window offset o of period P: o itself, then the
// same subset one period the other way (both ways for o = 0); 1 << 20 where there is none.
int candidate(int o, int period, int i) {
    if (i == 0) return o;
    if (o > 0) return i == 1 ? o - period : 1 << 20;
    if (o < 0) return i == 1 ? o + period : 1 << 20;
    return i == 1 ? -period : period;
}

// `ours`' fallback: p shades the subsets of the window slots in `missing` itself, each invocation
// walking its own list (lowest slot first: a SIMD group or warp then pays for its longest list,
// not for the union of its lanes' missing subsets, as a loop over every slot with a test would),
// adds them to the found estimates' sums and returns the mean over the M N subsets (`specular`
// the specular one). With `fallback=pairs` (FALLBACK_PAIRS) fallback.comp does the same sums in
// the same order in passes of their own, and this runs only where their lists are full.
vec3 shade_missing(ivec2 px, vec3 p, vec3 n, float ns, uvec2 missing, vec3 sum, vec3 sum_spec,
                   out vec3 specular) {
    while (missing.x != 0u || missing.y != 0u) {
        uint word = missing.x != 0u ? 0u : 1u;
        uint t = uint(findLSB(missing[word]));
        missing[word] &= ~(1u << t);
        t += 32u * word;
        ivec2 o = ivec2(int(t % uint(TILE_M)) - (TILE_M - 1) / 2,
                        int(t / uint(TILE_M)) - (TILE_N - 1) / 2);
        uint k = subset_of(px + o);
        sum += subset_irradiance(p, n, k, pc.counts.y, pc.params.x);
#ifdef DIRECT
        subset_direct(sum, sum_spec, p, n, ns, k, uvec3(frame.counts.xy, pc.counts.x));
#endif
    }
    specular = sum_spec / float(SUBSETS);
    return sum / float(SUBSETS);
}

#ifdef FALLBACK_PAIRS
// What interleaved_irradiance leaves to the fallback passes: the missing window slots (none: it
// returned the pixel's irradiance) and the found estimates' sum.
uvec2 g_pending = uvec2(0u);
vec3 g_pending_sum = vec3(0.0);
#endif

// The filtered irradiance; `bits` gets the debug bits (edge, fallback count), `specular` the
// filtered specular estimate (DIRECT; 0 otherwise). ns: p's specular exponent.
vec3 interleaved_irradiance(ivec2 px, uint object, vec3 p, vec3 n, float ns, out uint bits,
                            out vec3 specular) {
    bits = subset_of(px);
    specular = vec3(0.0);
#if FILTER == 0 || FILTER == 3
#if defined(DEBUG) && FILTER == 3
    if (seed_edge(px)) bits |= DBG_EDGE;
#elif defined(DEBUG)
    for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
        for (int ox = -(TILE_M - 1) / 2; ox <= TILE_M / 2; ++ox) {
            ivec2 q = px + ivec2(ox, oy);
            if (on_screen(q) && !same_surface(q, object, p, n)) bits |= DBG_EDGE;
        }
    }
#endif
#ifdef DIRECT
    specular = texelFetch(g_specular, px, 0).rgb;
#endif
    return texelFetch(g_irradiance, px, 0).rgb;
#else
    vec3 sum = vec3(0.0);
    vec3 sum_spec = vec3(0.0);
    uint found = 0u;
    uvec2 missing = uvec2(0u);  // window slots (t = row M + column) with no estimate to use
#if FILTER == 1 && defined(BOX_ROWS)
    // The gather's window rows (gather.comp, BOX_ROWS): each row's on-screen pixels summed, so the
    // window takes N taps, not M N. The on-screen slots are a rectangle: count them.
    for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
        ivec2 q = px + ivec2(0, oy);
        if (q.y >= 0 && q.y < int(pc.counts.w)) {
            sum += texelFetch(g_irradiance, q, 0).rgb;
#ifdef DIRECT
            sum_spec += texelFetch(g_specular, q, 0).rgb;
#endif
        }
    }
    ivec2 lo = max(px - ivec2((TILE_M - 1) / 2, (TILE_N - 1) / 2), ivec2(0));
    ivec2 hi = min(px + ivec2(TILE_M / 2, TILE_N / 2), ivec2(pc.counts.zw) - 1);
    found = uint((hi.x - lo.x + 1) * (hi.y - lo.y + 1));
#ifdef DEBUG
    for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
        for (int ox = -(TILE_M - 1) / 2; ox <= TILE_M / 2; ++ox) {
            ivec2 q = px + ivec2(ox, oy);
            if (on_screen(q) && !same_surface(q, object, p, n)) bits |= DBG_EDGE;
        }
    }
#endif
#else
    for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
        for (int ox = -(TILE_M - 1) / 2; ox <= TILE_M / 2; ++ox) {
            ivec2 q = px + ivec2(ox, oy);
            bool on = on_screen(q);
            bool here = on && same_surface(q, object, p, n);
            if (on && !here) bits |= DBG_EDGE;
#if FILTER == 1
            bool use = on;
#else
            bool use = here;
            // Not on p's surface: the same subset one period further, nearest first (SEARCH 1).
            for (int s = 1; s <= 4 * SEARCH && !use; ++s) {
                for (int i = max(0, s - 2); i <= min(s, 2) && !use; ++i) {
                    int dx = candidate(ox, TILE_M, i);
                    int dy = candidate(oy, TILE_N, s - i);
                    if (dx == (1 << 20) || dy == (1 << 20)) continue;
                    ivec2 c = px + ivec2(dx, dy);
                    if (on_screen(c) && same_surface(c, object, p, n)) {
                        q = c;
                        use = true;
                    }
                }
            }
#endif
            if (use) {
                sum += window_irradiance(q);
#ifdef DIRECT
                sum_spec += window_specular(q);
#endif
                found += 1u;
            } else {
                uint t = uint((oy + (TILE_N - 1) / 2) * TILE_M + ox + (TILE_M - 1) / 2);
                missing[t >> 5] |= 1u << (t & 31u);
            }
        }
    }
#endif
#if FILTER == 2 && EXACT_EDGES > 0
    // `exact-edges=R`: a pixel with a pixel off its surface in the (2R+1) x (2R+1) square around
    // it (a band of R pixels along every boundary, which FLIP's edge features magnify) shades
    // every subset itself, the reference's value there.
    bool boundary = false;
    const int side = 2 * EXACT_EDGES + 1;
#ifndef BAND_SIDE
#define BAND_SIDE 0
#endif
#if defined(BAND_CONTRAST) && defined(BAND_DEPTH)
    float tone = length(p);
#elif defined(BAND_CONTRAST)
    float tone = window_tone(px);
#endif
    for (int k = 0; k < side * side; ++k) {
        ivec2 q = px + ivec2(k % side - EXACT_EDGES, k / side - EXACT_EDGES);
#if defined(BAND_CONTRAST) && defined(BAND_DEPTH)
        // `band=depth`: only the background, or another object at another distance.
#if BAND_SIDE == 0
        if (on_screen(q) && window_id(q) != object &&
            (window_id(q) == 0u || band_contrast(tone, length(window_position(q)))))
            boundary = true;
#elif BAND_SIDE == 1
        // `side=near`: only p on the nearer side (q the background, or farther).
        if (on_screen(q) && window_id(q) != object) {
            float dq = length(window_position(q));
            if (window_id(q) == 0u || dq - tone >= BAND_CONTRAST * dq) boundary = true;
        }
#else
        // `side=far`: only p on the farther side (q nearer).
        if (on_screen(q) && window_id(q) != object && window_id(q) != 0u &&
            tone - length(window_position(q)) >= BAND_CONTRAST * tone)
            boundary = true;
#endif
#elif defined(BAND_CONTRAST)
        // `band=albedo`: only another object (or the background) of another tone.
        if (on_screen(q) && window_id(q) != object && band_contrast(tone, window_tone(q)))
            boundary = true;
#elif defined(BAND_OBJECTS)
        // `band=object`: only another object (or the background) makes the band.
        if (on_screen(q) && window_id(q) != object) boundary = true;
#else
        if (on_screen(q) && !same_surface(q, object, p, n)) boundary = true;
#endif
    }
    if (boundary) {
        sum = vec3(0.0);
        sum_spec = vec3(0.0);
        found = 0u;
        missing = uvec2(SUBSETS >= 32u ? ~0u : (1u << SUBSETS) - 1u,
                        SUBSETS > 32u ? (SUBSETS == 64u ? ~0u : (1u << (SUBSETS - 32u)) - 1u) : 0u);
    }
#endif
#if FILTER == 1
    // `box`: the mean of the window's on-screen pixels (p's own among them).
    specular = sum_spec / float(found);
    return sum / float(found);
#endif
#if FILTER == 2
    // Enough of p's own surface in the window: the mean of what it holds (each estimate is
    // one subset's, so any of them estimates all the VPLs).
    if (found >= uint(ENOUGH)) {
        specular = sum_spec / float(found);
        return sum / float(found);
    }
#endif
#if PARTS == 3
    // `parts=filter`: the fallback left out (a timing attribution).
    missing = uvec2(0u);
#endif
    bits |= uint(bitCount(missing.x) + bitCount(missing.y)) << DBG_FALLBACK_SHIFT;
#ifdef FALLBACK_PAIRS
    // `fallback=pairs`: the caller lists the missing subsets for the fallback passes
    // (fallback.comp), which shade them and finish the pixel with the same sums in the same order.
    g_pending = missing;
    g_pending_sum = sum;
    if (missing != uvec2(0u)) return vec3(0.0);
#endif
    return shade_missing(px, p, n, ns, missing, sum, sum_spec, specular);
#endif
}
