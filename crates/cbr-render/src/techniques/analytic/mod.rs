//! `analytic[:seed][:frags=K]`: anti-aliasing from the exact area of each pixel each triangle
//! covers, instead of from samples (docs/analytic.md).
//!
//! Passes per frame; the first two through the conservative raster (shaders/analytic/raster.geom
//! grows each near-clipped triangle by the pixel square, so every touched pixel is reached
//! without conservative rasterisation): (1) `analytic.select`: each fragment's exact coverage
//! (shaders/analytic/coverage.glsl) and sort key; the pixel keeps its K nearest keys (a 64-bit
//! atomicMin chain, sorted and independent of the order of arrival) and counts every fragment;
//! (2) `analytic.raster`: each fragment among its pixel's K leaves its albedo, normal and shading
//! point (the covered part's centroid) in its slot; the fragments beyond the K that no occluder
//! hides are recorded (shaders/analytic/tail_record.glsl); fragments holding the pixel centre also
//! write native's depth, velocity and IDs; (3) `analytic.tail`: lights the records, one
//! invocation each, into the pixel's tails (fixed-point sums, independent of the order); (4)
//! `analytic.resolve`: front to back per pixel (resolve.comp states the model), lighting only the
//! kept fragments it composites. When a frame records more fragments than the record buffer
//! holds, the buffer grows to what the frame counted and the frame is rendered again (the
//! timings are those of the second rendering). `:seed` replaces the exact area by the seed's column
//! shortcut and flags where it is off; `:frags=K` keeps K fragments per pixel (1 to 64;
//! default 32, lowered to what the device's largest storage buffer holds); `:samples=N` gives
//! the visibility mask N samples (32, 64 the default, or 128; shaders/analytic/mask.glsl); the
//! albedo texture is integrated over the footprint as a box (a grid of lookups, raster.frag's
//! `texture_box`), or with `:aniso` by one anisotropic trilinear filter (the taps along the
//! longer side only).

pub mod layers;
pub mod reference;

pub use layers::AnalyticLayers;

use cbr_gpu::{
    Access, BindingDesc, Buffer, Caps, ComputeDesc, DescriptorKind, DescriptorSet, GpuError,
    GraphicsDesc, Image, ImageDesc, Location, PassKind, Pipeline, Readback, Result, SetLayout,
    Write, vk,
};
use half::f16;

use super::{Coverage, linear_depths};
use crate::frame::FrameOutput;
use crate::memory::MemoryEstimate;
use crate::scene_pass::{self, MATERIAL_SET, SCENE_SET};
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};
use crate::technique::{
    BuildCtx, FrameCtx, Geometry, Outputs, Registration, Technique, unknown_param,
};

pub const REGISTRATION: Registration = Registration {
    name: "analytic",
    grammar: "analytic[:seed][:frags=K][:samples=N][:aniso]",
    about: "exact area of each pixel covered by each triangle, per-pixel fragment lists resolved \
            front to back; `seed`: the seed's column shortcut; `samples=N`: the visibility mask's \
            samples (32, 64, 128); `aniso`: the albedo texture filtered anisotropically, not as a box",
    outputs: Outputs {
        layers: &layers::LAYERS,
        stats: &layers::STATS,
        pngs: Some(layers::debug_pngs),
        settings: None,
    },
    check: |p| parse(p).map(|_| ()),
    needs,
    estimate: |ctx, p| {
        let c = parse(p)?;
        let frags = plan_lists(
            ctx.width,
            ctx.height,
            c.frags,
            c.samples,
            ctx.caps.max_storage_buffer_range,
        )?;
        Ok(Analytic::estimate(
            frags,
            c.samples,
            ctx.width,
            ctx.height,
            ctx.caps.max_storage_buffer_range,
        ))
    },
    passes: |_, p| {
        parse(p)?;
        Err("analytic's passes are not declared yet (crate::pass; issue 53 continues)".into())
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("analytic", p, e))?;
        Ok(Box::new(Analytic::new(ctx, c)?))
    },
};

/// Bytes of one kept fragment: its 64-bit key (depth, object, primitive), its slot (coverage,
/// mask, albedo as 3 x f16, flags), its depth plane ([`PLANE_BYTES`]) and its surface
/// ([`SURFACE_BYTES`]).
pub const KEY_BYTES: u64 = 8;
/// A slot is two 8-byte halves in two buffers (coverage + mask; colour + flags), so that each
/// buffer holds K x 8 bytes per pixel under `maxStorageBufferRange`.
pub const SLOT_BYTES: u64 = 16;
const HALF_SLOT_BYTES: u64 = SLOT_BYTES / 2;
/// A kept fragment's depth plane (depth at the pixel centre, its change per pixel in x and y: 3 x
/// f32) for the resolve's per-sample visibility, in two buffers: depth and x change; y change.
const PLANE_XY_BYTES: u64 = 8;
const PLANE_Y_BYTES: u64 = 4;
pub const PLANE_BYTES: u64 = PLANE_XY_BYTES + PLANE_Y_BYTES;
/// A kept fragment's shading normal (octahedral, 2 x snorm16) and shading point in the pixel
/// (2 x unorm16), from the raster pass to the resolve's lighting (shaders/analytic/surface.glsl).
pub const SURFACE_BYTES: u64 = 8;
/// A kept fragment's albedo grid: its albedo luminance in each cell of a 4 x 4 grid over the
/// pixel (16 x 8 bits), by which the resolve takes the albedo of the part that shows when other
/// fragments hide the rest (shaders/analytic/surface.glsl's pack_cells, resolve.comp's
/// `shown_albedo`); in two buffers of 8 bytes (`cells`, `cells_hi`), so that no buffer takes
/// more than 8 bytes a fragment (the kept fragments' K is what one buffer holds).
pub const HALF_CELLS_BYTES: u64 = 8;
pub const CELLS_BYTES: u64 = 2 * HALF_CELLS_BYTES;
/// All of one kept fragment's bytes with a 32-sample mask (the slot holds its one word).
pub const FRAGMENT_BYTES: u64 = KEY_BYTES + SLOT_BYTES + PLANE_BYTES + SURFACE_BYTES + CELLS_BYTES;
/// The visibility mask's sample counts (`samples=N`; shaders/analytic/mask.glsl) and the default.
pub const MASK_SAMPLE_COUNTS: [u32; 3] = [32, 64, 128];
pub const DEFAULT_SAMPLES: u32 = 64;
/// 32-bit words of an N-sample mask.
pub fn mask_words(samples: u32) -> u64 {
    u64::from(samples / 32)
}
/// A kept fragment's mask words beyond the slot's first, in their own buffer (`slot_masks`).
pub fn slot_mask_bytes(samples: u32) -> u64 {
    4 * (mask_words(samples) - 1)
}
/// All of one kept fragment's bytes with an N-sample mask.
pub fn fragment_bytes(samples: u32) -> u64 {
    FRAGMENT_BYTES + slot_mask_bytes(samples)
}
/// Per pixel and tail, the fixed-point sums of the fragments beyond the K nearest (4 x u64); two
/// tails (facing the camera, facing away), each in its own buffer.
pub const TAIL_BYTES: u64 = 32;
/// Per pixel, the two tails' sample-mask unions (2 masks of N / 32 words).
pub fn tail_mask_bytes(samples: u32) -> u64 {
    8 * mask_words(samples)
}
/// One recorded fragment beyond the K nearest (shaders/analytic/tail_record.glsl: 9 words and
/// the mask's).
pub fn tail_record_bytes(samples: u32) -> u64 {
    36 + 4 * mask_words(samples)
}
/// Records the buffer starts with, per pixel (it grows to what a frame needs, up to the device's
/// largest storage buffer).
pub const TAIL_RECORDS_PER_PIXEL_START: u64 = 1;
/// The tail pass's rows: groups of 64 invocations per row of its indirect dispatch, whose row
/// count the raster pass raises as it writes records (shaders/analytic/tail_record.glsl,
/// TailCount). Small, so that the last row's idle invocations are few; 65,535 rows of 1,024
/// records hold more than one storage buffer's records (3.4 million on lavapipe).
pub const TAIL_ROW_GROUPS: u32 = 16;
/// The records' count and the tail pass's VkDispatchIndirectCommand (4 x u32).
pub const TAIL_COUNT_BYTES: u64 = 16;
/// Per pixel and mask sample, the farthest depth over the pixel of the nearest fragment opaque
/// at that sample (f32 bits; 0 where none): fragments beyond the K nearest lying behind every
/// sample's are not shaded. One 4-byte word per sample, or per group of 2, 4, ... consecutive
/// samples (written only by a fragment opaque at the whole group) where 32 words a pixel would
/// not fit one storage buffer: [`occluder_group`].
pub const OCCLUDER_WORD_BYTES: u64 = 4;

/// Samples per occluder word at `px` pixels with an N-sample mask: the fewest (1, 2, 4, ... 32)
/// whose words fit `maxStorageBufferRange` (lavapipe's 128 MiB, 32 samples: 1 up to 1280x720, 2
/// at 1920x1080). A group is consecutive samples, adjacent in x but far apart in y on the
/// lattice, so a group is seldom covered whole by a partial occluder: grouping by default
/// (N / 32 a word) lost the occluders the albedo of the part that shows needs (test
/// `a_surface_seen_through_gaps_takes_the_albedo_of_the_part_that_shows`, 64 samples).
pub fn occluder_group(px: u64, max_range: u32, samples: u32) -> u32 {
    let mut group = 1u32;
    while group < 32 && px * occluder_pixel_bytes(group, samples) > u64::from(max_range) {
        group *= 2;
    }
    group
}

/// Occluder bytes per pixel with `group` samples per word.
fn occluder_pixel_bytes(group: u32, samples: u32) -> u64 {
    u64::from(samples / group) * OCCLUDER_WORD_BYTES
}

fn occluder_bytes(px: u64, max_range: u32, samples: u32) -> u64 {
    px * occluder_pixel_bytes(occluder_group(px, max_range, samples), samples)
}

/// The binding number of `name` in `bindings` (a set's list: RASTER_BINDINGS, ...).
fn binding_of(bindings: &[BindingDesc], name: &str) -> u32 {
    bindings
        .iter()
        .find(|b| b.name == name)
        .map(|b| b.binding)
        .unwrap_or_else(|| panic!("no binding `{name}`"))
}

/// The count a compute pass left in the first word of a buffer, read back (`tail_count`,
/// `albedo_count`; some past its buffer's capacity when the frame needed more).
fn count_read(rb: &Readback) -> Result<u64> {
    Ok(u64::from(bytemuck::cast_slice::<u8, u32>(rb.bytes()?)[0]))
}

/// Writes binding i of a set of storage buffers with `buffers[i]` (RASTER_BINDINGS and
/// TAIL_BINDINGS list their buffers in binding order).
fn buffer_writes<'a>(buffers: &[&'a Buffer]) -> Vec<Write<'a>> {
    buffers
        .iter()
        .zip(0u32..)
        .map(|(b, i)| Write::Buffer(i, b))
        .collect()
}

/// The most tail records one storage buffer holds on this device.
fn max_tail_capacity(max_range: u32, samples: u32) -> u64 {
    u64::from(max_range) / tail_record_bytes(samples)
}

/// The tail-record capacity a frame that recorded `needed` fragments beyond its pixels' `frags`
/// nearest grows the buffer to: `needed` and a quarter more, at most what one storage buffer
/// holds; or the refusal where that cannot hold `needed`.
pub fn grown_tail_capacity(
    needed: u64,
    frags: u32,
    samples: u32,
    max_range: u32,
) -> std::result::Result<u64, String> {
    let max = max_tail_capacity(max_range, samples);
    let record = tail_record_bytes(samples);
    if needed > max {
        return Err(format!(
            "analytic: this frame has {needed} fragments beyond the {frags} nearest of their \
             pixels that no occluder hides; their records ({needed} x {record} bytes) \
             exceed the largest storage buffer this device binds ({} bytes, \
             maxStorageBufferRange): lower the resolution",
            max * record
        ));
    }
    Ok((needed + needed / 4).min(max))
}

/// Tail records the buffer starts with at `px` pixels.
fn start_tail_capacity(px: u64, max_range: u32, samples: u32) -> u64 {
    (px * TAIL_RECORDS_PER_PIXEL_START).clamp(1, max_tail_capacity(max_range, samples))
}

/// One textured fragment's albedo lookups, left by the raster pass for the albedo pass
/// (shaders/analytic/albedo_job.glsl: 16 words).
pub const ALBEDO_JOB_BYTES: u64 = 64;
/// Jobs the buffer starts with, per pixel (it grows as the tail records' do).
pub const ALBEDO_JOBS_PER_PIXEL_START: u64 = 2;
/// The jobs' count and the albedo pass's VkDispatchIndirectCommand (4 x u32).
pub const ALBEDO_COUNT_BYTES: u64 = 16;
/// Per material: its jobs' count, offset and cursor in the order, and its dispatch
/// (albedo_job.glsl's AlbedoBin: 8 x u32).
pub const ALBEDO_BIN_BYTES: u64 = 32;
/// The most materials a scene may have (one bin each: 128 KiB).
pub const MAX_MATERIALS: usize = 4096;
/// Per job: its index in the order of materials (albedo_bin.comp).
pub const ALBEDO_ORDER_BYTES: u64 = 4;

/// The most albedo jobs one storage buffer holds on this device.
fn max_job_capacity(max_range: u32) -> u64 {
    u64::from(max_range) / ALBEDO_JOB_BYTES
}

/// The job capacity a frame that asked for `needed` grows the buffer to: `needed` and a quarter
/// more, at most what one storage buffer holds; or the refusal where that cannot hold `needed`.
pub fn grown_job_capacity(needed: u64, max_range: u32) -> std::result::Result<u64, String> {
    let max = max_job_capacity(max_range);
    if needed > max {
        return Err(format!(
            "analytic: this frame has {needed} textured fragments to filter; their jobs ({needed} \
             x {ALBEDO_JOB_BYTES} bytes) exceed the largest storage buffer this device binds ({} \
             bytes, maxStorageBufferRange): lower the resolution",
            max * ALBEDO_JOB_BYTES
        ));
    }
    Ok((needed + needed / 4).min(max))
}

/// Albedo jobs the buffer starts with at `px` pixels.
fn start_job_capacity(px: u64, max_range: u32) -> u64 {
    (px * ALBEDO_JOBS_PER_PIXEL_START).clamp(1, max_job_capacity(max_range))
}

/// Fragments kept per pixel unless `frags=K` says otherwise (lowered to what fits).
pub const DEFAULT_FRAGS: u32 = 32;
/// The most `frags=K` may ask for: resolve.comp holds the set of a pixel's kept fragments it
/// composites as the bits of two 32-bit words.
pub const MAX_FRAGS: u32 = 64;
/// The key's identity field: object IDs below 2^12, primitive IDs below 2^20.
pub const MAX_OBJECTS: usize = (1 << 12) - 1;
pub const MAX_PRIMITIVES: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnalyticConfig {
    pub seed: bool,
    /// Fragments kept per pixel asked for (`None`: the default, fitted to the device).
    pub frags: Option<u32>,
    /// The visibility mask's samples (one of [`MASK_SAMPLE_COUNTS`]).
    pub samples: u32,
    /// The albedo texture integrated over the footprint as a box (the default; `aniso`: one
    /// anisotropic trilinear filter).
    pub box_filter: bool,
}

pub fn parse(params: &[&str]) -> std::result::Result<AnalyticConfig, String> {
    let mut c = AnalyticConfig {
        seed: false,
        frags: None,
        samples: DEFAULT_SAMPLES,
        box_filter: true,
    };
    for p in params {
        match *p {
            "seed" => c.seed = true,
            "aniso" => c.box_filter = false,
            _ => {
                if let Some(n) = p.strip_prefix("frags=") {
                    let n: u32 = n
                        .parse()
                        .ok()
                        .filter(|&n| (1..=MAX_FRAGS).contains(&n))
                        .ok_or_else(|| format!("analytic frags=`{n}` (1 to {MAX_FRAGS})"))?;
                    c.frags = Some(n);
                } else if let Some(n) = p.strip_prefix("samples=") {
                    c.samples = n
                        .parse()
                        .ok()
                        .filter(|n| MASK_SAMPLE_COUNTS.contains(n))
                        .ok_or_else(|| format!("analytic samples=`{n}` (32, 64 or 128)"))?;
                } else {
                    return Err(unknown_param(
                        "analytic",
                        p,
                        "seed, frags=K, samples=N, aniso",
                    ));
                }
            }
        }
    }
    Ok(c)
}

fn needs(_: &[&str], caps: &Caps) -> Option<String> {
    if !caps.geometry_shader {
        return Some("the geometryShader feature (the conservative raster)".into());
    }
    if !caps.int64_atomics {
        return Some(
            "64-bit storage-buffer atomics (shaderInt64, shaderBufferInt64Atomics: the K nearest)"
                .into(),
        );
    }
    (!caps.fragment_stores_and_atomics)
        .then(|| "the fragmentStoresAndAtomics feature (fragment lists)".into())
}

/// Fragments kept per pixel at `width` x `height`, or the refusal (before anything is allocated)
/// with the bytes it would take and the device's limit: the keys, the two halves of the slots, the
/// surfaces and the two halves of the albedo grid are storage buffers of `K x 8` bytes per pixel
/// each (the further mask words of an N-sample mask `K x 4 (N / 32 - 1)`), which must fit
/// `maxStorageBufferRange`.
pub fn plan_lists(
    width: u32,
    height: u32,
    frags: Option<u32>,
    samples: u32,
    max_range: u32,
) -> std::result::Result<u32, String> {
    let px = u64::from(width) * u64::from(height);
    let widest = KEY_BYTES
        .max(HALF_SLOT_BYTES)
        .max(PLANE_XY_BYTES)
        .max(SURFACE_BYTES)
        .max(HALF_CELLS_BYTES)
        .max(slot_mask_bytes(samples));
    let fragment = fragment_bytes(samples);
    let fit = (u64::from(max_range) / (px * widest).max(1)).min(u64::from(MAX_FRAGS)) as u32;
    let refuse = |k: u32| {
        format!(
            "analytic at {width}x{height} with {k} fragments per pixel needs {} bytes of fragment \
             lists ({k} x {fragment} bytes per pixel), the largest buffer {} bytes; this device \
             binds at most {max_range} bytes in one storage buffer (maxStorageBufferRange): lower \
             the resolution or frags=K (at most {fit} fits)",
            px * u64::from(k) * fragment,
            px * u64::from(k) * widest
        )
    };
    match frags {
        Some(k) if k > fit => Err(refuse(k)),
        Some(k) => Ok(k),
        None if fit >= 2 => Ok(DEFAULT_FRAGS.min(fit)),
        None => Err(refuse(2)),
    }
}

/// Set 2 of the raster passes (set 0: the scene's, set 1: the material's).
pub const RASTER_BINDINGS: [BindingDesc; 16] = {
    use DescriptorKind::StorageBuffer as B;
    [
        BindingDesc::one("keys", 0, B),
        BindingDesc::one("slots", 1, B),
        BindingDesc::one("counts", 2, B),
        BindingDesc::one("colors", 3, B),
        BindingDesc::one("planes", 4, B),
        BindingDesc::one("planes_y", 5, B),
        BindingDesc::one("occluders", 6, B),
        BindingDesc::one("surfaces", 7, B),
        BindingDesc::one("tail_records", 8, B),
        BindingDesc::one("tail_count", 9, B),
        BindingDesc::one("cells", 10, B),
        BindingDesc::one("slot_masks", 11, B),
        BindingDesc::one("cells_hi", 12, B),
        BindingDesc::one("albedo_jobs", 13, B),
        BindingDesc::one("albedo_count", 14, B),
        BindingDesc::one("albedo_bins", 15, B),
    ]
};

/// Set 0 of the albedo pass (set 1: the scene's, set 2: the material's) and of the two passes
/// that order its jobs by material (albedo_bin.comp).
pub const ALBEDO_BINDINGS: [BindingDesc; 8] = {
    use DescriptorKind::StorageBuffer as B;
    [
        BindingDesc::one("albedo_jobs", 0, B),
        BindingDesc::one("albedo_count", 1, B),
        BindingDesc::one("colors", 2, B),
        BindingDesc::one("cells", 3, B),
        BindingDesc::one("cells_hi", 4, B),
        BindingDesc::one("tail_records", 5, B),
        BindingDesc::one("albedo_bins", 6, B),
        BindingDesc::one("albedo_order", 7, B),
    ]
};

/// Set 0 of the tail pass (set 1: the scene's).
pub const TAIL_BINDINGS: [BindingDesc; 5] = {
    use DescriptorKind::StorageBuffer as B;
    [
        BindingDesc::one("tail_records", 0, B),
        BindingDesc::one("tail_count", 1, B),
        BindingDesc::one("tail", 2, B),
        BindingDesc::one("tail_back", 3, B),
        BindingDesc::one("tail_masks", 4, B),
    ]
};

pub const RESOLVE_BINDINGS: [BindingDesc; 16] = {
    use DescriptorKind::{StorageBuffer as B, StorageImage as I};
    [
        BindingDesc::one("keys", 0, B),
        BindingDesc::one("slots", 1, B),
        BindingDesc::one("counts", 2, B),
        BindingDesc::one("out_color", 3, I),
        BindingDesc::one("out_coverage", 4, I),
        BindingDesc::one("out_counts", 5, I),
        BindingDesc::one("tail", 6, B),
        BindingDesc::one("colors", 7, B),
        BindingDesc::one("planes", 8, B),
        BindingDesc::one("planes_y", 9, B),
        BindingDesc::one("tail_back", 10, B),
        BindingDesc::one("tail_masks", 11, B),
        BindingDesc::one("surfaces", 12, B),
        BindingDesc::one("cells", 13, B),
        BindingDesc::one("slot_masks", 14, B),
        BindingDesc::one("cells_hi", 15, B),
    ]
};

/// Bits of the counts image's third channel (resolve.comp).
pub const FLAG_EDGE: u32 = 1;
pub const FLAG_SEED: u32 = 2;
pub const FLAG_OVERFLOW: u32 = 4;
pub const FLAG_NONFINITE: u32 = 8;

const COVERAGE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
const COUNTS_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

/// Native's layers, written by the list pass where a triangle holds the pixel centre.
struct Targets {
    velocity: Image,
    ids: Image,
    depth: Image,
}

/// One raster pass (select or shade): a pipeline per combination of material texture paths the
/// scene uses (MAT_FEATURES, as the scene pass).
struct Raster {
    pipelines: scene_pass::MaterialVariants<Pipeline>,
    name: &'static str,
}

pub struct Analytic {
    c: AnalyticConfig,
    frags: u32,
    occluder_group: u32,
    select: Raster,
    raster: Raster,
    raster_layout: SetLayout,
    tail_layout: SetLayout,
    albedo_layout: SetLayout,
    _layouts: Vec<SetLayout>,
    scene_set: DescriptorSet,
    material_sets: Vec<DescriptorSet>,
    raster_set: DescriptorSet,
    tail_pass: Pipeline,
    tail_set: DescriptorSet,
    /// The albedo pass, run once per textured material that is not alpha-tested (the ones whose
    /// fragments leave jobs), with that material's set.
    albedo_pass: Pipeline,
    albedo_set: DescriptorSet,
    albedo_materials: Vec<u32>,
    /// The jobs (grows: [`Analytic::grow_albedo_jobs`]), their count, and the count read back.
    albedo_jobs: Buffer,
    albedo_count: Buffer,
    albedo_count_rb: Readback,
    /// Ordering the jobs by material: the plan (offsets, dispatches) and the scatter.
    bin_plan: Pipeline,
    bin_scatter: Pipeline,
    albedo_bins: Buffer,
    albedo_order: Buffer,
    resolve: Pipeline,
    resolve_set: DescriptorSet,
    keys: Buffer,
    slots: Buffer,
    counts_buf: Buffer,
    tail: Buffer,
    tail_back: Buffer,
    tail_masks: Buffer,
    occluders: Buffer,
    colors: Buffer,
    planes: Buffer,
    planes_y: Buffer,
    surfaces: Buffer,
    cells: Buffer,
    cells_hi: Buffer,
    slot_masks: Buffer,
    /// Records of the fragments beyond the K (grows: [`Analytic::grow_tail_records`]), their
    /// count, and the count read back.
    tail_records: Buffer,
    max_range: u32,
    tail_count: Buffer,
    tail_count_rb: Readback,
    targets: Targets,
    color: Image,
    coverage: Image,
    counts: Image,
    readbacks: [Readback; 6],
    background: [f32; 3],
}

impl Analytic {
    /// What [`Analytic::new`] keeps with `frags` fragments per pixel: the keys and the two
    /// halves of the slots (K x 8 bytes per pixel each), the fragment counts and tails, native's
    /// velocity, ID and depth targets (its colour target is freed as soon as it is made), the
    /// resolved colour, coverage and counts, and six readbacks.
    pub fn estimate(frags: u32, samples: u32, w: u32, h: u32, max_range: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        let px = u64::from(w) * u64::from(h);
        let kept = px * u64::from(frags);
        e.storage_buffer("analytic.keys", kept * KEY_BYTES, false);
        e.storage_buffer("analytic.slots", kept * HALF_SLOT_BYTES, false);
        e.storage_buffer("analytic.colors", kept * HALF_SLOT_BYTES, false);
        e.storage_buffer("analytic.planes", kept * PLANE_XY_BYTES, false);
        e.storage_buffer("analytic.planes_y", kept * PLANE_Y_BYTES, false);
        e.storage_buffer("analytic.surfaces", kept * SURFACE_BYTES, false);
        e.storage_buffer("analytic.cells", kept * HALF_CELLS_BYTES, false);
        e.storage_buffer("analytic.cells_hi", kept * HALF_CELLS_BYTES, false);
        e.storage_buffer(
            "analytic.slot_masks",
            (kept * slot_mask_bytes(samples)).max(4),
            false,
        );
        e.storage_buffer("analytic.counts_buffer", px * 4, false);
        e.storage_buffer("analytic.tail", px * TAIL_BYTES, false);
        e.storage_buffer("analytic.tail_back", px * TAIL_BYTES, false);
        e.storage_buffer("analytic.tail_masks", px * tail_mask_bytes(samples), false);
        e.storage_buffer(
            "analytic.occluders",
            occluder_bytes(px, max_range, samples),
            false,
        );
        e.storage_buffer(
            "analytic.tail_records",
            start_tail_capacity(px, max_range, samples) * tail_record_bytes(samples),
            false,
        );
        e.storage_buffer("analytic.tail_count", TAIL_COUNT_BYTES, false);
        e.buffer("readback.analytic.tail_count", 4, true);
        e.storage_buffer(
            "analytic.albedo_jobs",
            start_job_capacity(px, max_range) * ALBEDO_JOB_BYTES,
            false,
        );
        e.storage_buffer("analytic.albedo_count", ALBEDO_COUNT_BYTES, false);
        e.storage_buffer(
            "analytic.albedo_bins",
            MAX_MATERIALS as u64 * ALBEDO_BIN_BYTES,
            false,
        );
        e.storage_buffer(
            "analytic.albedo_order",
            start_job_capacity(px, max_range) * ALBEDO_ORDER_BYTES,
            false,
        );
        e.buffer("readback.analytic.albedo_count", 4, true);
        e.image("analytic.velocity", VELOCITY_FORMAT, w, h);
        e.image("analytic.ids", ID_FORMAT, w, h);
        e.image("analytic.depth", DEPTH_FORMAT, w, h);
        let images = [
            ("color", COLOR_FORMAT),
            ("coverage", COVERAGE_FORMAT),
            ("counts", COUNTS_FORMAT),
        ];
        for (name, format) in images {
            e.image(format!("analytic.{name}"), format, w, h);
        }
        for (name, format) in images.into_iter().chain([
            ("depth", DEPTH_FORMAT),
            ("velocity", VELOCITY_FORMAT),
            ("ids", ID_FORMAT),
        ]) {
            e.readback(format!("readback.analytic.{name}"), format, w, h, 1);
        }
        e
    }

    pub fn new(ctx: &BuildCtx, c: AnalyticConfig) -> Result<Analytic> {
        let (gpu, w, h) = (ctx.gpu, ctx.width, ctx.height);
        let max_range = gpu.caps().max_storage_buffer_range;
        let samples = c.samples;
        let frags = plan_lists(w, h, c.frags, samples, max_range).map_err(GpuError::Other)?;
        let px = u64::from(w) * u64::from(h);
        let occluder_group = occluder_group(px, max_range, samples);
        if ctx.scene.draws.len() > MAX_OBJECTS
            || ctx
                .scene
                .draws
                .iter()
                .any(|d| d.index_count as usize / 3 > MAX_PRIMITIVES)
        {
            return Err(GpuError::Other(format!(
                "analytic keys fragments by object (< {}) and primitive (< {MAX_PRIMITIVES}); this \
                 scene has {} objects, the largest with {} triangles",
                MAX_OBJECTS + 1,
                ctx.scene.draws.len(),
                ctx.scene
                    .draws
                    .iter()
                    .map(|d| d.index_count / 3)
                    .max()
                    .unwrap_or(0)
            )));
        }
        if ctx.scene.material_textures.len() > MAX_MATERIALS {
            return Err(GpuError::Other(format!(
                "analytic orders its albedo lookups by material, at most {MAX_MATERIALS}; this \
                 scene has {}",
                ctx.scene.material_textures.len()
            )));
        }
        let scene_layout =
            SetLayout::new(gpu, "analytic.scene_layout", &SCENE_SET.binding_descs())?;
        let material_layout = SetLayout::new(
            gpu,
            "analytic.material_layout",
            &MATERIAL_SET.binding_descs(),
        )?;
        let raster_layout = SetLayout::new(gpu, "analytic.raster_layout", &RASTER_BINDINGS)?;
        let resolve_layout = SetLayout::new(gpu, "analytic.resolve_layout", &RESOLVE_BINDINGS)?;
        let tail_layout = SetLayout::new(gpu, "analytic.tail_layout", &TAIL_BINDINGS)?;
        let albedo_layout = SetLayout::new(gpu, "analytic.albedo_layout", &ALBEDO_BINDINGS)?;

        let mut defines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        defines.extend(RASTER_BINDINGS.iter().map(BindingDesc::define));
        let common = [
            ("K_SLOTS".to_string(), frags.to_string()),
            ("OCCLUDER_GROUP".to_string(), occluder_group.to_string()),
            ("TAIL_ROW_GROUPS".to_string(), TAIL_ROW_GROUPS.to_string()),
            ("MASK_SAMPLES".to_string(), samples.to_string()),
            (
                "MASK_GEN".to_string(),
                reference::mask_generator(samples).to_string(),
            ),
        ];
        defines.extend(common.iter().cloned());
        if c.seed {
            defines.push(("SEED".into(), "1".into()));
        }
        if c.box_filter {
            defines.push(("TEXTURE_BOX".into(), "1".into()));
        }
        let vs = ctx.shaders.compile("scene/forward.vert", &defines)?;
        let gs = ctx.shaders.compile("analytic/raster.geom", &defines)?;
        let layouts = [&scene_layout, &material_layout, &raster_layout];
        let graphics = |name: &'static str, select: bool| -> Result<Raster> {
            let pipelines =
                scene_pass::MaterialVariants::build(&ctx.scene.material_features, |f| {
                    let mut d = defines.clone();
                    d.push(("MAT_FEATURES".into(), f.to_string()));
                    if select {
                        d.push(("SELECT_PASS".into(), "1".into()));
                    }
                    let fs = ctx.shaders.compile("analytic/raster.frag", &d)?;
                    Pipeline::graphics(
                        gpu,
                        &GraphicsDesc {
                            name: &format!("{name}.mat{f}"),
                            vertex: &vs,
                            geometry: Some(&gs),
                            fragment: &fs,
                            set_layouts: &layouts,
                            push_constant_bytes: 4,
                            color_formats: &[VELOCITY_FORMAT, ID_FORMAT],
                            depth_format: Some(DEPTH_FORMAT),
                            depth_compare: if select {
                                vk::CompareOp::ALWAYS
                            } else {
                                vk::CompareOp::GREATER
                            },
                            depth_write: !select,
                            samples: 1,
                            min_sample_shading: None,
                            cull_back_faces: false,
                            sample_locations: false,
                        },
                    )
                })?;
            Ok(Raster { pipelines, name })
        };
        let raster = graphics("analytic.raster", false)?;
        let select = graphics("analytic.select", true)?;

        // The resolve also lights the visible kept fragments: the scene's set is its set 1.
        let mut rdefines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        rdefines.extend(RESOLVE_BINDINGS.iter().map(BindingDesc::define));
        rdefines.extend(common.iter().cloned());
        let mut tdefines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        tdefines.extend(TAIL_BINDINGS.iter().map(BindingDesc::define));
        tdefines.extend(common.iter().cloned());
        let tail_cs = ctx.shaders.compile("analytic/tail.comp", &tdefines)?;
        let tail_pass = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "analytic.tail",
                shader: &tail_cs,
                set_layouts: &[&tail_layout, &scene_layout],
                push_constant_bytes: 0,
            },
        )?;
        let mut adefines = scene_pass::shader_defines(scene_pass::LAYOUT_NATIVE);
        adefines.extend(ALBEDO_BINDINGS.iter().map(BindingDesc::define));
        adefines.extend(common.iter().cloned());
        if c.box_filter {
            adefines.push(("TEXTURE_BOX".into(), "1".into()));
        }
        let albedo_cs = ctx.shaders.compile("analytic/albedo.comp", &adefines)?;
        let bin_pipeline = |name: &str, plan: bool| -> Result<Pipeline> {
            let mut d = adefines.clone();
            if plan {
                d.push(("BIN_PLAN".into(), "1".into()));
            }
            let cs = ctx.shaders.compile("analytic/albedo_bin.comp", &d)?;
            Pipeline::compute(
                gpu,
                &ComputeDesc {
                    name,
                    shader: &cs,
                    set_layouts: &[&albedo_layout],
                    push_constant_bytes: 0,
                },
            )
        };
        let bin_plan = bin_pipeline("analytic.albedo_plan", true)?;
        let bin_scatter = bin_pipeline("analytic.albedo_scatter", false)?;
        let albedo_pass = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "analytic.albedo",
                shader: &albedo_cs,
                set_layouts: &[&albedo_layout, &scene_layout, &material_layout],
                push_constant_bytes: 4,
            },
        )?;
        // The materials whose fragments leave albedo jobs (raster.frag: an albedo texture, no
        // alpha test).
        let albedo_materials: Vec<u32> = ctx
            .scene
            .material_textures
            .iter()
            .zip(0u32..)
            .filter(|(t, _)| t[0].is_some() && t[1].is_none())
            .map(|(_, m)| m)
            .collect();
        let cs = ctx.shaders.compile("analytic/resolve.comp", &rdefines)?;
        let resolve = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "analytic.resolve",
                shader: &cs,
                set_layouts: &[&resolve_layout, &scene_layout],
                push_constant_bytes: 96,
            },
        )?;

        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let buffer =
            |name: &str, bytes: u64, usage| Buffer::new(gpu, name, bytes, usage, Location::GpuOnly);
        let kept = px * u64::from(frags);
        let keys = buffer("analytic.keys", kept * KEY_BYTES, storage)?;
        let slots = buffer("analytic.slots", kept * HALF_SLOT_BYTES, storage)?;
        let colors = buffer("analytic.colors", kept * HALF_SLOT_BYTES, storage)?;
        let planes = buffer("analytic.planes", kept * PLANE_XY_BYTES, storage)?;
        let planes_y = buffer("analytic.planes_y", kept * PLANE_Y_BYTES, storage)?;
        let surfaces = buffer("analytic.surfaces", kept * SURFACE_BYTES, storage)?;
        let cells = buffer("analytic.cells", kept * HALF_CELLS_BYTES, storage)?;
        let cells_hi = buffer("analytic.cells_hi", kept * HALF_CELLS_BYTES, storage)?;
        let slot_masks = buffer(
            "analytic.slot_masks",
            (kept * slot_mask_bytes(samples)).max(4),
            storage,
        )?;
        let counts_buf = buffer("analytic.counts_buffer", px * 4, storage)?;
        let tail = buffer("analytic.tail", px * TAIL_BYTES, storage)?;
        let tail_back = buffer("analytic.tail_back", px * TAIL_BYTES, storage)?;
        let tail_masks = buffer(
            "analytic.tail_masks",
            px * tail_mask_bytes(samples),
            storage,
        )?;
        let occluders = buffer(
            "analytic.occluders",
            occluder_bytes(px, max_range, samples),
            storage,
        )?;
        let tail_records = buffer(
            "analytic.tail_records",
            start_tail_capacity(px, max_range, samples) * tail_record_bytes(samples),
            storage,
        )?;
        let tail_count = buffer(
            "analytic.tail_count",
            TAIL_COUNT_BYTES,
            storage | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        let tail_count_rb = Readback::for_buffer(gpu, "readback.analytic.tail_count", 4, 1, 1)?;
        let albedo_jobs = buffer(
            "analytic.albedo_jobs",
            start_job_capacity(px, max_range) * ALBEDO_JOB_BYTES,
            storage,
        )?;
        let albedo_count = buffer(
            "analytic.albedo_count",
            ALBEDO_COUNT_BYTES,
            storage | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        let albedo_count_rb = Readback::for_buffer(gpu, "readback.analytic.albedo_count", 4, 1, 1)?;
        let albedo_bins = buffer(
            "analytic.albedo_bins",
            MAX_MATERIALS as u64 * ALBEDO_BIN_BYTES,
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
        )?;
        let albedo_order = buffer(
            "analytic.albedo_order",
            start_job_capacity(px, max_range) * ALBEDO_ORDER_BYTES,
            storage,
        )?;
        // Native's colour target is not drawn (the resolve writes the colour).
        let FrameTargets {
            velocity,
            ids,
            depth,
            ..
        } = FrameTargets::new(gpu, "analytic", w, h)?;
        let targets_color = {
            let usage = vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC;
            move |name: &str, format| Image::new(gpu, &ImageDesc::new_2d(name, format, w, h, usage))
        };
        let color = targets_color("analytic.color", COLOR_FORMAT)?;
        let coverage = targets_color("analytic.coverage", COVERAGE_FORMAT)?;
        let counts = targets_color("analytic.counts", COUNTS_FORMAT)?;
        let targets = Targets {
            velocity,
            ids,
            depth,
        };

        let scene_set = SCENE_SET.make(
            gpu,
            "analytic",
            &scene_layout,
            &scene_pass::scene_binds(ctx.scene, ctx.counter),
        )?;
        // The mask slot holds the coverage textures: the alpha test and the albedo of the
        // passing part in one lookup (raster.frag).
        let material_sets = scene_pass::material_sets(
            gpu,
            "analytic",
            &material_layout,
            ctx.scene,
            scene_pass::MaskSlot::Coverage,
        )?;
        let raster_set = DescriptorSet::new(
            gpu,
            "analytic.raster_set",
            &raster_layout,
            &buffer_writes(&[
                &keys,
                &slots,
                &counts_buf,
                &colors,
                &planes,
                &planes_y,
                &occluders,
                &surfaces,
                &tail_records,
                &tail_count,
                &cells,
                &slot_masks,
                &cells_hi,
                &albedo_jobs,
                &albedo_count,
                &albedo_bins,
            ]),
        )?;
        let albedo_set = DescriptorSet::new(
            gpu,
            "analytic.albedo_set",
            &albedo_layout,
            &buffer_writes(&[
                &albedo_jobs,
                &albedo_count,
                &colors,
                &cells,
                &cells_hi,
                &tail_records,
                &albedo_bins,
                &albedo_order,
            ]),
        )?;
        let tail_set = DescriptorSet::new(
            gpu,
            "analytic.tail_set",
            &tail_layout,
            &buffer_writes(&[&tail_records, &tail_count, &tail, &tail_back, &tail_masks]),
        )?;
        let resolve_set = DescriptorSet::new(
            gpu,
            "analytic.resolve_set",
            &resolve_layout,
            &[
                Write::Buffer(0, &keys),
                Write::Buffer(1, &slots),
                Write::Buffer(2, &counts_buf),
                Write::Storage(3, &color),
                Write::Storage(4, &coverage),
                Write::Storage(5, &counts),
                Write::Buffer(6, &tail),
                Write::Buffer(7, &colors),
                Write::Buffer(8, &planes),
                Write::Buffer(9, &planes_y),
                Write::Buffer(10, &tail_back),
                Write::Buffer(11, &tail_masks),
                Write::Buffer(12, &surfaces),
                Write::Buffer(13, &cells),
                Write::Buffer(14, &slot_masks),
                Write::Buffer(15, &cells_hi),
            ],
        )?;
        let rb = |name: &str, image: &Image| Readback::for_image(gpu, name, image);
        let readbacks = [
            rb("readback.analytic.color", &color)?,
            rb("readback.analytic.coverage", &coverage)?,
            rb("readback.analytic.counts", &counts)?,
            rb("readback.analytic.depth", &targets.depth)?,
            rb("readback.analytic.velocity", &targets.velocity)?,
            rb("readback.analytic.ids", &targets.ids)?,
        ];
        Ok(Analytic {
            c,
            frags,
            occluder_group,
            select,
            raster,
            raster_layout,
            tail_layout,
            albedo_layout,
            _layouts: vec![scene_layout, material_layout, resolve_layout],
            scene_set,
            material_sets,
            raster_set,
            tail_pass,
            tail_set,
            albedo_pass,
            albedo_set,
            albedo_materials,
            albedo_jobs,
            albedo_count,
            albedo_count_rb,
            bin_plan,
            bin_scatter,
            albedo_bins,
            albedo_order,
            resolve,
            resolve_set,
            keys,
            slots,
            counts_buf,
            tail,
            tail_back,
            tail_masks,
            occluders,
            colors,
            planes,
            planes_y,
            surfaces,
            cells,
            cells_hi,
            slot_masks,
            tail_records,
            max_range,
            tail_count,
            tail_count_rb,
            targets,
            color,
            coverage,
            counts,
            readbacks,
            background: ctx.scene.background,
        })
    }

    /// Fragments kept per pixel this technique was built with.
    pub fn kept_per_pixel(&self) -> u32 {
        self.frags
    }

    /// Records and submits the frame's passes once (render() checks the tail records' count).
    fn submit_frame(&self, ctx: &mut FrameCtx, world_from_clip: [f32; 16]) -> Result<()> {
        let counter = ctx.counter;
        ctx.submit("frame", |cmd, profiler, scene| {
            let scope = profiler.begin(cmd, "analytic.clear", PassKind::Transfer);
            cmd.fill_buffer(&self.keys, u32::MAX);
            cmd.fill_buffer(&self.counts_buf, 0);
            cmd.fill_buffer(&self.tail, 0);
            cmd.fill_buffer(&self.tail_back, 0);
            cmd.fill_buffer(&self.tail_masks, 0);
            cmd.fill_buffer(&self.occluders, 0);
            // No records yet; the tail pass's dispatch: rows of TAIL_ROW_GROUPS groups, none.
            cmd.update_buffer(&self.tail_count, &[0, TAIL_ROW_GROUPS, 0, 1]);
            cmd.update_buffer(&self.albedo_count, &[0, TAIL_ROW_GROUPS, 0, 1]);
            cmd.fill_buffer(&self.albedo_bins, 0);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::FragmentStorageWrite);
            // The select pass writes no attachment (its fragments all discard); the second pass
            // clears and writes them.
            self.record_raster(cmd, profiler, scene, &self.select, false);
            self.record_raster(cmd, profiler, scene, &self.raster, true);

            // The albedo pass: the textured fragments' lookups, one invocation per job, once per
            // material over that material's jobs (ordered by material first: the plan's offsets
            // and dispatches, then the scatter). Each dispatch writes other slots and records
            // than the one before, but the same buffers: a barrier between them.
            let scope = profiler.begin(cmd, "analytic.albedo", PassKind::Compute);
            cmd.use_buffer(&self.albedo_bins, Access::ComputeStorageReadWrite);
            cmd.bind_pipeline(&self.bin_plan);
            cmd.bind_set(&self.bin_plan, 0, &self.albedo_set);
            cmd.dispatch(1, 1, 1);
            cmd.use_buffer(&self.albedo_jobs, Access::ComputeSampled);
            cmd.use_buffer(&self.albedo_count, Access::ComputeIndirect);
            cmd.use_buffer(&self.albedo_bins, Access::ComputeStorageReadWrite);
            cmd.use_buffer(&self.albedo_order, Access::ComputeStorageWrite);
            cmd.bind_pipeline(&self.bin_scatter);
            cmd.bind_set(&self.bin_scatter, 0, &self.albedo_set);
            cmd.dispatch_indirect(&self.albedo_count, 4);
            // The bins are read both as the dispatches' parameters and by the shader: one barrier
            // for both kinds of read.
            cmd.full_barrier();
            cmd.use_buffer(&self.albedo_order, Access::ComputeSampled);
            cmd.use_buffer(&self.albedo_bins, Access::ComputeSampled);
            cmd.bind_pipeline(&self.albedo_pass);
            cmd.bind_set(&self.albedo_pass, 0, &self.albedo_set);
            cmd.bind_set(&self.albedo_pass, 1, &self.scene_set);
            for &m in &self.albedo_materials {
                for buf in [
                    &self.colors,
                    &self.cells,
                    &self.cells_hi,
                    &self.tail_records,
                ] {
                    cmd.use_buffer(buf, Access::ComputeStorageReadWrite);
                }
                cmd.bind_set(&self.albedo_pass, 2, &self.material_sets[m as usize]);
                cmd.push_constants(&self.albedo_pass, &m.to_le_bytes());
                cmd.dispatch_indirect(&self.albedo_bins, u64::from(m) * ALBEDO_BIN_BYTES + 16);
            }
            profiler.end(cmd, scope);

            // The tail pass: one invocation per record the buffer holds, in the rows the raster
            // pass counted (the count may run past the capacity: render() then grows the buffer
            // and renders again).
            cmd.use_buffer(&self.tail_records, Access::ComputeSampled);
            cmd.use_buffer(&self.tail_count, Access::ComputeIndirect);
            for buf in [&self.tail, &self.tail_back, &self.tail_masks] {
                cmd.use_buffer(buf, Access::ComputeStorageReadWrite);
            }
            let scope = profiler.begin(cmd, "analytic.tail", PassKind::Compute);
            cmd.bind_pipeline(&self.tail_pass);
            cmd.bind_set(&self.tail_pass, 0, &self.tail_set);
            cmd.bind_set(&self.tail_pass, 1, &self.scene_set);
            cmd.dispatch_indirect(&self.tail_count, 4);
            profiler.end(cmd, scope);

            for buf in [
                &self.keys,
                &self.slots,
                &self.colors,
                &self.planes,
                &self.planes_y,
                &self.counts_buf,
                &self.tail,
                &self.tail_back,
                &self.tail_masks,
                &self.surfaces,
                &self.cells,
                &self.cells_hi,
                &self.slot_masks,
            ] {
                cmd.use_buffer(buf, Access::ComputeSampled);
            }
            for img in [&self.color, &self.coverage, &self.counts] {
                cmd.use_image(img, Access::ComputeStorageWrite);
            }
            let scope = profiler.begin(cmd, "analytic.resolve", PassKind::Compute);
            cmd.bind_pipeline(&self.resolve);
            cmd.bind_set(&self.resolve, 0, &self.resolve_set);
            cmd.bind_set(&self.resolve, 1, &self.scene_set);
            let (w, h) = (self.color.width, self.color.height);
            let bg = self.background;
            let mut push = [0u32; 24];
            push[..3].copy_from_slice(&bg.map(f32::to_bits));
            push[4] = w;
            push[5] = h;
            push[8..].copy_from_slice(&world_from_clip.map(f32::to_bits));
            cmd.push_constants(&self.resolve, bytemuck::cast_slice(&push));
            cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            profiler.end(cmd, scope);

            let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
            let [c, cov, cnt, d, v, ids] = &self.readbacks;
            cmd.read_image(&self.color, c);
            cmd.read_image(&self.coverage, cov);
            cmd.read_image(&self.counts, cnt);
            cmd.read_image(&self.targets.depth, d);
            cmd.read_image(&self.targets.velocity, v);
            cmd.read_image(&self.targets.ids, ids);
            cmd.use_buffer(&self.tail_count, Access::TransferSrc);
            cmd.read_buffer(&self.tail_count, &self.tail_count_rb);
            cmd.use_buffer(&self.albedo_count, Access::TransferSrc);
            cmd.read_buffer(&self.albedo_count, &self.albedo_count_rb);
            profiler.end(cmd, scope);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    /// Albedo jobs the last submitted frame asked for (some beyond the capacity when it exceeds
    /// it).
    fn recorded_jobs(&self) -> Result<u64> {
        count_read(&self.albedo_count_rb)
    }

    /// Tail records the buffer holds.
    fn tail_capacity(&self) -> u64 {
        self.tail_records.size() / tail_record_bytes(self.c.samples)
    }

    /// Fragments the last submitted frame recorded for the tails (some beyond the capacity
    /// when it exceeds it).
    fn recorded_tails(&self) -> Result<u64> {
        count_read(&self.tail_count_rb)
    }

    /// Replaces the tail-record buffer by one holding `needed` records and a quarter more (at most
    /// the device's largest storage buffer) and points the two sets that bind it at the new one;
    /// or the refusal where one buffer cannot hold `needed`.
    fn grow_tail_records(&mut self, gpu: &cbr_gpu::Gpu, needed: u64) -> Result<()> {
        let capacity = grown_tail_capacity(needed, self.frags, self.c.samples, self.max_range)
            .map_err(GpuError::Other)?;
        tracing::info!(
            "analytic: {needed} tail records this frame, {} held: the buffer grows to {capacity}",
            self.tail_capacity()
        );
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        self.tail_records = Buffer::new(
            gpu,
            "analytic.tail_records",
            capacity * tail_record_bytes(self.c.samples),
            usage,
            Location::GpuOnly,
        )?;
        // The frame that counted them has completed (FrameCtx::submit waits), so the two sets
        // that bind the buffer are not in use.
        for (set, layout, bindings) in [
            (&self.raster_set, &self.raster_layout, &RASTER_BINDINGS[..]),
            (&self.tail_set, &self.tail_layout, &TAIL_BINDINGS[..]),
            (&self.albedo_set, &self.albedo_layout, &ALBEDO_BINDINGS[..]),
        ] {
            let binding = binding_of(bindings, "tail_records");
            set.update(gpu, layout, &[Write::Buffer(binding, &self.tail_records)])?;
        }
        Ok(())
    }

    /// Replaces the albedo-job buffer by one holding `needed` jobs and a quarter more (at most
    /// the device's largest storage buffer) and points the two sets that bind it at the new one;
    /// or the refusal where one buffer cannot hold `needed`.
    fn grow_albedo_jobs(&mut self, gpu: &cbr_gpu::Gpu, needed: u64) -> Result<()> {
        let capacity = grown_job_capacity(needed, self.max_range).map_err(GpuError::Other)?;
        tracing::info!(
            "analytic: {needed} albedo jobs this frame, {} held: the buffer grows to {capacity}",
            self.albedo_jobs.size() / ALBEDO_JOB_BYTES
        );
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        self.albedo_jobs = Buffer::new(
            gpu,
            "analytic.albedo_jobs",
            capacity * ALBEDO_JOB_BYTES,
            usage,
            Location::GpuOnly,
        )?;
        self.albedo_order = Buffer::new(
            gpu,
            "analytic.albedo_order",
            capacity * ALBEDO_ORDER_BYTES,
            usage,
            Location::GpuOnly,
        )?;
        self.raster_set.update(
            gpu,
            &self.raster_layout,
            &[Write::Buffer(
                binding_of(&RASTER_BINDINGS, "albedo_jobs"),
                &self.albedo_jobs,
            )],
        )?;
        self.albedo_set.update(
            gpu,
            &self.albedo_layout,
            &[
                Write::Buffer(
                    binding_of(&ALBEDO_BINDINGS, "albedo_jobs"),
                    &self.albedo_jobs,
                ),
                Write::Buffer(
                    binding_of(&ALBEDO_BINDINGS, "albedo_order"),
                    &self.albedo_order,
                ),
            ],
        )?;
        Ok(())
    }

    fn record_raster(
        &self,
        cmd: &mut cbr_gpu::Cmd,
        profiler: &mut cbr_gpu::Profiler,
        scene: &crate::gpu_scene::GpuScene,
        r: &Raster,
        clear: bool,
    ) {
        let scope = profiler.begin(cmd, r.name, PassKind::Graphics);
        scene_pass::use_scene_buffers(cmd, scene);
        for buf in [
            &self.keys,
            &self.slots,
            &self.colors,
            &self.planes,
            &self.planes_y,
            &self.counts_buf,
            &self.occluders,
            &self.surfaces,
            &self.tail_records,
            &self.tail_count,
            &self.cells,
            &self.cells_hi,
            &self.slot_masks,
            &self.albedo_jobs,
            &self.albedo_count,
            &self.albedo_bins,
        ] {
            cmd.use_buffer(buf, Access::FragmentStorageWrite);
        }
        let t = &self.targets;
        let color_clear = |uint: bool| {
            clear.then_some(vk::ClearValue {
                color: if uint {
                    vk::ClearColorValue { uint32: [0; 4] }
                } else {
                    vk::ClearColorValue { float32: [0.0; 4] }
                },
            })
        };
        let depth_clear = clear.then_some(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 0.0,
                stencil: 0,
            },
        });
        cmd.begin_rendering(
            &[
                cbr_gpu::Attachment {
                    image: &t.velocity,
                    clear: color_clear(false),
                },
                cbr_gpu::Attachment {
                    image: &t.ids,
                    clear: color_clear(true),
                },
            ],
            Some(cbr_gpu::Attachment {
                image: &t.depth,
                clear: depth_clear,
            }),
            1,
        );
        cmd.set_viewport(0.0, 0.0, t.depth.width as f32, t.depth.height as f32);
        cmd.bind_set(r.pipelines.first(), 0, &self.scene_set);
        cmd.bind_set(r.pipelines.first(), 2, &self.raster_set);
        scene_pass::draw_scene(cmd, scene, &self.material_sets, 1, 1, |m| r.pipelines.of(m));
        cmd.end_rendering();
        profiler.end(cmd, scope);
    }
}

impl Technique for Analytic {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        // Camera-relative world from unjittered clip space, the inverse of what gpu_scene.rs
        // builds every object's clip_from_local from (f64, then f32).
        let cam = &view.camera;
        let world_from_clip = (cam.projection(view.aspect) * cam.rotation())
            .inverse()
            .to_cols_array()
            .map(|v| v as f32);
        let timings_before = ctx.timings.clone();
        loop {
            self.submit_frame(ctx, world_from_clip)?;
            let recorded = self.recorded_tails()?;
            let jobs = self.recorded_jobs()?;
            let jobs_held = self.albedo_jobs.size() / ALBEDO_JOB_BYTES;
            if recorded <= self.tail_capacity() && jobs <= jobs_held {
                return Ok(());
            }
            // More fragments beyond the K, or textured fragments, than a buffer holds: grow it
            // and render the frame again (its timings replace the first rendering's).
            if recorded > self.tail_capacity() {
                self.grow_tail_records(ctx.gpu, recorded)?;
            }
            if jobs > jobs_held {
                self.grow_albedo_jobs(ctx.gpu, jobs)?;
            }
            ctx.timings = timings_before.clone();
        }
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        let t = &self.targets;
        Some(Geometry {
            velocity: &t.velocity,
            depth: &t.depth,
            ids: &t.ids,
            packed: false,
        })
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let [c, cov, cnt, d, v, ids] = &self.readbacks;
        let mut out = FrameOutput::new(
            ctx.view.width,
            ctx.view.height,
            bytemuck::cast_slice::<u8, f16>(c.bytes()?).to_vec(),
            linear_depths(bytemuck::cast_slice(d.bytes()?), ctx.view.camera.near),
            bytemuck::cast_slice::<u8, [f32; 2]>(v.bytes()?).to_vec(),
            bytemuck::cast_slice::<u8, [u32; 2]>(ids.bytes()?).to_vec(),
        );
        let counts: &[[u32; 4]] = bytemuck::cast_slice(cnt.bytes()?);
        let coverage = Coverage {
            edge: counts
                .iter()
                .map(|c| u8::from(c[2] & FLAG_EDGE != 0))
                .collect(),
            fraction: bytemuck::cast_slice::<u8, f32>(cov.bytes()?).to_vec(),
        };
        AnalyticLayers {
            fragments: counts.iter().map(|c| c[0]).collect(),
            overflow: counts.iter().map(|c| c[1]).collect(),
            visible: counts.iter().map(|c| c[3]).collect(),
            seed_differs: counts
                .iter()
                .map(|c| u8::from(self.c.seed && c[2] & FLAG_SEED != 0))
                .collect(),
            nonfinite: counts
                .iter()
                .map(|c| u8::from(c[2] & FLAG_NONFINITE != 0))
                .collect(),
            kept_per_pixel: self.frags,
            tail_fragments: self.recorded_tails()?,
            albedo_jobs: self.recorded_jobs()?,
        }
        .write(&coverage, &mut out)?;
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let px = u64::from(self.color.width) * u64::from(self.color.height);
        // K x (key + slot + plane + surface + albedo grid + further mask words) + the fragment
        // count (4), tails (2 x 32) and their masks (2 x 4 N / 32), the occluder words (4 N /
        // group) + colour (8), coverage (4), counts (16), depth (4), velocity (8), IDs (8); and
        // the tail records the buffer holds now.
        let samples = self.c.samples;
        self.tail_records.size()
            + px * (u64::from(self.frags) * fragment_bytes(samples)
                + 4
                + 2 * TAIL_BYTES
                + tail_mask_bytes(samples)
                + occluder_pixel_bytes(self.occluder_group, samples)
                + 8
                + 4
                + 16
                + 4
                + 8
                + 8)
    }
}
