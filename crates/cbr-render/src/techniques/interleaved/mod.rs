//! `interleaved:MxN[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D][:ours|seed|box|none]
//! [:search=S][:enough=K][:exact-edges[=R]][:band=B][:direct][:implicit][:debug][:floor][:fallback=F][:window=W][:flat=on|off][:parts=P]`: interleaved many-light
//! shading (Segovia et al. 2006; docs/interleaved.md) on `deferred`'s G-buffer and VPLs.
//!
//! Passes per frame, one submission: `interleaved.gbuffer` (deferred's G-buffer pass), the sun's
//! map and the VPLs (deferred::lights), then (split.rs) `interleaved.split` (the G-buffer into
//! M x N sub-images of every M-th column and N-th row), `interleaved.shade` (sub-image k with VPL
//! subset k, the k-th contiguous block of VPLs, times M N), `interleaved.gather` (the estimates back to their
//! pixels) or, with `implicit`, `interleaved.implicit` (each pixel its own subset, no split); with
//! `seed` the seed's blur; and `interleaved.lighting`: deferred's lighting pass, whose VPL term
//! becomes the filter (shaders/interleaved/filter.glsl) times albedo. Each pixel evaluates
//! N / (M N) VPLs instead of N, plus what `ours` shades for subsets its surface lacks nearby;
//! `deferred:vpls=N` is the reference. With `direct` the point lights (the scene's and
//! `points=N`) are shaded in subsets as well (light j in subset j mod M N), their diffuse term
//! filtered with the VPLs' irradiance and their specular term beside it; the lighting pass then
//! shades the directional lights only.

pub mod layers;
pub mod split;

use cbr_gpu::{Access, Image, Readback, Result, vk};

use super::LayerReadbacks;
use super::deferred::lighting::{InterleavedLighting, Interleaving, LightingPass, LightingPush};
use super::deferred::lights::ManyLights;
use super::deferred::{self, DeferredConfig, GBuffer};
use crate::frame::{FrameOutput, LayerDecl};
use crate::memory::MemoryEstimate;
use crate::scene_pass::{RasterConfig, ScenePass};
use crate::technique::{
    BuildCtx, FrameCtx, Geometry, Outputs, Registration, Technique, unknown_param,
};
pub use layers::InterleavedLayers;
use split::SplitPasses;

/// deferred's VPLs, then with `debug` the views.
const LAYERS: [LayerDecl; 3] = [
    deferred::VPL_LAYER,
    layers::DEBUG_LAYER,
    layers::MOSAIC_LAYER,
];

pub const REGISTRATION: Registration = Registration {
    name: "interleaved",
    grammar: "interleaved:MxN[:vpls=N][:points=N][:rsm=R][:reach=D][:clamp=D]\
              [:ours|seed|box|none][:search=S][:enough=K][:exact-edges[=R]][:band=surface|object|albedo|depth][:contrast=T][:side=both|near|far]\
              [:direct][:implicit][:debug]\
              [:floor][:fallback=pairs|inline][:window=tile|fetch][:flat=on|off][:parts=base|lights|filter]",
    about: "deferred's VPLs, interleaved: the G-buffer split into M x N sub-images, sub-image k \
            shaded with the k-th block of N / (M N) VPLs, gathered back, filtered (ours: \
            geometry-aware, missing subsets shaded at the pixel; seed: the seed's edge-skipping \
            Gaussian; box; none), times albedo; direct: the point lights in subsets too; implicit: \
            no split",
    outputs: Outputs {
        layers: &LAYERS,
        stats: &layers::STATS,
        pngs: Some(layers::debug_pngs),
        settings: None,
    },
    check: |p| parse(p).map(|_| ()),
    needs: |_, _| None,
    estimate: |ctx, p| Ok(Interleaved::estimate(&parse(p)?, ctx.width, ctx.height)),
    passes: |ctx, p| {
        let c = parse(p)?;
        let mut compute = Vec::new();
        if c.lights.vpls > 0 {
            compute.push(super::deferred::rsm::vpl_decl());
        }
        compute.extend(split::decls(&c));
        if c.floor {
            compute.push(crate::resolve::copy_floor_decl("interleaved.copy_floor"));
        }
        let variant = lighting_variant(&c);
        compute.push(super::deferred::lighting::decl_culled(
            Some(&variant),
            c.lights.cull,
        ));
        if variant.pairs {
            compute.push(super::deferred::lighting::fallback_decl(&variant, false));
            compute.push(super::deferred::lighting::fallback_decl(&variant, true));
        }
        Ok(crate::technique::PassList {
            compute,
            graphics: super::deferred::raster_decls(ctx, "interleaved", c.lights.vpls)?,
            packed_geometry: false,
        })
    },
    build: |ctx, p| {
        let c = parse(p).map_err(|e| crate::technique::refused("interleaved", p, e))?;
        Ok(Box::new(Interleaved::new(ctx, c)?))
    },
};

/// The largest M and N.
pub const MAX_TILE: u32 = 8;
/// The VPLs of subset `k` of `subsets` when there are `count` (a multiple of `subsets`): the k-th
/// contiguous block (shaders/interleaved/subsets.glsl). Consecutive points of the VPLs' Halton
/// pattern are stratified over the whole map; a stride through it is not (test below).
pub fn subset_range(k: u32, count: u32, subsets: u32) -> std::ops::Range<usize> {
    let size = (count / subsets) as usize;
    k as usize * size..(k as usize + 1) * size
}

/// The widest band `exact-edges=R` shades exactly.
pub const MAX_EXACT_EDGES: u32 = 3;
/// `ours`' same-surface test (filter.glsl): the least dot of two normals on one surface
/// (`normal=C`), and the plane distance as a share of p's distance (`plane=T`). The defaults are
/// the seed's edge thresholds; docs/interleaved.md sweeps both.
pub const DEFAULT_SAME_NORMAL_COS: f32 = 0.9;
pub const DEFAULT_PLANE_TOLERANCE: f32 = 0.02;
/// The contrast bands' (`band=albedo`, `band=depth`) threshold unless `contrast=T` says
/// otherwise: the least difference of the two sides' tones (albedo luminance, or the
/// background's radiance's) or distances from the camera, as a share of the larger.
pub const DEFAULT_BAND_CONTRAST: f32 = 0.5;
/// `ours`' search beyond the window unless `search=K` says otherwise.
pub const DEFAULT_SEARCH: u32 = 0;
/// VPLs unless `vpls=N` says otherwise.
pub const DEFAULT_VPLS: u32 = 1024;

/// `band=...`: which pixels `exact-edges=R` shades exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Band {
    Surface,
    Object,
    Albedo,
    Depth,
}

/// How the window's subset estimates become a pixel's VPL irradiance (the FILTER define).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// `none` (`raw`): each pixel keeps its own subset's estimate, the interleaved pattern.
    None = 0,
    /// `box`: the mean over the M x N window (one pixel of each subset), whatever the geometry.
    Box = 1,
    /// `ours` (the default): per subset, the window's pixel holding it if it lies on the pixel's
    /// surface (with `search=1`, else the nearest one a period further that does); a subset with
    /// none is shaded at the pixel (unless `enough=K` of them were found).
    Ours = 2,
    /// `seed`: the seed's edge detection (depth and normal against the 4 neighbours) and a
    /// separable Gaussian over non-edge pixels; edge pixels keep their own subset's estimate.
    Seed = 3,
}

impl Filter {
    pub fn name(self) -> &'static str {
        match self {
            Filter::None => "none",
            Filter::Box => "box",
            Filter::Ours => "ours",
            Filter::Seed => "seed",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterleavedConfig {
    pub m: u32,
    pub n: u32,
    pub filter: Filter,
    /// `implicit`: no split; each pixel shades the subset of its position (x mod M, y mod N) in
    /// one full-resolution pass.
    pub implicit: bool,
    /// `debug`: the debug views (subset, edge, fallback, split mosaic) read back each frame.
    pub debug: bool,
    /// `search=1`: `ours` looks for a subset one period further when the window's pixel is on
    /// another surface, before shading it at the pixel (`search=0`: the window only).
    pub search: u32,
    /// `enough=K` (`ours`): a pixel that finds at least K subsets on its surface takes their
    /// mean; with fewer it shades the missing ones itself. M N unless set.
    pub enough: u32,
    /// `exact-edges=R` (`ours`; R from 1 to [`MAX_EXACT_EDGES`], 0 off): a pixel with a pixel
    /// off its surface (another object, a crease, the background) within R, in the square of
    /// side 2R + 1, shades every subset itself: the reference's value in a band of R pixels
    /// along the boundaries, at the cost of M N subsets there.
    pub exact_edges: u32,
    /// `band=surface|object` (with `exact-edges=R`): which pixels form the band: those with a
    /// pixel off their surface within R (`surface`, the default: other objects, creases, depth
    /// steps, the background), or only those with a pixel of another object or the background
    /// within R (`object`: silhouettes and contacts, where FLIP's edge features magnify an error
    /// most; a crease within an object keeps the ordinary filter and its fallback).
    pub band_objects: bool,
    /// `band=albedo|depth` (with `exact-edges=R`; they set `band_objects` too), `contrast=T`: of
    /// the object band's pixels only those whose square holds the background or a pixel of
    /// another object whose tone (`albedo`: the luminance of its albedo, the background's
    /// radiance's) or distance from the camera (`depth`; the background always differs) differs
    /// from the pixel's by at least T of the larger of the two. 0: off (the object band, or the
    /// surface band).
    pub band_contrast: f32,
    /// `band=depth`: the contrast band's two sides compared by their distance from the camera
    /// (the background always differs), not by their tone.
    pub band_depth: bool,
    /// `side=both|near|far` (`band=depth`): 0 both sides of a depth step make the band, 1 the
    /// nearer side only (the background counts as farther), 2 the farther side only.
    pub band_side: u32,
    /// `normal=C` (`ours`): a window pixel is on p's surface only where the two normals' dot is
    /// at least C (default [`DEFAULT_SAME_NORMAL_COS`]).
    pub same_normal_cos: f32,
    /// `plane=T` (`ours`): ... and it lies within T times p's distance from the camera of p's
    /// tangent plane (default [`DEFAULT_PLANE_TOLERANCE`]).
    pub plane_tolerance: f32,
    /// `floor`: also run a copy kernel moving the split and gather passes' bytes (their
    /// bandwidth floor), timed as `interleaved.copy_floor`.
    pub floor: bool,
    /// `direct`: the point lights (the scene's and `points=N`) are shaded in subsets too, light
    /// j by the sub-image of subset j mod M N, times M N; their diffuse term joins the VPLs'
    /// estimate and their specular term is filtered beside it with the same choices.
    pub direct: bool,
    /// `parts=base|lights|filter` (timing only; the frame is not the technique's): the lighting
    /// pass stops after a part, so that one bench run attributes its time (docs/interleaved.md,
    /// "Where the lighting pass's time goes"). [`Parts::All`] unless set.
    pub parts: Parts,
    /// `fallback=pairs|inline` (`ours`): where the fallback shades the missing subsets: in
    /// passes of their own over a list of (pixel, subset) pairs (`pairs`, the default without
    /// `direct`), or in the lighting pass, each pixel its own list (`inline`, the only one with
    /// `direct`). The frames are the same (the same sums in the same order).
    pub pairs: bool,
    /// `window=tile|fetch` (`ours`): the filter's window (and `search`'s candidates) read from a
    /// tile of the workgroup's pixels and their apron fetched into shared memory once (`tile`,
    /// the default; with `search=1` since 2026-12-01), or each texel fetched by every window that
    /// holds it (`fetch`). The same frame.
    pub window_tile: bool,
    /// `flat=on|off` (`ours`, with either window): a workgroup whose tile lies on one plane-like
    /// surface (shaders/interleaved/filter.glsl, FLAT_TILES: every same-surface test there would
    /// pass, by a bound) takes the box mean of each window without the tests (`on`, the default),
    /// or tests every slot as elsewhere (`off`). The same frame.
    pub flat_tiles: bool,
    pub lights: DeferredConfig,
}

/// How much of the lighting pass runs (the PARTS define of lighting.comp; `parts=...`, a timing
/// attribution: every variant but `All` writes a frame that is not the technique's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parts {
    /// Everything (the technique).
    All = 0,
    /// `parts=base`: the G-buffer's fetches, emission, ambient and the directional lights only.
    Base = 1,
    /// `parts=lights`: `base` and the point lights the pass shades per pixel (without `direct`,
    /// the scene's point lights and `points=N`; with `direct`, none: it is `base`).
    Lights = 2,
    /// `parts=filter`: `lights` and the filter (the window's same-surface tests and fetches),
    /// without `ours`' fallback (a missing subset is left out).
    Filter = 3,
}

impl Parts {
    pub fn name(self) -> &'static str {
        match self {
            Parts::All => "all",
            Parts::Base => "base",
            Parts::Lights => "lights",
            Parts::Filter => "filter",
        }
    }
}

impl InterleavedConfig {
    /// `box` with the split passes: the gather sums each pixel's window row and the lighting pass
    /// adds the rows (the BOX_ROWS define of both); `implicit` has no gather.
    pub fn box_rows(&self) -> bool {
        self.filter == Filter::Box && !self.implicit
    }
}

fn tile(p: &str) -> std::result::Result<(u32, u32), String> {
    let bad = || {
        format!(
            "interleaved `{p}`: give the sub-images as MxN, M and N from 1 to {MAX_TILE} (`4x4`)"
        )
    };
    let (m, n) = p.split_once('x').ok_or_else(bad)?;
    let side = |v: &str| v.parse::<u32>().ok().filter(|v| (1..=MAX_TILE).contains(v));
    Ok((side(m).ok_or_else(bad)?, side(n).ok_or_else(bad)?))
}

pub fn parse(params: &[&str]) -> std::result::Result<InterleavedConfig, String> {
    let Some((first, rest)) = params.split_first() else {
        return Err("interleaved needs its sub-images, MxN (`interleaved:4x4`)".into());
    };
    let (m, n) = tile(first)?;
    let mut filter = None;
    let (mut implicit, mut debug, mut floor, mut direct) = (false, false, false, false);
    let mut exact_edges = 0;
    let mut band = None;
    let mut contrast = None;
    let mut band_side = None;
    let mut parts = Parts::All;
    let mut fallback = None;
    let mut window = None;
    let mut flat = None;
    let mut search = DEFAULT_SEARCH;
    let mut enough = None;
    let mut same_normal_cos = DEFAULT_SAME_NORMAL_COS;
    let mut plane_tolerance = DEFAULT_PLANE_TOLERANCE;
    let mut surface_test = None;
    let mut light_params = Vec::new();
    for p in rest {
        let key = p.split_once('=').map_or(*p, |(k, _)| k);
        let f = match key {
            "none" | "raw" => Some(Filter::None),
            "box" => Some(Filter::Box),
            "ours" => Some(Filter::Ours),
            "seed" => Some(Filter::Seed),
            "implicit" => {
                implicit = true;
                None
            }
            "debug" => {
                debug = true;
                None
            }
            "floor" => {
                floor = true;
                None
            }
            "direct" => {
                direct = true;
                None
            }
            "fallback" => {
                fallback = match p.split_once('=').map(|(_, v)| v) {
                    Some("pairs") => Some(true),
                    Some("inline") => Some(false),
                    _ => {
                        return Err(format!(
                            "interleaved `{p}`: fallback=pairs or fallback=inline"
                        ));
                    }
                };
                None
            }
            "flat" => {
                flat = match p.split_once('=').map(|(_, v)| v) {
                    Some("on") => Some(true),
                    Some("off") => Some(false),
                    _ => return Err(format!("interleaved `{p}`: flat=on or flat=off")),
                };
                None
            }
            "window" => {
                window = match p.split_once('=').map(|(_, v)| v) {
                    Some("tile") => Some(true),
                    Some("fetch") => Some(false),
                    _ => return Err(format!("interleaved `{p}`: window=tile or window=fetch")),
                };
                None
            }
            "parts" => {
                parts = match p.split_once('=').map(|(_, v)| v) {
                    Some("base") => Parts::Base,
                    Some("lights") => Parts::Lights,
                    Some("filter") => Parts::Filter,
                    Some("all") => Parts::All,
                    _ => {
                        return Err(format!(
                            "interleaved `{p}`: parts=base, parts=lights, parts=filter or \
                             parts=all (a timing attribution of the lighting pass)"
                        ));
                    }
                };
                None
            }
            "exact-edges" => {
                let r = p.split_once('=').map(|(_, v)| v.parse::<u32>().ok());
                exact_edges = match r {
                    None => 1,
                    Some(Some(r)) if r <= MAX_EXACT_EDGES => r,
                    Some(_) => {
                        return Err(format!(
                            "interleaved `{p}`: exact-edges=R with R from 0 to {MAX_EXACT_EDGES} \
                             (`exact-edges` alone: 1)"
                        ));
                    }
                };
                None
            }
            "band" => {
                band = match p.split_once('=').map(|(_, v)| v) {
                    Some("surface") => Some(Band::Surface),
                    Some("object") => Some(Band::Object),
                    Some("albedo") => Some(Band::Albedo),
                    Some("depth") => Some(Band::Depth),
                    _ => {
                        return Err(format!(
                            "interleaved `{p}`: band=surface, band=object, band=albedo or band=depth"
                        ));
                    }
                };
                None
            }
            "side" => {
                band_side = match p.split_once('=').map(|(_, v)| v) {
                    Some("both") => Some(0),
                    Some("near") => Some(1),
                    Some("far") => Some(2),
                    _ => {
                        return Err(format!(
                            "interleaved `{p}`: side=both, side=near or side=far"
                        ));
                    }
                };
                None
            }
            "contrast" => {
                let t = p.split_once('=').and_then(|(_, v)| v.parse::<f32>().ok());
                contrast = Some(t.filter(|t| *t > 0.0 && *t <= 1.0).ok_or_else(|| {
                    format!(
                        "interleaved `{p}`: contrast=T with T a share of the larger of the two \
                         sides' tones or distances, above 0 and at most 1"
                    )
                })?);
                None
            }
            "search" => {
                search = match p.split_once('=').map(|(_, v)| v) {
                    Some("0") => 0,
                    Some("1") => 1,
                    _ => return Err(format!("interleaved `{p}`: search=0 or search=1")),
                };
                None
            }
            "enough" => {
                let k = p.split_once('=').and_then(|(_, v)| v.parse::<u32>().ok());
                enough = Some(k.filter(|&k| (1..=m * n).contains(&k)).ok_or_else(|| {
                    format!(
                        "interleaved:{m}x{n} `{p}`: enough=K with K from 1 to {}",
                        m * n
                    )
                })?);
                None
            }
            "normal" | "plane" => {
                let v = p.split_once('=').and_then(|(_, v)| v.parse::<f32>().ok());
                if key == "normal" {
                    same_normal_cos = v.filter(|c| (-1.0..=1.0).contains(c)).ok_or_else(|| {
                        format!("interleaved `{p}`: normal=C with C a cosine from -1 to 1")
                    })?;
                } else {
                    plane_tolerance = v.filter(|t| *t > 0.0 && t.is_finite()).ok_or_else(|| {
                        format!(
                            "interleaved `{p}`: plane=T with T a positive share of the distance"
                        )
                    })?;
                }
                surface_test = Some(*p);
                None
            }
            "vpls" | "points" | "rsm" | "reach" | "clamp" | "cull" => {
                light_params.push(*p);
                None
            }
            _ => {
                return Err(unknown_param(
                    "interleaved",
                    p,
                    "vpls=N, points=N, rsm=R, reach=D, clamp=D, one filter of none (raw), box, \
                     ours, seed, and search=0|1, enough=K, exact-edges[=R], \
                     band=surface|object|albedo|depth, contrast=T, side=both|near|far, normal=C, \
                     plane=T, \
                     direct, implicit, debug, floor, fallback=pairs|inline, window=tile|fetch, \
                     flat=on|off, parts=base|lights|filter",
                ));
            }
        };
        if let Some(f) = f {
            if filter.is_some_and(|old| old != f) {
                return Err(format!(
                    "interleaved: one filter at a time (`{}` and `{}`)",
                    filter.map_or("", Filter::name),
                    f.name()
                ));
            }
            filter = Some(f);
        }
    }
    // deferred's parameters, read by deferred's reader; its messages name it.
    let mut lights =
        deferred::parse(&light_params).map_err(|e| e.replacen("deferred", "interleaved", 1))?;
    if !light_params.iter().any(|p| p.starts_with("vpls=")) {
        lights.vpls = DEFAULT_VPLS;
    }
    let subsets = m * n;
    if lights.vpls == 0 || lights.vpls % subsets != 0 {
        return Err(format!(
            "interleaved:{m}x{n} vpls={}: a positive multiple of {subsets}, so that each of the \
             {subsets} sub-images shades as many VPLs",
            lights.vpls
        ));
    }
    let filter = filter.unwrap_or(Filter::Ours);
    if let Some(p) = surface_test.filter(|_| filter != Filter::Ours) {
        return Err(format!(
            "interleaved: `{p}` sets the same-surface test of the `ours` filter, not of `{}`",
            filter.name()
        ));
    }
    if fallback.is_some() && filter != Filter::Ours {
        return Err(format!(
            "interleaved: `fallback=...` places the fallback of the `ours` filter, which `{}` \
             does not have",
            filter.name()
        ));
    }
    if fallback == Some(true) && direct {
        return Err(
            "interleaved: `fallback=pairs` lists the VPL subsets only; with `direct` the fallback \
             is inline"
                .into(),
        );
    }
    let pairs = fallback.unwrap_or(filter == Filter::Ours && !direct);
    if window.is_some() && filter != Filter::Ours {
        return Err("interleaved: `window=...` is how the `ours` filter reads its window".into());
    }
    let window_tile = window.unwrap_or(filter == Filter::Ours);
    if flat.is_some() && filter != Filter::Ours {
        return Err(format!(
            "interleaved: `flat=...` is how the `ours` filter takes its flat tiles, which `{}` \
             does not have",
            filter.name()
        ));
    }
    let flat_tiles = flat.unwrap_or(true) && filter == Filter::Ours;
    if exact_edges > 0 && filter != Filter::Ours {
        return Err(format!(
            "interleaved: `exact-edges` is a variant of the `ours` filter, not of `{}`",
            filter.name()
        ));
    }
    if band.is_some() && exact_edges == 0 {
        return Err(
            "interleaved: `band=...` says which pixels `exact-edges=R` shades exactly; give \
             `exact-edges` too"
                .into(),
        );
    }
    if band_side.is_some() && band != Some(Band::Depth) {
        return Err(
            "interleaved: `side=...` says which side of a depth step `band=depth` takes; give \
             `band=depth` too"
                .into(),
        );
    }
    if contrast.is_some() && !matches!(band, Some(Band::Albedo | Band::Depth)) {
        return Err(
            "interleaved: `contrast=T` is the threshold of a contrast band; give \
             `band=albedo` or `band=depth` too"
                .into(),
        );
    }
    if implicit && floor {
        return Err(
            "interleaved: `floor` measures the split and gather passes, which `implicit` does not \
             have"
                .into(),
        );
    }
    Ok(InterleavedConfig {
        m,
        n,
        filter,
        implicit,
        debug,
        search,
        enough: enough.unwrap_or(m * n),
        exact_edges,
        band_objects: matches!(band, Some(Band::Object | Band::Albedo | Band::Depth)),
        band_contrast: match band {
            Some(Band::Albedo | Band::Depth) => contrast.unwrap_or(DEFAULT_BAND_CONTRAST),
            _ => 0.0,
        },
        band_depth: band == Some(Band::Depth),
        band_side: band_side.unwrap_or(0),
        same_normal_cos,
        plane_tolerance,
        floor,
        direct,
        parts,
        pairs,
        window_tile,
        flat_tiles,
        lights,
    })
}

pub struct Interleaved {
    config: InterleavedConfig,
    raster: RasterConfig,
    gbuffer_pass: ScenePass,
    g: GBuffer,
    lights: ManyLights,
    split: SplitPasses,
    lighting: LightingPass,
    readbacks: LayerReadbacks,
    /// `debug`: the lighting pass's debug bits (filter.glsl) and their readback.
    debug: Option<(Image, Readback)>,
    size: (u32, u32),
}

/// The debug bits' format (filter.glsl): one u32 per pixel.
const DEBUG_FORMAT: vk::Format = vk::Format::R32_UINT;

/// `debug`: the per-pixel debug bits and their readback (`readback.interleaved_bits`).
fn debug_resources(w: u32, h: u32) -> [crate::pass::ResourceDecl; 2] {
    use crate::pass::ResourceDecl;
    [
        ResourceDecl::image("debug_bits", DEBUG_FORMAT, w, h),
        ResourceDecl::readback("interleaved_bits", DEBUG_FORMAT, w, h),
    ]
}

impl Interleaved {
    /// What [`Interleaved::new`] allocates (crate::memory): deferred's G-buffer and lights, the
    /// M x N split images (none with `implicit`), the gathered estimates, the seed's blur images,
    /// the copy floor's buffers, the debug bits and mosaic, and the readbacks.
    pub fn estimate(config: &InterleavedConfig, w: u32, h: u32) -> MemoryEstimate {
        let mut e = MemoryEstimate::new();
        deferred::estimate_gbuffer_and_lights(&mut e, "interleaved", &config.lights, w, h);
        SplitPasses::estimate(&mut e, config, w, h);
        super::deferred::lighting::estimate(&mut e, &lighting_variant(config), w, h);
        if config.debug {
            let [bits, rb] = debug_resources(w, h);
            e.append(crate::pass::estimate(&[bits], "interleaved"));
            e.append(crate::pass::estimate(&[rb], "readback"));
        }
        LayerReadbacks::estimate(&mut e, w, h);
        e
    }

    pub fn new(ctx: &BuildCtx, config: InterleavedConfig) -> Result<Interleaved> {
        let lights = ManyLights::new(ctx, &config.lights, "interleaved")?;
        let (raster, gbuffer_pass, g) = deferred::gbuffer(ctx, "interleaved")?;
        let split = SplitPasses::new(ctx, &config)?;
        let debug = if config.debug {
            let [bits, rb] = debug_resources(ctx.width, ctx.height);
            let image = bits.make_image(ctx.gpu, "interleaved")?;
            Some((image, rb.make_readback(ctx.gpu, "readback")?))
        } else {
            None
        };
        let lighting = LightingPass::new(ctx, Some(&lighting_variant(&config)), config.lights.cull)?;
        let readbacks = LayerReadbacks::new(ctx.gpu, g.layers())?;
        Ok(Interleaved {
            config,
            raster,
            gbuffer_pass,
            g,
            lights,
            split,
            lighting,
            readbacks,
            debug,
            size: (ctx.width, ctx.height),
        })
    }

    /// The debug views from this frame's readbacks.
    fn layers(&self) -> Result<Option<InterleavedLayers>> {
        let Some((_, bits)) = &self.debug else {
            return Ok(None);
        };
        let words: &[u32] = bytemuck::cast_slice(bits.bytes()?);
        let mosaic = match &self.split.mosaic {
            Some(rb) => {
                let texels: &[[f32; 4]] = bytemuck::cast_slice(rb.bytes()?);
                let (w, h) = self.split.mosaic_size();
                Some((w, h, texels.iter().map(|t| [t[0], t[1], t[2]]).collect()))
            }
            None => None,
        };
        Ok(Some(InterleavedLayers {
            tile: (self.config.m, self.config.n),
            subset: words.iter().map(|&b| (b & 0x3f) as u8).collect(),
            edge: words.iter().map(|&b| u8::from(b & DBG_EDGE != 0)).collect(),
            fallback: words.iter().map(|&b| ((b >> 8) & 0x7f) as u8).collect(),
            roundtrip_mismatches: words.iter().filter(|&&b| b & DBG_ROUNDTRIP != 0).count() as u64,
            flat_tile_pixels: words.iter().filter(|&&b| b & DBG_FLAT != 0).count() as u64,
            mosaic,
        }))
    }
}

/// The lighting pass's view of `config`'s filter over `split`'s estimates.
/// The lighting pass's variant for `config`.
pub fn lighting_variant(config: &InterleavedConfig) -> InterleavedLighting {
    InterleavedLighting {
        m: config.m,
        n: config.n,
        search: config.search,
        enough: config.enough,
        exact_edges: config.exact_edges,
        band_objects: config.band_objects,
        band_contrast: config.band_contrast,
        band_depth: config.band_depth,
        band_side: config.band_side,
        same_normal_cos: config.same_normal_cos,
        plane_tolerance: config.plane_tolerance,
        filter: config.filter as u32,
        box_rows: config.box_rows(),
        direct: config.direct,
        debug: config.debug,
        parts: config.parts as u32,
        pairs: config.pairs,
        window_tile: config.window_tile,
        flat_tiles: config.flat_tiles,
    }
}

fn interleaving<'a>(
    config: &InterleavedConfig,
    split: &'a SplitPasses,
    debug: Option<&'a (Image, Readback)>,
) -> Interleaving<'a> {
    Interleaving {
        variant: lighting_variant(config),
        irradiance: split.output(),
        specular: split.specular_output(),
        debug: debug.map(|d| &d.0),
    }
}

/// filter.glsl's debug bits: bits 0-5 the subset, 6 edge, 8-14 fallback subsets, 16 round trip,
/// 17 a flat tile's pixel.
const DBG_EDGE: u32 = 1 << 6;
const DBG_ROUNDTRIP: u32 = 1 << 16;
const DBG_FLAT: u32 = 1 << 17;

impl Technique for Interleaved {
    fn render(&mut self, ctx: &mut FrameCtx) -> Result<()> {
        let view = ctx.view.clone();
        ctx.upload(&view)?;
        let sun = self.lights.prepare(ctx)?;
        let push = LightingPush::new(ctx, &self.config.lights, self.size, sun.as_ref());
        let counter = ctx.counter;
        // `direct`'s lights: directional, the scene's point lights, `points=N`'s.
        let (dirs, scene_points) = ctx.gpu_scene.light_count;
        let lights = [dirs, scene_points, self.config.lights.points];
        let this = &*self;
        ctx.submit("frame", |cmd, profiler, gs| {
            let g = &this.g;
            this.gbuffer_pass
                .record(cmd, profiler, gs, &g.bind(), counter, &this.raster)?;
            this.lights.record(cmd, profiler, gs, sun.as_ref())?;
            let sources = this.lights.sources();
            this.split.record(
                cmd,
                profiler,
                gs,
                g,
                &sources,
                this.config.lights.vpls,
                lights,
                push.params[0],
            )?;
            let interleaving = interleaving(&this.config, &this.split, this.debug.as_ref());
            this.lighting.record(
                cmd,
                profiler,
                gs,
                g,
                &sources,
                counter,
                &push,
                Some(&interleaving),
            )?;
            this.readbacks.record(cmd, profiler, g.layers());
            if let Some((image, rb)) = &this.debug {
                cmd.read_image(image, rb);
                this.split.record_readback(cmd);
            }
            this.lights.record_readback(cmd);
            cmd.use_buffer(counter, Access::HostRead);
            Ok(())
        })
    }

    fn color(&self, _frame: u32) -> Option<&Image> {
        Some(&self.g.color)
    }

    fn geometry(&self, _frame: u32) -> Option<Geometry<'_>> {
        Some(self.g.geometry())
    }

    fn output(&self, ctx: &FrameCtx) -> Result<FrameOutput> {
        let mut out = deferred::output(&self.readbacks, &self.lights, ctx)?;
        if let Some(views) = self.layers()? {
            views.write(&mut out)?;
        }
        Ok(out)
    }

    fn target_bytes(&self) -> u64 {
        let (w, h) = self.size;
        GBuffer::bytes(w, h) + self.lights.bytes() + self.split.bytes() + self.lighting.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::deferred::vpl::vpl_texels;

    /// Cells of an 8 x 8 grid over the map that the VPLs of `indices` fall in.
    fn cells(texels: &[[u32; 2]], indices: impl Iterator<Item = usize>, side: u32) -> usize {
        let mut hit = [false; 64];
        for i in indices {
            let [u, v] = texels[i];
            hit[(v * 8 / side * 8 + u * 8 / side) as usize] = true;
        }
        hit.iter().filter(|&&h| h).count()
    }

    /// Each subset spreads over the whole map: every one of the 16 subsets of 1024 VPLs (64 each)
    /// falls in at least 40 of the 64 cells of an 8 x 8 grid, for several seeds. The stride the
    /// first version used (every 16th VPL from the k-th) puts a subset in one 1/16 column of the
    /// map: at most 16 cells (two columns of 8, where the seed's shift straddles a boundary).
    #[test]
    fn subsets_cover_the_whole_map() {
        let side = 512;
        for seed in [0u64, 1, 7, 12345] {
            let texels = vpl_texels(seed, 1024, side);
            for k in 0..16u32 {
                let block = cells(&texels, subset_range(k, 1024, 16), side);
                assert!(block >= 40, "seed {seed}, subset {k}: {block} of 64 cells");
                let stride = cells(&texels, (k as usize..1024).step_by(16), side);
                assert!(stride <= 16, "seed {seed}, stride {k}: {stride} cells");
            }
        }
    }

    #[test]
    fn subset_ranges_partition_the_vpls() {
        let mut all: Vec<usize> = (0..12).flat_map(|k| subset_range(k, 96, 12)).collect();
        all.dedup();
        assert_eq!(all, (0..96).collect::<Vec<_>>());
    }
}
