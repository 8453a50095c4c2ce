//! What the deferred and interleaved tests share: the fp16 comparison ("within fp16 rounding"),
//! and the floor-and-wall scene with its f64 reference of the VPL lighting.
#![allow(dead_code)]

use cbr_render::FrameOutput;
use cbr_render::gpu_types::Vpl;
use cbr_scene::{
    CameraKey, CameraPath, DirLight, LoadStats, Material, Object, Scene, Settings, Texture, Vertex,
};
use glam::{DMat4, DVec3, DVec4};

/// fp16 values as integers in order (sign-magnitude to two's complement): adjacent values
/// differ by one, whatever their sign.
pub fn ordered(bits: u16) -> i32 {
    let mag = i32::from(bits & 0x7fff);
    if bits & 0x8000 != 0 { -mag } else { mag }
}

/// What "within fp16 rounding" allows and what a comparison found.
#[derive(Debug, Default)]
pub struct Diff {
    /// Largest distance in fp16 steps (ulps) over every colour channel.
    pub max_ulps: i32,
    pub max_abs: f32,
    /// Channels that differ at all.
    pub differing: usize,
    pub channels: usize,
}

/// Colour against colour channel by channel; the other layers must be the same bits.
pub fn compare(name: &str, want: &FrameOutput, got: &FrameOutput) -> Diff {
    assert_eq!(want.depth.len(), got.depth.len(), "{name}");
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(
        bits(&want.depth) == bits(&got.depth),
        "{name}: depth differs"
    );
    assert!(want.ids == got.ids, "{name}: IDs differ");
    let vel = |o: &FrameOutput| {
        o.velocity
            .iter()
            .flat_map(|v| v.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert!(vel(want) == vel(got), "{name}: velocity differs");
    let mut d = Diff {
        channels: want.color.len(),
        ..Diff::default()
    };
    for (a, b) in want.color.iter().zip(&got.color) {
        assert!(
            a.is_finite() && b.is_finite(),
            "{name}: a non-finite colour"
        );
        let u = (ordered(a.to_bits()) - ordered(b.to_bits())).abs();
        if u > 0 {
            d.differing += 1;
        }
        d.max_ulps = d.max_ulps.max(u);
        d.max_abs = d.max_abs.max((a.to_f32() - b.to_f32()).abs());
    }
    d
}

pub fn quad(name: &str, corners: [[f32; 3]; 4], normal: [f32; 3], material: u32) -> Object {
    Object {
        name: name.into(),
        vertices: corners
            .iter()
            .map(|&pos| Vertex {
                pos,
                normal,
                uv: [0.0, 0.0],
            })
            .collect(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        origin: [0.0; 3],
    }
}

pub const FLOOR_ALBEDO: f32 = 0.5;
pub const WALL_ALBEDO: f32 = 0.75;
pub const SUN: f32 = 2.0;

/// A floor (y = 0, x in [-1, 3], z in [-2, 2]) under a sun shining straight down, and a wall
/// (x = -1, facing +x, 2 m high) edge-on to it: the sun's map holds the floor only, so the wall
/// is lit by the floor's VPLs alone, and the camera looks at the wall across the floor.
pub fn floor_and_wall(with_floor: bool, w: u32, h: u32) -> Scene {
    let mut floor = Material::named("floor");
    floor.kd = [FLOOR_ALBEDO; 3];
    let mut wall = Material::named("wall");
    wall.kd = [WALL_ALBEDO; 3];
    let mut objects = vec![quad(
        "wall",
        [
            [-1.0, 0.0, 2.0],
            [-1.0, 0.0, -2.0],
            [-1.0, 2.0, -2.0],
            [-1.0, 2.0, 2.0],
        ],
        [1.0, 0.0, 0.0],
        1,
    )];
    if with_floor {
        objects.push(quad(
            "floor",
            [
                [-1.0, 0.0, -2.0],
                [3.0, 0.0, -2.0],
                [3.0, 0.0, 2.0],
                [-1.0, 0.0, 2.0],
            ],
            [0.0, 1.0, 0.0],
            0,
        ));
    }
    Scene {
        name: "floor-and-wall".into(),
        source: "test".into(),
        objects,
        materials: vec![floor, wall],
        textures: Vec::<Texture>::new(),
        camera: CameraPath {
            keys: vec![CameraKey {
                time: 0.0,
                position: [2.5, 1.2, 0.3],
                target: [-1.0, 0.7, 0.0],
                fov_y_deg: 70.0,
                cut: false,
            }],
            near: 0.05,
        },
        directional: vec![DirLight {
            direction: [0.0, -1.0, 0.0],
            color: [1.0; 3],
            intensity: SUN,
        }],
        points: vec![],
        motions: vec![],
        settings: Settings {
            width: w,
            height: h,
            frames: 1,
            fps: 30.0,
            seed: 11,
            exposure: 0.0,
            ambient: [0.0; 3],
            background: [0.0; 3],
            bump: false,
            anisotropy: 1,
        },
        stats: LoadStats::default(),
    }
}

/// Where pixel (x, y)'s centre ray from the camera meets the plane `axis` = `value` (world),
/// camera-relative, in f64.
pub fn hit(s: &Scene, x: u32, y: u32, axis: usize, value: f64) -> DVec3 {
    let (w, h) = (f64::from(s.settings.width), f64::from(s.settings.height));
    let cam = s.camera.at(0.0);
    let clip_from_rel = cam.projection(w / h) * cam.rotation();
    let inv: DMat4 = clip_from_rel.inverse();
    let ndc = [
        (f64::from(x) + 0.5) / w * 2.0 - 1.0,
        (f64::from(y) + 0.5) / h * 2.0 - 1.0,
    ];
    let p = inv * DVec4::new(ndc[0], ndc[1], 0.5, 1.0);
    let dir = (p.truncate() / p.w).normalize();
    let plane = value - cam.position[axis];
    dir * (plane / dir[axis])
}

/// The spacing of fp16 values at `v` (> 0): 2^(exponent - 10), 2^-24 below the normal range.
pub fn fp16_step(v: f64) -> f64 {
    2f64.powi((v.log2().floor() as i32).max(-14) - 10)
}

/// The sun's light on a surface of normal `n` (straight down, irradiance SUN).
pub fn direct(n: DVec3, albedo: f64) -> f64 {
    albedo * f64::from(SUN) * n.dot(DVec3::Y).max(0.0)
}

/// The irradiance (red channel) at p, normal n, from `vpls`, in f64: the shader's formula
/// (docs/interleaved.md).
pub fn irradiance<'a>(
    p: DVec3,
    n: DVec3,
    vpls: impl IntoIterator<Item = &'a Vpl>,
    clamp_d2: f64,
) -> f64 {
    let mut e = 0.0;
    for v in vpls {
        let x = DVec3::new(
            v.position[0].into(),
            v.position[1].into(),
            v.position[2].into(),
        );
        let nv = DVec3::new(v.normal[0].into(), v.normal[1].into(), v.normal[2].into());
        let d = p - x;
        let d2 = d.length_squared();
        let cosines = nv.dot(d).max(0.0) * (-n.dot(d)).max(0.0);
        if cosines > 0.0 {
            e += f64::from(v.flux[0]) * cosines / (std::f64::consts::PI * d2 * d2.max(clamp_d2));
        }
    }
    e
}

/// The f64 reference of one pixel: the sun on `n`, then every VPL.
pub fn reference(p: DVec3, n: DVec3, albedo: f64, vpls: &[Vpl], clamp_d2: f64) -> f64 {
    direct(n, albedo) + albedo * irradiance(p, n, vpls, clamp_d2)
}

/// A pixel of the floor-and-wall frame: its camera-relative point, normal and albedo, from the
/// object ID it shows (`None`: background).
pub fn surface(s: &Scene, id: u32, x: u32, y: u32) -> Option<(DVec3, DVec3, f64)> {
    match id {
        1 => Some((hit(s, x, y, 0, -1.0), DVec3::X, f64::from(WALL_ALBEDO))),
        2 => Some((hit(s, x, y, 1, 0.0), DVec3::Y, f64::from(FLOOR_ALBEDO))),
        _ => None,
    }
}
