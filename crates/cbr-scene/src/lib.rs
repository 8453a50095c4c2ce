//! Scenes for cbr: OBJ/MTL (through tobj), textures (through image) with mip chains, the scene
//! TOML, camera paths, rigid animation, lights and the procedural scenes. No Vulkan.
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod camera;
pub mod cases;
pub mod desc;
pub mod error;
pub mod files;
pub mod obj;
pub mod procedural;
pub mod rng;
pub mod scene;
pub mod texture;

use std::path::Path;

use glam::DVec3;

pub use camera::{Camera, CameraKey, CameraPath};
pub use error::{Result, SceneError};
pub use files::{Disk, Files, MemoryFiles};
pub use obj::{MissingTextures, ObjOptions};
pub use scene::{
    AlphaSource, Bounds, DirLight, LoadStats, MAX_COORDINATE, MAX_RESOLUTION, Material, Motion,
    Object, PointLight, Scene, Settings, Up, Vertex, check_coordinate, check_resolution,
};
pub use texture::Texture;

/// Scenes compiled into the binary, by name (`builtin:NAME` on the command line): the demo, then
/// the hard-case gallery ([`cases::CASES`], whose entries say what each one tests).
pub const BUILTINS: &[&str] = &[
    "demo",
    "wires",
    "horizon",
    "foliage",
    "spinner",
    "texture",
    "slivers",
    "far",
    "specular",
    "thin-motion",
    "firefly",
    "cut",
    "zfight",
    "nan",
];

/// Options the command line can impose on any scene.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    pub missing_textures: Option<MissingTextures>,
}

/// The most lookups anisotropic texture filtering takes along a footprint (`anisotropy`), as
/// GPUs' 16x.
pub const MAX_ANISOTROPY: u32 = 16;

/// Refuses an `anisotropy` (a scene's, or `--anisotropy`) outside 1..=[`MAX_ANISOTROPY`].
pub fn check_anisotropy(a: u32) -> std::result::Result<(), String> {
    if (1..=MAX_ANISOTROPY).contains(&a) {
        Ok(())
    } else {
        Err(format!(
            "{a} lookups; anisotropic filtering takes 1 (isotropic) to {MAX_ANISOTROPY}"
        ))
    }
}

/// Loads `builtin:NAME`, a scene TOML, or a bare OBJ (framed by an automatic camera).
pub fn load(spec: &str, opts: &LoadOptions) -> Result<Scene> {
    load_from(&Disk, spec, opts)
}

/// [`load`], reading every file (TOML, OBJ, MTL, textures) from `files`.
pub fn load_from(files: &dyn Files, spec: &str, opts: &LoadOptions) -> Result<Scene> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        return builtin(name);
    }
    let path = Path::new(spec);
    let scene = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("toml") => load_toml(files, path, opts)?,
        Some("obj") => load_bare_obj(files, path, opts)?,
        _ => {
            return Err(SceneError::file(
                path,
                "expected a .toml scene, an .obj file, or builtin:NAME (builtin:demo)",
            ));
        }
    };
    // TOML keys are checked with their lines when parsed; this catches a framing camera.
    scene
        .camera
        .check()
        .map_err(|e| SceneError::file(path, e))?;
    Ok(scene)
}

pub fn builtin(name: &str) -> Result<Scene> {
    let scene = match name {
        "demo" => procedural::demo(),
        other => match cases::build(other) {
            Some(built) => built.map_err(SceneError::Invalid)?,
            None => {
                return Err(SceneError::Invalid(format!(
                    "no built-in scene `{other}`; built-ins: {} (`far:METRES` places `far` \
                     elsewhere)",
                    BUILTINS.join(", ")
                )));
            }
        },
    };
    scene
        .camera
        .check()
        .map_err(|e| SceneError::Invalid(format!("builtin:{name}: {e}")))?;
    Ok(scene)
}

fn default_lights(scene: &mut Scene) {
    scene.directional = vec![DirLight {
        direction: [-0.3, -1.0, -0.5],
        color: [1.0; 3],
        intensity: 2.5,
    }];
    scene.settings.ambient = [0.15; 3];
}

fn scene_from_obj(files: &dyn Files, path: &Path, obj_opts: &ObjOptions) -> Result<Scene> {
    let data = obj::load_obj_from(files, path, obj_opts)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let settings = Settings::default();
    let bounds = scene::bounds_of(&data.objects);
    let aspect = f64::from(settings.width) / f64::from(settings.height);
    let mut s = Scene {
        name,
        source: path.display().to_string(),
        objects: data.objects,
        materials: data.materials,
        textures: data.textures,
        camera: CameraPath::framing(&bounds, aspect),
        directional: Vec::new(),
        points: Vec::new(),
        motions: Vec::new(),
        settings,
        stats: data.stats,
    };
    default_lights(&mut s);
    Ok(s)
}

fn load_bare_obj(files: &dyn Files, path: &Path, opts: &LoadOptions) -> Result<Scene> {
    let o = ObjOptions {
        missing_textures: opts.missing_textures.unwrap_or_default(),
        ..Default::default()
    };
    scene_from_obj(files, path, &o)
}

fn load_toml(files: &dyn Files, path: &Path, opts: &LoadOptions) -> Result<Scene> {
    let bytes = files
        .read(path)
        .map_err(|e| SceneError::file(path, format!("cannot read: {e}")))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| SceneError::file(path, format!("cannot read: not UTF-8 text ({e})")))?;
    let d = desc::SceneDesc::parse(&text, path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scene = match (&d.obj, &d.procedural) {
        (Some(obj), None) => {
            let o = ObjOptions {
                mtl_override: d.mtl.as_ref().map(|m| dir.join(m)),
                default_material: d.default_material.clone(),
                missing_textures: opts
                    .missing_textures
                    .or(d.missing_textures)
                    .unwrap_or_default(),
                up: d.up,
            };
            scene_from_obj(files, &dir.join(obj), &o)?
        }
        (None, Some(name)) => builtin(name).map_err(|e| SceneError::file(path, e.to_string()))?,
        _ => {
            return Err(SceneError::file(
                path,
                "give exactly one of `obj` and `procedural`",
            ));
        }
    };
    scene.source = path.display().to_string();
    if let Some(n) = &d.name {
        scene.name = n.clone();
    } else if let Some(stem) = path.file_stem() {
        scene.name = stem.to_string_lossy().into_owned();
    }
    apply_settings(&mut scene, &d, path)?;
    let up = |v: [f64; 3]| d.up.to_y_up(v);
    if let Some(mut cam) = desc::camera_path(d.camera.as_ref()) {
        for k in &mut cam.keys {
            k.position = up(k.position);
            k.target = up(k.target);
        }
        scene.camera = cam;
    } else if d.obj.is_some() && (d.width.is_some() || d.height.is_some()) {
        // An OBJ's automatic framing depends on the aspect; a procedural scene keeps its own
        // camera path (its projection follows the resolution anyway).
        let aspect = f64::from(scene.settings.width) / f64::from(scene.settings.height);
        scene.camera = CameraPath::framing(&scene.bounds(), aspect);
    }
    if let Some(l) = &d.lights {
        apply_lights(&mut scene, l, d.up);
    }
    for (i, a) in d.animate.iter().enumerate() {
        let objects: Vec<u32> = scene
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.name == a.object)
            .map(|(k, _)| k as u32)
            .collect();
        if objects.is_empty() {
            let mut names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
            names.dedup();
            return Err(SceneError::file(
                path,
                format!(
                    "`animate[{i}].object`: `{}` matches no object (objects: {})",
                    a.object,
                    names.join(", ")
                ),
            ));
        }
        let picked: Vec<Object> = objects
            .iter()
            .map(|&k| scene.objects[k as usize].clone())
            .collect();
        let pivot = a
            .pivot
            .map(up)
            .unwrap_or_else(|| scene::bounds_of(&picked).center().to_array());
        scene.motions.push(Motion {
            name: a.object.clone(),
            objects,
            pivot,
            spin_axis: a.spin_axis.map(up).unwrap_or([0.0, 1.0, 0.0]),
            spin_rad_per_s: a.spin_deg_per_s.to_radians(),
            velocity: a.velocity.map(up).unwrap_or([0.0; 3]),
        });
    }
    Ok(scene)
}

fn apply_settings(scene: &mut Scene, d: &desc::SceneDesc, path: &Path) -> Result<()> {
    let s = &mut scene.settings;
    s.width = d.width.unwrap_or(s.width);
    s.height = d.height.unwrap_or(s.height);
    check_resolution(s.width, s.height).map_err(|e| SceneError::file(path, e))?;
    s.frames = d.frames.unwrap_or(s.frames);
    if s.frames == 0 {
        return Err(SceneError::file(path, "`frames` must be at least 1"));
    }
    s.fps = d.fps.unwrap_or(s.fps);
    if !(s.fps.is_finite() && s.fps > 0.0) {
        return Err(SceneError::file(path, "`fps` must be a positive number"));
    }
    s.seed = d.seed.unwrap_or(s.seed);
    s.exposure = d.exposure.unwrap_or(s.exposure);
    s.ambient = d.ambient.unwrap_or(s.ambient);
    s.background = d.background.unwrap_or(s.background);
    s.bump = d.bump.unwrap_or(s.bump);
    if let Some(a) = &d.anisotropy {
        s.anisotropy = *a.get_ref();
    }
    if d.textures == Some(false) {
        for m in &mut scene.materials {
            m.kd_tex = None;
            m.alpha = AlphaSource::Opaque;
            m.bump_tex = None;
        }
    }
    Ok(())
}

fn apply_lights(scene: &mut Scene, l: &desc::LightsDesc, up_axis: Up) {
    scene.directional = l
        .directional
        .iter()
        .map(|d| DirLight {
            direction: up_axis.to_y_up(d.direction),
            color: d.color,
            intensity: d.intensity,
        })
        .collect();
    let radius = scene.bounds().radius() as f32;
    scene.points = l
        .point
        .iter()
        .map(|p| PointLight {
            position: up_axis.to_y_up(*p.position.get_ref()),
            color: p.color,
            intensity: p.intensity,
            range: p.range.unwrap_or(radius),
        })
        .collect();
    if let Some(r) = &l.random_points {
        let b = scene.bounds();
        let min = r
            .min
            .map(|v| DVec3::from(up_axis.to_y_up(v)))
            .unwrap_or(b.min);
        let max = r
            .max
            .map(|v| DVec3::from(up_axis.to_y_up(v)))
            .unwrap_or(b.max);
        let (lo, hi) = (min.min(max), min.max(max));
        let mut rng = rng::SplitMix(r.seed.unwrap_or(scene.settings.seed));
        let range = r.range.unwrap_or(radius * 0.25);
        for _ in 0..*r.count.get_ref() {
            let p = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            scene.points.push(PointLight {
                position: p.to_array(),
                color: rng.hue(),
                intensity: r.intensity,
                range,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_has_a_usable_camera() {
        for name in BUILTINS {
            let scene = builtin(name).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(scene.camera.check(), Ok(()), "builtin:{name}");
        }
    }

    #[test]
    fn a_toml_camera_looking_nowhere_fails_the_load_naming_the_line() {
        let mut files = MemoryFiles::new();
        files.insert(
            "s/t.toml",
            "procedural = \"demo\"\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [1, 1, 1]\ntarget = [1, 1, 1]\n",
        );
        let err = load_from(&files, "s/t.toml", &LoadOptions::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.starts_with("s/t.toml:6: `camera.keys[0].target`: the target"),
            "{err}"
        );
    }
}
