//! The `interlaced` resolve (shaders/interlaced/resolve.comp, docs/interlaced.md): rendered rows
//! pass through, missing rows come from the previous resolved frame (reprojected, validated by
//! object ID and depth) or from the rows above and below. Two slots of full-resolution colour and
//! geometry, ping-ponged by frame parity: the frame writes one and reads the other as history,
//! and both serve post passes (`Technique::color`, `Technique::geometry`).

use cbr_gpu::{
    Access, BindingDesc, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Gpu, GpuError, Image,
    ImageDesc, PassKind, Pipeline, Profiler, Readback, Result, Sampler, SamplerDesc, SetLayout,
    Shaders, Write, vk,
};
use half::f16;

use crate::memory::MemoryEstimate;
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

pub const BINDINGS: [BindingDesc; 13] = {
    use DescriptorKind::{CombinedImageSampler as S, StorageImage as I};
    [
        BindingDesc::one("color", 0, S),
        BindingDesc::one("velocity", 1, S),
        BindingDesc::one("ids", 2, S),
        BindingDesc::one("depth", 3, S),
        BindingDesc::one("hist_color", 4, S),
        BindingDesc::one("hist_velocity", 5, S),
        BindingDesc::one("hist_ids", 6, S),
        BindingDesc::one("hist_depth", 7, S),
        BindingDesc::one("out_color", 8, I),
        BindingDesc::one("out_velocity", 9, I),
        BindingDesc::one("out_ids", 10, I),
        BindingDesc::one("out_depth", 11, I),
        BindingDesc::one("debug_bits", 12, I),
    ]
};

/// The push constants of resolve.comp (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct InterlacedPush {
    pub size_parity: [i32; 4],
    pub flags: [u32; 4],
    pub params: [f32; 4],
}

/// One slot: a resolved frame at full resolution (this frame's output, the next one's history).
pub struct Resolved {
    /// RGBA16F, alpha 1.
    pub color: Image,
    /// RG32F, pixels, current - previous.
    pub velocity: Image,
    /// RG32UI: object, primitive.
    pub ids: Image,
    /// R32F reverse-Z.
    pub depth: Image,
}

impl Resolved {
    /// Colour, depth, velocity, IDs: the order of the common layers.
    pub fn layers(&self) -> [&Image; 4] {
        [&self.color, &self.depth, &self.velocity, &self.ids]
    }

    fn new(gpu: &Gpu, k: usize, w: u32, h: u32) -> Result<Resolved> {
        // SAMPLED: the next frame's history and post passes; TRANSFER_SRC: readbacks.
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let img = |name: &str, format| {
            let name = format!("interlaced.resolved[{k}].{name}");
            Image::new(gpu, &ImageDesc::new_2d(&name, format, w, h, usage))
        };
        Ok(Resolved {
            color: img("color", COLOR_FORMAT)?,
            velocity: img("velocity", VELOCITY_FORMAT)?,
            ids: img("ids", ID_FORMAT)?,
            depth: img("depth", RESOLVED_DEPTH_FORMAT)?,
        })
    }
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
    pipeline: Pipeline,
    _layout: SetLayout,
    sets: [DescriptorSet; 2],
    _sampler: Sampler,
    pub slots: [Resolved; 2],
    pub debug_bits: Image,
    settings: InterlacedSettings,
    width: u32,
    height: u32,
}

impl InterlacedResolve {
    /// What [`InterlacedResolve::new`] and [`InterlacedResolve::readbacks`] allocate at
    /// `w` x `h`: two slots of colour, velocity, IDs and depth, the debug bits, one slot's
    /// readbacks (and the debug bits' with `debug`).
    pub fn estimate(e: &mut MemoryEstimate, settings: &InterlacedSettings, w: u32, h: u32) {
        let layers = [
            ("color", COLOR_FORMAT),
            ("velocity", VELOCITY_FORMAT),
            ("ids", ID_FORMAT),
            ("depth", RESOLVED_DEPTH_FORMAT),
        ];
        for k in 0..2 {
            for (name, format) in layers {
                e.image(format!("interlaced.resolved[{k}].{name}"), format, w, h);
            }
        }
        e.image("interlaced.debug_bits", vk::Format::R32_UINT, w, h);
        for (name, format) in layers {
            e.readback(format!("readback.{name}"), format, w, h, 1);
        }
        if settings.debug {
            e.readback("readback.interlaced_debug", vk::Format::R32_UINT, w, h, 1);
        }
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
        let layout = SetLayout::new(gpu, "interlaced.resolve.set_layout", &BINDINGS)?;
        let mut defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        defines.push(("DEBUG".into(), u32::from(settings.debug).to_string()));
        let cs = shaders.compile("interlaced/resolve.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "interlaced.resolve",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: std::mem::size_of::<InterlacedPush>() as u32,
            },
        )?;
        let sampler = Sampler::new(gpu, "interlaced.resolve.sampler", SamplerDesc::NEAREST)?;
        let slots = [Resolved::new(gpu, 0, w, h)?, Resolved::new(gpu, 1, w, h)?];
        let debug_bits = Image::new(
            gpu,
            &ImageDesc::new_2d(
                "interlaced.debug_bits",
                vk::Format::R32_UINT,
                w,
                h,
                vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
        )?;
        let set = |k: usize| -> Result<DescriptorSet> {
            let (out, prev) = (&slots[k], &slots[1 - k]);
            DescriptorSet::new(
                gpu,
                &format!("interlaced.resolve.set[{k}]"),
                &layout,
                &[
                    Write::Sampled(0, vec![(&targets.color, &sampler)]),
                    Write::Sampled(1, vec![(&targets.velocity, &sampler)]),
                    Write::Sampled(2, vec![(&targets.ids, &sampler)]),
                    Write::Sampled(3, vec![(&targets.depth, &sampler)]),
                    Write::Sampled(4, vec![(&prev.color, &sampler)]),
                    Write::Sampled(5, vec![(&prev.velocity, &sampler)]),
                    Write::Sampled(6, vec![(&prev.ids, &sampler)]),
                    Write::Sampled(7, vec![(&prev.depth, &sampler)]),
                    Write::Storage(8, &out.color),
                    Write::Storage(9, &out.velocity),
                    Write::Storage(10, &out.ids),
                    Write::Storage(11, &out.depth),
                    Write::Storage(12, &debug_bits),
                ],
            )
        };
        let sets = [set(0)?, set(1)?];
        Ok(InterlacedResolve {
            pipeline,
            _layout: layout,
            sets,
            _sampler: sampler,
            slots,
            debug_bits,
            settings: *settings,
            width: w,
            height: h,
        })
    }

    pub fn settings(&self) -> &InterlacedSettings {
        &self.settings
    }

    /// Records the resolve of one frame (the raster targets are complete).
    pub fn record(
        &self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        targets: &FrameTargets,
        frame: &InterlacedFrame,
    ) {
        let (out, prev) = (&self.slots[frame.slot], &self.slots[1 - frame.slot]);
        let t = targets;
        for img in [&t.color, &t.velocity, &t.ids, &t.depth] {
            cmd.use_image(img, Access::ComputeSampled);
        }
        for img in prev.layers() {
            cmd.use_image(img, Access::ComputeSampled);
        }
        for img in out.layers() {
            cmd.use_image(img, Access::ComputeStorageWrite);
        }
        cmd.use_image(&self.debug_bits, Access::ComputeStorageWrite);
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
        let scope = profiler.begin(cmd, "interlaced.resolve", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.sets[frame.slot]);
        cmd.push_constants(&self.pipeline, bytemuck::bytes_of(&push));
        // One invocation per vertical pair of pixels (rows 2j, 2j + 1): the shader's main.
        cmd.dispatch(
            self.width.div_ceil(8),
            self.height.div_ceil(2).div_ceil(8),
            1,
        );
        profiler.end(cmd, scope);
    }

    /// Readbacks sized for one slot (and the debug bits).
    pub fn readbacks(&self, gpu: &Gpu) -> Result<ResolvedReadbacks> {
        let s = &self.slots[0];
        let rb = |name: &str, img: &Image| Readback::for_image(gpu, name, img);
        Ok(ResolvedReadbacks {
            color: rb("readback.color", &s.color)?,
            velocity: rb("readback.velocity", &s.velocity)?,
            ids: rb("readback.ids", &s.ids)?,
            depth: rb("readback.depth", &s.depth)?,
            debug: match self.settings.debug {
                true => Some(rb("readback.interlaced_debug", &self.debug_bits)?),
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
    ) {
        let s = &self.slots[slot];
        let scope = profiler.begin(cmd, "readback", PassKind::Transfer);
        cmd.read_image(&s.color, &rb.color);
        cmd.read_image(&s.velocity, &rb.velocity);
        cmd.read_image(&s.ids, &rb.ids);
        cmd.read_image(&s.depth, &rb.depth);
        if let Some(d) = &rb.debug {
            cmd.read_image(&self.debug_bits, d);
        }
        profiler.end(cmd, scope);
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
