#version 460
#extension GL_GOOGLE_include_directive : require
// `analytic`, resolve: per pixel, its K nearest fragments, each with its exact coverage a, its
// MASK_SAMPLES-sample mask (mask.glsl) and its depth plane. The visibility model (docs/analytic.md):
// 1. Per mask sample, its winner: the nearest fragment there by the fragments' depth planes
//    (ties: the earlier key, object then primitive), among the fragments whose mask holds the
//    sample. An alpha-tested fragment's mask holds only its samples that pass the test
//    (raster.frag), so it hides and is hidden per sample; one too small to hold a sample has an
//    estimated passing share and holes (FRAG_HOLES): it wins no samples. Fragments too small to
//    hold a sample carry a stand-in bit (the sample nearest their centroid, which lies outside
//    them, often in a neighbour of their own mesh): they win only samples that no real mask
//    holds.
// 2. Fragment k loses a sample of its mask to the winner there. A stand-in loses its sample only
//    where the winner is in front of its plane there, by more than 1e-3 of the depth if the
//    winner is its own object (else the same surface: a sliver beside its neighbour), by more
//    than 1e-5 if another (the planes' rounding: coplanar objects abutting); and it is
//    hidden where the rest of its surface in the pixel is hidden at every sample (its object, its
//    facing, a normal within SAME_SURFACE_COS, a plane through its depth within
//    SAME_SURFACE_DEPTH). A fragment that loses no sample is unoccluded: it adds its exact
//    coverage a; one that loses every sample to its own object is hidden (the back of a
//    closed mesh behind its front). Otherwise each winner w occludes it by w's visible coverage
//    spread evenly over the samples w won:
//        v = a - sum over k's lost samples s of v(w(s)) / won(w(s)).
//    Exact for an opaque surface in front of another that covers the rest of the pixel (the far
//    one gets exactly 1 - a_near) and for abutting triangles; where two partial surfaces overlap
//    or two surfaces intersect inside the pixel, the overlap's shape is sampled by the MASK_SAMPLES samples
//    and its area by the exact coverages. v depends on the winners' v: two sweeps in key order,
//    the first from v = a won / m.
// 3. Front to back in key order, through each sample's transmittance past the fragments with
//    holes composited before (over compositing per sample: their holes are unrelated to anything
//    else, and abutting ones do not darken their shared edge): a fragment with holes shows
//    through the mean transmittance of its samples that no opaque winner in front of it holds,
//    an opaque one through that of the samples it keeps. Then v is clamped to what nearer ones
//    left, v = min(v, 1 - sum): colour += v c.
//    A fragment some of whose samples are hidden shows only the rest of its mask: its albedo is
//    scaled to their cells' in its albedo grid (shown_albedo; surface.glsl), and it is lit at
//    their centroid.
//    Only the fragments composited with v > 0 are lit, here, after the visibility (shaders
//    /inc/shading.glsl's `shade` at the fragment's shading point: the albedo, normal and point
//    the raster pass left in its slot, surface.glsl; the point's camera-relative position is its
//    depth plane there, unprojected by pc.world_from_clip, the inverse of the camera's unjittered
//    projection, made in f64 on the CPU, after the jitter is taken off). A non-finite colour
//    drops the fragment as the raster pass drops one (coverage 0, holes, flagged) and the
//    visibility is settled again without it.
// 4. Only the K nearest fragments of a pixel are kept (the select pass); those beyond count as
//    overflow and are merged into two tail fragments (coverage-weighted mean colour, summed
//    coverage, union of masks), those facing the camera, then those facing away, composited
//    after the K, each by the share of its samples not held by the K (nor the front tail), at
//    most the fraction of the pixel's samples that share is (a tail's summed coverage counts
//    its overlapping layers once each), and through the transmittance of its open samples: no
//    surface is dropped, only its order within its tail and the overlaps among it are
//    estimated. The background fills the remainder.
#extension GL_ARB_gpu_shader_int64 : require
#define EMPTY_KEY 0xFFFFFFFFFFFFFFFFul  // a slot no fragment took
#include "../inc/scene_types.glsl"
#include "coverage.glsl"
#include "surface.glsl"

layout(local_size_x = LOCAL_SIZE_X, local_size_y = LOCAL_SIZE_Y) in;

layout(std430, set = 0, binding = BINDING_KEYS) readonly buffer Keys { uint64_t keys[]; };
layout(std430, set = 0, binding = BINDING_SLOTS) readonly buffer Slots { uvec2 slots[]; };
layout(std430, set = 0, binding = BINDING_SLOT_MASKS) readonly buffer SlotMasks { uint slot_masks[]; };
layout(std430, set = 0, binding = BINDING_COLORS) readonly buffer Colors { uvec2 colors[]; };
layout(std430, set = 0, binding = BINDING_COUNTS) readonly buffer Counts { uint counts[]; };
layout(std430, set = 0, binding = BINDING_TAIL) readonly buffer Tail { uint64_t tail[]; };
layout(std430, set = 0, binding = BINDING_TAIL_BACK) readonly buffer TailBack { uint64_t tail_back[]; };
layout(std430, set = 0, binding = BINDING_TAIL_MASKS) readonly buffer TailMasks { uint tail_masks[]; };
layout(std430, set = 0, binding = BINDING_PLANES) readonly buffer Planes { vec2 planes[]; };
layout(std430, set = 0, binding = BINDING_PLANES_Y) readonly buffer PlanesY { float planes_y[]; };
layout(std430, set = 0, binding = BINDING_SURFACES) readonly buffer Surfaces { uvec2 surfaces[]; };
layout(std430, set = 0, binding = BINDING_CELLS) readonly buffer Cells { uvec2 cells[]; };
layout(std430, set = 0, binding = BINDING_CELLS_HI) readonly buffer CellsHi { uvec2 cells_hi[]; };
// The scene's buffers, for the lighting.
layout(set = 0, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = 0, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = 0, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(set = 0, binding = BINDING_OUT_COLOR, rgba16f) uniform writeonly image2D out_color;
layout(set = 0, binding = BINDING_OUT_COVERAGE, r32f) uniform writeonly image2D out_coverage;
layout(set = 0, binding = BINDING_OUT_COUNTS, rgba32ui) uniform writeonly uimage2D out_counts;
// pc.background (rgb), pc.size (width, height), pc.world_from_clip (passes.rs's ResolvePush).
PUSH_CONSTANTS

#include "../inc/shading.glsl"

// Counts' channels: fragments that touched the pixel, overflow (beyond the K nearest), flags,
// visible fragments. The flags' bits are defines from Rust (passes.rs): FLAG_EDGE, a visible
// fragment covers the pixel partly, or the background shows; FLAG_SEED, analytic:seed: a visible
// fragment's shortcut area is off by > 1e-3; FLAG_OVERFLOW; FLAG_NONFINITE, a kept fragment's
// shading was not finite (dropped).
// A fragment's own flags (raster.frag).
#define FRAG_SEED_OFF 1u   // analytic:seed: its shortcut area is off by > 1e-3
#define FRAG_HOLES 2u      // alpha-tested without samples, or not finite: wins no samples
#define FRAG_NONFINITE 4u
#define FRAG_STAND_IN 8u   // its mask is the one sample nearest its centroid
#define FRAG_FACING_AWAY 16u  // its normal faces away from the camera (shaded from the other side)
// Two fragments of one object facing the same way whose shading normals are within this cosine
// (about 32 degrees) and whose depth planes agree within this share of the depth at the stand-in's
// centroid count as one surface for the stand-in rule (step 2).
#define SAME_SURFACE_COS 0.85
#define SAME_SURFACE_DEPTH 1e-2

// Fragment k's depth at mask sample q (pixel-local).
float plane_depth(uint slot, vec2 q) {
    vec2 p = planes[slot];
    return p.x + p.y * (q.x - 0.5) + planes_y[slot] * (q.y - 0.5);
}

// The albedo of the part of a fragment that shows, relative to its albedo over its mask: where
// nearer fragments hide some of its samples (`kept` is the rest of `mask`), the mean of its
// albedo grid's cells (surface.glsl) over the kept samples against that over the mask. The raster pass
// filtered the albedo over the pixel's footprint; a surface seen through a gap between nearer
// ones (the floor between a fence's slats, behind leaves) shows only the part of it in the gap.
float shown_albedo(uint slot, Mask mask, Mask kept) {
    if (kept == mask) return 1.0;
    uvec4 packed = uvec4(cells[slot], cells_hi[slot]);
    if (all(equal(packed, uvec4(0xFFFFFFFFu)))) return 1.0;  // one albedo over the pixel
    float all_luma = 0.0;
    float shown_luma = 0.0;
    float in_mask = 0.0;
    float in_kept = 0.0;
    Mask rest = mask;
    while (mask_any(rest)) {
        int s = mask_pop(rest);
        float l = unpack_cell(packed, cell_of(mask_sample(s)));
        all_luma += l;
        in_mask += 1.0;
        if (mask_has(kept, s)) {
            shown_luma += l;
            in_kept += 1.0;
        }
    }
    all_luma /= in_mask;
    shown_luma /= in_kept;
    return all_luma > 0.0 ? shown_luma / all_luma : 1.0;
}

// The light of the fragment in `slot` (of object `object`) at pixel px, its albedo scaled by
// `albedo_scale` (shown_albedo), lit at pixel-local point `at` where at.x >= 0 (the part of it
// that shows), else at its own shading point.
vec3 shade_slot(uint slot, uint object, ivec2 px, float albedo_scale, vec2 at) {
    uvec2 cl = colors[slot];
    vec3 albedo = vec3(unpackHalf2x16(cl.x), unpackHalf2x16(cl.y).x) * albedo_scale;
    vec3 nrm;
    vec2 point;
    unpack_surface(surfaces[slot], nrm, point);
    if (at.x >= 0.0) point = at;
    float z = plane_depth(slot, point);
    vec2 jitter = frame.screen_jitter.xy * 2.0 * frame.output_size.zw;
    vec2 ndc = (vec2(px) + point) * frame.output_size.zw * 2.0 - 1.0 - jitter;
    vec4 h = pc.world_from_clip * vec4(ndc, z, 1.0);
    MaterialData mat = materials[objects[object - 1u].ids.y];
    return shade(h.xyz / h.w, nrm, albedo, mat, frame);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(pc.size.x) || px.y >= int(pc.size.y)) return;
    uint pixel = uint(px.y) * pc.size.x + uint(px.x);
    uint base = pixel * uint(K_SLOTS);

    // The slots hold the K nearest keys in order (the select pass's insertion).
    uint objs[K_SLOTS];
    Mask masks[K_SLOTS];
    uint fl[K_SLOTS];
    float area[K_SLOTS];
    float alpha[K_SLOTS];  // an alpha-tested fragment's passing share of its covered part
    int count = 0;
    for (int k = 0; k < K_SLOTS; ++k) {
        uint64_t key = keys[base + uint(k)];
        if (key == EMPTY_KEY) break;
        objs[k] = uint(key & 0xFFFFFFFFul) >> 20u;
        uvec2 sl = slots[base + uint(k)];
        area[k] = uintBitsToFloat(sl.x);
        masks[k] = Mask(sl.y);
        for (int w = 1; w < MASK_WORDS; ++w)
            mask_set_word(masks[k], w, slot_masks[(base + uint(k)) * uint(MASK_WORDS - 1) + uint(w - 1)]);
        uint packed = colors[base + uint(k)].y;
        fl[k] = (packed >> 16u) & 0xFFu;
        alpha[k] = float(packed >> 24u) / 255.0;
        ++count;
    }

    float trans[MASK_SAMPLES];
    float sum;
    vec3 color;
    uint flags;
    uint visible;
    bool pixel_holes;  // a kept fragment has holes: the per-sample transmittances are used
    // Settled again without a fragment whose light turned out non-finite (at most once per
    // fragment).
    for (int attempt = 0; attempt <= K_SLOTS; ++attempt) {
    // (steps 1-3 are not indented: the attempt loop is their whole body)
    // 1. Each mask sample's winner (a slot index, 0xFF for none) and its depth there.
    uint winner[MASK_SAMPLES];
    float wz[MASK_SAMPLES];
    Mask won[K_SLOTS];
    for (int k = 0; k < count; ++k) won[k] = Mask(0u);
    // Fragment by fragment in key order, over its own samples only (a pixel's fragments hold
    // few of the samples each): at each sample the candidates come in the same order as a loop
    // over the fragments per sample would take them, so the winners are the same.
    // winner[s] and wz[s] are set where `claimed` holds s (no per-sample initialisation: at 128
    // samples the private arrays' stores were a measurable part of the pass).
    Mask claimed = Mask(0u);
    Mask real_won = Mask(0u);  // the samples a real (not stand-in) fragment wins so far
    for (int k = 0; k < count; ++k) {
        if ((fl[k] & FRAG_HOLES) != 0u) continue;
        // The nearest real sample of the mask wins; where none holds it, the nearest stand-in.
        bool real = (fl[k] & FRAG_STAND_IN) == 0u;
        Mask rest = masks[k];
        while (mask_any(rest)) {
            int s = mask_pop(rest);
            float z = plane_depth(base + uint(k), mask_sample(s));
            bool best_real = mask_has(real_won, s);
            // Reverse-Z: nearer is larger; ties keep the earlier key.
            if (!mask_has(claimed, s) || (real && !best_real) || (real == best_real && z > wz[s])) {
                winner[s] = uint(k);
                wz[s] = z;
                if (real) real_won |= mask_bit(s);
            }
        }
        claimed |= masks[k];
    }
    {
        Mask rest = claimed;
        while (mask_any(rest)) {
            int s = mask_pop(rest);
            won[winner[s]] |= mask_bit(s);
        }
    }

    // 2. The samples each fragment lost to a winner in front of it, and the visible coverages:
    // settled (unoccluded, or hidden behind its own mesh) or by the occlusion sum (two sweeps).
    Mask lost[K_SLOTS];
    float vis[K_SLOTS];
    bool settled[K_SLOTS];
    for (int k = 0; k < count; ++k) {
        Mask l = Mask(0u);
        bool own = true;  // every lost sample lost to its own object
        if ((fl[k] & (FRAG_HOLES | FRAG_STAND_IN)) == 0u) {
            // A real sample is lost to any winner but itself: every sample of the mask it did not
            // win. Whether all went to its own object matters only where it lost them all.
            l = masks[k] & ~won[k];
            if (l == masks[k]) {
                for (int j = 0; j < count; ++j) {
                    if (objs[j] != objs[k] && mask_any(won[j] & l)) own = false;
                }
            }
        } else if ((fl[k] & FRAG_HOLES) == 0u) {
            Mask rest = masks[k] & ~won[k];
            while (mask_any(rest)) {
                int s = mask_pop(rest);
                uint w = winner[s];
                float zk = plane_depth(base + uint(k), mask_sample(s));
                bool same_object = objs[w] == objs[k];
                // A stand-in is behind the winner where its plane, extrapolated to its sample,
                // is: beyond 1e-3 of the depth when the winner is its own object (the same
                // surface), beyond 1e-5 (the planes' rounding) when it is another: coplanar
                // surfaces of two objects abutting in the pixel keep their slivers.
                bool behind = wz[s] - zk > (same_object ? 1e-3 : 1e-5) * abs(zk);
                if (behind) {
                    l |= mask_bit(s);
                    own = own && same_object;
                }
            }
        }
        lost[k] = l;
        uint m = uint(mask_count(masks[k]));
        // Hidden (l == mask) gives 0, unoccluded (l == 0) gives a.
        vis[k] = m > 0u ? area[k] * float(m - uint(mask_count(l))) / float(m) : area[k];
        settled[k] = !mask_any(l) || (l == masks[k] && own);
    }
    // A stand-in's sample lies outside it, so the winner there can be a surface behind it while
    // what hides it lies over its real place (a sliver under a nearer surface's edge, or the back
    // of a mesh along its contour: its own sample out in the open, where only a far wall is).
    // Where the rest of its surface in the pixel (real fragments of its object facing the same
    // way, normals within SAME_SURFACE_COS, their planes through its centroid's depth within
    // SAME_SURFACE_DEPTH) is hidden at every sample, it is hidden too.
    for (int k = 0; k < count; ++k) {
        if ((fl[k] & (FRAG_STAND_IN | FRAG_HOLES)) != FRAG_STAND_IN || mask_any(lost[k])) continue;
        vec3 nk;
        vec2 ck;
        unpack_surface(surfaces[base + uint(k)], nk, ck);
        float zk = plane_depth(base + uint(k), ck);
        bool sibling = false;
        bool all_hidden = true;
        for (int j = 0; j < count; ++j) {
            if (j == k || (fl[j] & (FRAG_STAND_IN | FRAG_HOLES)) != 0u || objs[j] != objs[k]
                || ((fl[j] ^ fl[k]) & FRAG_FACING_AWAY) != 0u) continue;
            vec3 nj = oct_decode(unpackSnorm2x16(surfaces[base + uint(j)].x));
            if (dot(nj, nk) < SAME_SURFACE_COS
                || abs(plane_depth(base + uint(j), ck) - zk) > SAME_SURFACE_DEPTH * abs(zk)) continue;
            sibling = true;
            all_hidden = all_hidden && lost[j] == masks[j];
        }
        if (sibling && all_hidden) {
            lost[k] = masks[k];
            vis[k] = 0.0;
            settled[k] = true;
        }
    }
    // Fragment by fragment: winner j occludes k by v(j) times the share of j's samples that k
    // lost to it (the sum over k's lost samples, grouped by their winner: a pixel has far fewer
    // fragments than a fragment has samples).
    float won_count[K_SLOTS];
    for (int j = 0; j < count; ++j) won_count[j] = float(mask_count(won[j]));
    for (int sweep = 0; sweep < 2; ++sweep) {
        for (int k = 0; k < count; ++k) {
            if (settled[k]) continue;
            float occ = 0.0;
            for (int j = 0; j < count; ++j) {
                Mask by_j = lost[k] & won[j];
                if (mask_any(by_j)) occ += vis[j] * float(mask_count(by_j)) / won_count[j];
            }
            vis[k] = clamp(area[k] - occ, 0.0, area[k]);
        }
    }

    // 3. Front to back in key order, with each sample's transmittance through the alpha-tested
    // fragments composited so far (their holes are unrelated to anything else: over compositing,
    // but per sample, so that abutting cards do not darken their shared edge). An alpha-tested
    // fragment shows through its samples' transmittance where no opaque winner lies in front of
    // it; an opaque one through the mean transmittance over the samples it keeps. Then clamped to
    // what nearer ones left, v = min(v, 1 - sum).
    // The transmittances are needed only where a fragment has holes.
    pixel_holes = false;
    for (int k = 0; k < count; ++k) {
        pixel_holes = pixel_holes || (fl[k] & (FRAG_HOLES | FRAG_NONFINITE)) == FRAG_HOLES;
    }
    if (pixel_holes) {
        for (int s = 0; s < MASK_SAMPLES; ++s) trans[s] = 1.0;
    }
    bool any_holes = false;
    sum = 0.0;
    color = vec3(0.0);
    flags = 0u;
    visible = 0u;
    float shown[K_SLOTS];  // the composited v of the fragments in `show`
    float scale[K_SLOTS];  // and their shown_albedo
    vec2 at[K_SLOTS];      // and where they are lit (x < 0: at their own shading point)
    uvec2 show = uvec2(0u);  // slot k in bit k % 32 of word k / 32 (K_SLOTS <= 64)
    for (int k = 0; k < count; ++k) {
        uint fflags = fl[k];
        float a = area[k];
        if ((fflags & FRAG_SEED_OFF) != 0u) flags |= FLAG_SEED;
        if ((fflags & FRAG_NONFINITE) != 0u) flags |= FLAG_NONFINITE;
        bool holes = (fflags & (FRAG_HOLES | FRAG_NONFINITE)) == FRAG_HOLES;
        float v = vis[k];
        // The samples it shows through: an alpha-tested one's whole mask, an opaque one's kept
        // samples (its mask where it lost them all: a fragment settled by the occlusion sum).
        Mask keep = holes ? masks[k] : masks[k] & ~lost[k];
        if (!mask_any(keep)) keep = masks[k];
        if (holes || any_holes) {
            float t = 0.0;
            uint n = 0u;
            Mask rest = keep;
            while (mask_any(rest)) {
                int s = mask_pop(rest);
                // An alpha-tested fragment is hidden where an opaque winner is in front of it.
                bool open = !holes || !mask_has(claimed, s)
                    || wz[s] <= plane_depth(base + uint(k), mask_sample(s));
                t += open ? trans[s] : 0.0;
                ++n;
                if (holes) trans[s] *= 1.0 - alpha[k];
            }
            v *= n > 0u ? t / float(n) : 1.0;
            any_holes = any_holes || holes;
        }
        v = min(v, 1.0 - sum);
        if (v <= 0.0) continue;
        shown[k] = v;
        scale[k] = shown_albedo(base + uint(k), masks[k], keep);
        // A fragment of which only a part shows is lit at that part's centroid (its kept
        // samples' mean): near a point light the light changes across the pixel (the ground
        // seen through leaves, by a lamp among them).
        at[k] = vec2(-1.0);
        if (keep != masks[k]) {
            vec2 sum_at = vec2(0.0);
            float n_at = 0.0;
            Mask rest = keep;
            while (mask_any(rest)) {
                sum_at += mask_sample(mask_pop(rest));
                n_at += 1.0;
            }
            at[k] = sum_at / n_at;
        }
        show[k >> 5] |= 1u << uint(k & 31);
        sum += v;
        ++visible;
        if (a < 1.0 - 1e-6) flags |= FLAG_EDGE;
    }
    // The light of the composited fragments only, in key order; each invocation walks its own
    // list (a SIMD group pays for its longest, not for every slot).
    bool again = false;
    while (show != uvec2(0u)) {
        int w = show.x != 0u ? 0 : 1;
        int k = w * 32 + findLSB(show[w]);
        show[w] &= show[w] - 1u;
        vec3 c = shade_slot(base + uint(k), objs[k], px, scale[k], at[k]);
        if (any(isnan(c)) || any(isinf(c))) {
            fl[k] |= FRAG_HOLES | FRAG_NONFINITE;
            area[k] = 0.0;
            again = true;
        } else {
            color += shown[k] * c;
        }
    }
    if (!again) break;
    }
    uint seen = counts[pixel];
    uint overflow = seen - uint(count);
    if (overflow > 0u) flags |= FLAG_OVERFLOW;
    if (sum < 1.0 - 1e-6 && visible > 0u) flags |= FLAG_EDGE;
    // The fragments beyond the K nearest, merged into two (their coverage-weighted mean colours,
    // their summed coverages, the union of their masks): those facing the camera, then those
    // facing away (of a closed mesh, behind its front). Each fills what the nearest left, in
    // proportion to the share of its mask's samples that no kept fragment (nor, for the back
    // tail, the front tail) holds: the tails lie behind the K.
    Mask held = Mask(0u);
    for (int k = 0; k < count; ++k) {
        if ((fl[k] & FRAG_HOLES) == 0u) held |= masks[k];
    }
    for (uint part = 0u; part < 2u && overflow > 0u && sum < 1.0; ++part) {
        uint t = pixel * 4u;
        const float unit = 1.0 / 16777216.0;
        u64vec4 sums = part == 0u
            ? u64vec4(tail[t], tail[t + 1u], tail[t + 2u], tail[t + 3u])
            : u64vec4(tail_back[t], tail_back[t + 1u], tail_back[t + 2u], tail_back[t + 3u]);
        float ta = float(sums.w) * unit;
        Mask tm = Mask(0u);
        for (int w = 0; w < MASK_WORDS; ++w)
            mask_set_word(tm, w, tail_masks[(pixel * 2u + part) * uint(MASK_WORDS) + uint(w)]);
        if (ta > 0.0 && mask_any(tm)) {
            vec3 tc = vec3(sums.xyz) * unit / ta;
            // Its summed coverage counts overlapping layers of the tail once each: no more than
            // the share of the pixel's samples it holds open.
            Mask open_mask = tm & ~held;
            uint open_bits = uint(mask_count(open_mask));
            float open_share = float(open_bits) / float(mask_count(tm));
            // Through the kept alpha-tested fragments: the mean transmittance of its open samples.
            float t = float(open_bits);
            if (pixel_holes) {
                t = 0.0;
                Mask rest = open_mask;
                while (mask_any(rest)) {
                    int s = mask_pop(rest);
                    t += trans[s];
                }
            }
            t = open_bits > 0u ? t / float(open_bits) : 0.0;
            float v = min(min(ta * open_share, float(open_bits) / float(MASK_SAMPLES)) * t, 1.0 - sum);
            color += v * tc;
            sum += v;
        }
        held |= tm;
    }
    color += max(1.0 - sum, 0.0) * pc.background.rgb;
    imageStore(out_color, px, vec4(color, 1.0));
    imageStore(out_coverage, px, vec4(sum));
    imageStore(out_counts, px, uvec4(seen, overflow, flags, visible));
}
