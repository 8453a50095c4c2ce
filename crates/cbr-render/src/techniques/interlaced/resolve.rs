//! The `interlaced` resolve (shaders/interlaced/resolve.comp, docs/interlaced.md): rendered rows
//! pass through, missing rows come from the previous resolved frame (reprojected, validated by
//! object ID and depth) or from the rows above and below. Two slots of full-resolution colour and
//! geometry, ping-ponged by frame parity: the frame writes one and reads the other as history,
//! and both serve post passes (`Technique::color`, `Technique::geometry`).

use cbr_gpu::{Cmd, Gpu, GpuError, Image, PassKind, Profiler, Readback, Result, Shaders, vk};
use half::f16;

use crate::memory::MemoryEstimate;
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::targets::{COLOR_FORMAT, FrameTargets, ID_FORMAT, VELOCITY_FORMAT};

/// The resolved reverse-Z depth: a storage image, so R32F rather than a depth format.
pub const RESOLVED_DEPTH_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

/// Push-constant flags (F_* in resolve.comp).
pub const F_RESET: u32 = 1;
pub const F_NO_DEPTH: u32 = 2;
pub const F_NO_IDS: u32 = 4;
pub const F_NO_CLAMP: u32 = 8;
pub const F_NO_DIAGONALS: u32 = 16;

/// How missing rows are reconstructed; every input can be switched off (ablations).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct InterlacedSettings {
    /// Relative linear-depth tolerance of the history validation.
    pub depth_tolerance: f32,
    /// Below this motion (pixels) a pixel is still: the still rule, and no clamp.
    pub static_threshold: f32,
    /// Use the previous frame (off: the spatial fill everywhere).
    pub history: bool,
    /// Validate history by object ID (and reject spatial pairs across objects).
    pub ids: bool,
    /// Validate history by depth.
    pub depth: bool,
    /// Clamp moving history to the six rendered neighbours' YCoCg box.
    pub clamp: bool,
    /// The clamp box's margin on each side, a fraction of its extent.
    pub clamp_margin: f32,
    /// Spatial fill along the best of three directions (off: the vertical pair only).
    pub diagonals: bool,
    /// Write the debug bits (resolve::DBG_*).
    pub debug: bool,
}

impl Default for InterlacedSettings {
    fn default() -> Self {
        InterlacedSettings {
            depth_tolerance: 0.05,
            static_threshold: 1.0 / 64.0,
            history: true,
            ids: true,
            depth: true,
            clamp: true,
            clamp_margin: 0.5,
            diagonals: true,
            debug: false,
        }
    }
}

impl InterlacedSettings {
    pub fn flags(&self, reset: bool) -> u32 {
        let mut f = 0;
        for (on, flag) in [
            (reset || !self.history, F_RESET),
            (!self.depth, F_NO_DEPTH),
            (!self.ids, F_NO_IDS),
            (!self.clamp, F_NO_CLAMP),
            (!self.diagonals, F_NO_DIAGONALS),
        ] {
            if on {
                f |= flag;
            }
        }
        f
    }
}

crate::push_constants! {
    /// The push constants of resolve.comp (48 bytes).
    pub struct InterlacedPush {
        /// W, H, parity (the rendered rows' y mod 2), 0.
        size_parity: [i32; 4],
        /// x: the F_* flags.
        flags: [u32; 4],
        /// x: depth tolerance, y: static threshold (px), z: clamp margin, w: 0.
        params: [f32; 4],
    }
}

/// The resolve (shaders/interlaced/resolve.comp): this frame's raster and the previous
/// resolved frame in, this frame's resolved colour and geometry out.
pub fn decl(settings: &InterlacedSettings) -> ComputeDecl {
    use crate::resolve as r;
    ComputeDecl::new("interlaced.resolve", "interlaced/resolve.comp")
        .define("DEBUG", u32::from(settings.debug))
        .constants(&[
            ("F_RESET", F_RESET),
            ("F_NO_DEPTH", F_NO_DEPTH),
            ("F_NO_IDS", F_NO_IDS),
            ("F_NO_CLAMP", F_NO_CLAMP),
            ("F_NO_DIAGONALS", F_NO_DIAGONALS),
            // The checkerboard resolve's debug bits, so `cbr render` writes the same views.
            ("DBG_RENDERED", r::DBG_RENDERED),
            ("DBG_MISSING", r::DBG_MISSING),
            ("DBG_REPROJECTED", r::DBG_REPROJECTED),
            ("DBG_REJECT_ID", r::DBG_REJECT_ID),
            ("DBG_REJECT_DEPTH", r::DBG_REJECT_DEPTH),
            ("DBG_CLAMPED", r::DBG_CLAMPED),
            ("DBG_SPATIAL", r::DBG_SPATIAL),
            ("DBG_STILL", r::DBG_STILL),
        ])
        .bindings(&[
            Binding::sampled("color"),
            Binding::sampled("velocity"),
            Binding::sampled("ids"),
            Binding::sampled("depth"),
            Binding::sampled("hist_color"),
            Binding::sampled("hist_velocity"),
            Binding::sampled("hist_ids"),
            Binding::sampled("hist_depth"),
            Binding::image("out_color", Use::Write),
            Binding::image("out_velocity", Use::Write),
            Binding::image("out_ids", Use::Write),
            Binding::image("out_depth", Use::Write),
            Binding::image("debug_bits", Use::Write),
        ])
        .push::<InterlacedPush>()
}

/// The resolved frame's layers, each a history (this frame's output, the next one's history),
/// and the debug bits.
/// The readbacks of one slot's layers (colour, velocity, IDs, depth) and with `debug` the
/// debug bits.
fn readbacks(settings: &InterlacedSettings, w: u32, h: u32) -> Vec<ResourceDecl> {
    let mut r = vec![
        ResourceDecl::readback("color", COLOR_FORMAT, w, h),
        ResourceDecl::readback("velocity", VELOCITY_FORMAT, w, h),
        ResourceDecl::readback("ids", ID_FORMAT, w, h),
        ResourceDecl::readback("depth", RESOLVED_DEPTH_FORMAT, w, h),
    ];
    if settings.debug {
        r.push(ResourceDecl::readback(
            "interlaced_debug",
            vk::Format::R32_UINT,
            w,
            h,
        ));
    }
    r
}

fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![
        ResourceDecl::image("resolved_color", COLOR_FORMAT, w, h).history(),
        ResourceDecl::image("resolved_velocity", VELOCITY_FORMAT, w, h).history(),
        ResourceDecl::image("resolved_ids", ID_FORMAT, w, h).history(),
        ResourceDecl::image("resolved_depth", RESOLVED_DEPTH_FORMAT, w, h).history(),
        ResourceDecl::image("debug_bits", vk::Format::R32_UINT, w, h),
    ]
}

/// What one frame's resolve needs besides the samples.
#[derive(Clone, Copy, Debug)]
pub struct InterlacedFrame {
    /// The slot to write (frame mod 2); the other is the history.
    pub slot: usize,
    /// The rendered rows' y mod 2.
    pub parity: u32,
    /// No usable history.
    pub reset: bool,
}

pub struct InterlacedResolve {
    pass: ComputePass,
    res: Resources,
    settings: InterlacedSettings,
    width: u32,
    height: u32,
}

const LAYERS: [&str; 4] = [
    "resolved_color",
    "resolved_depth",
    "resolved_velocity",
    "resolved_ids",
];

impl InterlacedResolve {
    /// What [`InterlacedResolve::new`] and [`InterlacedResolve::readbacks`] allocate at
    /// `w` x `h`: the declared resources, one slot's readbacks (and the debug bits' with
    /// `debug`).
    pub fn estimate(e: &mut MemoryEstimate, settings: &InterlacedSettings, w: u32, h: u32) {
        e.append(crate::pass::estimate(&resources(w, h), "interlaced"));
        e.append(crate::pass::estimate(
            &readbacks(settings, w, h),
            "readback",
        ));
    }

    /// The resolve of `targets` (a full-resolution raster).
    pub fn new(
        gpu: &Gpu,
        shaders: &Shaders,
        settings: &InterlacedSettings,
        targets: &FrameTargets,
    ) -> Result<InterlacedResolve> {
        let (w, h) = (targets.color.width, targets.color.height);
        if w < 2 || h < 2 {
            return Err(GpuError::Other(format!(
                "the interlaced resolve needs at least 2x2 pixels, not {w}x{h}"
            )));
        }
        Ok(InterlacedResolve {
            pass: decl(settings).build(gpu, shaders)?,
            res: Resources::new(gpu, "interlaced", &resources(w, h))?,
            settings: *settings,
            width: w,
            height: h,
        })
    }

    pub fn settings(&self) -> &InterlacedSettings {
        &self.settings
    }

    /// Colour, depth, velocity, IDs of slot `slot`: the order of the common layers.
    pub fn layers(&self, slot: usize) -> Result<[&Image; 4]> {
        let l = |n| Ok::<_, GpuError>(self.res.history(n)?.slot(slot));
        Ok([l(LAYERS[0])?, l(LAYERS[1])?, l(LAYERS[2])?, l(LAYERS[3])?])
    }

    /// Records the resolve of one frame (the raster targets are complete).
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        targets: &FrameTargets,
        frame: &InterlacedFrame,
    ) -> Result<()> {
        let [oc, od, ov, oi] = self.layers(frame.slot)?;
        let [hc, hd, hv, hi] = self.layers(1 - frame.slot % 2)?;
        let binds = targets
            .bind(Binds::of(&self.res))
            .image("hist_color", hc)
            .image("hist_velocity", hv)
            .image("hist_ids", hi)
            .image("hist_depth", hd)
            .image("out_color", oc)
            .image("out_velocity", ov)
            .image("out_ids", oi)
            .image("out_depth", od);
        let s = &self.settings;
        let push = InterlacedPush {
            size_parity: [
                self.width as i32,
                self.height as i32,
                frame.parity as i32,
                0,
            ],
            flags: [s.flags(frame.reset), 0, 0, 0],
            params: [s.depth_tolerance, s.static_threshold, s.clamp_margin, 0.0],
        };
        // One invocation per vertical pair of pixels (rows 2j, 2j + 1): the shader's main.
        let groups = [
            self.width.div_ceil(8),
            self.height.div_ceil(2).div_ceil(8),
            1,
        ];
        self.pass.dispatch(cmd, profiler, &binds, &push, groups)
    }

    /// Readbacks sized for one slot (and the debug bits).
    pub fn readbacks(&self, gpu: &Gpu) -> Result<ResolvedReadbacks> {
        let decls = readbacks(&self.settings, self.width, self.height);
        let rb = |i: usize| decls[i].make_readback(gpu, "readback");
        Ok(ResolvedReadbacks {
            color: rb(0)?,
            velocity: rb(1)?,
            ids: rb(2)?,
            depth: rb(3)?,
            debug: match self.settings.debug {
                true => Some(rb(4)?),
                false => None,
            },
        })
    }

    /// Records the copies of slot `slot` (and the debug bits) into `rb` (timed as `readback`).
    pub fn read(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        slot: usize,
        rb: &ResolvedReadbacks,
    ) -> Result<()> {
        let [c, d, v, i] = self.layers(slot)?;
        let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
        cmd.read_image(c, &rb.color);
        cmd.read_image(v, &rb.velocity);
        cmd.read_image(i, &rb.ids);
        cmd.read_image(d, &rb.depth);
        if let Some(dbg) = &rb.debug {
            cmd.read_image(self.res.image("debug_bits")?, dbg);
        }
        profiler.end(cmd, scope);
        Ok(())
    }
}

pub struct ResolvedReadbacks {
    color: Readback,
    velocity: Readback,
    ids: Readback,
    depth: Readback,
    debug: Option<Readback>,
}

/// A resolved frame as stored on the GPU.
#[derive(Clone, Debug)]
pub struct RawFrame {
    pub color: Vec<[f16; 4]>,
    pub velocity: Vec<[f32; 2]>,
    pub ids: Vec<[u32; 2]>,
    /// Reverse-Z.
    pub depth: Vec<f32>,
    /// resolve::DBG_* bits, with `debug`.
    pub debug: Option<Vec<u32>>,
}

impl ResolvedReadbacks {
    /// The frame read back last.
    pub fn frame(&self) -> Result<RawFrame> {
        Ok(RawFrame {
            color: bytemuck::cast_slice(self.color.bytes()?).to_vec(),
            velocity: bytemuck::cast_slice(self.velocity.bytes()?).to_vec(),
            ids: bytemuck::cast_slice(self.ids.bytes()?).to_vec(),
            depth: bytemuck::cast_slice(self.depth.bytes()?).to_vec(),
            debug: match &self.debug {
                Some(d) => Some(bytemuck::cast_slice(d.bytes()?).to_vec()),
                None => None,
            },
        })
    }
}
