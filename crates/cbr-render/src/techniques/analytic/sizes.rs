//! `analytic`'s sizes: the bytes of a kept fragment, a tail and a record, how many fragments a
//! pixel keeps on a device, the occluder words' grouping, and the capacities of the buffers that
//! grow (tail records, albedo jobs).

use super::config::{DEFAULT_FRAGS, MAX_FRAGS};

/// Bytes of one kept fragment: its 64-bit key (depth, object, primitive), its slot (coverage,
/// mask, albedo as 3 x f16, flags), its depth plane ([`PLANE_BYTES`]) and its surface
/// ([`SURFACE_BYTES`]).
pub const KEY_BYTES: u64 = 8;
/// A slot is two 8-byte halves in two buffers (coverage + mask; colour + flags), so that each
/// buffer holds K x 8 bytes per pixel under `maxStorageBufferRange`.
pub const SLOT_BYTES: u64 = 16;
pub(super) const HALF_SLOT_BYTES: u64 = SLOT_BYTES / 2;
/// A kept fragment's depth plane (depth at the pixel centre, its change per pixel in x and y: 3 x
/// f32) for the resolve's per-sample visibility, in two buffers: depth and x change; y change.
pub(super) const PLANE_XY_BYTES: u64 = 8;
pub(super) const PLANE_Y_BYTES: u64 = 4;
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
pub(super) fn occluder_pixel_bytes(group: u32, samples: u32) -> u64 {
    u64::from(samples / group) * OCCLUDER_WORD_BYTES
}

pub(super) fn occluder_bytes(px: u64, max_range: u32, samples: u32) -> u64 {
    px * occluder_pixel_bytes(occluder_group(px, max_range, samples), samples)
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
pub(super) fn start_tail_capacity(px: u64, max_range: u32, samples: u32) -> u64 {
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
pub(super) fn start_job_capacity(px: u64, max_range: u32) -> u64 {
    (px * ALBEDO_JOBS_PER_PIXEL_START).clamp(1, max_job_capacity(max_range))
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

/// Bytes of the technique's targets (run.json's `target_bytes`) at `px` pixels keeping `frags`
/// fragments each, with `tail_records` bytes of tail records held now: K x (key + slot + plane +
/// surface + albedo grid + further mask words) + the fragment count (4), tails (2 x 32) and their
/// masks (2 x 4 N / 32), the occluder words (4 N / group) + colour (8), coverage (4), counts
/// (16), depth (4), velocity (8), IDs (8).
pub fn target_bytes(
    px: u64,
    frags: u32,
    samples: u32,
    occluder_group: u32,
    tail_records: u64,
) -> u64 {
    tail_records
        + px * (u64::from(frags) * fragment_bytes(samples)
            + 4
            + 2 * TAIL_BYTES
            + tail_mask_bytes(samples)
            + occluder_pixel_bytes(occluder_group, samples)
            + 8
            + 4
            + 16
            + 4
            + 8
            + 8)
}
