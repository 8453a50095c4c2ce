//! The checkerboard resolve (shaders/resolve/resolve.comp, docs/resolve.md): reconstructs the full
//! frame from this frame's checkerboard samples (read through the layout fetch include, so every
//! layout works) and the previous resolved frame, with history ping-pong of colour, depth and IDs.
//! `reference` is the CPU implementation the shader is tested against.

pub mod layers;
pub mod reference;

use cbr_gpu::{
    Access, Buffer, Cmd, Gpu, GpuError, Image, LevelCopy, Location, Profiler, Readback, Result,
    Shaders, vk,
};

pub use layers::{DEBUG_LAYERS, ResolveOutput};

use crate::layouts::LayoutPlan;
use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, Filter, ResourceDecl, Resources, Use};
use crate::scene_pass::layout_id;
use crate::targets::FrameTargets;

/// `--resolve`: how missing pixels are reconstructed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ResolveMode {
    /// ID-, depth- and velocity-validated history with a YCoCg clamp, else an ID-aware
    /// differential spatial blend.
    Ours,
    /// The Stadia write-up's resolve.
    Pq4k,
    /// Camera-only depth reprojection with a depth occlusion test, else a Reinhard-weighted
    /// average of the four neighbours.
    Intel,
    /// No history: `ours`' spatial blend everywhere.
    Spatial,
    /// History at p - v, no validation, no clamp.
    Temporal,
}

impl ResolveMode {
    pub const ALL: [ResolveMode; 5] = [
        ResolveMode::Ours,
        ResolveMode::Pq4k,
        ResolveMode::Intel,
        ResolveMode::Spatial,
        ResolveMode::Temporal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ResolveMode::Ours => "ours",
            ResolveMode::Pq4k => "pq4k",
            ResolveMode::Intel => "intel",
            ResolveMode::Spatial => "spatial",
            ResolveMode::Temporal => "temporal",
        }
    }

    fn id(self) -> u32 {
        self as u32
    }
}

/// `--resolve-mapping`: what one compute invocation writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mapping {
    /// One output pixel.
    Pixel,
    /// One 2x2 quad: its 2 rendered and 2 missing pixels.
    Quad,
}

/// Inputs of `ours` that can be switched off for ablation (all on by default).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Ablation {
    pub velocity: bool,
    pub depth: bool,
    pub ids: bool,
    pub clamp: bool,
    /// Use the native-resolution depth + ID prepass when the renderer has one.
    pub prepass: bool,
}

impl Default for Ablation {
    fn default() -> Self {
        Ablation {
            velocity: true,
            depth: true,
            ids: true,
            clamp: true,
            prepass: true,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ResolveSettings {
    pub mode: ResolveMode,
    pub mapping: Mapping,
    /// Workgroup side: 8 or 16.
    pub group: u32,
    /// Colour arithmetic in float16.
    pub fp16: bool,
    /// History colour stored as RGBA32F instead of RGBA16F.
    pub f32_history: bool,
    /// Write the debug bits and the velocity used (extra EXR layers and PNGs).
    pub debug: bool,
    /// Write the velocity each pixel used (a temporal post pass reads it: `+taa`).
    pub velocity: bool,
    /// Checkerboard and TAA in one history (`ours` only): rendered pixels blend their sample
    /// into their validated, variance-clipped history with weight [`FUSED_ALPHA`]; the frame is
    /// jittered by Halton(2, 3) advancing every second frame (docs/post-aa.md).
    pub fused: bool,
    /// Relative linear-depth tolerance of the history validation (`ours`, `intel`).
    pub depth_tolerance: f32,
    /// Below this motion (pixels) `ours` takes validated history unclamped.
    pub static_threshold: f32,
    /// `pq4k`: above this motion (pixels) history is clamped and blended with the average.
    pub motion_threshold: f32,
    pub ablation: Ablation,
    /// Also run a copy kernel that moves the resolve's minimum bytes (its bandwidth floor).
    pub bandwidth_floor: bool,
}

impl Default for ResolveSettings {
    fn default() -> Self {
        ResolveSettings {
            mode: ResolveMode::Ours,
            mapping: Mapping::Quad,
            group: 8,
            fp16: false,
            f32_history: false,
            debug: false,
            velocity: false,
            fused: false,
            depth_tolerance: 0.05,
            static_threshold: 1.0 / 64.0,
            motion_threshold: 0.25,
            ablation: Ablation::default(),
            bandwidth_floor: false,
        }
    }
}

/// `fused`: the weight of a rendered pixel's fresh sample against its history (each pixel is
/// rendered every second frame: twice `+taa`'s 0.1 per frame).
pub const FUSED_ALPHA: f32 = 0.2;
/// `fused`: the sample's weight rises linearly with the pixel's speed to FUSED_ALPHA_MAX at
/// FUSED_SPEED pixels per frame (`+taa`'s speed term and values).
pub const FUSED_ALPHA_MAX: f32 = 0.5;
pub const FUSED_SPEED: f32 = 2.0;
/// `ours`: the history's share in the moving blend with the spatial estimate (resolve.comp's
/// `history_share`; docs/resolve.md says how these were chosen): HISTORY_WEIGHT, raised towards
/// HISTORY_WEIGHT_DETAIL as the smaller of the two opposite pairs' tonemapped luminance
/// differences reaches DETAIL_CONTRAST, lowered to 0 as the larger exceeds the smaller by
/// EDGE_CONTRAST.
pub const HISTORY_WEIGHT: f32 = 0.65;
pub const HISTORY_WEIGHT_DETAIL: f32 = 0.9;
pub const DETAIL_CONTRAST: f32 = 0.1;
pub const EDGE_CONTRAST: f32 = 0.2;

/// `fused`: the frame's jitter (pixels): Halton(2, 3) of length 8 advancing every second frame, so
/// each parity's pixels see the whole sequence.
pub fn fused_jitter(frame: u32) -> [f32; 2] {
    crate::post::taa::jitter(8, frame / 2)
}

/// Push-constant flags (F_* in resolve.comp).
pub const F_RESET: u32 = 1;
pub const F_NO_VELOCITY: u32 = 2;
pub const F_NO_DEPTH: u32 = 4;
pub const F_NO_IDS: u32 = 8;
pub const F_NO_CLAMP: u32 = 16;
pub const F_PREPASS: u32 = 32;

/// Debug bits (DBG_* in resolve.comp).
pub const DBG_RENDERED: u32 = 1;
pub const DBG_MISSING: u32 = 2;
pub const DBG_REPROJECTED: u32 = 4;
pub const DBG_REJECT_ID: u32 = 8;
pub const DBG_REJECT_DEPTH: u32 = 16;
pub const DBG_CLAMPED: u32 = 32;
pub const DBG_SPATIAL: u32 = 64;
pub const DBG_STILL: u32 = 128;

/// History IDs carry `ID_MOVED` where the pixel moved more than the static threshold.
pub const ID_MOVED: u32 = 0x8000_0000;
pub const ID_MASK: u32 = 0x7fff_ffff;

/// The debug views: (name, bit).
pub const DEBUG_VIEWS: [(&str, u32); 8] = [
    ("parity", DBG_RENDERED),
    ("missing", DBG_MISSING),
    ("reprojected", DBG_REPROJECTED),
    ("rejected_id", DBG_REJECT_ID),
    ("rejected_depth", DBG_REJECT_DEPTH),
    ("clamped", DBG_CLAMPED),
    ("spatial", DBG_SPATIAL),
    ("still", DBG_STILL),
];

impl ResolveSettings {
    pub fn flags(&self, reset: bool, prepass: bool) -> u32 {
        let a = &self.ablation;
        let mut f = 0;
        if reset {
            f |= F_RESET;
        }
        if !a.velocity {
            f |= F_NO_VELOCITY;
        }
        if !a.depth {
            f |= F_NO_DEPTH;
        }
        if !a.ids {
            f |= F_NO_IDS;
        }
        if !a.clamp {
            f |= F_NO_CLAMP;
        }
        if prepass && a.prepass {
            f |= F_PREPASS;
        }
        f
    }

    /// resolve.comp's `params`: depth tolerance, static threshold, pq4k motion threshold, and
    /// the depth test's factor min(1 - tolerance, 1) (resolve.comp `depth_agrees`; the CPU
    /// reference computes it the same way, in f32).
    pub fn params(&self) -> [f32; 4] {
        [
            self.depth_tolerance,
            self.static_threshold,
            self.motion_threshold,
            (1.0 - self.depth_tolerance).min(1.0),
        ]
    }

    pub fn validate(&self) -> std::result::Result<(), String> {
        if self.fused && self.mode != ResolveMode::Ours {
            return Err(format!(
                "`fused` is a variant of the `ours` resolve, not of `{}`",
                self.mode.name()
            ));
        }
        if self.group != 8 && self.group != 16 {
            return Err(format!("resolve group {} (8 or 16)", self.group));
        }
        if !(self.depth_tolerance >= 0.0 && self.depth_tolerance.is_finite()) {
            return Err(format!("depth tolerance {}", self.depth_tolerance));
        }
        Ok(())
    }
}

crate::push_constants! {
    /// The push constants of resolve.comp (128 bytes).
    pub struct ResolvePush {
        /// W, H, parity, tangram side.
        size_parity_side: [i32; 4],
        /// x: the F_* flags.
        flags: [u32; 4],
        /// x: depth tolerance, y: static threshold (px), z: pq4k motion threshold (px), w: the
        /// depth test's factor ([`ResolveSettings::params`]).
        params: [f32; 4],
        /// 1 / W, 1 / H, 0, 0: the history geometry's gathers take normalised coordinates.
        inv_size: [f32; 4],
        /// Column-major: previous clip from current (NDC x, NDC y, depth, 1).
        reproj: [[f32; 4]; 4],
    }
}

/// What one frame's resolve needs besides the samples.
#[derive(Clone, Copy, Debug)]
pub struct ResolveFrame {
    /// Which history slot to write (frame index mod 2); the other is read.
    pub slot: usize,
    pub parity: u32,
    /// No usable history.
    pub reset: bool,
    pub reproj: [f32; 16],
}

/// History geometry, one texel per pixel: object ID (with `ID_MOVED`) and the reverse-Z depth
/// bits it shows (one fetch per validation).
pub const HISTORY_GEOM_FORMAT: vk::Format = vk::Format::R32G32_UINT;

/// The resolve (shaders/resolve/resolve.comp) for `settings`, a layout plan's layout and
/// sample locations, with or without the prepass.
pub fn decl(settings: &ResolveSettings, plan: &LayoutPlan, prepass: bool) -> ComputeDecl {
    let out_format = if settings.f32_history {
        "rgba32f"
    } else {
        "rgba16f"
    };
    ComputeDecl::new("resolve", "resolve/resolve.comp")
        .define("LAYOUT", layout_id(plan.layout))
        .define("MSAA_LOCATIONS", u32::from(plan.sample_locations.is_some()))
        .define("MODE", settings.mode.id())
        .define("MAPPING", u32::from(settings.mapping == Mapping::Quad))
        .define("FP16", u32::from(settings.fp16))
        .define("OUT_FORMAT", out_format)
        .define("DEBUG", u32::from(settings.debug))
        .define("FUSED", u32::from(settings.fused))
        // Every flag but F_RESET, compiled in (resolve.comp `has`).
        .define("STATIC_FLAGS", settings.flags(false, prepass))
        .define("FUSED_ALPHA", format!("{FUSED_ALPHA:?}"))
        .define("FUSED_ALPHA_MAX", format!("{FUSED_ALPHA_MAX:?}"))
        .define("FUSED_SPEED", format!("{FUSED_SPEED:?}"))
        .define("HISTORY_WEIGHT", format!("{HISTORY_WEIGHT:?}"))
        .define(
            "HISTORY_WEIGHT_DETAIL",
            format!("{HISTORY_WEIGHT_DETAIL:?}"),
        )
        .define("DETAIL_CONTRAST", format!("{DETAIL_CONTRAST:?}"))
        .define("EDGE_CONTRAST", format!("{EDGE_CONTRAST:?}"))
        .define(
            "OUT_VELOCITY",
            u32::from(settings.debug || settings.velocity),
        )
        // Plain integers: the preprocessor compares them (`#if MODE == MODE_OURS`).
        .define("MODE_OURS", ResolveMode::Ours.id())
        .define("MODE_PQ4K", ResolveMode::Pq4k.id())
        .define("MODE_INTEL", ResolveMode::Intel.id())
        .define("MODE_SPATIAL", ResolveMode::Spatial.id())
        .define("MODE_TEMPORAL", ResolveMode::Temporal.id())
        .constants(&[
            ("F_RESET", F_RESET),
            ("F_NO_VELOCITY", F_NO_VELOCITY),
            ("F_NO_DEPTH", F_NO_DEPTH),
            ("F_NO_IDS", F_NO_IDS),
            ("F_NO_CLAMP", F_NO_CLAMP),
            ("F_PREPASS", F_PREPASS),
            ("DBG_RENDERED", DBG_RENDERED),
            ("DBG_MISSING", DBG_MISSING),
            ("DBG_REPROJECTED", DBG_REPROJECTED),
            ("DBG_REJECT_ID", DBG_REJECT_ID),
            ("DBG_REJECT_DEPTH", DBG_REJECT_DEPTH),
            ("DBG_CLAMPED", DBG_CLAMPED),
            ("DBG_SPATIAL", DBG_SPATIAL),
            ("DBG_STILL", DBG_STILL),
            ("ID_MOVED", ID_MOVED),
            ("ID_MASK", ID_MASK),
        ])
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("velocity"),
            Binding::sampled("ids"),
            Binding::sampled("depth"),
            // `ours`' Catmull-Rom takes 5 bilinear taps in texel units (resolve.comp,
            // history_resampled); texelFetch ignores the sampler.
            Binding::sampled_with("hist_color", Filter::LinearTexels),
            Binding::sampled("hist_geom"),
            Binding::sampled("pre_depth"),
            Binding::sampled("pre_ids"),
            Binding::image("out_color", Use::Write),
            Binding::image("out_geom", Use::Write),
            Binding::image("debug_bits", Use::Write),
            Binding::image("debug_velocity", Use::Write),
        ])
        .push::<ResolvePush>()
        .group(settings.group, settings.group)
}

/// Two history slots (colour, geometry) and the debug bits and velocity, filled by copies too
/// (tests seed the history).
/// The readbacks of the resolved colour (the history's format), the history geometry and the
/// debug bits and velocity.
fn readbacks(settings: &ResolveSettings, w: u32, h: u32) -> [ResourceDecl; 4] {
    let color = if settings.f32_history {
        vk::Format::R32G32B32A32_SFLOAT
    } else {
        vk::Format::R16G16B16A16_SFLOAT
    };
    [
        ResourceDecl::readback("resolved", color, w, h),
        ResourceDecl::readback("resolved_geom", HISTORY_GEOM_FORMAT, w, h),
        ResourceDecl::readback("resolve_debug", vk::Format::R32_UINT, w, h),
        ResourceDecl::readback("resolve_velocity", vk::Format::R32G32_SFLOAT, w, h),
    ]
}

fn resources(settings: &ResolveSettings, w: u32, h: u32) -> Vec<ResourceDecl> {
    let color = if settings.f32_history {
        vk::Format::R32G32B32A32_SFLOAT
    } else {
        vk::Format::R16G16B16A16_SFLOAT
    };
    let dst = vk::ImageUsageFlags::TRANSFER_DST;
    vec![
        ResourceDecl::image("history_color", color, w, h)
            .usage(dst)
            .history(),
        ResourceDecl::image("history_geom", HISTORY_GEOM_FORMAT, w, h)
            .usage(dst)
            .history(),
        ResourceDecl::image("debug_bits", vk::Format::R32_UINT, w, h).usage(dst),
        ResourceDecl::image("debug_velocity", vk::Format::R32G32_SFLOAT, w, h).usage(dst),
    ]
}

pub struct ResolvePass {
    pass: ComputePass,
    res: Resources,
    floor: Option<CopyFloor>,
    settings: ResolveSettings,
    width: u32,
    height: u32,
    tangram: u32,
    has_prepass: bool,
}

impl ResolvePass {
    /// What [`ResolvePass::new`] and [`ResolvePass::readbacks`] allocate at `width` x `height`:
    /// the declared resources, the copy floor's buffers (`bandwidth_floor`), and the readbacks.
    pub fn estimate(e: &mut MemoryEstimate, settings: &ResolveSettings, width: u32, height: u32) {
        let (w, h) = (width, height);
        e.append(crate::pass::estimate(&resources(settings, w, h), "resolve"));
        if settings.bandwidth_floor {
            CopyFloor::estimate(
                e,
                "copy_floor",
                CopyFloor::bytes(w, h, settings.f32_history),
            );
        }
        e.append(crate::pass::estimate(
            &readbacks(settings, w, h),
            "readback",
        ));
    }

    /// `prepass`: whether the native-resolution ID and depth images are bound when it records.
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        settings: &ResolveSettings,
        plan: &LayoutPlan,
        prepass: bool,
    ) -> Result<ResolvePass> {
        settings.validate().map_err(GpuError::Other)?;
        let (w, h) = (plan.width, plan.height);
        if w < 2 || h < 2 {
            return Err(GpuError::Other(format!(
                "the checkerboard resolve needs at least 2x2 pixels, not {w}x{h}"
            )));
        }
        if settings.fp16 && !gpu.caps().shader_float16 {
            return Err(GpuError::Unsupported {
                device: gpu.info().name.clone(),
                feature: "--resolve-fp16 (shaderFloat16)".into(),
            });
        }
        let floor = if settings.bandwidth_floor {
            Some(CopyFloor::new(gpu, shaders, w, h, settings.f32_history)?)
        } else {
            None
        };
        Ok(ResolvePass {
            pass: decl(settings, plan, prepass).build(gpu, shaders)?,
            res: Resources::new(gpu, "resolve", &resources(settings, w, h))?,
            floor,
            settings: *settings,
            width: w,
            height: h,
            tangram: plan.tangram,
            has_prepass: prepass,
        })
    }

    pub fn settings(&self) -> &ResolveSettings {
        &self.settings
    }

    fn history(&self, name: &str, slot: usize) -> Result<&Image> {
        Ok(self.res.history(name)?.slot(slot))
    }

    /// The resolved colour written by the frame that used `slot`.
    pub fn output(&self, slot: usize) -> Option<&Image> {
        self.history("history_color", slot).ok()
    }

    /// Records the resolve of one frame (the raster targets are complete), then the copy floor.
    /// `prepass`: the native-resolution (IDs, depth), when the pass was built with it.
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        targets: &FrameTargets,
        prepass: Option<(&Image, &Image)>,
        frame: &ResolveFrame,
    ) -> Result<()> {
        let (k, prev) = (frame.slot, 1 - frame.slot % 2);
        let (prev_color, prev_geom) = (
            self.history("history_color", prev)?,
            self.history("history_geom", prev)?,
        );
        // Without a prepass its bindings hold the previous history, never read.
        let (pre_ids, pre_depth) = prepass.unwrap_or((prev_geom, prev_color));
        let binds = targets
            .bind(Binds::of(&self.res))
            .image("hist_color", prev_color)
            .image("hist_geom", prev_geom)
            .image("pre_depth", pre_depth)
            .image("pre_ids", pre_ids)
            .image("out_color", self.history("history_color", k)?)
            .image("out_geom", self.history("history_geom", k)?);
        let r = frame.reproj;
        let push = ResolvePush {
            size_parity_side: [
                self.width as i32,
                self.height as i32,
                frame.parity as i32,
                self.tangram as i32,
            ],
            flags: [self.settings.flags(frame.reset, self.has_prepass), 0, 0, 0],
            params: self.settings.params(),
            inv_size: [1.0 / self.width as f32, 1.0 / self.height as f32, 0.0, 0.0],
            reproj: [
                [r[0], r[1], r[2], r[3]],
                [r[4], r[5], r[6], r[7]],
                [r[8], r[9], r[10], r[11]],
                [r[12], r[13], r[14], r[15]],
            ],
        };
        let (gx, gy) = self.groups();
        self.pass
            .dispatch(cmd, profiler, &binds, &push, [gx, gy, 1])?;
        if let Some(f) = &self.floor {
            f.record(cmd, profiler)?;
        }
        Ok(())
    }

    /// The frame's geometry (`ResolveSettings::velocity`): the velocity each pixel used, and the
    /// history geometry of slot `slot` (object ID | moved bit, reverse-Z depth bits) as IDs and
    /// depth both.
    pub fn geometry(&self, slot: usize) -> Option<crate::frame::Geometry<'_>> {
        let g = self.history("history_geom", slot).ok()?;
        Some(crate::frame::Geometry {
            velocity: self.res.image("debug_velocity").ok()?,
            depth: g,
            ids: g,
            packed: true,
        })
    }

    /// Workgroups of the dispatch.
    pub fn groups(&self) -> (u32, u32) {
        let g = self.settings.group;
        match self.settings.mapping {
            Mapping::Pixel => (self.width.div_ceil(g), self.height.div_ceil(g)),
            Mapping::Quad => (
                self.width.div_ceil(2).div_ceil(g),
                self.height.div_ceil(2).div_ceil(g),
            ),
        }
    }

    /// Fills history slot `slot` (read by the next frame that writes the other slot): colour
    /// (RGB, converted to the history format), reverse-Z depth and object IDs. Tests use it to
    /// start from a known history; the staging buffer lives until the submission completes.
    pub fn seed_history(
        &self,
        gpu: &Gpu,
        slot: usize,
        color: &[[f32; 3]],
        depth: &[f32],
        ids: &[u32],
    ) -> Result<()> {
        let n = (self.width * self.height) as usize;
        if color.len() != n || depth.len() != n || ids.len() != n {
            return Err(GpuError::Other("seed_history: wrong sizes".into()));
        }
        let mut bytes: Vec<u8> = Vec::new();
        if self.settings.f32_history {
            for c in color {
                bytes.extend_from_slice(bytemuck::cast_slice(&[c[0], c[1], c[2], 1.0]));
            }
        } else {
            for c in color {
                let h = [c[0], c[1], c[2], 1.0].map(half::f16::from_f32);
                bytes.extend_from_slice(bytemuck::cast_slice(&h));
            }
        }
        let geom_at = bytes.len() as u64;
        for (&d, &id) in depth.iter().zip(ids) {
            bytes.extend_from_slice(bytemuck::cast_slice(&[id, d.to_bits()]));
        }
        let mut staging = Buffer::new(
            gpu,
            "resolve.seed",
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            Location::CpuToGpu,
        )?;
        staging.write(0, &bytes)?;
        let (hc, hg) = (
            self.history("history_color", slot)?,
            self.history("history_geom", slot)?,
        );
        let level = |offset| {
            [LevelCopy {
                buffer_offset: offset,
                level: 0,
                width: self.width,
                height: self.height,
            }]
        };
        gpu.submit("resolve.seed_history", |cmd| {
            cmd.upload_levels(&staging, hc, &level(0), Access::ComputeSampled);
            cmd.upload_levels(&staging, hg, &level(geom_at), Access::ComputeSampled);
            Ok(())
        })
    }

    /// Readbacks sized for the resolved colour, the debug bits and the debug velocity.
    pub fn readbacks(&self, gpu: &Gpu) -> Result<ResolveReadbacks> {
        let (w, h) = (self.width, self.height);
        let [color, geom, debug_bits, debug_velocity] =
            readbacks(&self.settings, w, h).map(|r| r.make_readback(gpu, "readback"));
        Ok(ResolveReadbacks {
            color: color?,
            geom: geom?,
            debug_bits: debug_bits?,
            debug_velocity: debug_velocity?,
        })
    }

    /// Records the copies of the frame's outputs (slot `slot`) into `rb`: the resolved colour,
    /// the debug views when enabled, and with `geometry` the history IDs and depths (tests).
    pub fn read(
        &self,
        cmd: &mut Cmd,
        slot: usize,
        rb: &ResolveReadbacks,
        geometry: bool,
    ) -> Result<()> {
        cmd.read_image(self.history("history_color", slot)?, &rb.color);
        if geometry {
            cmd.read_image(self.history("history_geom", slot)?, &rb.geom);
        }
        if self.settings.debug {
            cmd.read_image(self.res.image("debug_bits")?, &rb.debug_bits);
            cmd.read_image(self.res.image("debug_velocity")?, &rb.debug_velocity);
        }
        Ok(())
    }
}

pub struct ResolveReadbacks {
    pub color: Readback,
    /// Object ID (with `ID_MOVED`) and reverse-Z depth bits per pixel.
    pub geom: Readback,
    pub debug_bits: Readback,
    pub debug_velocity: Readback,
}

impl ResolveReadbacks {
    /// The resolved reverse-Z depths and object IDs (with `ID_MOVED`).
    pub fn depth_ids(&self) -> Result<(Vec<f32>, Vec<u32>)> {
        let g: &[[u32; 2]] = bytemuck::cast_slice(self.geom.bytes()?);
        Ok((
            g.iter().map(|v| f32::from_bits(v[1])).collect(),
            g.iter().map(|v| v[0]).collect(),
        ))
    }

    /// The resolved colour as RGB f32, whatever the history format.
    pub fn color_rgb(&self, f32_history: bool) -> Result<Vec<[f32; 3]>> {
        let b = self.color.bytes()?;
        Ok(if f32_history {
            bytemuck::cast_slice::<u8, [f32; 4]>(b)
                .iter()
                .map(|c| [c[0], c[1], c[2]])
                .collect()
        } else {
            bytemuck::cast_slice::<u8, [half::f16; 4]>(b)
                .iter()
                .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32()])
                .collect()
        })
    }
}

/// The bandwidth floor of the resolve: a compute copy that reads and writes as many bytes as the
/// resolve must at least (every rendered sample's colour, velocity, IDs and depth, one history
/// texel of colour, depth and ID per missing pixel; one colour, depth and ID per output pixel),
/// as 16-byte words, in the same command buffer.
pub struct CopyFloor {
    pass: ComputePass,
    res: Resources,
    words_in: u32,
    words_out: u32,
}

crate::push_constants! {
    struct CopyPush {
        words_in: u32,
        words_out: u32,
    }
}

/// The copy kernel (shaders/resolve/copy_floor.comp), timed as `name`.
pub fn copy_floor_decl(name: &str) -> ComputeDecl {
    ComputeDecl::new(name, "resolve/copy_floor.comp")
        .bind(Binding::buffer("src", Use::Read))
        .bind(Binding::buffer("dst", Use::Write))
        .push::<CopyPush>()
        .group(256, 1)
}

fn copy_floor_resources((read, write): (u64, u64)) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::buffer("src", read.div_ceil(16) * 16),
        ResourceDecl::buffer("dst", write.div_ceil(16) * 16),
    ]
}

impl CopyFloor {
    /// Bytes the resolve of a W x H frame reads and writes at least.
    pub fn bytes(width: u32, height: u32, f32_history: bool) -> (u64, u64) {
        let px = u64::from(width) * u64::from(height);
        let color = if f32_history { 16 } else { 8 };
        let sample = crate::targets::BYTES_PER_SAMPLE;
        let read = px.div_ceil(2) * sample + (px / 2) * (color + 4 + 4);
        let write = px * (color + 4 + 4);
        (read, write)
    }

    fn new(gpu: &Gpu, shaders: &Shaders, w: u32, h: u32, f32_history: bool) -> Result<CopyFloor> {
        let (read, write) = CopyFloor::bytes(w, h, f32_history);
        CopyFloor::named(
            gpu,
            shaders,
            "resolve.copy_floor",
            "copy_floor",
            (read, write),
        )
    }

    /// A copy kernel reading `read` and writing `write` bytes (rounded up to 16-byte words),
    /// timed as the pass `name`; its buffers are `{buffers}.src` and `{buffers}.dst`.
    pub fn named(
        gpu: &Gpu,
        shaders: &Shaders,
        name: &'static str,
        buffers: &str,
        bytes: (u64, u64),
    ) -> Result<CopyFloor> {
        Ok(CopyFloor {
            pass: copy_floor_decl(name).build(gpu, shaders)?,
            res: Resources::new(gpu, buffers, &copy_floor_resources(bytes))?,
            words_in: bytes.0.div_ceil(16) as u32,
            words_out: bytes.1.div_ceil(16) as u32,
        })
    }

    /// What [`CopyFloor::named`] allocates.
    pub fn estimate(e: &mut crate::memory::MemoryEstimate, buffers: &str, bytes: (u64, u64)) {
        e.append(crate::pass::estimate(&copy_floor_resources(bytes), buffers));
    }

    pub fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler) -> Result<()> {
        let push = CopyPush {
            words_in: self.words_in,
            words_out: self.words_out,
        };
        let groups = [self.words_out.div_ceil(256), 1, 1];
        self.pass
            .dispatch(cmd, profiler, &Binds::of(&self.res), &push, groups)
    }
}
