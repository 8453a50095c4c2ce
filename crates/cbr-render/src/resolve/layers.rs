//! What a resolved frame (the checkerboard resolve, and `interlaced`'s, which writes the same
//! debug bits) adds to its [`FrameOutput`]: the `resolve_reset` and `parity` statistics, and
//! with `debug` one 0/1 layer per debug bit ([`DEBUG_VIEWS`]: `resolve_parity`,
//! `resolve_missing`, ...) and `resolve_velocity`; their debug PNGs.

use cbr_gpu::{GpuError, Result};

use super::DEBUG_VIEWS;
use crate::frame::{DebugPng, ExrType, FrameOutput, LayerDecl, SampleType, Stat, StatDecl};

const fn bit_layer(name: &'static str) -> LayerDecl {
    LayerDecl {
        name,
        channels: &["Y"],
        samples: SampleType::U8,
        exr: Some(ExrType::Float),
        about: "1 where the resolve's debug bit of that name is set (with `debug`)",
    }
}

/// One layer per debug view, in [`DEBUG_VIEWS`]' order (a unit test holds the names to it),
/// then the velocity each pixel used.
pub const DEBUG_LAYERS: [LayerDecl; 9] = [
    bit_layer("resolve_parity"),
    bit_layer("resolve_missing"),
    bit_layer("resolve_reprojected"),
    bit_layer("resolve_rejected_id"),
    bit_layer("resolve_rejected_depth"),
    bit_layer("resolve_clamped"),
    bit_layer("resolve_spatial"),
    bit_layer("resolve_still"),
    LayerDecl {
        name: "resolve_velocity",
        channels: &["X", "Y"],
        samples: SampleType::F32,
        exr: Some(ExrType::Float),
        about: "the velocity each pixel's resolve used, in pixels (with `debug`)",
    },
];

/// The statistics of a frame with a resolve (and of a raw checkerboard frame: its parity).
pub const STATS: [StatDecl; 2] = [
    StatDecl {
        name: "parity",
        about: "the frame's parity: which half of the pixels (or rows) it shaded",
    },
    StatDecl {
        name: "resolve_reset",
        about: "whether the resolve's history was reset (first frame, a gap, a camera cut)",
    },
];

/// What the resolve adds to a frame's output, typed: whether history was reset, and with
/// `debug` the debug bits (DBG_*) and the velocity each pixel used.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResolveOutput {
    pub reset: bool,
    /// Per pixel: the resolve::DBG_* bits (with `debug`).
    pub debug_bits: Option<Vec<u32>>,
    /// Per pixel: the velocity the resolve used (with `debug`).
    pub velocity: Option<Vec<[f32; 2]>>,
}

impl ResolveOutput {
    /// Writes this into `out` (of `out.width` x `out.height`): the `resolve_reset` statistic and
    /// the debug layers. A debug bit outside [`DEBUG_VIEWS`] is an error (it would be lost).
    pub fn write(&self, out: &mut FrameOutput) -> Result<()> {
        let (w, h) = (out.width, out.height);
        out.set_stat("resolve_reset", Stat::Flag(self.reset));
        if let Some(bits) = &self.debug_bits {
            let all = DEBUG_VIEWS.iter().fold(0, |a, (_, b)| a | b);
            if let Some(b) = bits.iter().find(|&&b| b & !all != 0) {
                return Err(GpuError::Other(format!(
                    "resolve debug bits {b:#x}: a bit no debug view names"
                )));
            }
            for ((_, bit), decl) in DEBUG_VIEWS.iter().zip(&DEBUG_LAYERS) {
                let plane = bits.iter().map(|b| u8::from(b & bit != 0)).collect();
                out.layers.push(decl.layer(w, h, vec![plane])?);
            }
        }
        if let Some(v) = &self.velocity {
            let planes = vec![
                v.iter().map(|v| v[0]).collect(),
                v.iter().map(|v| v[1]).collect(),
            ];
            out.layers.push(DEBUG_LAYERS[8].layer(w, h, planes)?);
        }
        Ok(())
    }

    /// A frame's resolve outputs, when it was resolved.
    pub fn from_frame(out: &FrameOutput) -> Option<ResolveOutput> {
        let reset = out.flag("resolve_reset")?;
        let mut bits: Option<Vec<u32>> = None;
        for ((_, bit), decl) in DEBUG_VIEWS.iter().zip(&DEBUG_LAYERS) {
            let Some(plane) = out.channel::<u8>(decl.name, "Y") else {
                break;
            };
            let b = bits.get_or_insert_with(|| vec![0; plane.len()]);
            for (b, &p) in b.iter_mut().zip(plane) {
                if p != 0 {
                    *b |= bit;
                }
            }
        }
        let velocity = out.layer(DEBUG_LAYERS[8].name).and_then(|l| {
            let (x, y) = (l.channel::<f32>("X")?, l.channel::<f32>("Y")?);
            Some(x.iter().zip(y).map(|(&x, &y)| [x, y]).collect())
        });
        Some(ResolveOutput {
            reset,
            debug_bits: bits,
            velocity,
        })
    }
}

/// The debug PNGs of a resolved frame with `debug` (none otherwise): one per view, white where
/// the bit is set (`parity`, `missing`, ...), the velocity (|v| on a log scale, 0..16 px) and
/// the object IDs (hashed colours).
pub fn debug_pngs(out: &FrameOutput, _display: &[u8]) -> Vec<DebugPng> {
    let (w, h) = (out.width, out.height);
    let png = |name: &str, rgba: Vec<u8>| DebugPng {
        name: name.to_string(),
        width: w,
        height: h,
        rgba,
    };
    let mut pngs = Vec::new();
    let views = DEBUG_VIEWS.iter().zip(&DEBUG_LAYERS);
    let planes: Vec<(&str, &[u8])> = views
        .filter_map(|((name, _), d)| Some((*name, out.channel::<u8>(d.name, "Y")?)))
        .collect();
    if planes.is_empty() {
        return pngs;
    }
    for (name, plane) in planes {
        let rgba = plane
            .iter()
            .flat_map(|&b| {
                let v = if b != 0 { 255 } else { 0 };
                [v, v, v, 255]
            })
            .collect();
        pngs.push(png(name, rgba));
    }
    if let Some(v) = ResolveOutput::from_frame(out).and_then(|r| r.velocity) {
        let rgba = v
            .iter()
            .flat_map(|v| {
                let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
                let t = ((1.0 + len).log2() / 17f32.log2()).clamp(0.0, 1.0);
                let g = (t * 255.0).round() as u8;
                [g, g, g, 255]
            })
            .collect();
        pngs.push(png("velocity", rgba));
    }
    let rgba = out
        .ids
        .iter()
        .flat_map(|id| {
            let hsh = id[0].wrapping_mul(2654435761);
            [(hsh >> 24) as u8, (hsh >> 16) as u8, (hsh >> 8) as u8, 255]
        })
        .collect();
    pngs.push(png("ids", rgba));
    pngs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_names_follow_the_views() {
        for ((view, _), d) in DEBUG_VIEWS.iter().zip(&DEBUG_LAYERS) {
            assert_eq!(d.name, format!("resolve_{view}"));
        }
        assert_eq!(DEBUG_LAYERS.len(), DEBUG_VIEWS.len() + 1);
    }

    #[test]
    fn debug_bits_round_trip_through_the_layers() {
        let mut out = FrameOutput::new(3, 1, vec![], vec![], vec![], vec![]);
        let r = ResolveOutput {
            reset: true,
            debug_bits: Some(vec![0, 0xff, 0x41]),
            velocity: Some(vec![[1.0, -2.0], [0.5, 0.0], [0.0, 3.0]]),
        };
        r.write(&mut out).expect("written");
        assert_eq!(out.layers.len(), 9);
        assert_eq!(ResolveOutput::from_frame(&out), Some(r));
        let mut bad = FrameOutput::new(1, 1, vec![], vec![], vec![], vec![]);
        let r = ResolveOutput {
            debug_bits: Some(vec![0x100]),
            ..ResolveOutput::default()
        };
        assert!(r.write(&mut bad).is_err(), "a bit no view names");
    }
}
