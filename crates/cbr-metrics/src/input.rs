//! Loading the images to compare: EXR (a chosen layer and channels, linear HDR) or PNG/JPEG/...
//! (sRGB-encoded LDR).

use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use exr::prelude::*;
use std::result::Result;

use crate::error::MetricsError;
use crate::planes::{Plane, Rgb};

/// How the stored values relate to light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// Linear HDR radiance (EXR).
    Linear,
    /// sRGB-encoded display values in [0, 1] (PNG, JPEG, ...).
    Srgb,
}

pub struct InputImage {
    pub path: PathBuf,
    /// The EXR layer and channels read (empty for LDR files).
    pub layer: String,
    pub channels: Vec<String>,
    pub rgb: Rgb,
    pub encoding: Encoding,
}

fn err(path: &Path, msg: impl Into<String>) -> MetricsError {
    MetricsError::Input {
        path: path.to_path_buf(),
        msg: msg.into(),
    }
}

/// The first four bytes of every OpenEXR file.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Loads `path`. For EXR, `layer` defaults to `color` (else the first layer with R, G and B, else
/// the first layer) and `channels` to R,G,B (else the layer's first channel); one channel is
/// replicated to grey. The format is found from the contents (see [`read`]).
pub fn load(
    path: &Path,
    layer: Option<&str>,
    channels: Option<&[String]>,
) -> Result<InputImage, MetricsError> {
    if path.is_dir() {
        return Err(err(path, "is a directory, not an image"));
    }
    if !path.is_file() {
        return Err(err(path, "no such file"));
    }
    let file = std::fs::File::open(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
    read(path, BufReader::new(file), layer, channels)
}

/// Reads an image from `reader`; `path` names it in errors and in [`InputImage::path`]. EXR is
/// recognised by its magic number or the `.exr` extension; anything else goes to the `image` crate (PNG, JPEG, TGA, BMP),
/// which guesses from the contents, else from the extension.
pub fn read(
    path: &Path,
    mut reader: impl BufRead + Seek,
    layer: Option<&str>,
    channels: Option<&[String]>,
) -> Result<InputImage, MetricsError> {
    let head = reader
        .fill_buf()
        .map_err(|e| err(path, format!("cannot read: {e}")))?;
    let exr_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if head.starts_with(&EXR_MAGIC) || exr_name {
        read_exr(path, reader, layer, channels)
    } else {
        read_ldr(path, reader)
    }
}

fn read_ldr(path: &Path, mut reader: impl BufRead + Seek) -> Result<InputImage, MetricsError> {
    let io = |e: std::io::Error| err(path, format!("cannot read: {e}"));
    let decode_err = |e| err(path, format!("cannot decode: {e}"));
    let start = reader.stream_position().map_err(io)?;
    fn open<R: BufRead + Seek>(path: &Path, reader: R) -> std::io::Result<image::ImageReader<R>> {
        let mut r = image::ImageReader::new(reader);
        if let Ok(format) = image::ImageFormat::from_path(path) {
            r.set_format(format);
        }
        r.with_guessed_format()
    }
    // The header first: a few bytes can declare gigapixels (as for EXR, check_exr_size).
    let (w, h) = open(path, &mut reader)
        .map_err(io)?
        .into_dimensions()
        .map_err(decode_err)?;
    if w as usize > MAX_EXR_SIDE || h as usize > MAX_EXR_SIDE {
        return Err(err(
            path,
            format!("image is {w}x{h} pixels; at most {MAX_EXR_SIDE} per side"),
        ));
    }
    reader.seek(SeekFrom::Start(start)).map_err(io)?;
    let img = open(path, &mut reader)
        .map_err(io)?
        .decode()
        .map_err(decode_err)?;
    let rgb = img.to_rgb32f();
    let (w, h) = rgb.dimensions();
    Ok(InputImage {
        path: path.to_path_buf(),
        layer: String::new(),
        channels: vec![],
        rgb: Rgb::from_interleaved(w as usize, h as usize, rgb.as_raw()),
        encoding: Encoding::Srgb,
    })
}

/// The widest and tallest image (EXR layer, PNG, ...) read: cbr's largest resolution.
pub const MAX_EXR_SIDE: usize = 16384;
/// The most bytes of samples an EXR may decode to (every layer and channel is decoded).
pub const MAX_EXR_BYTES: u64 = 8 << 30;

/// Refuses, from the headers alone, an EXR whose layers exceed [`MAX_EXR_SIDE`] or whose samples
/// need more than [`MAX_EXR_BYTES`]: the decoder allocates every layer at its declared size
/// before reading a block, so a few bytes of header could ask for terabytes. Leaves `reader`
/// where it was.
fn check_exr_size(path: &Path, reader: &mut (impl BufRead + Seek)) -> Result<(), MetricsError> {
    let io = |e: std::io::Error| err(path, format!("cannot read: {e}"));
    let start = reader.stream_position().map_err(io)?;
    let meta = exr::meta::MetaData::read_from_buffered(&mut *reader, false)
        .map_err(|e| err(path, format!("cannot read EXR: {e}")))?;
    reader.seek(SeekFrom::Start(start)).map_err(io)?;
    let mut bytes = 0u64;
    for (i, h) in meta.headers.iter().enumerate() {
        let Vec2(w, hgt) = h.layer_size;
        if w > MAX_EXR_SIDE || hgt > MAX_EXR_SIDE {
            let name = h
                .own_attributes
                .layer_name
                .as_ref()
                .map(|n| format!("`{n}`"))
                .unwrap_or_else(|| format!("{i}"));
            return Err(err(
                path,
                format!("layer {name} is {w}x{hgt} pixels; at most {MAX_EXR_SIDE} per side"),
            ));
        }
        bytes += (w as u64) * (hgt as u64) * h.channels.bytes_per_pixel as u64;
    }
    if bytes > MAX_EXR_BYTES {
        return Err(err(
            path,
            format!(
                "the layers need {:.1} GiB decoded; at most {} GiB",
                bytes as f64 / f64::from(1u32 << 30),
                MAX_EXR_BYTES >> 30
            ),
        ));
    }
    Ok(())
}

fn read_exr(
    path: &Path,
    mut reader: impl BufRead + Seek,
    layer: Option<&str>,
    channels: Option<&[String]>,
) -> Result<InputImage, MetricsError> {
    check_exr_size(path, &mut reader)?;
    let img = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(reader)
        .map_err(|e| err(path, format!("cannot read EXR: {e}")))?;
    let name_of = |l: &Layer<FlatSamples2>| {
        l.attributes
            .layer_name
            .as_ref()
            .map(|t| t.to_string())
            .unwrap_or_default()
    };
    let has = |l: &Layer<FlatSamples2>, c: &str| {
        l.channel_data
            .list
            .iter()
            .any(|ch| ch.name.to_string() == c)
    };
    let layers = &img.layer_data;
    let chosen = match layer {
        Some(n) => layers.iter().find(|l| name_of(l) == n).ok_or_else(|| {
            let names: Vec<String> = layers.iter().map(name_of).collect();
            err(
                path,
                format!("no layer `{n}` (layers: {})", names.join(", ")),
            )
        })?,
        None => layers
            .iter()
            .find(|l| name_of(l) == "color")
            .or_else(|| {
                layers
                    .iter()
                    .find(|l| ["R", "G", "B"].iter().all(|c| has(l, c)))
            })
            .or_else(|| layers.first())
            .ok_or_else(|| err(path, "no layers"))?,
    };
    let available: Vec<String> = chosen
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let wanted: Vec<String> = match channels {
        Some(c) => c.to_vec(),
        None if ["R", "G", "B"]
            .iter()
            .all(|c| available.iter().any(|a| a == c)) =>
        {
            vec!["R".into(), "G".into(), "B".into()]
        }
        None => available.first().cloned().into_iter().collect(),
    };
    if wanted.len() != 1 && wanted.len() != 3 {
        return Err(err(
            path,
            format!("choose 1 or 3 channels, not {}", wanted.len()),
        ));
    }
    let (w, h) = (chosen.size.0, chosen.size.1);
    let mut planes = Vec::with_capacity(3);
    for c in &wanted {
        let ch = chosen
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == *c)
            .ok_or_else(|| {
                err(
                    path,
                    format!(
                        "layer `{}` has no channel `{c}` (channels: {})",
                        name_of(chosen),
                        available.join(", ")
                    ),
                )
            })?;
        planes.push(Plane {
            width: w,
            height: h,
            data: ch.sample_data.values_as_f32().collect(),
        });
    }
    while planes.len() < 3 {
        planes.push(planes[0].clone());
    }
    let [r, g, b]: [Plane; 3] = planes.try_into().map_err(|_| err(path, "channel count"))?;
    Ok(InputImage {
        path: path.to_path_buf(),
        layer: name_of(chosen),
        channels: wanted,
        rgb: Rgb {
            width: w,
            height: h,
            c: [r, g, b],
        },
        encoding: Encoding::Linear,
    })
}

type FlatSamples2 = AnyChannels<FlatSamples>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// An 8x8 EXR with `n` float channels whose data window is then patched to `side` x `side`.
    fn exr_declaring(n: usize, side: i32) -> Vec<u8> {
        let channels: smallvec::SmallVec<[AnyChannel<FlatSamples>; 4]> = (0..n)
            .map(|i| AnyChannel::new(format!("c{i}").as_str(), FlatSamples::F32(vec![0.5; 64])))
            .collect();
        let layer = Layer::new(
            Vec2(8, 8),
            LayerAttributes::named("big"),
            exr::prelude::Encoding::UNCOMPRESSED,
            AnyChannels::sort(channels),
        );
        let mut out = Cursor::new(Vec::new());
        Image::from_layer(layer)
            .write()
            .to_buffered(&mut out)
            .expect("write");
        let mut bytes = out.into_inner();
        for attr in [&b"dataWindow\0box2i\0"[..], b"displayWindow\0box2i\0"] {
            let at = bytes
                .windows(attr.len())
                .position(|w| w == attr)
                .expect("window attribute")
                + attr.len()
                + 4;
            bytes[at + 8..at + 12].copy_from_slice(&(side - 1).to_le_bytes());
            bytes[at + 12..at + 16].copy_from_slice(&(side - 1).to_le_bytes());
        }
        bytes
    }

    fn read_err(bytes: Vec<u8>) -> String {
        match read(Path::new("big.exr"), Cursor::new(bytes), None, None) {
            Ok(_) => "read".into(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn oversized_exrs_are_refused_from_their_headers() {
        assert_eq!(
            read_err(exr_declaring(3, 8)),
            "read",
            "the unpatched file reads"
        );
        let err = read_err(exr_declaring(1, 20000));
        assert_eq!(
            err,
            "big.exr: layer `big` is 20000x20000 pixels; at most 16384 per side"
        );
        // 16384^2 x 9 f32 channels: 9 GiB.
        let err = read_err(exr_declaring(9, 16384));
        assert_eq!(
            err,
            "big.exr: the layers need 9.0 GiB decoded; at most 8 GiB"
        );
    }

    #[test]
    fn oversized_ldr_images_are_refused_from_their_headers() {
        // A 54-byte BMP header declaring 20000 x 20000 pixels of 24 bits, and no pixels.
        let mut bmp = b"BM".to_vec();
        for v in [54u32, 0, 54, 40, 20000, 20000] {
            bmp.extend_from_slice(&v.to_le_bytes());
        }
        bmp.extend_from_slice(&1u16.to_le_bytes());
        bmp.extend_from_slice(&24u16.to_le_bytes());
        bmp.extend_from_slice(&[0; 24]);
        let err = match read(Path::new("big.bmp"), Cursor::new(bmp), None, None) {
            Ok(_) => "read".into(),
            Err(e) => e.to_string(),
        };
        assert_eq!(
            err,
            "big.bmp: image is 20000x20000 pixels; at most 16384 per side"
        );
    }
}
