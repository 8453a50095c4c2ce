//! What `interleaved:...:debug` adds to a frame (docs/interleaved.md, the debug views): the
//! `interleaved` layer (subset, edge, fallback per pixel), the split mosaic (host only: its own
//! size), the `interleaved.*` statistics of run.json and the debug PNGs.

use cbr_gpu::Result;

use crate::frame::{DebugPng, ExrType, FrameOutput, LayerDecl, SampleType, Stat, StatDecl};

/// `interleaved` (with `debug`): per pixel its VPL subset, the edge mask and the subsets it
/// shaded itself.
pub const DEBUG_LAYER: LayerDecl = LayerDecl {
    name: "interleaved",
    channels: &["subset", "edge", "fallback"],
    samples: SampleType::U8,
    exr: Some(ExrType::Float),
    about: "subset: the pixel's VPL subset; edge: the filter's window holds another surface \
            (`seed`: the seed's edge test); fallback: the subsets the pixel shaded itself",
};

/// `interleaved_mosaic` (with `debug`, not `implicit`): the split mosaic of the subset estimates
/// (M Ws x N Hs texels, RGB); on the host only (not the frame's size).
pub const MOSAIC_LAYER: LayerDecl = LayerDecl {
    name: "interleaved_mosaic",
    channels: &["R", "G", "B"],
    samples: SampleType::F32,
    exr: None,
    about: "the split mosaic of the subset estimates (irradiance)",
};

/// run.json's per-frame `interleaved` object (with `debug`).
pub const STATS: [StatDecl; 7] = [
    StatDecl {
        name: "interleaved.tile",
        about: "M, N",
    },
    StatDecl {
        name: "interleaved.visible_pixels",
        about: "pixels on a surface",
    },
    StatDecl {
        name: "interleaved.edge_pixels",
        about: "pixels on a surface whose filter window holds another surface",
    },
    StatDecl {
        name: "interleaved.fallback_pixels",
        about: "pixels on a surface that shaded a subset themselves",
    },
    StatDecl {
        name: "interleaved.fallback_subsets_per_visible_pixel",
        about: "the mean number of subsets a pixel on a surface shaded itself",
    },
    StatDecl {
        name: "interleaved.roundtrip_mismatches",
        about: "pixels where the split G-buffer gathered back differs from the G-buffer (0 \
                unless the split and gather are not inverses)",
    },
    StatDecl {
        name: "interleaved.flat_tile_pixels",
        about: "pixels on a surface in a flat tile (`flat=on`): their filter took the window's \
                mean without its same-surface tests",
    },
];

/// The debug views, typed.
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
    /// Pixels on a surface whose workgroup's tile was flat (`flat=on`, filter.glsl's FLAT_TILES).
    pub flat_tile_pixels: u64,
    /// The split mosaic of the subset estimates (M Ws x N Hs texels, RGB); `None` with
    /// `implicit`, which has no split.
    pub mosaic: Option<(u32, u32, Vec<[f32; 3]>)>,
}

impl InterleavedLayers {
    /// Writes the views into `out` (whose IDs are the frame's): the layers and the statistics.
    pub fn write(&self, out: &mut FrameOutput) -> Result<()> {
        let (w, h) = (out.width, out.height);
        let planes = vec![
            self.subset.clone(),
            self.edge.clone(),
            self.fallback.clone(),
        ];
        out.layers.push(DEBUG_LAYER.layer(w, h, planes)?);
        if let Some((mw, mh, texels)) = &self.mosaic {
            let planes = (0..3).map(|c| texels.iter().map(|t| t[c]).collect());
            out.layers
                .push(MOSAIC_LAYER.layer(*mw, *mh, planes.collect())?);
        }
        let drawn: Vec<bool> = out.ids.iter().map(|id| id[0] != 0).collect();
        let count = |v: &[u8]| v.iter().zip(&drawn).filter(|&(&x, &d)| x != 0 && d).count() as u64;
        let visible = drawn.iter().filter(|&&d| d).count() as u64;
        let shaded: u64 = self.fallback.iter().map(|&x| u64::from(x)).sum();
        let (m, n) = self.tile;
        let stats = [
            Stat::Counts(vec![u64::from(m), u64::from(n)]),
            Stat::Count(visible),
            Stat::Count(count(&self.edge)),
            Stat::Count(count(&self.fallback)),
            Stat::Real(if visible > 0 {
                shaded as f64 / visible as f64
            } else {
                0.0
            }),
            Stat::Count(self.roundtrip_mismatches),
            Stat::Count(self.flat_tile_pixels),
        ];
        for (d, s) in STATS.iter().zip(stats) {
            out.set_stat(d.name, s);
        }
        Ok(())
    }

    /// A frame's debug views, when it has them.
    pub fn from_frame(out: &FrameOutput) -> Option<InterleavedLayers> {
        let l = out.layer(DEBUG_LAYER.name)?;
        let tile = match out.stat("interleaved.tile")? {
            Stat::Counts(t) if t.len() == 2 => (t[0] as u32, t[1] as u32),
            _ => return None,
        };
        let mosaic = out.layer(MOSAIC_LAYER.name).and_then(|m| {
            let (r, g, b) = (m.channel::<f32>("R")?, m.channel("G")?, m.channel("B")?);
            let texels = r.iter().zip(g).zip(b).map(|((&r, &g), &b)| [r, g, b]);
            Some((m.width, m.height, texels.collect()))
        });
        Some(InterleavedLayers {
            tile,
            subset: l.channel::<u8>("subset")?.to_vec(),
            edge: l.channel::<u8>("edge")?.to_vec(),
            fallback: l.channel::<u8>("fallback")?.to_vec(),
            roundtrip_mismatches: out.count("interleaved.roundtrip_mismatches")?,
            flat_tile_pixels: out.count("interleaved.flat_tile_pixels")?,
            mosaic,
        })
    }
}

/// `interleaved:...:debug`: interleaved_{mosaic,subset,edges,fallback}: the split mosaic of the
/// subset estimates (x / (1 + x), sRGB-like 1/2.2; not with `implicit`), the subset index (grey
/// k / (M N - 1)), the edge mask (white) and the fallback (black none, then dark red to yellow as
/// the subsets shaded at the pixel go from 1 to M N).
pub fn debug_pngs(out: &FrameOutput, _display: &[u8]) -> Vec<DebugPng> {
    let Some(i) = InterleavedLayers::from_frame(out) else {
        return Vec::new();
    };
    let mut pngs = Vec::new();
    let mut png = |name: &str, width: u32, height: u32, rgba: Vec<u8>| {
        pngs.push(DebugPng {
            name: format!("interleaved_{name}"),
            width,
            height,
            rgba,
        })
    };
    if let Some((w, h, texels)) = &i.mosaic {
        // Its own curve, not the frame's display transform: the mosaic holds irradiance without
        // albedo, dim at the frame's exposure (lit sub-images then read as black).
        let tone = |x: f32| {
            let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
            ((x / (1.0 + x)).powf(1.0 / 2.2) * 255.0).round() as u8
        };
        let rgba = texels
            .iter()
            .flat_map(|t| [tone(t[0]), tone(t[1]), tone(t[2]), 255])
            .collect();
        png("mosaic", *w, *h, rgba);
    }
    let (w, h) = (out.width, out.height);
    let subsets = (i.tile.0 * i.tile.1).max(2) - 1;
    let grey = |v: u8| [v, v, v, 255];
    png(
        "subset",
        w,
        h,
        i.subset
            .iter()
            .flat_map(|&k| grey((u32::from(k) * 255 / subsets) as u8))
            .collect(),
    );
    png(
        "edges",
        w,
        h,
        i.edge.iter().flat_map(|&e| grey(e * 255)).collect(),
    );
    let all = (i.tile.0 * i.tile.1) as f32;
    let heat = |n: u8| {
        if n == 0 {
            return [0, 0, 0, 255];
        }
        let t = f32::from(n) / all;
        [
            (128.0 + 127.0 * t.min(0.5) * 2.0) as u8,
            (255.0 * ((t - 0.5).max(0.0) * 2.0)) as u8,
            0,
            255,
        ]
    };
    png(
        "fallback",
        w,
        h,
        i.fallback.iter().flat_map(|&n| heat(n)).collect(),
    );
    pngs
}
