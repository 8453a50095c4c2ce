//! What a rendered frame is on the host: the layers and statistics a technique reads back, the
//! sequencer completes (index, time, timings, counters) and the CLI, the bench and the cache
//! consume. A leaf: it imports nothing of the sequencer or the techniques.

use std::collections::BTreeMap;

use cbr_gpu::{GpuError, Image, PassTiming, Result};
use half::f16;

/// One rendered frame, read back to the host: the four layers every technique writes (typed:
/// everything uses them), the technique's own layers and per-frame statistics (named, declared
/// once in its [`crate::technique::Registration`]), and what the sequencer adds.
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
    /// The technique's own layers, in the order it declares and writes them (the EXR's order):
    /// e.g. checkerboard's `mask`, `ssaa`'s `coverage`. Each technique module has typed
    /// accessors of its own (`Coverage::from_frame`, ...).
    pub layers: Vec<Layer>,
    /// The technique's per-frame statistics by name; `a.b` is entry `b` of run.json's per-frame
    /// object `a` (e.g. `analytic.tail_fragments`), a name without a dot a field of its own
    /// (`parity`, `resolve_reset`).
    pub stats: BTreeMap<String, Stat>,
    /// Shaded (non-helper) fragments, when counted. Generic: the sequencer reads it for every
    /// technique from the scene shaders' counter.
    pub shaded_fragments: Option<u64>,
    /// Fragments whose shading was NaN or infinite (written black, never kept in a history);
    /// `None` for frames read from the cache. Generic, as `shaded_fragments`.
    pub nonfinite_fragments: Option<u64>,
    /// Where the frame came from when it was not rendered now (a cache file).
    pub cached: Option<std::path::PathBuf>,
    pub timings: Vec<PassTiming>,
}

/// The host type of a layer's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleType {
    U8,
    U32,
    F16,
    F32,
}

/// How a layer's channels are stored in the frame's EXR (OpenEXR's three sample types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExrType {
    Half,
    Float,
    Uint,
}

/// A layer's samples: every channel's `width * height` values in turn (planar), rows top to
/// bottom.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    U8(Vec<u8>),
    U32(Vec<u32>),
    F16(Vec<f16>),
    F32(Vec<f32>),
}

impl Samples {
    pub fn sample_type(&self) -> SampleType {
        match self {
            Samples::U8(_) => SampleType::U8,
            Samples::U32(_) => SampleType::U32,
            Samples::F16(_) => SampleType::F16,
            Samples::F32(_) => SampleType::F32,
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::U32(v) => v.len(),
            Samples::F16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A host sample type: what [`Layer::channel`] can return.
pub trait Sample: Copy + Sized {
    const TYPE: SampleType;
    fn slice(s: &Samples) -> Option<&[Self]>;
    fn wrap(v: Vec<Self>) -> Samples;
}

macro_rules! sample {
    ($t:ty, $v:ident) => {
        impl Sample for $t {
            const TYPE: SampleType = SampleType::$v;
            fn slice(s: &Samples) -> Option<&[$t]> {
                match s {
                    Samples::$v(v) => Some(v),
                    _ => None,
                }
            }
            fn wrap(v: Vec<$t>) -> Samples {
                Samples::$v(v)
            }
        }
    };
}
sample!(u8, U8);
sample!(u32, U32);
sample!(f16, F16);
sample!(f32, F32);

/// A layer a technique writes beyond the four common ones, declared once (in its registration's
/// `outputs.layers`) and filled per frame with [`LayerDecl::layer`].
#[derive(Clone, Copy, Debug)]
pub struct LayerDecl {
    /// The EXR part's name (and the name a frame's layer is looked up by).
    pub name: &'static str,
    pub channels: &'static [&'static str],
    /// What the host holds.
    pub samples: SampleType,
    /// How the EXR writer stores it; `None`: on the host only (not an image of the frame's
    /// size, like a list of lights, or not part of the EXR).
    pub exr: Option<ExrType>,
    pub about: &'static str,
}

impl LayerDecl {
    /// This layer at `width` x `height` from its channels' planes in the declared order; the
    /// planes' type and sizes are checked against the declaration.
    pub fn layer<T: Sample>(&self, width: u32, height: u32, planes: Vec<Vec<T>>) -> Result<Layer> {
        let bad = |why: String| GpuError::Other(format!("layer `{}`: {why}", self.name));
        if T::TYPE != self.samples {
            return Err(bad(format!(
                "{:?} samples, declared {:?}",
                T::TYPE,
                self.samples
            )));
        }
        if planes.len() != self.channels.len() {
            return Err(bad(format!(
                "{} channels, declared {}",
                planes.len(),
                self.channels.len()
            )));
        }
        let n = width as usize * height as usize;
        if let Some(p) = planes.iter().find(|p| p.len() != n) {
            return Err(bad(format!("{} values for {width} x {height}", p.len())));
        }
        Ok(Layer {
            name: self.name.to_string(),
            channels: self.channels.iter().map(|c| c.to_string()).collect(),
            width,
            height,
            samples: T::wrap(planes.concat()),
            exr: self.exr,
        })
    }
}

/// `a` then `b`: a registration's layer list from shared declarations (e.g. `mask` and the
/// resolve's debug layers), in a constant.
pub const fn join<const A: usize, const B: usize, const C: usize>(
    a: [LayerDecl; A],
    b: [LayerDecl; B],
) -> [LayerDecl; C] {
    assert!(A + B == C, "join: C must be A + B");
    let mut out = [EMPTY_DECL; C];
    let mut i = 0;
    while i < A {
        out[i] = a[i];
        i += 1;
    }
    while i < C {
        out[i] = b[i - A];
        i += 1;
    }
    out
}

const EMPTY_DECL: LayerDecl = LayerDecl {
    name: "",
    channels: &[],
    samples: SampleType::U8,
    exr: None,
    about: "",
};

/// One layer of a frame (see [`LayerDecl`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    pub name: String,
    pub channels: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub samples: Samples,
    pub exr: Option<ExrType>,
}

impl Layer {
    /// Channel `name`'s values, when the layer holds `T`.
    pub fn channel<T: Sample>(&self, name: &str) -> Option<&[T]> {
        let c = self.channels.iter().position(|c| c == name)?;
        let n = self.width as usize * self.height as usize;
        T::slice(&self.samples)?.get(c * n..(c + 1) * n)
    }
}

/// A per-frame statistic: a count, a real number, a flag or a list of counts (e.g. a tile size).
/// Written to run.json as the plain JSON value.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum Stat {
    Count(u64),
    Real(f64),
    Flag(bool),
    Counts(Vec<u64>),
}

/// A per-frame statistic a technique writes, declared once (its registration's
/// `outputs.stats`): run.json writes `null` for a declared one a frame lacks.
#[derive(Clone, Copy, Debug)]
pub struct StatDecl {
    pub name: &'static str,
    pub about: &'static str,
}

/// A debug image of a frame (`cbr render` writes it as debug/frame_NNNN_<name>.png).
pub struct DebugPng {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
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

    /// The technique's layer `name`.
    pub fn layer(&self, name: &str) -> Option<&Layer> {
        self.layers.iter().find(|l| l.name == name)
    }

    /// Channel `channel` of layer `layer`, when it holds `T`.
    pub fn channel<T: Sample>(&self, layer: &str, channel: &str) -> Option<&[T]> {
        self.layer(layer)?.channel(channel)
    }

    pub fn stat(&self, name: &str) -> Option<&Stat> {
        self.stats.get(name)
    }

    /// Statistic `name` when it is a count.
    pub fn count(&self, name: &str) -> Option<u64> {
        match self.stats.get(name)? {
            Stat::Count(n) => Some(*n),
            _ => None,
        }
    }

    /// Statistic `name` when it is a flag.
    pub fn flag(&self, name: &str) -> Option<bool> {
        match self.stats.get(name)? {
            Stat::Flag(b) => Some(*b),
            _ => None,
        }
    }

    pub fn set_stat(&mut self, name: &str, value: Stat) {
        self.stats.insert(name.to_string(), value);
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

impl<'a> Geometry<'a> {
    /// The geometry of a pass that writes colour, depth, velocity and IDs as four full-resolution
    /// layers, in that order (`upscale`, `interlaced`).
    pub fn of_layers([_, depth, velocity, ids]: [&'a Image; 4]) -> Geometry<'a> {
        Geometry {
            velocity,
            depth,
            ids,
            packed: false,
        }
    }
}
