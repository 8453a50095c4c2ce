//! `deferred`'s lighting pass (shaders/deferred/lighting.comp): the G-buffer's surfaces through
//! the forward pass's `shade`, the extra point lights and the VPLs, into the RGBA16F frame. For
//! `interleaved` the same pass takes the VPLs' light from the gathered sub-image estimates through
//! its filter (the INTERLEAVED define, shaders/interleaved/filter.glsl).

use cbr_gpu::{Buffer, Cmd, Image, Profiler, Result};

use super::config::DeferredConfig;
use super::gbuffer::GBuffer;
use super::vpl::SunView;
use crate::gpu_scene::{GpuScene, LIGHT_BINDINGS};
use crate::gpu_types::SplitBuffer;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Use};
use crate::technique::{BuildCtx, FrameCtx};

crate::push_constants! {
    /// Push constants (lighting.comp's).
    pub struct LightingPush {
        /// rgb: the background radiance.
        background: [f32; 4],
        /// Extra point lights, VPLs, width, height.
        counts: [u32; 4],
        /// x: the VPL clamp c of 1/max(d^2, c), in m^2.
        params: [f32; 4],
    }
}

/// The sun's map this frame.
pub struct SunFrame {
    /// `None`: nothing of the scene within reach; the map stays empty.
    pub view: Option<SunView>,
    /// The VPL clamp c of 1/max(d^2, c), in m^2.
    pub clamp_d2: f32,
}

/// The defines of `deferred`'s lighting pass (gpu_types' layout test compiles with them).
pub fn shader_defines() -> Vec<(String, String)> {
    decl(None).all_defines()
}

impl LightingPush {
    /// This frame's constants for `config`'s lights at `size`.
    pub fn new(
        ctx: &FrameCtx,
        config: &DeferredConfig,
        size: (u32, u32),
        sun: Option<&SunFrame>,
    ) -> LightingPush {
        let bg = ctx.gpu_scene.background;
        LightingPush {
            background: [bg[0], bg[1], bg[2], 0.0],
            counts: [config.points, config.vpls, size.0, size.1],
            params: [sun.map_or(1.0, |s| s.clamp_d2), 0.0, 0.0, 0.0],
        }
    }
}

/// `interleaved`'s variant of the pass: the filter that combines the M x N sub-images'
/// estimates (shaders/interleaved/filter.glsl) and what it reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterleavedLighting {
    pub m: u32,
    pub n: u32,
    /// The SEARCH define (`ours` only): 1 looks one period beyond the window.
    pub search: u32,
    /// The EXACT_EDGES define (`ours` only): R > 0 makes a pixel with a pixel off its surface
    /// within R (a square) shade every subset itself; 0 off.
    pub exact_edges: u32,
    /// The BAND_OBJECTS define (`band=object`, with `exact-edges=R`): the band is the pixels with
    /// a pixel of another object (or none) within R, not those with a pixel off their surface.
    pub band_objects: bool,
    /// The BAND_CONTRAST define (`band=albedo|depth:contrast=T`, with `band_objects`): T > 0 keeps
    /// only the object band's pixels with another object (or the background) of another tone
    /// within R; 0 off.
    pub band_contrast: f32,
    /// The BAND_DEPTH define (`band=depth`, with `band_contrast`): the two sides' distances
    /// from the camera, not their tones; the background always differs.
    pub band_depth: bool,
    /// The BAND_SIDE define (`side=...`, with `band_depth`): 0 both sides, 1 the nearer, 2 the
    /// farther.
    pub band_side: u32,
    /// The ENOUGH define (`ours` only): found subsets that spare the fallback.
    pub enough: u32,
    /// The SAME_NORMAL_COS and PLANE_TOLERANCE defines (`ours` only): its same-surface test.
    pub same_normal_cos: f32,
    pub plane_tolerance: f32,
    /// The FILTER define: 0 none (each pixel its own subset), 1 box over the M x N window,
    /// 2 ours (geometry-aware), 3 seed (the image is already the seed's blur).
    pub filter: u32,
    /// The BOX_ROWS define (`box` with the split passes): `irradiance` (and `specular`) hold
    /// each pixel's window row summed by the gather, not its own estimate.
    pub box_rows: bool,
    /// `direct`: the point lights' specular estimates are filtered too (the DIRECT define).
    pub direct: bool,
    /// `debug`: the pass writes its debug bits (the DEBUG define).
    pub debug: bool,
    /// The PARTS define (`parts=...`, interleaved::Parts): 0 the whole pass, 1 base, 2 + the
    /// per-pixel point lights, 3 + the filter without the fallback.
    pub parts: u32,
    /// `fallback=pairs` (FALLBACK_PAIRS; `ours` without `direct`): the lighting pass lists the
    /// fallback's (pixel, subset) pairs and `interleaved.fallback` and `interleaved.finish` shade
    /// them and finish those pixels (shaders/interleaved/fallback_list.glsl).
    pub pairs: bool,
    /// `window=tile` (WINDOW_TILE; `ours`, the default): the filter reads the
    /// window's G-buffer texels and estimates from a tile fetched into shared memory once per
    /// workgroup (shaders/interleaved/filter.glsl); `window=fetch` fetches each per window.
    pub window_tile: bool,
    /// `flat=on` (FLAT_TILES; `ours`, the default): a tile on one plane-like surface
    /// takes the box mean of each window without the same-surface tests (filter.glsl).
    pub flat_tiles: bool,
}

/// The fallback passes' work groups (fallback_list.glsl's FALLBACK_GROUP).
const FALLBACK_GROUP: u32 = 64;
/// Bytes of a fallback entry (fallback_list.glsl's FallbackEntry), a pair and a pair's result.
const ENTRY_BYTES: u64 = 48;
const PAIR_BYTES: u64 = 4;
const RESULT_BYTES: u64 = 12;
/// The fallback's counters and indirect dispatches (fallback_list.glsl's FallbackArgs), u32s:
/// entries, pairs, two unused, the fallback's groups (x, y, z), the
/// finish's groups, the entry and pair capacities.
const ARGS_WORDS: usize = 12;
/// Byte offsets of the two indirect dispatches in the counters.
const PAIR_DISPATCH: u64 = 16;
const ENTRY_DISPATCH: u64 = 28;
/// The largest side `fallback=pairs` takes: a pair holds x and y in 13 bits each.
pub const MAX_PAIRS_SIDE: u32 = 8191;

/// The fallback lists' capacities at W x H: entries for three quarters of the pixels, pairs for
/// four a pixel (at 320x180 the demo lists 0.34 entries and 2.3 pairs a visible pixel, foliage 0.44
/// and 3.0, Šibenik 0.51 and 3.2; fewer at 1280x720). 16 bytes a pair, 48 an entry: 92 MB at
/// 1280x720. Pixels beyond them take the inline loop (the same frame).
pub fn fallback_caps(width: u32, height: u32) -> (u32, u32) {
    let px = width * height;
    ((3 * px).div_ceil(4).max(FALLBACK_GROUP), (4 * px).max(FALLBACK_GROUP))
}

/// The fallback lists' buffers at W x H.
fn fallback_resources(width: u32, height: u32) -> [ResourceDecl; 4] {
    let (entries, pairs) = fallback_caps(width, height);
    [
        ResourceDecl::buffer("fallback_args", ARGS_WORDS as u64 * 4).indirect(),
        ResourceDecl::buffer("fallback_entries", u64::from(entries) * ENTRY_BYTES),
        ResourceDecl::buffer("fallback_pairs", u64::from(pairs) * PAIR_BYTES),
        ResourceDecl::buffer("fallback_results", u64::from(pairs) * RESULT_BYTES),
    ]
}

/// What [`LightingPass::new`] allocates for `interleaving` at W x H (the fallback lists).
pub fn estimate(e: &mut MemoryEstimate, interleaving: &InterleavedLighting, w: u32, h: u32) {
    if interleaving.pairs {
        e.append(crate::pass::estimate(
            &fallback_resources(w, h),
            "interleaved",
        ));
    }
}

/// `fallback=pairs`: `interleaved.fallback` (one invocation per pair) or, `finish`,
/// `interleaved.finish` (one per listed pixel).
pub fn fallback_decl(i: &InterleavedLighting, finish: bool) -> ComputeDecl {
    let name = match finish {
        false => "interleaved.fallback",
        true => "interleaved.finish",
    };
    let mut d = ComputeDecl::new(name, "interleaved/fallback.comp")
        .define("TILE_M", i.m)
        .define("TILE_N", i.n)
        .bindings(&LIGHT_BINDINGS)
        .bindings(&VPL_BINDINGS)
        .bindings(&[Binding::buffer("fallback_args", Use::Read)])
        .push::<LightingPush>()
        .group(FALLBACK_GROUP, 1);
    d = match finish {
        false => d.bindings(&[
            Binding::sampled("position"),
            Binding::sampled("normal"),
            Binding::buffer("fallback_pairs", Use::Read),
            Binding::buffer("fallback_results", Use::Write),
        ]),
        true => d.define("FINISH", 1).bindings(&[
            Binding::uniform("frame"),
            Binding::buffer("counter", Use::ReadWrite),
            Binding::sampled("albedo"),
            Binding::image("out_color", Use::Write),
            Binding::buffer("fallback_entries", Use::Read),
            Binding::buffer("fallback_results", Use::Read),
        ]),
    };
    d
}

/// `interleaved`'s VPL light: the M x N sub-images' estimates gathered back to full resolution.
pub struct Interleaving<'a> {
    pub variant: InterleavedLighting,
    pub irradiance: &'a Image,
    /// `direct`: the point lights' specular estimates (the DIRECT define).
    pub specular: Option<&'a Image>,
    /// `debug`: the R32UI image the pass writes its debug bits to.
    pub debug: Option<&'a Image>,
}

/// What the lighting pass reads besides the G-buffer and the scene.
pub struct LightSources<'a> {
    /// Extra point lights (`points=N`), camera-relative, host-written each frame.
    pub points: &'a Buffer,
    /// The VPLs (`vpls=N`), written by the VPL pass this frame.
    pub vpls: &'a Buffer,
}

impl<'a> LightSources<'a> {
    /// Binds `points` and `more_points`, `vpls` and `more_vpls`.
    pub fn bind(&self, binds: Binds<'a>) -> Binds<'a> {
        let binds = SplitBuffer::LIGHTS.bind(binds, self.points, "points", "more_points");
        SplitBuffer::VPLS.bind(binds, self.vpls, "vpls", "more_vpls")
    }
}

/// The bindings of the extra point lights and of the VPLs ([`LightSources::bind`]).
pub const POINT_BINDINGS: [Binding; 2] = [
    Binding::uniform("points"),
    Binding::buffer("more_points", Use::Read),
];
pub const VPL_BINDINGS: [Binding; 2] = [
    Binding::uniform("vpls"),
    Binding::buffer("more_vpls", Use::Read),
];

/// The lighting pass (shaders/deferred/lighting.comp): `deferred`'s, or with `interleaving`
/// `interleaved`'s variant (the VPLs' light from the sub-image estimates).
pub fn decl(interleaving: Option<&InterleavedLighting>) -> ComputeDecl {
    decl_culled(interleaving, true)
}

/// [`decl`]; `cull` false (`cull=0`) shades every point light at every pixel (CULL_LIGHTS 0).
pub fn decl_culled(interleaving: Option<&InterleavedLighting>, cull: bool) -> ComputeDecl {
    let name = match interleaving {
        None => "deferred.lighting",
        Some(_) => "interleaved.lighting",
    };
    let mut d = ComputeDecl::new(name, "deferred/lighting.comp")
        .bindings(&[
            Binding::uniform("frame"),
            Binding::buffer("objects", Use::Read),
            Binding::buffer("materials", Use::Read),
            LIGHT_BINDINGS[0],
            LIGHT_BINDINGS[1],
            POINT_BINDINGS[0],
            POINT_BINDINGS[1],
            VPL_BINDINGS[0],
            VPL_BINDINGS[1],
            Binding::buffer("counter", Use::ReadWrite),
            Binding::sampled("position"),
            Binding::sampled("normal"),
            Binding::sampled("albedo"),
            Binding::sampled("ids"),
            Binding::image("out_color", Use::Write),
        ])
        .push::<LightingPush>();
    if !cull {
        d = d.define("CULL_LIGHTS", 0);
    }
    if let Some(i) = interleaving {
        d = d
            .define("INTERLEAVED", 1)
            .define("TILE_M", i.m)
            .define("TILE_N", i.n)
            .define("FILTER", i.filter)
            .define("SEARCH", i.search)
            .define("EXACT_EDGES", i.exact_edges)
            .define("ENOUGH", i.enough)
            // `{:?}` keeps the decimal point (0.9, 1.0, 1e-5): a GLSL float literal.
            .define("SAME_NORMAL_COS", format!("{:?}", i.same_normal_cos))
            .define("PLANE_TOLERANCE", format!("{:?}", i.plane_tolerance))
            .define("PARTS", i.parts)
            // The gathered sub-image estimates of the VPLs' irradiance, and (`direct`) of the
            // point lights' specular: without `direct` the binding holds the irradiance, never
            // read.
            .bind(Binding::sampled("irradiance"))
            .bind(Binding::sampled("specular"));
        if i.debug {
            d = d
                .define("DEBUG", 1)
                .bind(Binding::image("debug_bits", Use::Write));
        }
        if i.box_rows {
            d = d.define("BOX_ROWS", 1);
        }
        if i.direct {
            d = d.define("DIRECT", 1);
        }
        if i.window_tile {
            d = d.define("WINDOW_TILE", 1);
        }
        if i.flat_tiles {
            d = d.define("FLAT_TILES", 1);
        }
        if i.band_objects {
            d = d.define("BAND_OBJECTS", 1);
        }
        if i.band_contrast > 0.0 {
            d = d.define("BAND_CONTRAST", format!("{:?}", i.band_contrast));
        }
        if i.band_depth {
            d = d.define("BAND_DEPTH", 1).define("BAND_SIDE", i.band_side);
        }
        if i.pairs {
            d = d.define("FALLBACK_PAIRS", 1).bindings(&[
                Binding::buffer("fallback_args", Use::ReadWrite),
                Binding::buffer("fallback_entries", Use::Write),
                Binding::buffer("fallback_pairs", Use::Write),
            ]);
        }
    }
    d
}

/// `fallback=pairs`: the fallback and finish passes and the lists they share with the lighting
/// pass.
struct FallbackPasses {
    fallback: ComputePass,
    finish: ComputePass,
    args: Buffer,
    entries: Buffer,
    pairs: Buffer,
    results: Buffer,
    caps: (u32, u32),
}

pub struct LightingPass {
    pass: ComputePass,
    fallback: Option<FallbackPasses>,
}

impl LightingPass {
    /// The pass; with `interleaving`, the VPLs' light comes from the sub-image estimates
    /// instead of every VPL at every pixel.
    /// `cull`: [`DeferredConfig::cull`].
    pub fn new(
        ctx: &BuildCtx,
        interleaving: Option<&InterleavedLighting>,
        cull: bool,
    ) -> Result<LightingPass> {
        let fallback = match interleaving.filter(|i| i.pairs) {
            Some(i) => {
                let (w, h) = (ctx.width, ctx.height);
                if w > MAX_PAIRS_SIDE || h > MAX_PAIRS_SIDE {
                    return Err(cbr_gpu::GpuError::Other(format!(
                        "interleaved fallback=pairs: at most {MAX_PAIRS_SIDE} pixels a side \
                         (fallback=inline has no limit)"
                    )));
                }
                let [args, entries, pairs, results] =
                    fallback_resources(w, h).map(|d| d.make_buffer(ctx.gpu, "interleaved"));
                Some(FallbackPasses {
                    fallback: fallback_decl(i, false).build(ctx.gpu, ctx.shaders)?,
                    finish: fallback_decl(i, true).build(ctx.gpu, ctx.shaders)?,
                    args: args?,
                    entries: entries?,
                    pairs: pairs?,
                    results: results?,
                    caps: fallback_caps(w, h),
                })
            }
            None => None,
        };
        Ok(LightingPass {
            pass: decl_culled(interleaving, cull).build(ctx.gpu, ctx.shaders)?,
            fallback,
        })
    }

    /// Bytes of the fallback lists (`fallback=pairs`).
    pub fn bytes(&self) -> u64 {
        self.fallback.as_ref().map_or(0, |f| {
            f.args.size() + f.entries.size() + f.pairs.size() + f.results.size()
        })
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        scene: &GpuScene,
        g: &GBuffer,
        sources: &LightSources,
        counter: &Buffer,
        push: &LightingPush,
        interleaving: Option<&Interleaving>,
    ) -> Result<()> {
        let binds = Binds::new()
            .buffer("frame", &scene.frame)
            .buffer("objects", &scene.objects)
            .buffer("materials", &scene.materials);
        let mut binds = sources
            .bind(scene.bind_lights(binds))
            .buffer("counter", counter)
            .image("position", &g.position)
            .image("normal", &g.normal)
            .image("albedo", &g.albedo)
            .image("ids", &g.ids)
            .image("out_color", &g.color);
        if let Some(i) = interleaving {
            binds = binds
                .image("irradiance", i.irradiance)
                .image("specular", i.specular.unwrap_or(i.irradiance));
            if let Some(d) = i.debug {
                binds = binds.image("debug_bits", d);
            }
        }
        if let Some(f) = &self.fallback {
            // No entries or pairs yet, no groups: the counters of fallback_list.glsl.
            let (entry_cap, pair_cap) = f.caps;
            let words: [u32; ARGS_WORDS] = [0, 0, 0, 0, 0, 1, 1, 0, 1, 1, entry_cap, pair_cap];
            cmd.update_buffer(&f.args, &words);
            binds = binds
                .buffer("fallback_args", &f.args)
                .buffer("fallback_entries", &f.entries)
                .buffer("fallback_pairs", &f.pairs)
                .buffer("fallback_results", &f.results);
        }
        let [_, _, w, h] = push.counts;
        self.pass
            .dispatch_2d(cmd, profiler, &binds.only(&self.pass), push, (w, h))?;
        if let Some(f) = &self.fallback {
            let args = |offset| (&f.args, offset);
            f.fallback.dispatch_indirect(
                cmd,
                profiler,
                &binds.only(&f.fallback),
                push,
                args(PAIR_DISPATCH),
            )?;
            f.finish.dispatch_indirect(
                cmd,
                profiler,
                &binds.only(&f.finish),
                push,
                args(ENTRY_DISPATCH),
            )?;
        }
        Ok(())
    }
}
