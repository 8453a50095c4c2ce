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
// FLAT_TILES only with `ours` (the host sets it only then).
#if defined(FLAT_TILES) && FILTER != 2
#undef FLAT_TILES
#endif
layout(set = 0, binding = BINDING_IRRADIANCE) uniform sampler2D g_irradiance;
layout(set = 0, binding = BINDING_SPECULAR) uniform sampler2D g_specular;
#ifdef DEBUG
// Per pixel (docs/interleaved.md, debug views): bits 0-5 the pixel's subset, bit 6 edge (the
// window holds a pixel not on p's surface; `seed`: the seed's edge test), bits 8-14 the subsets
// p shaded itself, bit 16 where gather(split(G-buffer)) differs from the G-buffer, bit 17 a pixel
// of a flat tile (FLAT_TILES).
layout(set = 0, binding = BINDING_DEBUG_BITS, r32ui) uniform writeonly uimage2D debug_bits;
#endif

const uint DBG_EDGE = 1u << 6;
const uint DBG_FALLBACK_SHIFT = 8u;
const uint DBG_ROUNDTRIP = 1u << 16;
const uint DBG_FLAT = 1u << 17;

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
#if FILTER == 2
const int APRON_X0 = max(max((TILE_M - 1) / 2, SEARCH * TILE_M), EXACT_EDGES);
const int APRON_X1 = max(max(TILE_M / 2, SEARCH * TILE_M), EXACT_EDGES);
const int APRON_Y0 = max(max((TILE_N - 1) / 2, SEARCH * TILE_N), EXACT_EDGES);
const int APRON_Y1 = max(max(TILE_N / 2, SEARCH * TILE_N), EXACT_EDGES);
const int WIN_W = LOCAL_SIZE_X + APRON_X0 + APRON_X1;
const int WIN_H = LOCAL_SIZE_Y + APRON_Y0 + APRON_Y1;
// The core of the tile (FLAT_TILES): the texels the workgroup's window slots and `exact-edges`'
// squares reach, without `search`'s candidates. Where every slot is on p's surface no candidate
// is looked at, and where no texel of another object is within the square no band is tested, so
// a tile's flatness (and its being of one object) is a property of its core alone.
const int CORE_X0 = max((TILE_M - 1) / 2, EXACT_EDGES);
const int CORE_X1 = max(TILE_M / 2, EXACT_EDGES);
const int CORE_Y0 = max((TILE_N - 1) / 2, EXACT_EDGES);
const int CORE_Y1 = max(TILE_N / 2, EXACT_EDGES);
const int CORE_W = LOCAL_SIZE_X + CORE_X0 + CORE_X1;
const int CORE_H = LOCAL_SIZE_Y + CORE_Y0 + CORE_Y1;
#ifdef WINDOW_TILE
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
#endif

ivec2 window_origin() {
    return ivec2(gl_WorkGroupID.xy) * ivec2(LOCAL_SIZE_X, LOCAL_SIZE_Y) - ivec2(APRON_X0, APRON_Y0);
}

#ifdef FLAT_TILES
// `flat=on` (FLAT_TILES, the default of the tile): a tile whose core (every texel the
// workgroup's window slots and `exact-edges`' squares reach, CORE_*) lies on one plane-like
// surface is *flat*, and its pixels take the box mean of their windows without a test, because
// every test of the filter would pass there (the same bits: the same sums in the same order;
// `search`'s candidates are looked at only for a slot off p's surface, so they do not count).
// Flat: every texel of the core on the screen and of the reference texel's object (the workgroup's centre
// pixel c, not the background), every normal within e of c's (|n_q - n_c| <= e, |n_q|^2 within
// 1% of 1), every position within R of c's, and the signed distances h_q = n_c . (p_q - p_c)
// spanning S. For any two texels p, q then
//   n_p . n_q >= (|n_p|^2 + |n_q|^2 - (2e)^2) / 2 >= 0.99 - 2 e^2, and
//   |n_p . (p_q - p)| <= |n_c . (p_q - p)| + |n_p - n_c| |p_q - p| <= S + 2 e R,
// so same_surface holds for every pair when 0.99 - 2 e^2 >= SAME_NORMAL_COS + 0.001 and
// S + 2 e R <= 0.9 PLANE_TOLERANCE (|p_c| - R) (|p| >= |p_c| - R; the 10% and 0.001 cover the
// shader's float rounding, about 1e-7 of |p|). The object band and the contrast bands need
// another object, so no pixel of a flat tile is in a band either.
shared uint t_rough;
shared uint t_span_pos;
shared uint t_span_neg;
shared uint t_e2;
shared uint t_r2;
bool g_flat = false;
// The tile's core holds one object only (every texel on the screen and of the centre texel's object):
// then no pixel of it has another object (or the background) within reach, and the object and
// contrast bands, which need one, are empty there without their square's tests.
bool g_one_object = false;
#endif

// A tile texel's G-buffer values (its estimates come apart: a flat tile does not keep them).
struct TileTexel {
    uint id;
    vec3 p;
    vec3 n;
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
    float tone;
#endif
};

TileTexel tile_fetch(ivec2 q) {
    TileTexel x;
    x.id = 0u;
    x.p = vec3(0.0);
    x.n = vec3(0.0);
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
    x.tone = 0.0;
#endif
    if (on_screen(q)) {
        x.id = texelFetch(g_ids, q, 0).x;
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
        x.tone = band_tone_fetch(q, x.id);
#endif
        x.p = texelFetch(g_position, q, 0).xyz;
        x.n = texelFetch(g_normal, q, 0).xyz;
    }
    return x;
}

#ifdef WINDOW_TILE
// Texel t of the tile (at q) into shared memory, with its estimates.
void tile_store(uint t, ivec2 q, TileTexel x) {
    vec3 eq = vec3(0.0), sq = vec3(0.0);
    if (on_screen(q)) {
        eq = texelFetch(g_irradiance, q, 0).rgb;
#ifdef DIRECT
        sq = texelFetch(g_specular, q, 0).rgb;
#endif
    }
    w_ids[t] = x.id;
    w_position[t] = x.p;
    w_normal[t] = x.n;
    w_irradiance[t] = eq;
#ifdef DIRECT
    w_specular[t] = sq;
#endif
#if defined(BAND_CONTRAST) && !defined(BAND_DEPTH)
    w_tone[t] = x.tone;
#endif
}

#endif

ivec2 tile_texel(uint t) {
    return window_origin() + ivec2(int(t) % WIN_W, int(t) / WIN_W);
}

#ifdef FLAT_TILES
ivec2 core_origin() {
    return ivec2(gl_WorkGroupID.xy) * ivec2(LOCAL_SIZE_X, LOCAL_SIZE_Y) - ivec2(CORE_X0, CORE_Y0);
}
#endif

const uint TILE_TEXELS = uint(WIN_W * WIN_H);
const uint GROUP_SIZE = uint(LOCAL_SIZE_X * LOCAL_SIZE_Y);

// Every invocation of the workgroup, before any returns: the tile into shared memory, then a
// barrier. Texels off the screen get object 0 (never on a surface; the filter tests on_screen
// first anyway). With FLAT_TILES the G-buffer texels are fetched first and the tile's flatness
// taken from them (g_flat, the same in every invocation); a flat tile stores nothing (its
// pixels read their estimates by texel fetches: on llvmpipe a fetch's gather costs less than a
// shared-memory read, which is a per-lane loop), any other stores its texels and estimates.
void window_load() {
#ifdef FLAT_TILES
#ifdef WINDOW_TILE
    const uint CLASS_TEXELS = TILE_TEXELS;
#else
    const uint CLASS_TEXELS = uint(CORE_W * CORE_H);
#endif
    const uint PER_INVOCATION = (CLASS_TEXELS + GROUP_SIZE - 1u) / GROUP_SIZE;
    if (gl_LocalInvocationIndex == 0u) {
        t_rough = 0u;
        t_span_pos = 0u;
        t_span_neg = 0u;
        t_e2 = 0u;
        t_r2 = 0u;
    }
    barrier();
    ivec2 c = ivec2(gl_WorkGroupID.xy) * ivec2(LOCAL_SIZE_X, LOCAL_SIZE_Y) +
              ivec2(LOCAL_SIZE_X / 2, LOCAL_SIZE_Y / 2);
    TileTexel ref = tile_fetch(c);
    bool others = !on_screen(c) || ref.id == 0u;
    bool rough = others;
    float span_pos = 0.0, span_neg = 0.0, e2 = 0.0, r2 = 0.0;
#ifdef WINDOW_TILE
    TileTexel mine[PER_INVOCATION];
#endif
    // With the tile the invocations fetch all of it (a rough tile stores it) and measure its core
    // (below); with `window=fetch` they fetch the core alone.
    for (uint k = 0u; k < PER_INVOCATION; ++k) {
        uint t = gl_LocalInvocationIndex + k * GROUP_SIZE;
        if (t >= CLASS_TEXELS) break;
#ifdef WINDOW_TILE
        ivec2 q = tile_texel(t);
        TileTexel x = tile_fetch(q);
        mine[k] = x;
        ivec2 l = q - core_origin();
        if (l.x < 0 || l.y < 0 || l.x >= CORE_W || l.y >= CORE_H) continue;
#else
        TileTexel x = tile_fetch(core_origin() + ivec2(int(t) % CORE_W, int(t) / CORE_W));
#endif
        float h = dot(ref.n, x.p - ref.p);
        vec3 dn = x.n - ref.n, dp = x.p - ref.p;
        span_pos = max(span_pos, h);
        span_neg = max(span_neg, -h);
        e2 = max(e2, dot(dn, dn));
        r2 = max(r2, dot(dp, dp));
        // Off the screen (id 0), another object, a normal not of unit length, or anything not
        // finite (every comparison with a NaN is false) makes the tile rough.
        others = others || x.id != ref.id;
        rough = rough || others || !(abs(dot(x.n, x.n) - 1.0) <= 0.01) ||
                !(abs(h) <= 1e30) || !(dot(dn, dn) <= 1e30) || !(dot(dp, dp) <= 1e30);
    }
    // The workgroup's extremes (each is >= 0, so its bits order as the floats do).
    rough = subgroupAny(rough);
    others = subgroupAny(others);
    span_pos = subgroupMax(span_pos);
    span_neg = subgroupMax(span_neg);
    e2 = subgroupMax(e2);
    r2 = subgroupMax(r2);
    if (subgroupElect()) {
        if (rough) atomicOr(t_rough, others ? 3u : 1u);
        atomicMax(t_span_pos, floatBitsToUint(span_pos));
        atomicMax(t_span_neg, floatBitsToUint(span_neg));
        atomicMax(t_e2, floatBitsToUint(e2));
        atomicMax(t_r2, floatBitsToUint(r2));
    }
    barrier();
    float s = uintBitsToFloat(t_span_pos) + uintBitsToFloat(t_span_neg);
    float e = sqrt(uintBitsToFloat(t_e2));
    float r = sqrt(uintBitsToFloat(t_r2));
    float nearest = length(ref.p) - r;
    g_one_object = (t_rough & 2u) == 0u;
    g_flat = t_rough == 0u && 0.99 - 2.0 * e * e >= SAME_NORMAL_COS + 0.001 && nearest > 0.0 &&
             s + 2.0 * e * r <= 0.9 * PLANE_TOLERANCE * nearest;
#ifdef WINDOW_TILE
    if (!g_flat) {
        for (uint k = 0u; k < PER_INVOCATION; ++k) {
            uint t = gl_LocalInvocationIndex + k * GROUP_SIZE;
            if (t >= TILE_TEXELS) break;
            tile_store(t, tile_texel(t), mine[k]);
        }
        barrier();
    }
#endif
#elif defined(WINDOW_TILE)
    for (uint t = gl_LocalInvocationIndex; t < TILE_TEXELS; t += GROUP_SIZE) {
        ivec2 q = tile_texel(t);
        tile_store(t, q, tile_fetch(q));
    }
    barrier();
#endif
}

#endif

#if FILTER == 2 && defined(WINDOW_TILE)
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
#if FILTER != 2
void window_load() {}
#endif
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
#ifdef FLAT_TILES
    // A flat tile (window_load): every slot is on p's surface and on the screen, and no pixel is
    // in a band, so the filter is the window's mean, summed in the loop's order below.
    if (g_flat) {
        for (int oy = -(TILE_N - 1) / 2; oy <= TILE_N / 2; ++oy) {
            for (int ox = -(TILE_M - 1) / 2; ox <= TILE_M / 2; ++ox) {
                ivec2 q = px + ivec2(ox, oy);
                sum += texelFetch(g_irradiance, q, 0).rgb;
#ifdef DIRECT
                sum_spec += texelFetch(g_specular, q, 0).rgb;
#endif
                found += 1u;
            }
        }
        bits |= DBG_FLAT;
        specular = sum_spec / float(found);
        return sum / float(found);
    }
#endif
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
#if defined(FLAT_TILES) && defined(BAND_OBJECTS)
    // A tile of one object has no pixel of another within R (window_load): no band to test.
    if (!g_one_object)
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
