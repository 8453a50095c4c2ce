//! A frame's debug PNGs, under debug/ in `cbr render`'s output folder: what the spec's
//! technique's registration draws of the frame (`outputs.pngs`: the resolve's views,
//! `analytic:seed`'s figure, `interleaved:...:debug`'s views), named debug/frame_NNNN_<name>.png.

use std::path::Path;

use anyhow::{Context, Result};
use cbr_metrics::io::write_png_rgba8;
use cbr_render::{FrameOutput, Spec};

/// Every debug PNG of frame `f` (none for most techniques); `rgba` is the displayed frame.
pub fn write(dir: &Path, f: u32, spec: &Spec, out: &FrameOutput, rgba: &[u8]) -> Result<()> {
    let Some(draw) = cbr_render::registry::find(&spec.technique.name).and_then(|r| r.outputs.pngs)
    else {
        return Ok(());
    };
    let pngs = draw(out, rgba);
    if pngs.is_empty() {
        return Ok(());
    }
    let dbg = dir.join("debug");
    std::fs::create_dir_all(&dbg).with_context(|| format!("cannot create {}", dbg.display()))?;
    for p in pngs {
        let path = dbg.join(format!("frame_{f:04}_{}.png", p.name));
        write_png_rgba8(&path, p.width, p.height, &p.rgba)?;
    }
    Ok(())
}
