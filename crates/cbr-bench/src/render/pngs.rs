//! The debug PNGs of particular techniques, under debug/ in `cbr render`'s output folder: the
//! resolve's views, `analytic:seed`'s figure, `interleaved:...:debug`'s views.

use std::path::Path;

use anyhow::{Context, Result};
use cbr_metrics::io::write_png_rgba8;
use cbr_render::FrameOutput;
use cbr_render::resolve::DEBUG_VIEWS;

/// Every debug PNG of frame `f` (none for most techniques); `rgba` is the displayed frame.
pub fn write(dir: &Path, f: u32, out: &FrameOutput, rgba: &[u8]) -> Result<()> {
    write_debug_pngs(dir, f, out)?;
    write_seed_figure(dir, f, out, rgba)?;
    write_interleaved_pngs(dir, f, out)
}

/// `interleaved:...:debug`: debug/frame_NNNN_interleaved_{mosaic,subset,edges,fallback}.png: the
/// split mosaic of the subset estimates (x / (1 + x), sRGB-like 1/2.2; not with `implicit`), the
/// subset index (grey k / (M N - 1)), the edge mask (white) and the fallback (black none, then
/// dark red to yellow as the subsets shaded at the pixel go from 1 to M N).
fn write_interleaved_pngs(dir: &Path, f: u32, out: &FrameOutput) -> Result<()> {
    let Some(i) = &out.interleaved else {
        return Ok(());
    };
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let png = |name: &str, w: u32, h: u32, rgba: Vec<u8>| {
        write_png_rgba8(
            &dbg.join(format!("frame_{f:04}_interleaved_{name}.png")),
            w,
            h,
            &rgba,
        )
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
        png("mosaic", *w, *h, rgba)?;
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
    )?;
    png(
        "edges",
        w,
        h,
        i.edge.iter().flat_map(|&e| grey(e * 255)).collect(),
    )?;
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
    )?;
    Ok(())
}

/// `analytic:seed`: debug/frame_NNNN_seed_differs.png, the frame with the pixels where the seed's
/// shortcut is off the exact area by more than 1e-3 in red (docs/analytic.md's figure).
fn write_seed_figure(dir: &Path, f: u32, out: &FrameOutput, rgba: &[u8]) -> Result<()> {
    let Some(a) = &out.analytic else {
        return Ok(());
    };
    if !a.seed_differs.iter().any(|&s| s != 0) {
        return Ok(());
    }
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let marked: Vec<u8> = rgba
        .chunks_exact(4)
        .zip(&a.seed_differs)
        .flat_map(|(p, &s)| {
            if s != 0 {
                [255, 0, 0, 255]
            } else {
                // The rest dimmed, so the marks stand out.
                [p[0] / 3, p[1] / 3, p[2] / 3, 255]
            }
        })
        .collect();
    write_png_rgba8(
        &dbg.join(format!("frame_{f:04}_seed_differs.png")),
        out.width,
        out.height,
        &marked,
    )?;
    Ok(())
}

/// PNGs of the debug views: debug/frame_NNNN_<view>.png (white where the bit is set), the
/// velocity (|v| on a log scale, 0..16 px) and the object IDs (hashed colours).
fn write_debug_pngs(dir: &Path, f: u32, out: &FrameOutput) -> Result<()> {
    let Some(r) = &out.resolve else {
        return Ok(());
    };
    let Some(bits) = &r.debug_bits else {
        return Ok(());
    };
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    let (w, h) = (out.width, out.height);
    let png = |name: &str, rgba: Vec<u8>| {
        write_png_rgba8(&dbg.join(format!("frame_{f:04}_{name}.png")), w, h, &rgba)
    };
    for (name, bit) in DEBUG_VIEWS {
        let rgba = bits
            .iter()
            .flat_map(|b| {
                let v = if b & bit != 0 { 255 } else { 0 };
                [v, v, v, 255]
            })
            .collect();
        png(name, rgba)?;
    }
    if let Some(v) = &r.velocity {
        let rgba = v
            .iter()
            .flat_map(|v| {
                let len = (v[0] * v[0] + v[1] * v[1]).sqrt();
                let t = ((1.0 + len).log2() / 17f32.log2()).clamp(0.0, 1.0);
                let g = (t * 255.0).round() as u8;
                [g, g, g, 255]
            })
            .collect();
        png("velocity", rgba)?;
    }
    let rgba = out
        .ids
        .iter()
        .flat_map(|id| {
            let hsh = id[0].wrapping_mul(2654435761);
            [(hsh >> 24) as u8, (hsh >> 16) as u8, (hsh >> 8) as u8, 255]
        })
        .collect();
    png("ids", rgba)?;
    Ok(())
}
