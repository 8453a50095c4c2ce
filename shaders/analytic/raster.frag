#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_gpu_shader_int64 : require
#define EMPTY_KEY 0xFFFFFFFFFFFFFFFFul  // a slot no fragment took
#extension GL_EXT_shader_atomic_int64 : require
// `analytic`, fragment stage: one invocation per (triangle, pixel it may touch). Computes the
// exact area of the pixel the triangle covers and the fragment's sort key (depth at the pixel
// centre, then object and primitive). SELECT_PASS: inserts the key into the pixel's K nearest
// (a 64-bit atomicMin chain: each slot keeps the smaller key and passes the larger on, so the
// slots end sorted and hold the K nearest whatever the order of arrival) and counts the
// fragment. Otherwise: a fragment whose key is among its pixel's K takes its albedo and normal at
// the centroid of its covered part and writes (coverage, sample mask, albedo) and its surface
// (surface.glsl) into that slot, for the resolve to light it if it shows; in a pixel with more
// than K fragments the others that are not hidden are recorded (tail_record.glsl) for the tail
// pass (tail.comp), which lights them and sums them into the pixel's tails (facing the camera;
// facing away).
// Fragments whose triangle holds the pixel centre also write native's depth, velocity and IDs
// through the depth test.
#include "../inc/scene_types.glsl"
#include "surface.glsl"
#include "mask.glsl"
#include "tail_record.glsl"
#include "albedo_job.glsl"

layout(set = SET_SCENE, binding = BINDING_FRAME) uniform Frame { FrameConstants frame; };
layout(std430, set = SET_SCENE, binding = BINDING_OBJECTS) readonly buffer Objects { ObjectData objects[]; };
layout(std430, set = SET_SCENE, binding = BINDING_MATERIALS) readonly buffer Materials { MaterialData materials[]; };
layout(set = SET_MATERIAL, binding = BINDING_ALBEDO) uniform sampler2D albedo_tex;
layout(set = SET_MATERIAL, binding = BINDING_MASK) uniform sampler2D mask_tex;
layout(set = SET_MATERIAL, binding = BINDING_BUMP) uniform sampler2D bump_tex;
layout(std430, set = SET_PASS, binding = BINDING_KEYS) buffer Keys { uint64_t keys[]; };
#ifdef SELECT_PASS
// The same keys as 32-bit words (little-endian: word 2 i + 1 is key i's high word, its depth
// part), for the select pass's plain reads: a 32-bit read is never torn.
layout(std430, set = SET_PASS, binding = BINDING_KEYS) buffer KeyWords { uint key_words[]; };
#endif
// A kept fragment's slot, in two buffers (each must fit maxStorageBufferRange): coverage and
// sample mask; colour (3 x f16), flags (8 bits) and the passing share of an alpha-tested
// fragment without samples (8 bits, for the resolve's transmittance).
layout(std430, set = SET_PASS, binding = BINDING_SLOTS) buffer Slots { uvec2 slots[]; };
// The sample mask's words after the first (MASK_WORDS - 1 per slot; unused with 32 samples).
layout(std430, set = SET_PASS, binding = BINDING_SLOT_MASKS) buffer SlotMasks { uint slot_masks[]; };
layout(std430, set = SET_PASS, binding = BINDING_COLORS) buffer Colors { uvec2 colors[]; };
// A kept fragment's depth plane in the pixel: depth at the pixel centre and its change per pixel
// in x (planes) and y (planes_y), for the resolve's per-sample visibility.
layout(std430, set = SET_PASS, binding = BINDING_PLANES) buffer Planes { uvec2 planes[]; };
layout(std430, set = SET_PASS, binding = BINDING_PLANES_Y) buffer PlanesY { uint planes_y[]; };
layout(std430, set = SET_PASS, binding = BINDING_COUNTS) buffer Counts { uint counts[]; };
// Per pixel and mask sample, the farthest depth over the pixel (f32 bits, reverse-Z: larger is
// nearer; 0 where none) of the nearest fragment opaque at that sample: the select pass's
// atomicMax. Behind the least of them, a fragment is hidden at every sample. A word per
// OCCLUDER_GROUP consecutive samples (1 unless MASK_SAMPLES words a pixel exceed a storage buffer), written
// only by fragments opaque at the whole group.
#define OCCLUDER_WORDS (MASK_SAMPLES / OCCLUDER_GROUP)
layout(std430, set = SET_PASS, binding = BINDING_OCCLUDERS) buffer Occluders { uint occluders[]; };
// A kept fragment's shading normal and point, for the resolve's lighting (surface.glsl).
layout(std430, set = SET_PASS, binding = BINDING_SURFACES) buffer Surfaces { uvec2 surfaces[]; };
// Its albedo's luminance in the cells of a grid over the pixel (surface.glsl's pack_cells), for
// the resolve's albedo of the part that shows (resolve.comp, shown_albedo).
layout(std430, set = SET_PASS, binding = BINDING_CELLS) buffer Cells { uvec2 cells[]; };
layout(std430, set = SET_PASS, binding = BINDING_CELLS_HI) buffer CellsHi { uvec2 cells_hi[]; };
#ifndef SELECT_PASS
// The fragments beyond the K nearest that are not hidden, for the tail pass (tail.comp) to light
// and sum into the tails (tail_record.glsl); the buffer's length is the capacity, and the count
// runs on past it when the frame needs more (the technique grows the buffer and renders again).
layout(std430, set = SET_PASS, binding = BINDING_TAIL_RECORDS) writeonly buffer TailRecords { TailRecord tail_records[]; };
layout(std430, set = SET_PASS, binding = BINDING_TAIL_COUNT) buffer TailCounts { TailCount tail_count; };
// The textured fragments' albedo lookups, for the albedo pass (albedo_job.glsl).
layout(std430, set = SET_PASS, binding = BINDING_ALBEDO_JOBS) writeonly buffer AlbedoJobs { AlbedoJob albedo_jobs[]; };
layout(std430, set = SET_PASS, binding = BINDING_ALBEDO_COUNT) buffer AlbedoCounts { AlbedoCount albedo_count; };
layout(std430, set = SET_PASS, binding = BINDING_ALBEDO_BINS) buffer AlbedoBins { AlbedoBin albedo_bins[]; };
#endif
// pc.object_index (scene_pass.rs's ScenePush).
PUSH_CONSTANTS

#include "coverage.glsl"
#define RASTER_IO in
#include "raster_io.glsl"

#ifndef SELECT_PASS
layout(location = 0) out vec2 o_velocity;
layout(location = 1) out uvec2 o_ids;
#endif

// Perspective-correct barycentrics of the triangle at screen point s (pixels): the homogeneous
// 2D rasteriser's form (Olano & Greer 1997), valid whatever the vertices' w signs.
mat3 inv_clip;  // inverse of the matrix of the vertices' clip (x, y, w), set once in main

vec3 barycentrics(vec2 s) {
    vec2 ndc = s * frame.output_size.zw * 2.0 - 1.0;
    vec3 b = inv_clip * vec3(ndc, 1.0);
    return b / (b.x + b.y + b.z);
}

// The barycentrics of a point of the triangle (the shading point): rounding in a nearly singular
// clip matrix (tiny or distant triangles) may push them outside [0, 1] or make them non-finite;
// clamped and renormalised they keep the attributes within the triangle's.
vec3 point_barycentrics(vec2 s) {
    vec3 b = clamp(barycentrics(s), 0.0, 1.0);
    float sum = b.x + b.y + b.z;
    return sum > 0.0 ? b / sum : vec3(1.0 / 3.0);
}

float depth_at(vec2 s) {
    vec3 b = barycentrics(s);
    vec3 z = vec3(g_clip[0].z, g_clip[1].z, g_clip[2].z);
    vec3 w = vec3(g_clip[0].w, g_clip[1].w, g_clip[2].w);
    return dot(b, z) / dot(b, w);
}

vec2 uv_at(vec3 b) {
    return b.x * g_uv01.xy + b.y * g_uv01.zw + b.z * g_uv2;
}

vec3 world_at(vec3 b) {
    return b.x * g_world[0] + b.y * g_world[1] + b.z * g_world[2];
}

// Bump mapping without tangents (Mikkelsen 2010) from the exact screen derivatives of position
// and height (the raster's quads are not neighbouring pixels of one triangle here).
vec3 bump_from(vec3 n, vec3 dpdx, vec3 dpdy, float dhdx, float dhdy) {
    vec3 r1 = cross(dpdy, n);
    vec3 r2 = cross(n, dpdx);
    float det = dot(dpdx, r1);
    if (abs(det) < 1e-20) return n;
    vec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
    return normalize(abs(det) * n - grad);
}

#include "texture.glsl"

// Alpha-tested materials, per sample. The mask slot holds the material's coverage texture
// (cbr_scene::Texture::alpha_coverage): the passing share in alpha, the albedo premultiplied by it
// in rgb, both averaged by the mips, so one lookup gives the test and the colour of the part that
// passes. The test runs at each of the covered part's mask samples (the UV carried there by its
// screen derivatives dx, dy), filtered over a sixteenth of a pixel: about a point, as the
// supersampled reference tests it (a quarter pixel, the samples' spacing, blurred the cards'
// holes and thin parts before the test: docs/analytic.md). Returns the passing samples; `pass` is
// their share of the covered part's, by which its coverage scales, and `albedo` the mean over
// them of the passing texels' albedo (rgb / alpha): the albedo's own mips would mix in the colour
// of texels that fail, which the reference never sees. Such a fragment then hides and is hidden
// per sample like an opaque one. One too small to hold a sample has none to test: the share of
// it that passes is estimated from the alpha at the shading point and its change over one pixel
// (alpha taken as linear across the pixel), its albedo is the passing texels' over the pixel's
// footprint, and it has holes: its stand-in neither hides nor is hidden, and the resolve
// composites it through the transmittance of the alpha-tested fragments in front.
#define ALPHA_SAMPLE_FILTER 0.0625
Mask alpha_test(Mask geo_mask, vec2 uv, vec2 dx, vec2 dy, vec2 gx, vec2 gy, vec2 mean_point,
                out float pass, out vec3 albedo, inout float cell_luma[CELLS]) {
    if (!mask_any(geo_mask)) {
        float a = textureGrad(mask_tex, uv, gx, gy).a;
        float ax = textureGrad(mask_tex, uv + gx, gx, gy).a;
        float ay = textureGrad(mask_tex, uv + gy, gx, gy).a;
        float width = abs(ax - a) + abs(ay - a);
        pass = clamp((a - 0.5) / max(width, 1e-4) + 0.5, 0.0, 1.0);
        albedo = vec3(1.0);
#ifndef SELECT_PASS
        vec4 c = texture_aniso(mask_tex, uv, gx, gy);
        if (c.a > 0.0) albedo = c.rgb / c.a;
#endif
        return Mask(0u);
    }
    Mask passing = Mask(0u);
    Mask rest = geo_mask;
    vec4 sum = vec4(0.0);
    vec2 csum[CELLS];  // per cell: the passing samples' premultiplied albedo luminance, and alpha
    for (int i = 0; i < CELLS; ++i) csum[i] = vec2(0.0);
    while (mask_any(rest)) {
        int k = mask_pop(rest);
        vec2 d = mask_sample(k) - mean_point;
        vec4 c = textureGrad(mask_tex, uv + dx * d.x + dy * d.y, ALPHA_SAMPLE_FILTER * gx,
                             ALPHA_SAMPLE_FILTER * gy);
        if (c.a >= 0.5) {
            passing |= mask_bit(k);
            sum += c;
            csum[cell_of(mask_sample(k))] += vec2(albedo_luma(c.rgb), c.a);
        }
    }
    pass = float(mask_count(passing)) / float(mask_count(geo_mask));
    albedo = sum.a > 0.0 ? sum.rgb / sum.a : vec3(1.0);
    // Each cell's passing samples' albedo (the mean where the cell has none: it holds no
    // sample of the mask, so the resolve never weighs it).
    float mean_luma = albedo_luma(albedo);
    for (int i = 0; i < CELLS; ++i) cell_luma[i] = csum[i].y > 0.0 ? csum[i].x / csum[i].y : mean_luma;
    return passing;
}

#ifndef SELECT_PASS
// Appends a job for the albedo pass; past the buffer's capacity only counted (the technique grows
// it and renders the frame again). The first job of a row of the pass's dispatch adds the row.
void emit_albedo_job(uint target, vec2 uv, vec2 fx, vec2 fy, vec2 dx, vec2 dy, vec2 mean_point,
                     uint material, uint info) {
    uint j = atomicAdd(albedo_count.count, 1u);
    if (j >= uint(albedo_jobs.length())) return;
    albedo_jobs[j] = AlbedoJob(uv, fx, fy, dx, dy, mean_point, target, material, info, 0u);
    atomicAdd(albedo_bins[material].count, 1u);
    if (j % (64u * uint(TAIL_ROW_GROUPS)) == 0u) atomicAdd(albedo_count.groups_y, 1u);
}
#endif

void main() {
    ivec2 pix = ivec2(gl_FragCoord.xy);
    vec2 corner = vec2(pix);
    int n = int(g_info.x);
    vec2 screen[MAX_POLY] = vec2[MAX_POLY](g_poly01.xy, g_poly01.zw, g_poly23.xy, g_poly23.zw);
    vec2 p[MAX_POLY];
    vec2 lo[MAX_POLY];
    to_local(screen, corner, p, lo);
    PixelCoverage cov = exact_coverage(p, lo, n);
    if (!(cov.area > 0.0)) discard;
    inv_clip = inverse(mat3(g_clip[0].xyw, g_clip[1].xyw, g_clip[2].xyw));
    uint pixel = uint(pix.y) * uint(frame.output_size.x) + uint(pix.x);
    ObjectData o = objects[pc.object_index];
    MaterialData mat = materials[o.ids.y];
    // The sort depth: where the triangle holds the pixel centre, its depth there (a point common
    // to every such fragment, so coplanar surfaces compare equal, as in a depth buffer); else its
    // depth at the covered part's centroid (extrapolating the plane to a centre it misses can put
    // a far surface in front: a ground plane's plane above its horizon). Clamped to the depths
    // the polygon spans, without the 4 lowest mantissa bits (within ~1e-6: coplanar, first
    // drawn wins).
    float zlo = 1e30;
    float zhi = -1e30;
    for (int i = 0; i < n; ++i) {
        float zi = depth_at(screen[i]);
        zlo = min(zlo, zi);
        zhi = max(zhi, zi);
    }
    float orient = orientation(p, n);
    bool holds_centre = inside(p, n, orient, vec2(0.5));
    float zc = depth_at(holds_centre ? corner + 0.5 : corner + cov.mean_point);
    float z = isnan(zc) ? zlo : clamp(zc, zlo, zhi);
    // Reverse-Z: nearer is larger, and the smaller key must be the nearer.
    uint zkey = 0xFFFFFFFu - (floatBitsToUint(max(z, 0.0)) >> 4u);
    uint64_t key = (uint64_t(zkey) << 32) | uint64_t((o.ids.x << 20u) | (g_info.y & 0xFFFFFu));
    uint base = pixel * uint(K_SLOTS);

    // Shading at the covered part's centroid: for attributes affine in the screen, their mean
    // over the covered part; and always a point of the triangle (no extrapolated normals or UVs).
    vec2 sp = corner + cov.mean_point;
    vec3 b = point_barycentrics(sp);
    vec3 bx = barycentrics(sp + vec2(1.0, 0.0));
    vec3 by = barycentrics(sp + vec2(0.0, 1.0));
    vec2 uv = uv_at(b);
    // Texture footprint: the exact screen derivatives of the UV map at the shading point (one
    // pixel step), scaled by the LOD bias.
    float lod_scale = exp2(frame.ambient.w);
    vec2 dx = uv_at(bx) - uv;
    vec2 dy = uv_at(by) - uv;
    vec2 gx = dx * lod_scale;
    vec2 gy = dy * lod_scale;
    // Alpha-tested materials: the passing samples of the covered part (below); a fragment that
    // passes nowhere is dropped before it takes a slot.
    float alpha_pass = 1.0;
    vec3 alpha_albedo = vec3(1.0);
    // The albedo's luminance in the cells of the pixel's grid (surface.glsl; equal: untextured).
    float cell_luma[CELLS];
    for (int i = 0; i < CELLS; ++i) cell_luma[i] = 1.0;
    Mask alpha_mask = Mask(0u);
    Mask geo_mask = Mask(0u);
    // The plane's depth at the pixel's corners: over the covered part (inside the pixel) the
    // affine z / w lies between their extremes.
    vec4 zc4 = vec4(depth_at(corner), depth_at(corner + vec2(1.0, 0.0)),
                    depth_at(corner + vec2(0.0, 1.0)), depth_at(corner + 1.0));
    // The fragment's farthest depth in the pixel (reverse-Z: the least).
    float far = min(min(zc4.x, zc4.y), min(zc4.z, zc4.w));
    far = isnan(far) ? zlo : max(far, zlo);
#ifndef SELECT_PASS
    // The slots hold the K nearest keys sorted (the select pass): a binary search, its steps the
    // powers of two from the largest not above K (halving K itself, e.g. 18, 9, 4, 2, 1, skips
    // positions: a kept fragment was not found, and its slot was left unwritten).
    int first = 0;
    for (int step = 1 << findMSB(K_SLOTS); step > 0; step >>= 1) {
        int probe = first + step - 1;
        if (probe < K_SLOTS && keys[base + uint(probe)] < key) first = probe + 1;
    }
    int slot = first < K_SLOTS && keys[base + uint(first)] == key ? first : -1;
    // A fragment beyond the K nearest whose nearest depth in the pixel lies behind every
    // sample's occluder is hidden at every sample (and behind an opaque fragment at the centre,
    // so native's layers do not need it either): it is not recorded for the tails. The kept
    // ones are written whatever their depth.
    float near = max(max(zc4.x, zc4.y), max(zc4.z, zc4.w));
    near = isnan(near) ? zhi : min(near, zhi);
    if (slot < 0) {
        float occ = 1e30;
        for (uint k = 0u; k < uint(OCCLUDER_WORDS); ++k)
            occ = min(occ, uintBitsToFloat(occluders[pixel * uint(OCCLUDER_WORDS) + k]));
        // Strictly behind, by more than rounding: coplanar neighbours (abutting triangles of one
        // surface) evaluate their corners' depths with different rounding, and neither hides
        // the other.
        if (near < occ * (1.0 - 1e-5)) discard;
    }
#endif
    // MAT_FEATURES (scene_types.glsl): only the texture paths of this pipeline's materials.
#if (MAT_FEATURES & MAT_MASK) != 0
    if (mat.tex.y >= 0) {
        geo_mask = sample_mask(p, n, orient);
        alpha_mask = alpha_test(geo_mask, uv, dx, dy, gx, gy, cov.mean_point, alpha_pass,
                                alpha_albedo, cell_luma);
        if (alpha_pass <= 0.0) discard;
    }
#endif
#ifdef SELECT_PASS
    // The samples where this fragment is opaque (an alpha-tested one's passing samples) are
    // hidden behind its farthest depth in the pixel; each keeps the nearest such depth.
    {
        Mask opaque = mat.tex.y >= 0 ? alpha_mask : sample_mask(p, n, orient);
        if (far > 0.0 && !isinf(far)) {
            uint fb = floatBitsToUint(far);
            // A group of OCCLUDER_GROUP consecutive samples lies within one mask word.
            for (int w = 0; w < MASK_WORDS; ++w) {
                uint bits = mask_word(opaque, w);
                uint left = bits;
                while (left != 0u) {
                    uint g = uint(findLSB(left)) / uint(OCCLUDER_GROUP);
                    uint gm = (0xFFFFFFFFu >> uint(32 - OCCLUDER_GROUP)) << (g * uint(OCCLUDER_GROUP));
                    // The words only grow: one already at or beyond fb needs no atomic (a plain
                    // 32-bit read, never torn; a stale one is only smaller).
                    uint word = pixel * uint(OCCLUDER_WORDS) + uint(w * (32 / OCCLUDER_GROUP)) + g;
                    if ((bits & gm) == gm && occluders[word] < fb) atomicMax(occluders[word], fb);
                    left &= ~gm;
                }
            }
        }
    }
#endif
#ifdef SELECT_PASS
    atomicAdd(counts[pixel], 1u);
    // The chain needs no atomic at a slot holding a key below the fragment's: atomicMin there
    // returns that key and passes the fragment's on unchanged. The slots are sorted at every
    // moment (each atomicMin puts a key no smaller than the slots before it) and only decrease,
    // so a slot read once below the key stays below, and so do the slots before it. A binary
    // search over plain reads of the slots' high words (the depth part; strictly below is below
    // whatever the low words) finds where the chain's first change can be, and the chain starts
    // there: the same K keys, in the same order, as the chain from slot 0, with no atomic at all
    // for a fragment behind a full pixel's K nearest.
    uint hi = uint(key >> 32);
    int first = 0;
    for (int step = 1 << findMSB(K_SLOTS); step > 0; step >>= 1) {
        int probe = first + step - 1;
        if (probe < K_SLOTS && key_words[(base + uint(probe)) * 2u + 1u] < hi) first = probe + 1;
    }
    uint64_t cand = key;
    for (int i = first; i < K_SLOTS; ++i) {
        uint64_t old = atomicMin(keys[base + uint(i)], cand);
        if (old == EMPTY_KEY) break;
        cand = max(old, cand);
    }
    discard;
#else
    // Fragments beyond their pixel's K nearest are recorded for the tails.
    if (slot >= 0 || counts[pixel] > uint(K_SLOTS)) {
    // (the payload block is not indented: it is the whole surface path)
    // The covered part's mask samples (an alpha-tested fragment's: above).
    if (mat.tex.y < 0) geo_mask = sample_mask(p, n, orient);
    vec3 albedo = mat.kd.rgb;
    // A textured fragment's albedo lookups, deferred to the albedo pass (albedo_job.glsl).
    bool job = false;
    vec2 job_fx = vec2(0.0);
    vec2 job_fy = vec2(0.0);
    uint job_info = 0u;
    // An alpha-tested fragment's albedo is that of its passing part (alpha_test); the others'
    // is filtered over the footprint of the part of the pixel they cover.
#if (MAT_FEATURES & MAT_MASK) != 0
    if (mat.tex.y >= 0) {
        albedo *= alpha_albedo;
    } else
#endif
    {
#if (MAT_FEATURES & MAT_ALBEDO) != 0
        if (mat.tex.x >= 0) {
            // The footprint of the covered part (coverage.glsl's covered_footprint: its
            // principal axes and widths, carried into the texture by the UV map's
            // derivatives); the pixel's own where the triangle covers the whole pixel, to
            // rounding: there the covariance is isotropic and its axes would be rounding's
            // choice, where the pixel's are the continuous one.
            vec2 fx = gx;
            vec2 fy = gy;
            if (cov.area < 0.9999) {
                mat2 f = covered_footprint(cov);
                fx = gx * f[0].x + gy * f[0].y;
                fy = gx * f[1].x + gy * f[1].y;
            }
            // The lookups themselves run in the albedo pass (albedo.comp, over the dense list of
            // these jobs): texture_box over (fx, fy) (`boxed` where the fragment covers at least
            // BOX_MIN_AREA), or texture_aniso without TEXTURE_BOX; the albedo stays kd here.
            job = true;
            job_fx = fx;
            job_fy = fy;
            job_info = cov.area >= BOX_MIN_AREA ? JOB_BOXED : 0u;
            // Each cell's own footprint (a quarter of the pixel's, centred in it: surface.glsl's
            // grid; anisotropic, at most CELL_ANISO lookups), for the part of the fragment that
            // shows when other fragments hide the rest (resolve.comp). Needed only where some
            // but not all of its samples may be hidden: where an occluder word (the farthest
            // depth in the pixel of an opaque fragment holding the sample, the select pass) is
            // nearer than this fragment's farthest depth in the pixel, so a surface in front or
            // one crossing it (a card standing on the ground) may hide the sample. Not in a
            // pixel of one fragment, nor for a fragment hidden or open at every sample; and only
            // the cells holding samples of its mask (the resolve weighs no other); and only for a
            // kept fragment (a slot): a record beyond the K carries no grid. Each lane's loops
            // end with its own work, so a SIMD group with none skips them.
            Mask maybe_hidden = Mask(0u);
            Mask rest = slot >= 0 && counts[pixel] > 1u ? geo_mask : Mask(0u);
            while (mask_any(rest)) {
                int k = mask_pop(rest);
                uint word = pixel * uint(OCCLUDER_WORDS) + uint(k / OCCLUDER_GROUP);
                if (far < uintBitsToFloat(occluders[word]) * (1.0 - 1e-5)) maybe_hidden |= mask_bit(k);
            }
            uint cells = 0u;
            if (mask_any(maybe_hidden) && maybe_hidden != geo_mask) {
                Mask left = geo_mask;
                while (mask_any(left)) cells |= 1u << uint(cell_of(mask_sample(mask_pop(left))));
            }
            // The cells' lookups (the albedo pass): each a quarter of the pixel's footprint
            // centred in the cell, at most CELL_ANISO taps.
            job_info |= cells;
        }
#endif
    }
    vec3 world = world_at(b);
    vec3 nrm = normalize(b.x * g_normal[0] + b.y * g_normal[1] + b.z * g_normal[2]);
    // Facing away: the back of a surface (of a closed mesh, behind its front); shaded from the
    // side the camera sees, and summed into the back tail (tail.comp).
    bool facing_away = dot(nrm, -world) < 0.0;
    if (facing_away) nrm = -nrm;
    // The height's change over one pixel step (isotropic: anisotropic taps here cost on lavapipe
    // and changed no measured error).
#if (MAT_FEATURES & MAT_BUMP) != 0
    if (mat.tex.w >= 0) {
        float h = textureGrad(bump_tex, uv, gx, gy).r * mat.ke.w;
        float hx = textureGrad(bump_tex, uv + gx, gx, gy).r * mat.ke.w;
        float hy = textureGrad(bump_tex, uv + gy, gx, gy).r * mat.ke.w;
        nrm = bump_from(nrm, world_at(bx) - world, world_at(by) - world, hx - h, hy - h);
    }
#endif
    // No light is computed here. A kept fragment leaves its albedo, normal and shading point in
    // its slot, and the resolve lights it if it shows; one beyond the K is recorded, and the
    // tail pass lights it. Here every SIMD group holding one such fragment would run the light
    // loop for all its lanes, most of them outside the triangle (the grown polygon's pixels it
    // does not touch); the compute passes light dense lists.
    vec3 color = albedo;
    bool finite = !any(isnan(color)) && !any(isinf(color));

    // The mask: for the resolve's per-sample visibility (a slot) or the tail's (beyond the K), and
    // the seed's vertex columns.
    Mask mask = mat.tex.y >= 0 ? alpha_mask : geo_mask;
    float coverage = cov.area;
    uint flags = 0u;
#ifdef SEED
    coverage = seed_coverage(p, n, geo_mask);
    if (abs(coverage - cov.area) > 1e-3) flags |= 1u;
#endif
    coverage *= alpha_pass;
    if (mat.tex.y >= 0 && !mask_any(geo_mask)) flags |= 2u;
    if (!finite) {
        // Never let a non-finite colour into the pixel: the fragment covers nothing, flagged.
        color = vec3(0.0);
        coverage = 0.0;
        flags |= 6u;
    }
    if (!mask_any(mask)) {
        mask = nearest_sample_bit(cov.mean_point);
        flags |= 8u;  // a stand-in bit (the resolve treats it as one sample of this fragment)
    }
    if (facing_away) flags |= 16u;  // the resolve's stand-in rule compares surfaces by facing
    if (slot >= 0) {
        // The depth plane: z / w is affine in the screen, z(ndc) = gz . (ndc, 1) / gw . (ndc, 1)
        // with gw = (0, 0, 1) up to rounding (the clip matrix's third row is the w's).
        vec3 gz = vec3(g_clip[0].z, g_clip[1].z, g_clip[2].z) * inv_clip;
        vec3 gw = vec3(g_clip[0].w, g_clip[1].w, g_clip[2].w) * inv_clip;
        vec3 ndc_c = vec3((corner + 0.5) * frame.output_size.zw * 2.0 - 1.0, 1.0);
        float norm = dot(gw, ndc_c);
        vec3 plane = vec3(dot(gz, ndc_c), gz.xy * 2.0 * frame.output_size.zw) / norm;
        if (any(isnan(plane)) || any(isinf(plane)) || !finite) plane = vec3(z, 0.0, 0.0);
        planes[base + uint(slot)] = floatBitsToUint(plane.xy);
        planes_y[base + uint(slot)] = floatBitsToUint(plane.z);
        slots[base + uint(slot)] = uvec2(floatBitsToUint(coverage), mask_word(mask, 0));
        for (int w = 1; w < MASK_WORDS; ++w)
            slot_masks[(base + uint(slot)) * uint(MASK_WORDS - 1) + uint(w - 1)] = mask_word(mask, w);
        surfaces[base + uint(slot)] = pack_surface(nrm, cov.mean_point);
        uvec4 packed_cells = pack_cells(cell_luma);
        cells[base + uint(slot)] = packed_cells.xy;
        cells_hi[base + uint(slot)] = packed_cells.zw;
        colors[base + uint(slot)] = uvec2(packHalf2x16(color.rg),
                                          (packHalf2x16(vec2(color.b, 0.0)) & 0xFFFFu) | (flags << 16u)
                                          | (uint(round(alpha_pass * 255.0)) << 24u));
        if (job && finite) emit_albedo_job(base + uint(slot), uv, job_fx, job_fy, dx, dy,
                                           cov.mean_point, o.ids.y, job_info);
    } else if (coverage > 0.0) {
        // Beyond the K: recorded for the tail pass (tail_record.glsl), which lights it and adds
        // it to the pixel's tail, facing the camera or away.
        uint i = atomicAdd(tail_count.count, 1u);
        if (i < uint(tail_records.length())) {
            tail_records[i] = make_tail_record(pixel, coverage, mask, o.ids.y, facing_away, world,
                                               nrm, albedo);
            if (job) emit_albedo_job(i | JOB_TAIL, uv, job_fx, job_fy, dx, dy, cov.mean_point,
                                     o.ids.y, job_info);
            // The first record of a row of the tail pass's dispatch adds the row.
            if (i % (64u * uint(TAIL_ROW_GROUPS)) == 0u) atomicAdd(tail_count.groups_y, 1u);
        }
    }
    }

    // Native's layers: the triangle holding the pixel centre, nearest through the depth test.
    if (!inside(p, n, orient, vec2(0.5))) discard;
    vec2 centre = corner + 0.5;
    vec3 bc = barycentrics(centre);
    gl_FragDepth = depth_at(centre);
    vec3 prev = bc.x * g_prev[0] + bc.y * g_prev[1] + bc.z * g_prev[2];
    vec2 prev_px = (prev.xy / prev.z * 0.5 + 0.5) * frame.output_size.xy;
    // The velocity excludes the frame's jitter (the triangle's positions carry it).
    o_velocity = (centre - frame.screen_jitter.xy) - prev_px;
    o_ids = uvec2(o.ids.x, g_info.y);
#endif
}
