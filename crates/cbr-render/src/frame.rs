//! What a rendered frame is on the host: the layers and statistics a technique reads back, the
//! sequencer completes (index, time, timings, counters) and the CLI, the bench and the cache
//! consume. A leaf: it imports nothing of the sequencer or the techniques.

use cbr_gpu::{Image, PassTiming};
use half::f16;

/// One rendered frame, read back to the host.
#[derive(Clone, Default)]
pub struct FrameOutput {
    pub index: u32,
    pub time: f64,
    pub width: u32,
    pub height: u32,
    /// Linear HDR radiance, RGBA, rows top to bottom. Alpha 1 where shaded this frame.
    pub color: Vec<f16>,
    /// View-space distance along the camera axis (metres); +inf where nothing was drawn.
    pub depth: Vec<f32>,
    /// Screen-space motion since the previous frame in pixels (current - previous), x right, y down.
    pub velocity: Vec<[f32; 2]>,
    /// [object ID (index + 1, 0 = background), primitive ID within the object].
    pub ids: Vec<[u32; 2]>,
    /// Checkerboard frames: 1 where this frame shaded the pixel, and the frame's parity.
    pub mask: Option<Vec<u8>>,
    pub parity: Option<u32>,
    /// Shaded (non-helper) fragments, when counted.
    pub shaded_fragments: Option<u64>,
    /// Fragments whose shading was NaN or infinite (written black, never kept in a history);
    /// `None` for frames read from the cache.
    pub nonfinite_fragments: Option<u64>,
    /// The `id_prepass` outputs at full resolution: view depth (+inf where empty) and IDs.
    pub prepass: Option<(Vec<f32>, Vec<[u32; 2]>)>,
    /// Resolved checkerboard frames: whether history was reset, and with `debug` the debug bits
    /// (resolve::DEBUG_VIEWS) and the velocity each pixel used.
    pub resolve: Option<ResolveOutput>,
    /// Supersampled frames: the per-pixel edge mask and the fraction of samples on geometry.
    pub coverage: Option<Coverage>,
    /// `analytic` frames: the fragment lists' statistics per pixel.
    pub analytic: Option<AnalyticLayers>,
    /// `deferred:vpls=N` frames: the frame's virtual point lights (camera-relative).
    pub vpls: Option<Vec<crate::gpu_types::Vpl>>,
    /// `interleaved:...:debug` frames: the debug views.
    pub interleaved: Option<InterleavedLayers>,
    /// Where the frame came from when it was not rendered now (a cache file).
    pub cached: Option<std::path::PathBuf>,
    pub timings: Vec<PassTiming>,
}

/// What the resolve adds to a frame's output.
#[derive(Clone)]
pub struct ResolveOutput {
    pub reset: bool,
    /// Per pixel: the resolve::DBG_* bits (with `debug`).
    pub debug_bits: Option<Vec<u32>>,
    /// Per pixel: the velocity the resolve used (with `debug`).
    pub velocity: Option<Vec<[f32; 2]>>,
}

/// The `coverage` layer of supersampled frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// 1 where the pixel's samples saw more than one object ID (background counts as one).
    pub edge: Vec<u8>,
    /// Fraction of the pixel's samples that hit geometry.
    pub fraction: Vec<f32>,
}

/// What `interleaved:...:debug` adds to a frame (docs/interleaved.md, the debug views).
#[derive(Clone, Debug, Default)]
pub struct InterleavedLayers {
    /// M, N.
    pub tile: (u32, u32),
    /// Per pixel: its VPL subset, (x mod M) + M (y mod N); 0 where nothing was drawn.
    pub subset: Vec<u8>,
    /// Per pixel: 1 where the filter's M x N window holds a pixel that is not on the pixel's
    /// surface (`seed`: the seed's own edge test).
    pub edge: Vec<u8>,
    /// Per pixel: the subsets the pixel shaded itself (`ours`' fallback; 0 with other filters).
    pub fallback: Vec<u8>,
    /// Pixels where the G-buffer split and gathered back differs from the G-buffer (position or
    /// normal, bit for bit): 0 unless the split and gather are not inverses.
    pub roundtrip_mismatches: u64,
    /// The split mosaic of the subset estimates (M Ws x N Hs texels, RGB); `None` with
    /// `implicit`, which has no split.
    pub mosaic: Option<(u32, u32, Vec<[f32; 3]>)>,
}

/// What `analytic` adds to a frame: per pixel, the fragments that touched it, the overflow (those
/// beyond the K nearest, not composited), the fragments that contributed, and with `analytic:seed` whether a
/// visible fragment's shortcut area is off the exact area by more than 1e-3.
#[derive(Clone, Debug, Default)]
pub struct AnalyticLayers {
    pub fragments: Vec<u32>,
    pub overflow: Vec<u32>,
    pub visible: Vec<u32>,
    pub seed_differs: Vec<u8>,
    /// 1 where a kept fragment's shading was not finite (it was dropped, not composited).
    pub nonfinite: Vec<u8>,
    /// Fragments kept per pixel (K) this frame was built with.
    pub kept_per_pixel: u32,
    /// Fragments beyond their pixel's K that no occluder hid: lit by the tail pass and merged
    /// into the tails.
    pub tail_fragments: u64,
    /// Textured fragments (kept or in a tail) whose albedo the albedo pass filtered.
    pub albedo_jobs: u64,
}

impl FrameOutput {
    /// A frame of the four common layers; the sequencer fills index, time and timings.
    pub fn new(
        width: u32,
        height: u32,
        color: Vec<f16>,
        depth: Vec<f32>,
        velocity: Vec<[f32; 2]>,
        ids: Vec<[u32; 2]>,
    ) -> FrameOutput {
        FrameOutput {
            width,
            height,
            color,
            depth,
            velocity,
            ids,
            ..FrameOutput::default()
        }
    }
}

/// A frame's geometry at the output resolution (`upscale` gives its upscaled layers), sampled by
/// temporal post passes.
pub struct Geometry<'a> {
    /// RG32F: screen motion since the previous frame in pixels of this image (current - previous),
    /// without the frame's jitter.
    pub velocity: &'a Image,
    /// Reverse-Z depth (0 = nothing drawn): D32 or R32F, read through `.r` of a sampler.
    pub depth: &'a Image,
    /// RG32UI: object ID (0 = background), primitive ID; or, when `packed`, (object ID | bit 31
    /// set where the pixel moved, reverse-Z depth bits) and `depth` is this image too (the
    /// checkerboard resolve's history geometry).
    pub ids: &'a Image,
    pub packed: bool,
}
