//! Loading the images to compare: EXR (a chosen layer and channels, linear HDR) or PNG/JPEG/...
//! (sRGB-encoded LDR).

use std::io::{BufRead, BufReader, Seek};
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

fn read_ldr(path: &Path, reader: impl BufRead + Seek) -> Result<InputImage, MetricsError> {
    let mut r = image::ImageReader::new(reader);
    if let Ok(format) = image::ImageFormat::from_path(path) {
        r.set_format(format);
    }
    let img = r
        .with_guessed_format()
        .map_err(|e| err(path, format!("cannot read: {e}")))?
        .decode()
        .map_err(|e| err(path, format!("cannot decode: {e}")))?;
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

fn read_exr(
    path: &Path,
    reader: impl BufRead + Seek,
    layer: Option<&str>,
    channels: Option<&[String]>,
) -> Result<InputImage, MetricsError> {
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
