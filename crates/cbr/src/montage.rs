//! `cbr montage`: side-by-side strips of 8-bit images (the PNGs `render` and `bench` write, FLIP
//! maps included), optionally cropped to one window and enlarged by pixel replication; the
//! picture strips of docs/hard-cases.md are made with it.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};

#[derive(clap::Args)]
pub struct MontageArgs {
    /// Images (PNG, JPEG, ...), placed left to right, then row by row; `-` leaves a tile blank.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// The window of every image to keep, x,y,w,h in pixels (default: the whole image).
    #[arg(long, value_name = "X,Y,W,H")]
    crop: Option<String>,
    /// Images per row (default: all in one row).
    #[arg(long)]
    columns: Option<usize>,
    /// Enlarge each tile this many times by pixel replication (1 to 16).
    #[arg(long, default_value_t = 1)]
    scale: u32,
    /// White pixels between tiles.
    #[arg(long, default_value_t = 2)]
    gap: u32,
    /// The strip, a PNG.
    #[arg(short, long)]
    out: PathBuf,
}

fn parse_crop(s: &str) -> Result<[u32; 4]> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--crop {s}: expected x,y,w,h (whole pixels)"))?;
    match v[..] {
        [x, y, w, h] if w > 0 && h > 0 => Ok([x, y, w, h]),
        _ => bail!("--crop {s}: expected x,y,w,h with a positive width and height"),
    }
}

pub fn run(a: &MontageArgs) -> Result<()> {
    if !(1..=16).contains(&a.scale) {
        bail!("--scale {}: give 1 to 16", a.scale);
    }
    if a.gap > 64 {
        bail!("--gap {}: give at most 64 pixels", a.gap);
    }
    let crop = a.crop.as_deref().map(parse_crop).transpose()?;
    let mut tiles = Vec::with_capacity(a.images.len());
    let mut blanks = Vec::new();
    for (i, path) in a.images.iter().enumerate() {
        if path.as_os_str() == "-" {
            blanks.push(i);
            continue;
        }
        let img = image::open(path)
            .with_context(|| format!("{}: cannot read the image", path.display()))?
            .to_rgba8();
        let (w, h) = img.dimensions();
        let [x, y, cw, ch] = crop.unwrap_or([0, 0, w, h]);
        if u64::from(x) + u64::from(cw) > u64::from(w)
            || u64::from(y) + u64::from(ch) > u64::from(h)
        {
            bail!(
                "{}: the crop {x},{y},{cw},{ch} does not fit its {w}x{h} pixels",
                path.display()
            );
        }
        tiles.push(image::imageops::crop_imm(&img, x, y, cw, ch).to_image());
    }
    let Some(first) = tiles.first() else {
        bail!("every image is `-`: nothing to place");
    };
    let (tw, th) = first.dimensions();
    if let Some((p, t)) = a
        .images
        .iter()
        .filter(|p| p.as_os_str() != "-")
        .zip(&tiles)
        .find(|(_, t)| t.dimensions() != (tw, th))
    {
        bail!(
            "{}: {}x{} pixels, and the first image {}x{} (give images of one size, or --crop)",
            p.display(),
            t.width(),
            t.height(),
            tw,
            th
        );
    }
    let columns = a.columns.unwrap_or(tiles.len()).clamp(1, tiles.len());
    let rows = tiles.len().div_ceil(columns);
    let (sw, sh) = (u64::from(tw * a.scale), u64::from(th * a.scale));
    let gap = u64::from(a.gap);
    let width = columns as u64 * sw + (columns as u64 - 1) * gap;
    let height = rows as u64 * sh + (rows as u64 - 1) * gap;
    if width > 32768 || height > 32768 {
        bail!("the strip would be {width}x{height} pixels; at most 32768 per side");
    }
    let (width, height) = (width as u32, height as u32);
    let mut out = image::RgbaImage::from_pixel(width, height, image::Rgba([255; 4]));
    let blank = image::RgbaImage::from_pixel(tw, th, image::Rgba([255; 4]));
    for &i in &blanks {
        tiles.insert(i, blank.clone());
    }
    for (i, t) in tiles.iter().enumerate() {
        let (cx, cy) = ((i % columns) as u64, (i / columns) as u64);
        let (ox, oy) = ((cx * (sw + gap)) as u32, (cy * (sh + gap)) as u32);
        for y in 0..th * a.scale {
            for x in 0..tw * a.scale {
                out.put_pixel(ox + x, oy + y, *t.get_pixel(x / a.scale, y / a.scale));
            }
        }
    }
    cbr_metrics::io::write_png_rgba8(&a.out, width, height, out.as_raw())
        .with_context(|| format!("{}: cannot write the strip", a.out.display()))?;
    println!(
        "{}: {} images, {columns} per row, {width}x{height}",
        a.out.display(),
        tiles.len()
    );
    Ok(())
}
