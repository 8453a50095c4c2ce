//! The hard-case gallery: built-in scenes with one hard case each (`builtin:NAME`), small and
//! procedural. `just hard-cases` runs every technique on each (docs/hard-cases.md); the stability
//! tests use `far`, `zfight` and `nan`.

use glam::{Vec2, Vec3};

use crate::camera::{CameraKey, CameraPath};
use crate::procedural::{
    MeshBuilder, bricks_texture, checker_texture, leaf_texture, stripes_texture, texture,
};
use crate::rng::SplitMix;
use crate::scene::{
    AlphaSource, DirLight, LoadStats, Material, Motion, Object, PointLight, Scene, Settings,
};
use crate::texture::Texture;

/// One case: its name (`builtin:NAME`) and what makes it hard.
pub struct Case {
    pub name: &'static str,
    pub about: &'static str,
}

/// The gallery, in the order docs/hard-cases.md shows it.
pub const CASES: &[Case] = &[
    Case {
        name: "wires",
        about: "sub-pixel wires (2 cm to 4 mm at 12 m) and a fence of 3 cm slats, camera panning",
    },
    Case {
        name: "horizon",
        about: "a 0.25 m checker plane to the horizon, camera moving forward",
    },
    Case {
        name: "foliage",
        about: "alpha-tested crossed foliage cards, camera orbiting",
    },
    Case {
        name: "spinner",
        about: "a striped torus spinning 1.5 rev/s before a brick wall (disocclusion), camera still",
    },
    Case {
        name: "texture",
        about: "a zone-plate texture (every frequency up to the texel) on a tilted plane, camera drifting",
    },
    Case {
        name: "slivers",
        about: "a fan of 240 sliver triangles and a field of sub-pixel triangles, camera drifting",
    },
    Case {
        name: "far",
        about: "a small scene 1,000 km from the origin, camera following (`far:METRES` places it elsewhere)",
    },
    Case {
        name: "specular",
        about: "shiny spheres (Blinn-Phong exponents 200 to 5000) under small point lights, camera orbiting",
    },
    Case {
        name: "thin-motion",
        about: "a wheel of 5 mm spokes turning 0.5 rev/s and a thin pole crossing at 2 m/s",
    },
    Case {
        name: "firefly",
        about: "a sub-pixel emitter of radiance 30,000 drifting over a dark room (an HDR firefly)",
    },
    Case {
        name: "cut",
        about: "the demo's geometry with a camera cut after frame 7 (histories must reset)",
    },
    Case {
        name: "zfight",
        about: "a decal 2 cm above a ground plane out to 2 km and walls 10 cm apart at 500 m, near plane 1 mm",
    },
    Case {
        name: "nan",
        about: "a material whose shading is NaN and one whose shading is infinite (containment)",
    },
];

/// Builds case `name` (`far` takes an optional `:METRES`).
pub fn build(name: &str) -> Option<Result<Scene, String>> {
    let (base, arg) = match name.split_once(':') {
        Some((b, a)) => (b, Some(a)),
        None => (name, None),
    };
    if arg.is_some() && base != "far" {
        return None;
    }
    Some(Ok(match base {
        "wires" => wires(),
        "horizon" => horizon(),
        "foliage" => foliage(),
        "spinner" => spinner(),
        "texture" => zone_plate(),
        "slivers" => slivers(),
        "far" => {
            let d = match arg {
                None => 1.0e6,
                Some(a) => match a.parse::<f64>() {
                    Ok(d) if d.is_finite() && d.abs() <= 1.0e9 => d,
                    _ => {
                        return Some(Err(format!(
                            "builtin:far:{a}: give the distance from the origin in metres, at most 1e9"
                        )));
                    }
                },
            };
            far(d)
        }
        "specular" => specular(),
        "thin-motion" => thin_motion(),
        "firefly" => firefly(),
        "cut" => cut(),
        "zfight" => zfight(),
        "nan" => nan(),
        _ => return None,
    }))
}

fn key(time: f64, position: [f64; 3], target: [f64; 3], fov_y_deg: f64) -> CameraKey {
    CameraKey {
        time,
        position,
        target,
        fov_y_deg,
        cut: false,
    }
}

fn sun() -> Vec<DirLight> {
    vec![DirLight {
        direction: [-0.4, -0.8, -0.45],
        color: [1.0, 0.95, 0.85],
        intensity: 2.0,
    }]
}

fn mat(name: &str, kd: [f32; 3], tex: Option<u32>) -> Material {
    let mut m = Material::named(name);
    m.kd = kd;
    m.kd_tex = tex;
    m
}

/// A square ground plane of half-side `s` at y = 0, UVs in units of `uv_metres`.
fn ground(s: f32, uv_metres: f32) -> MeshBuilder {
    let mut g = MeshBuilder::default();
    let t = 2.0 * s / uv_metres;
    g.quad(
        [
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
            Vec3::new(-s, 0.0, -s),
        ],
        [
            Vec2::new(0.0, 0.0),
            Vec2::new(t, 0.0),
            Vec2::new(t, t),
            Vec2::new(0.0, t),
        ],
    );
    g
}

/// A scene of the given parts with the gallery's defaults (960x540, 16 frames at 30 fps).
struct Parts {
    name: &'static str,
    objects: Vec<Object>,
    materials: Vec<Material>,
    textures: Vec<Texture>,
    keys: Vec<CameraKey>,
    near: f64,
    directional: Vec<DirLight>,
    points: Vec<PointLight>,
    motions: Vec<Motion>,
    ambient: [f32; 3],
    background: [f32; 3],
}

impl Parts {
    fn new(name: &'static str) -> Parts {
        Parts {
            name,
            objects: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            keys: Vec::new(),
            near: 0.05,
            directional: sun(),
            points: Vec::new(),
            motions: Vec::new(),
            ambient: [0.05, 0.06, 0.08],
            background: [0.35, 0.5, 0.8],
        }
    }
    fn texture(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        self.textures.len() as u32 - 1
    }
    fn material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }
    fn object(&mut self, mesh: MeshBuilder, name: &str, material: u32) -> u32 {
        self.objects.push(mesh.object(name, material));
        self.objects.len() as u32 - 1
    }
    fn scene(self) -> Scene {
        let stats = LoadStats {
            triangles: self.objects.iter().map(Object::triangles).sum(),
            ..Default::default()
        };
        Scene {
            name: self.name.into(),
            source: format!("builtin:{}", self.name),
            objects: self.objects,
            materials: self.materials,
            textures: self.textures,
            camera: CameraPath {
                keys: self.keys,
                near: self.near,
            },
            directional: self.directional,
            points: self.points,
            motions: self.motions,
            settings: Settings {
                width: 960,
                height: 540,
                frames: 16,
                fps: 30.0,
                seed: 0,
                exposure: 0.0,
                ambient: self.ambient,
                background: self.background,
                bump: false,
                anisotropy: 1,
            },
            stats,
        }
    }
}

fn spin(name: &str, objects: Vec<u32>, pivot: Vec3, axis: [f64; 3], rev_per_s: f64) -> Motion {
    Motion {
        name: name.into(),
        objects,
        pivot: pivot.as_dvec3().to_array(),
        spin_axis: axis,
        spin_rad_per_s: rev_per_s * std::f64::consts::TAU,
        velocity: [0.0; 3],
    }
}

fn wires() -> Scene {
    let mut p = Parts::new("wires");
    let grey = p.material(mat("ground", [0.45, 0.45, 0.42], None));
    let mut metal = mat("metal", [0.35, 0.35, 0.38], None);
    (metal.ks, metal.ns) = ([0.5; 3], 64.0);
    let metal = p.material(metal);
    p.object(ground(100.0, 1.0), "ground", grey);
    let mut w = MeshBuilder::default();
    w.poles_and_wires();
    p.object(w, "wires", metal);
    let mut f = MeshBuilder::default();
    f.fence(-6.0, 90, 4.8);
    p.object(f, "fence", metal);
    p.keys = vec![
        key(0.0, [-1.0, 1.7, 4.0], [0.0, 2.6, -8.0], 50.0),
        key(1.0, [1.0, 1.8, 4.0], [0.5, 2.6, -8.0], 50.0),
    ];
    p.scene()
}

fn horizon() -> Scene {
    let mut p = Parts::new("horizon");
    let t = p.texture(checker_texture("checker"));
    let m = p.material(mat("ground", [1.0; 3], Some(t)));
    // 0.25 m checks (16 texels per check, 256 texels per 4 m) over 2 km.
    p.object(ground(1000.0, 4.0), "ground", m);
    p.keys = vec![
        key(0.0, [0.0, 1.5, 0.0], [0.3, 1.0, -20.0], 60.0),
        key(1.0, [0.0, 1.5, -2.0], [0.3, 1.0, -22.0], 60.0),
    ];
    p.scene()
}

fn foliage() -> Scene {
    let mut p = Parts::new("foliage");
    let leaves = p.texture(leaf_texture(7));
    let g = p.material(mat("ground", [0.3, 0.28, 0.22], None));
    let mut m = mat("foliage", [1.0; 3], Some(leaves));
    m.alpha = AlphaSource::Texture {
        tex: leaves,
        channel: 3,
    };
    let m = p.material(m);
    p.object(ground(50.0, 1.0), "ground", g);
    let mut cards = MeshBuilder::default();
    cards.foliage_cards(11, 24, Vec2::new(-4.0, -6.0), Vec2::new(8.0, 6.0));
    p.object(cards, "foliage", m);
    p.keys = vec![
        key(0.0, [-2.5, 1.5, 4.0], [0.0, 0.9, -3.0], 50.0),
        key(1.0, [2.5, 1.6, 4.0], [0.0, 0.9, -3.0], 50.0),
    ];
    p.scene()
}

fn spinner() -> Scene {
    let mut p = Parts::new("spinner");
    let st = p.texture(stripes_texture("stripes"));
    let br = p.texture(bricks_texture("bricks"));
    let mut m = mat("spinner", [1.0; 3], Some(st));
    (m.ks, m.ns) = ([0.9; 3], 400.0);
    let spinner = p.material(m);
    let wall = p.material(mat("wall", [1.0; 3], Some(br)));
    let g = p.material(mat("ground", [0.4; 3], None));
    p.object(ground(30.0, 1.0), "ground", g);
    let mut w = MeshBuilder::default();
    w.cuboid(Vec3::new(-5.0, 0.0, -4.5), Vec3::new(5.0, 4.0, -4.0), 1.0);
    p.object(w, "wall", wall);
    let centre = Vec3::new(0.0, 1.3, -2.0);
    let mut t = MeshBuilder::default();
    t.standing_torus(centre);
    let i = p.object(t, "spinner", spinner);
    p.motions = vec![spin("spinner", vec![i], centre, [0.0, 1.0, 0.0], 1.5)];
    p.keys = vec![key(0.0, [0.0, 1.5, 3.0], [0.0, 1.3, -2.0], 50.0)];
    p.scene()
}

/// cos(pi k r^2): the local frequency grows linearly from the centre to the Nyquist limit of the
/// texture at its edge.
fn zone_plate() -> Scene {
    let mut p = Parts::new("texture");
    let n = 512u32;
    let t = p.texture(texture("zone_plate", n, true, move |x, y| {
        let (u, v) = (x as f64 - f64::from(n) / 2.0, y as f64 - f64::from(n) / 2.0);
        let r2 = u * u + v * v;
        let k = std::f64::consts::PI / f64::from(n);
        let c = 0.5 + 0.5 * (k * r2).cos();
        let g = (255.0 * c).round() as u8;
        [g, g, g, 255]
    }));
    let m = p.material(mat("zone_plate", [1.0; 3], Some(t)));
    let mut q = MeshBuilder::default();
    q.quad(
        [
            Vec3::new(-3.0, 0.0, -1.0),
            Vec3::new(3.0, 0.0, -1.0),
            Vec3::new(3.0, 3.5, -5.0),
            Vec3::new(-3.0, 3.5, -5.0),
        ],
        [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ],
    );
    p.object(q, "zone_plate", m);
    p.ambient = [0.5; 3];
    p.directional = Vec::new();
    p.keys = vec![
        key(0.0, [0.0, 1.6, 2.5], [0.0, 1.4, -3.0], 50.0),
        key(1.0, [0.4, 1.7, 2.2], [0.1, 1.4, -3.0], 50.0),
    ];
    p.scene()
}

fn slivers() -> Scene {
    let mut p = Parts::new("slivers");
    let a = p.material(mat("light", [0.9, 0.85, 0.7], None));
    let b = p.material(mat("dark", [0.15, 0.2, 0.45], None));
    let g = p.material(mat("ground", [0.35; 3], None));
    p.object(ground(30.0, 1.0), "ground", g);
    // A fan: 240 triangles from a common apex, alternating colours, each 1.5 degrees wide and 3 m
    // long: slivers thinner than a pixel near the apex.
    let (mut fa, mut fb) = (MeshBuilder::default(), MeshBuilder::default());
    let apex = Vec3::new(-1.5, 1.5, -4.0);
    let n = 240;
    for i in 0..n {
        let a0 = std::f32::consts::TAU * i as f32 / n as f32;
        let a1 = std::f32::consts::TAU * (i + 1) as f32 / n as f32;
        let r = 1.4;
        let tri = [
            apex,
            apex + Vec3::new(a0.cos(), a0.sin(), 0.0) * r,
            apex + Vec3::new(a1.cos(), a1.sin(), 0.0) * r,
        ];
        let m = if i % 2 == 0 { &mut fa } else { &mut fb };
        m.triangle(tri, [Vec2::ZERO, Vec2::X, Vec2::Y]);
    }
    p.object(fa, "fan_light", a);
    p.object(fb, "fan_dark", b);
    // Sub-pixel triangles: a 60 x 40 grid of 6 mm triangles at 4-6 m (a pixel is ~9 mm there).
    let mut dust = MeshBuilder::default();
    let mut rng = SplitMix(3);
    for j in 0..40 {
        for i in 0..60 {
            let c = Vec3::new(
                0.6 + 0.045 * i as f32,
                0.4 + 0.045 * j as f32,
                -4.0 - 2.0 * rng.next_f32(),
            );
            let s = 0.006;
            let ang = rng.next_f32() * std::f32::consts::TAU;
            let d = |k: f32| {
                let t = ang + k * std::f32::consts::TAU / 3.0;
                Vec3::new(t.cos(), t.sin(), 0.0) * s
            };
            dust.triangle([c + d(0.0), c + d(1.0), c + d(2.0)], [Vec2::ZERO; 3]);
        }
    }
    p.object(dust, "dust", a);
    p.keys = vec![
        key(0.0, [0.0, 1.5, 2.0], [0.0, 1.4, -4.0], 50.0),
        key(1.0, [0.3, 1.55, 2.0], [0.1, 1.4, -4.0], 50.0),
    ];
    p.scene()
}

/// A small scene (a checker ground, a brick box, a striped sphere, a pole) whose objects sit
/// `distance` metres from the world origin; the camera follows. Vertices stay small (f32,
/// relative to each object's f64 `origin`).
pub fn far(distance: f64) -> Scene {
    let mut p = Parts::new("far");
    let ct = p.texture(checker_texture("checker"));
    let bt = p.texture(bricks_texture("bricks"));
    let st = p.texture(stripes_texture("stripes"));
    let g = p.material(mat("ground", [1.0; 3], Some(ct)));
    let b = p.material(mat("box", [1.0; 3], Some(bt)));
    let mut s = mat("ball", [1.0; 3], Some(st));
    (s.ks, s.ns) = ([0.6; 3], 120.0);
    let s = p.material(s);
    p.object(ground(20.0, 4.0), "ground", g);
    let mut bx = MeshBuilder::default();
    bx.cuboid(Vec3::new(-2.0, 0.0, -4.0), Vec3::new(-0.5, 1.5, -2.5), 1.0);
    p.object(bx, "box", b);
    let mut ball = MeshBuilder::default();
    ball.sphere(Vec3::new(1.0, 0.8, -3.0), 0.8, 48, 24);
    p.object(ball, "ball", s);
    let mut pole = MeshBuilder::default();
    pole.beam(Vec3::new(2.5, 0.0, -5.0), Vec3::new(2.2, 3.0, -5.0), 0.02);
    p.object(pole, "pole", b);
    // Along a diagonal so every axis carries the distance.
    let o = glam::DVec3::new(0.8, 0.0, -0.6) * distance;
    for obj in &mut p.objects {
        obj.origin = o.to_array();
    }
    let at = |v: [f64; 3]| (o + glam::DVec3::from(v)).to_array();
    p.keys = vec![
        key(0.0, at([-1.0, 1.6, 3.0]), at([0.0, 0.8, -3.0]), 50.0),
        key(1.0, at([1.0, 1.7, 2.5]), at([0.2, 0.8, -3.0]), 50.0),
    ];
    p.points = vec![PointLight {
        position: at([0.0, 2.5, -1.0]),
        color: [1.0, 0.7, 0.4],
        intensity: 3.0,
        range: 8.0,
    }];
    p.scene()
}

/// The files of a scene whose OBJ carries its large coordinates itself, as a mesh exported in
/// world coordinates does (georeferenced city models, CAD, survey data): a small mesh (about 6 m
/// across: a checker ground, a box, a shiny ball, a 3 cm pole without normals, so the loader
/// computes them) with its vertices, camera keys and point light shifted by `distance` metres in x
/// and z; vertices written with four decimals (0.1 mm), as exporters write fixed decimals.
/// `far/far.toml` names `far/far.obj`, its `far.mtl` and `checker.png`; load it with
/// [`crate::load_from`]. The stability tests compare it with the files at distance 0.
pub fn far_obj(distance: f64) -> crate::files::MemoryFiles {
    use std::fmt::Write;
    let d = distance;
    let mut bx = MeshBuilder::default();
    bx.cuboid(Vec3::new(-1.6, 0.0, -3.9), Vec3::new(-0.2, 1.4, -2.5), 1.0);
    let mut ball = MeshBuilder::default();
    ball.sphere(Vec3::new(1.0, 0.8, -3.0), 0.8, 32, 16);
    let mut pole = MeshBuilder::default();
    pole.beam(Vec3::new(2.2, 0.0, -4.6), Vec3::new(2.25, 2.9, -4.57), 0.03);
    let mut obj = String::from("mtllib far.mtl\n");
    let mut base = 0;
    for (mesh, name, material, normals) in [
        (ground(3.0, 0.75), "ground", "ground", true),
        (bx, "box", "box", true),
        (ball, "ball", "ball", true),
        (pole, "pole", "box", false),
    ] {
        let o = mesh.object(name, 0);
        let _ = writeln!(obj, "o {name}\nusemtl {material}");
        for v in &o.vertices {
            let [x, y, z] = v.pos.map(f64::from);
            let (x, z) = (x + d, z + d);
            let ([n0, n1, n2], [s, t]) = (v.normal, v.uv);
            let _ = writeln!(obj, "v {x:.4} {y:.4} {z:.4}\nvt {s} {}", 1.0 - t);
            if normals {
                let _ = writeln!(obj, "vn {n0} {n1} {n2}");
            }
        }
        for t in o.indices.chunks_exact(3) {
            let c = [t[0], t[1], t[2]].map(|i| base + i + 1);
            let _ = if normals {
                writeln!(
                    obj,
                    "f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}",
                    c[0], c[1], c[2]
                )
            } else {
                writeln!(obj, "f {0}/{0} {1}/{1} {2}/{2}", c[0], c[1], c[2])
            };
        }
        base += o.vertices.len() as u32;
    }
    let mtl = "newmtl ground\nKd 1 1 1\nmap_Kd checker.png\nnewmtl box\nKd 0.8 0.35 0.15\nnewmtl ball\nKd 0.2 0.4 0.9\nKs 0.6 0.6 0.6\nNs 120\n";
    let checker = checker_texture("checker");
    let l = &checker.levels[0];
    let mut png = Vec::new();
    image::RgbaImage::from_raw(l.width, l.height, l.rgba.clone())
        .expect("checker texels")
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("PNG in memory");
    let at = |x: f64, y: f64, z: f64| format!("[{}, {y}, {}]", x + d, z + d);
    let toml = format!(
        "obj = \"far.obj\"\nwidth = 320\nheight = 180\nframes = 8\nambient = [0.05, 0.05, 0.05]\n\
         [camera]\nfov_y_deg = 50\n\
         [[camera.keys]]\ntime = 0\nposition = {}\ntarget = {}\n\
         [[camera.keys]]\ntime = 1\nposition = {}\ntarget = {}\n\
         [[lights.directional]]\ndirection = [-0.4, -1.0, -0.3]\nintensity = 1.5\n\
         [[lights.point]]\nposition = {}\ncolor = [1.0, 0.7, 0.4]\nintensity = 3.0\nrange = 8.0\n",
        at(-1.0, 1.6, 3.0),
        at(0.0, 0.8, -3.0),
        at(1.0, 1.7, 2.5),
        at(0.2, 0.8, -3.0),
        at(0.0, 2.5, -1.0),
    );
    let mut files = crate::files::MemoryFiles::new();
    files.insert("far/far.obj", obj);
    files.insert("far/far.mtl", mtl);
    files.insert("far/checker.png", png);
    files.insert("far/far.toml", toml);
    files
}

fn specular() -> Scene {
    let mut p = Parts::new("specular");
    let g = p.material(mat("ground", [0.08; 3], None));
    p.object(ground(30.0, 1.0), "ground", g);
    for (i, ns) in [200.0f32, 600.0, 1500.0, 3000.0, 5000.0]
        .into_iter()
        .enumerate()
    {
        let mut m = mat(&format!("shiny{i}"), [0.05, 0.05, 0.06], None);
        (m.ks, m.ns) = ([1.0; 3], ns);
        let m = p.material(m);
        let mut s = MeshBuilder::default();
        s.sphere(
            Vec3::new(-2.4 + 1.2 * i as f32, 0.5, -3.0 - 0.3 * i as f32),
            0.5,
            64,
            32,
        );
        p.object(s, &format!("sphere{i}"), m);
    }
    let mut rng = SplitMix(9);
    p.points = (0..6)
        .map(|_| PointLight {
            position: [
                -4.0 + 8.0 * rng.next_f64(),
                1.5 + 1.5 * rng.next_f64(),
                -1.0 + 2.0 * rng.next_f64(),
            ],
            color: rng.hue(),
            intensity: 4.0,
            range: 10.0,
        })
        .collect();
    p.directional = Vec::new();
    p.ambient = [0.02; 3];
    p.background = [0.02, 0.02, 0.03];
    p.keys = vec![
        key(0.0, [-1.0, 1.3, 2.5], [0.0, 0.5, -3.5], 50.0),
        key(1.0, [1.0, 1.4, 2.5], [0.0, 0.5, -3.5], 50.0),
    ];
    p.scene()
}

fn thin_motion() -> Scene {
    let mut p = Parts::new("thin-motion");
    let mut metal = mat("metal", [0.7, 0.7, 0.75], None);
    (metal.ks, metal.ns) = ([0.4; 3], 64.0);
    let metal = p.material(metal);
    let br = p.texture(bricks_texture("bricks"));
    let wall = p.material(mat("wall", [1.0; 3], Some(br)));
    let mut w = MeshBuilder::default();
    w.cuboid(Vec3::new(-5.0, 0.0, -3.5), Vec3::new(5.0, 4.0, -3.0), 1.0);
    p.object(w, "wall", wall);
    let hub = Vec3::new(-0.6, 1.5, -1.5);
    let mut wheel = MeshBuilder::default();
    for k in 0..24 {
        let a = std::f32::consts::TAU * k as f32 / 24.0;
        let d = Vec3::new(a.cos(), a.sin(), 0.0);
        wheel.beam(hub + d * 0.05, hub + d * 1.1, 0.005);
    }
    let wi = p.object(wheel, "wheel", metal);
    let mut pole = MeshBuilder::default();
    pole.beam(Vec3::new(0.0, 0.0, -0.8), Vec3::new(0.0, 3.0, -0.8), 0.01);
    let pi = p.object(pole, "pole", metal);
    p.motions = vec![
        spin("wheel", vec![wi], hub, [0.0, 0.0, 1.0], 0.5),
        Motion {
            name: "pole".into(),
            objects: vec![pi],
            pivot: [0.0; 3],
            spin_axis: [0.0, 1.0, 0.0],
            spin_rad_per_s: 0.0,
            velocity: [2.0, 0.0, 0.0],
        },
    ];
    p.keys = vec![key(0.0, [0.0, 1.5, 2.5], [0.0, 1.5, -2.0], 50.0)];
    p.scene()
}

fn firefly() -> Scene {
    let mut p = Parts::new("firefly");
    let g = p.material(mat("floor", [0.2; 3], None));
    let w = p.material(mat("wall", [0.25, 0.22, 0.2], None));
    let mut e = mat("firefly", [0.0; 3], None);
    e.ke = [30000.0, 27000.0, 20000.0];
    let e = p.material(e);
    p.object(ground(20.0, 1.0), "floor", g);
    let mut wall = MeshBuilder::default();
    wall.cuboid(Vec3::new(-6.0, 0.0, -6.5), Vec3::new(6.0, 4.0, -6.0), 1.0);
    p.object(wall, "wall", w);
    // 3 mm radius at 5 m: about 0.7 px across at 960x540 and 50 degrees.
    let mut f = MeshBuilder::default();
    f.sphere(Vec3::new(-0.2, 1.4, -3.0), 0.003, 12, 6);
    let fi = p.object(f, "firefly", e);
    let mut f2 = MeshBuilder::default();
    f2.sphere(Vec3::new(0.5, 1.2, -3.5), 0.003, 12, 6);
    p.object(f2, "firefly_still", e);
    p.motions = vec![Motion {
        name: "drift".into(),
        objects: vec![fi],
        pivot: [0.0; 3],
        spin_axis: [0.0, 1.0, 0.0],
        spin_rad_per_s: 0.0,
        velocity: [0.05, 0.02, 0.0],
    }];
    p.directional = vec![DirLight {
        direction: [-0.3, -0.8, -0.5],
        color: [1.0; 3],
        intensity: 0.3,
    }];
    p.ambient = [0.02; 3];
    p.background = [0.01; 3];
    p.keys = vec![key(0.0, [0.0, 1.4, 2.0], [0.0, 1.3, -3.0], 50.0)];
    p.scene()
}

fn cut() -> Scene {
    let mut s = crate::procedural::demo();
    s.name = "cut".into();
    s.source = "builtin:cut".into();
    let t = 8.0 / s.settings.fps;
    s.camera.keys = vec![
        key(0.0, [-4.0, 1.7, 6.0], [0.0, 1.2, -4.0], 50.0),
        key(t, [-3.0, 1.6, 5.5], [0.0, 1.2, -4.0], 50.0),
        CameraKey {
            cut: true,
            ..key(t, [5.0, 1.2, 1.0], [-2.0, 1.5, -5.0], 40.0)
        },
        key(1.0, [5.5, 1.3, 0.5], [-2.0, 1.5, -5.0], 40.0),
    ];
    s
}

fn zfight() -> Scene {
    let mut p = Parts::new("zfight");
    let red = p.material(mat("ground", [0.7, 0.15, 0.1], None));
    let white = p.material(mat("decal", [0.85, 0.85, 0.8], None));
    let blue = p.material(mat("back_wall", [0.1, 0.2, 0.7], None));
    let yellow = p.material(mat("front_wall", [0.8, 0.7, 0.1], None));
    p.object(ground(2000.0, 1.0), "ground", red);
    // Stripes 2 cm above the ground, 1 m wide every 4 m, out to 2 km.
    let mut d = MeshBuilder::default();
    for k in 0..500 {
        let z0 = -4.0 * k as f32 - 2.0;
        d.quad(
            [
                Vec3::new(-60.0, 0.02, z0),
                Vec3::new(60.0, 0.02, z0),
                Vec3::new(60.0, 0.02, z0 - 1.0),
                Vec3::new(-60.0, 0.02, z0 - 1.0),
            ],
            [Vec2::ZERO; 4],
        );
    }
    p.object(d, "decal", white);
    // Two walls 10 cm apart, 500 m away; the nearer one has windows showing the one behind.
    let mut back = MeshBuilder::default();
    back.quad(
        [
            Vec3::new(-60.0, 0.0, -500.1),
            Vec3::new(60.0, 0.0, -500.1),
            Vec3::new(60.0, 40.0, -500.1),
            Vec3::new(-60.0, 40.0, -500.1),
        ],
        [Vec2::ZERO; 4],
    );
    p.object(back, "back_wall", blue);
    let mut front = MeshBuilder::default();
    for i in 0..6 {
        for j in 0..2 {
            let (x0, y0) = (-60.0 + 20.0 * i as f32, 20.0 * j as f32);
            // A frame around a 10 x 10 m window.
            let r = |a: f32, b: f32, c: f32, e: f32, m: &mut MeshBuilder| {
                m.quad(
                    [
                        Vec3::new(a, b, -500.0),
                        Vec3::new(c, b, -500.0),
                        Vec3::new(c, e, -500.0),
                        Vec3::new(a, e, -500.0),
                    ],
                    [Vec2::ZERO; 4],
                )
            };
            r(x0, y0, x0 + 20.0, y0 + 5.0, &mut front);
            r(x0, y0 + 15.0, x0 + 20.0, y0 + 20.0, &mut front);
            r(x0, y0 + 5.0, x0 + 5.0, y0 + 15.0, &mut front);
            r(x0 + 15.0, y0 + 5.0, x0 + 20.0, y0 + 15.0, &mut front);
        }
    }
    p.object(front, "front_wall", yellow);
    p.near = 0.001;
    p.keys = vec![
        key(0.0, [0.0, 1.7, 0.0], [0.0, 2.0, -500.0], 30.0),
        key(1.0, [0.5, 1.7, -1.0], [0.0, 2.0, -500.0], 30.0),
    ];
    p.scene()
}

fn nan() -> Scene {
    let mut p = Parts::new("nan");
    let g = p.material(mat("ground", [0.5; 3], None));
    let bad = p.material(mat("nan", [f32::NAN, 0.5, 0.5], None));
    let mut inf = mat("inf", [0.0; 3], None);
    inf.ke = [f32::INFINITY, 0.0, 0.0];
    let inf = p.material(inf);
    p.object(ground(20.0, 1.0), "ground", g);
    let mut a = MeshBuilder::default();
    a.sphere(Vec3::new(-0.8, 0.7, -3.0), 0.7, 32, 16);
    p.object(a, "nan_ball", bad);
    let mut b = MeshBuilder::default();
    b.cuboid(Vec3::new(0.4, 0.0, -3.5), Vec3::new(1.4, 1.0, -2.5), 1.0);
    p.object(b, "inf_box", inf);
    p.keys = vec![
        key(0.0, [0.0, 1.4, 2.0], [0.0, 0.7, -3.0], 50.0),
        key(1.0, [0.5, 1.5, 2.0], [0.0, 0.7, -3.0], 50.0),
    ];
    p.scene()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_builds_with_a_usable_camera() {
        for c in CASES {
            let s = build(c.name).unwrap().unwrap();
            assert_eq!(s.camera.check(), Ok(()), "builtin:{}", c.name);
            assert_eq!(s.source, format!("builtin:{}", c.name));
            assert!(s.triangle_count() > 0);
        }
        assert!(build("far:1e5").unwrap().is_ok());
        assert!(build("far:x").unwrap().is_err());
        assert!(build("wires:3").is_none());
        assert!(build("nope").is_none());
    }

    #[test]
    fn far_keeps_its_geometry_small_and_its_placement_exact() {
        let near = far(0.0);
        let away = far(1.0e6);
        for (a, b) in near.objects.iter().zip(&away.objects) {
            assert_eq!(a.vertices, b.vertices);
            assert_eq!(b.origin, [800_000.0, 0.0, -600_000.0]);
        }
        let c = away.bounds().center() - near.bounds().center();
        assert!((c - glam::DVec3::new(800_000.0, 0.0, -600_000.0)).length() < 1e-6);
    }
}
