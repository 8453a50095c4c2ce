//! The built-in demo: a first version of the hard-case gallery, embedded in the binary.
//! A checker plane to the horizon, sub-pixel wires and a fence, alpha-tested foliage cards with a
//! generated mask, a fast-spinning shiny torus (disocclusion, sharp highlights), an emissive sphere
//! and a textured tower 2.9 km from the origin, under a sun and coloured point lights.

use glam::{Vec2, Vec3};

use crate::camera::{CameraKey, CameraPath};
use crate::rng::SplitMix;
use crate::scene::{
    AlphaSource, DirLight, LoadStats, Material, Motion, Object, PointLight, Scene, Settings, Vertex,
};
use crate::texture::Texture;

/// Builds meshes one quad at a time.
#[derive(Default)]
pub(crate) struct MeshBuilder {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
}

impl MeshBuilder {
    pub(crate) fn quad(&mut self, corners: [Vec3; 4], uvs: [Vec2; 4]) {
        let n = (corners[1] - corners[0])
            .cross(corners[3] - corners[0])
            .normalize_or_zero();
        let base = self.vertices.len() as u32;
        for (p, uv) in corners.iter().zip(uvs) {
            self.vertices.push(Vertex {
                pos: p.to_array(),
                normal: n.to_array(),
                uv: uv.to_array(),
            });
        }
        self.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// An axis-aligned box given by its two extreme corners (UVs in metres / `uv_scale`).
    pub(crate) fn cuboid(&mut self, min: Vec3, max: Vec3, uv_scale: f32) {
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b) = (min, max);
        let faces = [
            [
                c(a.x, a.y, b.z),
                c(b.x, a.y, b.z),
                c(b.x, b.y, b.z),
                c(a.x, b.y, b.z),
            ], // +z
            [
                c(b.x, a.y, a.z),
                c(a.x, a.y, a.z),
                c(a.x, b.y, a.z),
                c(b.x, b.y, a.z),
            ], // -z
            [
                c(b.x, a.y, b.z),
                c(b.x, a.y, a.z),
                c(b.x, b.y, a.z),
                c(b.x, b.y, b.z),
            ], // +x
            [
                c(a.x, a.y, a.z),
                c(a.x, a.y, b.z),
                c(a.x, b.y, b.z),
                c(a.x, b.y, a.z),
            ], // -x
            [
                c(a.x, b.y, b.z),
                c(b.x, b.y, b.z),
                c(b.x, b.y, a.z),
                c(a.x, b.y, a.z),
            ], // +y
            [
                c(a.x, a.y, a.z),
                c(b.x, a.y, a.z),
                c(b.x, a.y, b.z),
                c(a.x, a.y, b.z),
            ], // -y
        ];
        for f in faces {
            let w = (f[1] - f[0]).length() / uv_scale;
            let h = (f[3] - f[0]).length() / uv_scale;
            self.quad(
                f,
                [
                    Vec2::new(0.0, h),
                    Vec2::new(w, h),
                    Vec2::new(w, 0.0),
                    Vec2::new(0.0, 0.0),
                ],
            );
        }
    }

    /// A thin box from `a` to `b` with square cross-section `thickness`.
    pub(crate) fn beam(&mut self, a: Vec3, b: Vec3, thickness: f32) {
        let dir = (b - a).normalize_or_zero();
        let side = dir.any_orthonormal_vector() * (thickness * 0.5);
        let up = dir.cross(side).normalize_or_zero() * (thickness * 0.5);
        let ring = |p: Vec3| [p - side - up, p + side - up, p + side + up, p - side + up];
        let (ra, rb) = (ring(a), ring(b));
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        for k in 0..4 {
            let k1 = (k + 1) % 4;
            self.quad([ra[k], ra[k1], rb[k1], rb[k]], uv);
        }
        self.quad([rb[0], rb[1], rb[2], rb[3]], uv);
        self.quad([ra[3], ra[2], ra[1], ra[0]], uv);
    }

    /// A parametric surface over [0,1]^2 sampled on an `nu` x `nv` grid.
    pub(crate) fn surface(
        &mut self,
        nu: u32,
        nv: u32,
        f: impl Fn(f32, f32) -> (Vec3, Vec3),
        uv_repeat: Vec2,
    ) {
        let base = self.vertices.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
                let (p, n) = f(u, v);
                self.vertices.push(Vertex {
                    pos: p.to_array(),
                    normal: n.to_array(),
                    uv: [u * uv_repeat.x, v * uv_repeat.y],
                });
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let a = base + j * (nu + 1) + i;
                let b = a + nu + 1;
                self.indices.extend([a, b, a + 1, a + 1, b, b + 1]);
            }
        }
    }

    /// A UV sphere of radius `r` about `c`.
    pub(crate) fn sphere(&mut self, c: Vec3, r: f32, nu: u32, nv: u32) {
        self.surface(
            nu,
            nv,
            |u, v| {
                let (a, b) = (u * std::f32::consts::TAU, (v - 0.5) * std::f32::consts::PI);
                let n = Vec3::new(b.cos() * a.cos(), b.sin(), b.cos() * a.sin());
                (c + n * r, n)
            },
            Vec2::ONE,
        );
    }

    /// One triangle (flat normal).
    pub(crate) fn triangle(&mut self, p: [Vec3; 3], uv: [Vec2; 3]) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Y);
        let base = self.vertices.len() as u32;
        for (p, uv) in p.iter().zip(uv) {
            self.vertices.push(Vertex {
                pos: p.to_array(),
                normal: n.to_array(),
                uv: uv.to_array(),
            });
        }
        self.indices.extend([base, base + 1, base + 2]);
    }

    pub(crate) fn object(self, name: &str, material: u32) -> Object {
        Object {
            name: name.to_string(),
            vertices: self.vertices,
            indices: self.indices,
            material,
            origin: [0.0; 3],
        }
    }
}

pub(crate) fn texture(
    name: &str,
    size: u32,
    srgb: bool,
    f: impl Fn(u32, u32) -> [u8; 4],
) -> Texture {
    let rgba = (0..size * size)
        .flat_map(|i| f(i % size, i / size))
        .collect();
    Texture::from_rgba8(name, size, size, rgba, srgb)
}

/// Leaf clusters: overlapping ellipses from a seeded generator, alpha 0 between them.
pub(crate) fn leaf_texture(seed: u64) -> Texture {
    let mut rng = SplitMix(seed);
    let leaves: Vec<(f32, f32, f32, f32, f32)> = (0..70)
        .map(|_| {
            let r = 0.035 + 0.05 * rng.next_f32();
            (
                0.1 + 0.8 * rng.next_f32(),
                0.05 + 0.9 * rng.next_f32(),
                r,
                r * (0.35 + 0.3 * rng.next_f32()),
                rng.next_f32() * std::f32::consts::PI,
            )
        })
        .collect();
    texture("demo.leaves", 256, true, |x, y| {
        let p = Vec2::new((x as f32 + 0.5) / 256.0, (y as f32 + 0.5) / 256.0);
        let hit = leaves.iter().any(|&(cx, cy, a, b, ang)| {
            let d = p - Vec2::new(cx, cy);
            let (s, c) = ang.sin_cos();
            let (u, v) = (d.x * c + d.y * s, -d.x * s + d.y * c);
            (u / a).powi(2) + (v / b).powi(2) <= 1.0
        });
        let shade = 90 + ((x * 7 + y * 13) % 40) as u8;
        if hit {
            [40, shade, 30, 255]
        } else {
            [40, 90, 30, 0]
        }
    })
}

/// 0.25 m checks: 16-texel squares of a 256-texel sRGB texture (4 m per UV unit).
pub(crate) fn checker_texture(name: &str) -> Texture {
    texture(name, 256, true, |x, y| {
        let v = if ((x / 16) + (y / 16)) % 2 == 0 {
            225
        } else {
            35
        };
        [v, v, v, 255]
    })
}

/// Orange and cream stripes, 8 texels wide.
pub(crate) fn stripes_texture(name: &str) -> Texture {
    texture(name, 128, true, |x, _| {
        if (x / 8) % 2 == 0 {
            [230, 80, 40, 255]
        } else {
            [240, 220, 200, 255]
        }
    })
}

/// Running-bond bricks with light mortar.
pub(crate) fn bricks_texture(name: &str) -> Texture {
    texture(name, 128, true, |x, y| {
        let row = y / 16;
        let xs = x + if row % 2 == 0 { 0 } else { 16 };
        if y % 16 < 2 || xs % 32 < 2 {
            [200, 200, 190, 255]
        } else {
            [150, 60 + ((row * 17) % 30) as u8, 45, 255]
        }
    })
}

impl MeshBuilder {
    /// Two poles 12 m apart at z = -8 and five tilted wires from 2 cm down to 4 mm thick.
    pub(crate) fn poles_and_wires(&mut self) {
        self.cuboid(Vec3::new(-6.1, 0.0, -8.1), Vec3::new(-5.9, 5.0, -7.9), 1.0);
        self.cuboid(Vec3::new(5.9, 0.0, -8.1), Vec3::new(6.1, 5.5, -7.9), 1.0);
        for (k, t) in [0.02f32, 0.012, 0.008, 0.006, 0.004]
            .into_iter()
            .enumerate()
        {
            let y = 3.4 + 0.35 * k as f32;
            self.beam(Vec3::new(-6.0, y, -8.0), Vec3::new(6.0, y + 0.45, -8.0), t);
        }
    }

    /// A fence at z = -3: `slats` 3 cm slats every 12 cm from x = `x0`, two rails to `rail_end`.
    pub(crate) fn fence(&mut self, x0: f32, slats: u32, rail_end: f32) {
        for i in 0..slats {
            let x = x0 + 0.12 * i as f32;
            self.cuboid(
                Vec3::new(x, 0.0, -3.0),
                Vec3::new(x + 0.03, 1.2, -2.97),
                1.0,
            );
        }
        for y in [0.3f32, 0.95] {
            self.cuboid(
                Vec3::new(x0, y, -3.03),
                Vec3::new(rail_end, y + 0.06, -3.0),
                1.0,
            );
        }
    }

    /// `clusters` clumps of three crossed alpha-tested cards, placed by a seeded generator in
    /// the rectangle from `min` (x, z) spanning `size`.
    pub(crate) fn foliage_cards(&mut self, seed: u64, clusters: u32, min: Vec2, size: Vec2) {
        let mut rng = SplitMix(seed);
        for _ in 0..clusters {
            let c = Vec3::new(
                min.x + size.x * rng.next_f32(),
                0.0,
                min.y + size.y * rng.next_f32(),
            );
            let h = 1.0 + 1.2 * rng.next_f32();
            let a0 = rng.next_f32() * std::f32::consts::PI;
            for k in 0..3 {
                let a = a0 + k as f32 * std::f32::consts::FRAC_PI_3;
                let d = Vec3::new(a.cos(), 0.0, a.sin()) * (h * 0.5);
                self.quad(
                    [c - d, c + d, c + d + Vec3::Y * h, c - d + Vec3::Y * h],
                    [
                        Vec2::new(0.0, 1.0),
                        Vec2::new(1.0, 1.0),
                        Vec2::new(1.0, 0.0),
                        Vec2::new(0.0, 0.0),
                    ],
                );
            }
        }
    }

    /// A torus (radii 0.8 and 0.25 m) standing up about `centre` (its ring in the XY plane, so
    /// that a spin about Y sweeps what is behind it), stripes across the tube.
    pub(crate) fn standing_torus(&mut self, centre: Vec3) {
        let (big, small) = (0.8f32, 0.25f32);
        self.surface(
            96,
            32,
            |u, v| {
                let (a, b) = (u * std::f32::consts::TAU, v * std::f32::consts::TAU);
                let ring = Vec3::new(a.cos(), 0.0, a.sin());
                let n = ring * b.cos() + Vec3::Y * b.sin();
                let rot = |p: Vec3| Vec3::new(p.x, p.z, p.y);
                (centre + rot(ring * big + n * small), rot(n))
            },
            Vec2::new(8.0, 1.0),
        );
    }
}

pub fn demo() -> Scene {
    let mut textures = Vec::new();
    let mut add_tex = |t: Texture| {
        textures.push(t);
        textures.len() as u32 - 1
    };
    let checker = add_tex(checker_texture("demo.checker"));
    let leaves = add_tex(leaf_texture(7));
    let stripes = add_tex(stripes_texture("demo.stripes"));
    let bricks = add_tex(bricks_texture("demo.bricks"));

    let m = |name: &str, kd: [f32; 3], tex: Option<u32>| {
        let mut mat = Material::named(name);
        mat.kd = kd;
        mat.kd_tex = tex;
        mat
    };
    let mut materials = vec![
        m("ground", [1.0; 3], Some(checker)),
        m("metal", [0.35, 0.35, 0.38], None),
        m("foliage", [1.0; 3], Some(leaves)),
        m("spinner", [1.0; 3], Some(stripes)),
        m("lamp", [0.1; 3], None),
        m("tower", [1.0; 3], Some(bricks)),
    ];
    materials[1].ks = [0.5; 3];
    materials[1].ns = 64.0;
    materials[2].alpha = AlphaSource::Texture {
        tex: leaves,
        channel: 3,
    };
    materials[3].ks = [0.9; 3];
    materials[3].ns = 400.0;
    materials[4].ke = [6.0, 4.5, 2.0];

    let mut objects = Vec::new();
    // A checker plane to the horizon: 0.25 m checks over 1.2 km.
    let mut g = MeshBuilder::default();
    let s = 600.0;
    g.quad(
        [
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
            Vec3::new(-s, 0.0, -s),
        ],
        [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0 * s / 4.0, 0.0),
            Vec2::new(2.0 * s / 4.0, 2.0 * s / 4.0),
            Vec2::new(0.0, 2.0 * s / 4.0),
        ],
    );
    objects.push(g.object("ground", 0));

    // Two poles and tilted wires from 2 cm down to 4 mm thick (sub-pixel at 10 m and 720p).
    let mut w = MeshBuilder::default();
    w.poles_and_wires();
    objects.push(w.object("wires", 1));

    // A fence: 3 cm slats every 12 cm, two rails.
    let mut f = MeshBuilder::default();
    f.fence(-10.0, 70, -1.6);
    objects.push(f.object("fence", 1));

    // Foliage: crossed alpha-tested cards.
    let mut leaves_mesh = MeshBuilder::default();
    leaves_mesh.foliage_cards(11, 14, Vec2::new(2.0, -7.0), Vec2::new(8.0, 8.0));
    objects.push(leaves_mesh.object("foliage", 2));

    // A fast-spinning torus (1.5 rev/s), shiny: disocclusion and sharp highlights.
    let mut t = MeshBuilder::default();
    let centre = Vec3::new(0.0, 1.3, -2.0);
    t.standing_torus(centre);
    objects.push(t.object("spinner", 3));

    // An emissive sphere.
    let mut sph = MeshBuilder::default();
    sph.sphere(Vec3::new(-3.0, 2.4, -5.0), 0.3, 32, 16);
    objects.push(sph.object("lamp", 4));

    // A textured tower 2.9 km from the origin: float precision far away.
    let mut tw = MeshBuilder::default();
    tw.cuboid(
        Vec3::new(1460.0, 0.0, -2540.0),
        Vec3::new(1540.0, 140.0, -2460.0),
        8.0,
    );
    objects.push(tw.object("far_tower", 5));

    let mut points = Vec::new();
    let mut rng = SplitMix(5);
    for _ in 0..48 {
        let p = [
            -10.0 + 20.0 * rng.next_f64(),
            0.3 + 2.0 * rng.next_f64(),
            -10.0 + 14.0 * rng.next_f64(),
        ];
        points.push(PointLight {
            position: p,
            color: rng.hue(),
            intensity: 1.5,
            range: 4.0,
        });
    }

    let key = |time: f64, position: [f64; 3], target: [f64; 3]| CameraKey {
        time,
        position,
        target,
        fov_y_deg: 50.0,
        cut: false,
    };
    let spinner_index = objects
        .iter()
        .position(|o| o.name == "spinner")
        .unwrap_or(0) as u32;
    let stats = LoadStats {
        triangles: objects.iter().map(Object::triangles).sum(),
        ..Default::default()
    };
    Scene {
        name: "demo".into(),
        source: "builtin:demo".into(),
        objects,
        materials,
        textures,
        camera: CameraPath {
            keys: vec![
                key(0.0, [-4.0, 1.7, 6.0], [0.0, 1.2, -4.0]),
                key(1.0, [0.0, 1.5, 5.0], [1.0, 1.3, -5.0]),
                key(2.0, [4.0, 1.9, 6.0], [2.0, 1.0, -4.0]),
            ],
            near: 0.05,
        },
        directional: vec![DirLight {
            direction: [-0.4, -0.8, -0.45],
            color: [1.0, 0.95, 0.85],
            intensity: 2.0,
        }],
        points,
        motions: vec![Motion {
            name: "spinner".into(),
            objects: vec![spinner_index],
            pivot: [
                f64::from(centre.x),
                f64::from(centre.y),
                f64::from(centre.z),
            ],
            spin_axis: [0.0, 1.0, 0.0],
            spin_rad_per_s: 1.5 * std::f64::consts::TAU,
            velocity: [0.0; 3],
        }],
        settings: Settings {
            width: 960,
            height: 540,
            frames: 16,
            fps: 30.0,
            seed: 0,
            exposure: 0.0,
            ambient: [0.05, 0.06, 0.08],
            background: [0.35, 0.5, 0.8],
            bump: false,
            anisotropy: 1,
        },
        stats,
    }
}
