//! Writes the seed corpora under fuzz/seeds/<target>/: small files made here, never copied from
//! real scenes. Run from fuzz/: `cargo run --example make_seeds` (docs/fuzzing.md). Each seed of
//! `texture` and `image_input` starts with the selector byte its target reads.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use cbr_metrics::io::{ChannelSamples, FrameLayers, write_frame_exr};
use exr::prelude::*;
use half::f16;
use image::{DynamicImage, ImageFormat};

fn dir(target: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("seeds")
        .join(target);
    std::fs::create_dir_all(&d).expect("seed folder");
    d
}

fn put(target: &str, name: &str, bytes: &[u8]) {
    std::fs::write(dir(target).join(name), bytes).expect("write seed");
}

/// A w x h RGBA8 gradient with a transparent corner.
fn rgba(w: u32, h: u32) -> image::RgbaImage {
    image::RgbaImage::from_fn(w, h, |x, y| {
        let a = if x == 0 && y == 0 { 0 } else { 255 };
        image::Rgba([(x * 60) as u8, (y * 80) as u8, ((x + y) * 30) as u8, a])
    })
}

fn encode(img: &DynamicImage, format: ImageFormat) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, format).expect("encode");
    out.into_inner()
}

fn images() -> Vec<(&'static str, u8, Vec<u8>)> {
    let base = rgba(4, 3);
    let rgba8 = DynamicImage::ImageRgba8(base.clone());
    let rgb8 = DynamicImage::ImageRgb8(rgba8.to_rgb8());
    let l8 = DynamicImage::ImageLuma8(rgba8.to_luma8());
    let la8 = DynamicImage::ImageLumaA8(rgba8.to_luma_alpha8());
    let rgb16 = DynamicImage::ImageRgb16(rgba8.to_rgb16());
    // (name, extension index as the targets number them: 0 png, 1 jpg, 2 tga, 3 bmp), bytes
    vec![
        ("rgba8.png", 0, encode(&rgba8, ImageFormat::Png)),
        ("rgb8.png", 0, encode(&rgb8, ImageFormat::Png)),
        ("l8.png", 0, encode(&l8, ImageFormat::Png)),
        ("la8.png", 0, encode(&la8, ImageFormat::Png)),
        ("rgb16.png", 0, encode(&rgb16, ImageFormat::Png)),
        ("rgb8.jpg", 1, encode(&rgb8, ImageFormat::Jpeg)),
        ("l8.jpg", 1, encode(&l8, ImageFormat::Jpeg)),
        ("rgba8.tga", 2, encode(&rgba8, ImageFormat::Tga)),
        ("rgb8.tga", 2, encode(&rgb8, ImageFormat::Tga)),
        ("rgba8.bmp", 3, encode(&rgba8, ImageFormat::Bmp)),
        ("rgb8.bmp", 3, encode(&rgb8, ImageFormat::Bmp)),
    ]
}

fn texture_seeds() {
    for (name, ext, bytes) in images() {
        for srgb in [0u8, 4] {
            let mut seed = vec![ext | srgb];
            seed.extend_from_slice(&bytes);
            put("texture", &format!("{name}.{srgb}"), &seed);
        }
    }
}

/// A small cbr frame EXR (all layers, what `cbr render` writes) and single-part RGBA EXRs in each
/// compression the exr crate writes, scanline and tiled with mip levels.
fn exr_files(tmp: &Path) -> Vec<(String, Vec<u8>)> {
    let (w, h) = (5u32, 3u32);
    let n = (w * h) as usize;
    let color: Vec<f16> = (0..n * 4).map(|i| f16::from_f32(i as f32 * 0.1)).collect();
    let depth: Vec<f32> = (0..n)
        .map(|i| if i == 0 { f32::INFINITY } else { i as f32 })
        .collect();
    let velocity: Vec<[f32; 2]> = (0..n).map(|i| [i as f32 * 0.5, -1.0]).collect();
    let ids: Vec<[u32; 2]> = (0..n).map(|i| [i as u32 % 3, i as u32]).collect();
    let mask: Vec<f16> = (0..n).map(|i| f16::from_f32((i % 2) as f32)).collect();
    let frame = tmp.join("frame.exr");
    write_frame_exr(
        &frame,
        &FrameLayers {
            width: w,
            height: h,
            color: &color,
            depth: &depth,
            velocity: &velocity,
            ids: &ids,
            extra: vec![("mask".into(), vec![("Y".into(), ChannelSamples::F16(mask))])],
            metadata: vec![("cbr.frame".into(), "0".into())],
        },
    )
    .expect("frame exr");
    let mut out = vec![(
        "frame.exr".to_string(),
        std::fs::read(&frame).expect("read"),
    )];
    let pixels = |pos: Vec2<usize>| {
        let v = (pos.x() + pos.y()) as f32 * 0.25;
        (v, v * 0.5, 1.0 - v, 1.0)
    };
    for (cname, compression) in [
        ("none", Compression::Uncompressed),
        ("rle", Compression::RLE),
        ("zip1", Compression::ZIP1),
        ("zip16", Compression::ZIP16),
        ("piz", Compression::PIZ),
        ("pxr24", Compression::PXR24),
        ("b44", Compression::B44),
        ("b44a", Compression::B44A),
    ] {
        for tiled in [false, true] {
            let path = tmp.join(format!("{cname}{}.exr", if tiled { "-tiled" } else { "" }));
            let channels = SpecificChannels::rgba(|p: Vec2<usize>| {
                let (r, g, b, a) = pixels(p);
                (f16::from_f32(r), g, b, f16::from_f32(a))
            });
            let encoding = Encoding {
                compression,
                blocks: if tiled {
                    Blocks::Tiles(Vec2(4, 4))
                } else {
                    Blocks::ScanLines
                },
                line_order: LineOrder::Increasing,
            };
            let layer = Layer::new(
                Vec2(6, 5),
                LayerAttributes::named("rgba"),
                encoding,
                channels,
            );
            match Image::from_layer(layer).write().to_file(&path) {
                Ok(()) => out.push((
                    path.file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    std::fs::read(&path).expect("read"),
                )),
                Err(e) => eprintln!("skipped {cname} tiled={tiled}: {e}"),
            }
        }
    }
    out
}

fn image_input_seeds() {
    let tmp = std::env::temp_dir().join(format!("cbr-seeds-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).expect("tmp");
    for (name, bytes) in exr_files(&tmp) {
        // Selector: extension 0 (exr); layer/channels 0 (defaults), 1 (depth Z), 2 (color RGB).
        for sel in [0u8, 4, 8] {
            if sel != 0 && name != "frame.exr" {
                continue;
            }
            let mut seed = vec![sel];
            seed.extend_from_slice(&bytes);
            put("image_input", &format!("{name}.{sel}"), &seed);
        }
    }
    std::fs::remove_dir_all(&tmp).expect("clean tmp");
    // Extension index 1 png, 2 jpg, 3 tga (the texture targets number them 0 png, 1 jpg, 2 tga).
    for (name, ext, bytes) in images() {
        if ext > 2 {
            continue;
        }
        let mut seed = vec![ext + 1];
        seed.extend_from_slice(&bytes);
        put("image_input", name, &seed);
    }
}

fn obj_seeds() {
    let png = encode(&DynamicImage::ImageRgba8(rgba(2, 2)), ImageFormat::Png);
    let tri = "mtllib in.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
               usemtl m\nf 1/1/1 2/2/1 3/3/1\n";
    let quads = "# a quad and a pentagon, negative indices, groups, CRLF\r\nmtllib in.mtl\r\n\
                 o Quad\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nvt 0 0\r\nvt 1 1\r\n\
                 usemtl m\r\nf -4/-2 -3/-1 -2/-1 -1/-2\r\ng Pent\r\nv 2 0 0\r\nv 3 0 0\r\n\
                 v 3 1 1\r\nv 2.5 2 0\r\nv 2 1 0\r\nusemtl other\r\nf 5 6 7 8 9\r\nf 1 2\r\n\
                 l 1 2\r\np 3\r\ns 1\r\n";
    let no_uv = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1//1 2//1 4//1\nvn 0 1 0\n\
                 f 1//1 3//1 4//1\nf 2 2 3\n";
    let mtl = "newmtl m\nKa 0.1 0.1 0.1\nKd 0.8 0.7 0.6\nKs 0.5\nNs 32\nNi 1.5\nd 1\nillum 2\n\
               map_Kd tex.png\nmap_d tex.png\nmap_bump -bm 0.5 tex.png\n\
               newmtl other\nKd 0.2 0.3 0.4\nKe 1 1 1\nbump .\\tex.png\ndisp tex.png\n";
    let plain_mtl = "newmtl m\nKd 1 0 0\n";
    let join = |parts: &[&[u8]]| parts.join(&0u8);
    put("obj", "tri", &join(&[tri.as_bytes(), mtl.as_bytes(), &png]));
    put(
        "obj",
        "quads",
        &join(&[quads.as_bytes(), mtl.as_bytes(), &png]),
    );
    put("obj", "no_uv", no_uv.as_bytes());
    put(
        "obj",
        "plain",
        &join(&[tri.as_bytes(), plain_mtl.as_bytes()]),
    );
    put(
        "obj",
        "missing_texture",
        &join(&[tri.as_bytes(), b"newmtl m\nmap_Kd nothere.png\n"]),
    );
}

fn scene_toml_seeds() {
    let full = r#"# every key of the scene TOML
name = "fuzz"
obj = "t.obj"
up = "z"
mtl = "t.mtl"
default_material = "m"
missing_textures = "fallback"
width = 64
height = 36
frames = 4
fps = 30.0
seed = 7
exposure = -1.0
ambient = [0.1, 0.1, 0.1]
background = [0.0, 0.0, 0.2]
bump = true
[camera]
near = 0.05
fov_y_deg = 60.0
[[camera.keys]]
time = 0.0
position = [2.0, 1.0, 3.0]
target = [0.0, 0.0, 0.0]
[[camera.keys]]
time = 1.0
position = [3.0, 1.0, 2.0]
target = [0.0, 0.5, 0.0]
fov_y_deg = 40.0
cut = true
[[lights.directional]]
direction = [-0.3, -1.0, -0.2]
color = [1.0, 0.9, 0.8]
intensity = 3.0
[[lights.point]]
position = [0.0, 2.0, 0.0]
intensity = 5.0
range = 4.0
[lights.random_points]
count = 16
intensity = 0.5
range = 1.0
seed = 3
min = [-1.0, 0.0, -1.0]
max = [1.0, 2.0, 1.0]
[[animate]]
object = "A"
pivot = [0.0, 0.0, 0.0]
spin_axis = [0.0, 1.0, 0.0]
spin_deg_per_s = 90.0
velocity = [0.1, 0.0, 0.0]
"#;
    put("scene_toml", "full.toml", full.as_bytes());
    put("scene_toml", "minimal.toml", b"obj = \"t.obj\"\n");
    put(
        "scene_toml",
        "camera.toml",
        b"obj = \"t.obj\"\nwidth = 32\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [0, 0, 2]\ntarget = [0, 0, 0]\n",
    );
    put(
        "scene_toml",
        "animate.toml",
        b"obj = \"t.obj\"\n[[animate]]\nobject = \"B\"\nspin_deg_per_s = 360\n",
    );
}

fn main() {
    texture_seeds();
    image_input_seeds();
    obj_seeds();
    scene_toml_seeds();
    for t in ["obj", "scene_toml", "texture", "image_input"] {
        let d = dir(t);
        let (mut n, mut bytes) = (0, 0);
        for e in std::fs::read_dir(&d).expect("read seeds") {
            n += 1;
            bytes += e.expect("entry").metadata().expect("metadata").len();
        }
        println!("{}: {n} seeds, {bytes} bytes", d.display());
    }
}
