//! The scene TOML. Unknown keys and wrong types are errors naming the key path and the line.
//!
//! ```toml
//! obj = "../../shared/scenes/sibenik/sibenik.obj"   # or: procedural = "demo"
//! up = "y"                 # the OBJ's up axis: "y" or "z"
//! width = 1280             # resolution, frames, fps, seed, exposure (stops), ambient
//! frames = 8
//! [camera]
//! near = 0.05
//! [[camera.keys]]
//! time = 0.0
//! position = [-12.0, -8.0, 0.0]
//! target = [10.0, -10.0, 0.0]
//! fov_y_deg = 60.0
//! cut = false            # true: the camera jumps to this key (histories reset)
//! [[lights.directional]]
//! direction = [-0.3, -1.0, -0.2]
//! intensity = 3.0
//! [lights.random_points]
//! count = 1000
//! [[animate]]
//! object = "Spinner"
//! spin_deg_per_s = 360.0
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::camera::{CameraKey, CameraPath, check_direction, check_finite, check_fov, check_near};
use crate::error::{Result, SceneError};
use crate::obj::MissingTextures;
use crate::scene::Up;

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    pub name: Option<String>,
    pub obj: Option<PathBuf>,
    pub procedural: Option<String>,
    #[serde(default)]
    pub up: Up,
    pub mtl: Option<PathBuf>,
    pub default_material: Option<String>,
    pub missing_textures: Option<MissingTextures>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub frames: Option<u32>,
    pub fps: Option<f64>,
    pub seed: Option<u64>,
    pub exposure: Option<f32>,
    pub ambient: Option<[f32; 3]>,
    pub background: Option<[f32; 3]>,
    pub bump: Option<bool>,
    /// Anisotropic texture filtering: at most this many trilinear lookups along a footprint's
    /// longer side (1 to [`crate::MAX_ANISOTROPY`]; 1, the default: one isotropic lookup).
    pub anisotropy: Option<Spanned<u32>>,
    /// `false`: drop every material's textures (albedo, alpha mask, bump): geometry and flat
    /// materials only, to tell geometric aliasing from shading aliasing.
    pub textures: Option<bool>,
    pub camera: Option<CameraDesc>,
    pub lights: Option<LightsDesc>,
    #[serde(default)]
    pub animate: Vec<AnimDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub near: Option<Spanned<f64>>,
    pub fov_y_deg: Option<Spanned<f64>>,
    #[serde(default)]
    pub keys: Vec<KeyDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyDesc {
    pub time: Spanned<f64>,
    pub position: Spanned<[f64; 3]>,
    pub target: Spanned<[f64; 3]>,
    pub fov_y_deg: Option<Spanned<f64>>,
    /// A camera cut: the camera jumps to this key (histories reset).
    #[serde(default)]
    pub cut: bool,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LightsDesc {
    #[serde(default)]
    pub directional: Vec<DirDesc>,
    #[serde(default)]
    pub point: Vec<PointDesc>,
    pub random_points: Option<RandomPointsDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirDesc {
    pub direction: [f32; 3],
    #[serde(default = "white")]
    pub color: [f32; 3],
    #[serde(default = "one")]
    pub intensity: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointDesc {
    pub position: Spanned<[f64; 3]>,
    #[serde(default = "white")]
    pub color: [f32; 3],
    #[serde(default = "one")]
    pub intensity: f32,
    pub range: Option<f32>,
}

/// The most random point lights a scene may ask for (each fragment loops over every light).
pub const MAX_RANDOM_LIGHTS: u32 = 1 << 20;

/// `count` point lights placed uniformly in a box (default: the scene bounds) with random hues:
/// the knob that scales shading cost.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomPointsDesc {
    pub count: Spanned<u32>,
    #[serde(default = "one")]
    pub intensity: f32,
    pub range: Option<f32>,
    pub seed: Option<u64>,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimDesc {
    /// OBJ object/group name; every object of that name moves.
    pub object: String,
    /// Spin centre; default the centre of the objects' bounds.
    pub pivot: Option<[f64; 3]>,
    pub spin_axis: Option<[f64; 3]>,
    #[serde(default)]
    pub spin_deg_per_s: f64,
    pub velocity: Option<[f64; 3]>,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}
fn one() -> f32 {
    1.0
}

/// Line (1-based) of a byte offset in `text` (for errors about a parsed TOML's spans).
pub fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}

/// Reads a TOML document into `T`: syntax errors, unknown keys, wrong types and `nan` or `inf`
/// anywhere are one error naming the file, the line and the key path.
pub fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, file: &Path) -> Result<T> {
    let de = toml::Deserializer::parse(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start)).unwrap_or(1);
        SceneError::syntax(file, line, e.message().to_string())
    })?;
    if let Ok(table) = toml::de::DeTable::parse(text) {
        let span = table.span();
        let root = toml::de::DeValue::Table(table.into_inner());
        check_finite_floats(&root, "", span, text, file)?;
    }
    serde_path_to_error::deserialize(de).map_err(|e| {
        // A `Spanned` value's path names its private field: the key is the path without it.
        let path = e
            .path()
            .to_string()
            .replace(".$__serde_spanned_private_value", "");
        let inner = e.into_inner();
        let line = inner.span().map(|s| line_of(text, s.start)).unwrap_or(1);
        SceneError::syntax(file, line, format!("`{path}`: {}", inner.message()))
    })
}

impl SceneDesc {
    pub fn parse(text: &str, file: &Path) -> Result<SceneDesc> {
        let desc: SceneDesc = parse_toml(text, file)?;
        desc.check_camera(text, file)?;
        for (i, p) in desc.lights.iter().flat_map(|l| l.point.iter()).enumerate() {
            check_finite(*p.position.get_ref()).map_err(|e| {
                SceneError::syntax(
                    file,
                    line_of(text, p.position.span().start),
                    format!("`lights.point[{i}].position`: {e}"),
                )
            })?;
        }
        if let Some(a) = &desc.anisotropy {
            crate::check_anisotropy(*a.get_ref()).map_err(|e| {
                SceneError::syntax(
                    file,
                    line_of(text, a.span().start),
                    format!("`anisotropy`: {e}"),
                )
            })?;
        }
        if let Some(r) = desc.lights.as_ref().and_then(|l| l.random_points.as_ref())
            && *r.count.get_ref() > MAX_RANDOM_LIGHTS
        {
            return Err(SceneError::syntax(
                file,
                line_of(text, r.count.span().start),
                format!(
                    "`lights.random_points.count`: {} lights; at most {MAX_RANDOM_LIGHTS}",
                    r.count.get_ref()
                ),
            ));
        }
        Ok(desc)
    }

    /// Refuses cameras that cannot make a picture (a field of view outside (0, 180) degrees, a
    /// target equal to the position, a near plane that is not positive, non-finite numbers),
    /// naming the key and its line.
    fn check_camera(&self, text: &str, file: &Path) -> Result<()> {
        let Some(c) = &self.camera else {
            return Ok(());
        };
        let at = |key: String, span: std::ops::Range<usize>, e: String| {
            SceneError::syntax(file, line_of(text, span.start), format!("`{key}`: {e}"))
        };
        if let Some(near) = &c.near {
            check_near(*near.get_ref()).map_err(|e| at("camera.near".into(), near.span(), e))?;
        }
        if let Some(fov) = &c.fov_y_deg {
            check_fov(*fov.get_ref()).map_err(|e| at("camera.fov_y_deg".into(), fov.span(), e))?;
        }
        for (i, k) in c.keys.iter().enumerate() {
            let key = |field: &str| format!("camera.keys[{i}].{field}");
            if !k.time.get_ref().is_finite() {
                let e = format!("the time {} is not a finite number", k.time.get_ref());
                return Err(at(key("time"), k.time.span(), e));
            }
            if let Some(fov) = &k.fov_y_deg {
                check_fov(*fov.get_ref()).map_err(|e| at(key("fov_y_deg"), fov.span(), e))?;
            }
            check_finite(*k.position.get_ref())
                .map_err(|e| at(key("position"), k.position.span(), e))?;
            check_direction(*k.position.get_ref(), *k.target.get_ref())
                .map_err(|e| at(key("target"), k.target.span(), e))?;
        }
        Ok(())
    }
}

/// Refuses `nan` and `inf` anywhere in a scene TOML (no key means anything by them), naming the
/// key and its line.
fn check_finite_floats(
    value: &toml::de::DeValue,
    key: &str,
    span: std::ops::Range<usize>,
    text: &str,
    file: &Path,
) -> Result<()> {
    use toml::de::DeValue;
    match value {
        DeValue::Float(f) if f.as_str().contains("nan") || f.as_str().contains("inf") => {
            Err(SceneError::syntax(
                file,
                line_of(text, span.start),
                format!("`{key}`: {} is not a finite number", f.as_str()),
            ))
        }
        DeValue::Table(t) => {
            for (k, v) in t {
                let sub = if key.is_empty() {
                    k.get_ref().to_string()
                } else {
                    format!("{key}.{}", k.get_ref())
                };
                check_finite_floats(v.get_ref(), &sub, v.span(), text, file)?;
            }
            Ok(())
        }
        DeValue::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                check_finite_floats(v.get_ref(), &format!("{key}[{i}]"), v.span(), text, file)?;
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

pub(crate) fn camera_path(desc: Option<&CameraDesc>) -> Option<CameraPath> {
    let c = desc?;
    if c.keys.is_empty() {
        return None;
    }
    let fov = c.fov_y_deg.as_ref().map_or(50.0, |f| *f.get_ref());
    let mut keys: Vec<CameraKey> = c
        .keys
        .iter()
        .map(|k| CameraKey {
            time: *k.time.get_ref(),
            position: *k.position.get_ref(),
            target: *k.target.get_ref(),
            fov_y_deg: k.fov_y_deg.as_ref().map_or(fov, |f| *f.get_ref()),
            cut: k.cut,
        })
        .collect();
    keys.sort_by(|a, b| a.time.total_cmp(&b.time));
    Some(CameraPath {
        keys,
        near: c.near.as_ref().map_or(0.05, |n| *n.get_ref()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<SceneDesc> {
        SceneDesc::parse(s, Path::new("s.toml"))
    }

    #[test]
    fn unknown_keys_name_the_path_and_line() {
        let err = parse("obj = \"a.obj\"\n[camera]\nnear = 0.1\n[[camera.keys]]\ntime = 0\nposition = [0,0,0]\ntarget = [0,0,-1]\nfvo = 3\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("s.toml:8:"), "{err}");
        assert!(err.contains("camera.keys[0]"), "{err}");
        assert!(err.contains("fvo"), "{err}");
    }

    #[test]
    fn wrong_types_name_the_path() {
        let err = parse("width = \"wide\"\n").unwrap_err().to_string();
        assert!(err.starts_with("s.toml:1:"), "{err}");
        assert!(err.contains("`width`"), "{err}");
        let err = parse("[lights]\n[[lights.point]]\nposition = [0, 0]\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("lights.point[0].position"), "{err}");
    }

    #[test]
    fn syntax_errors_name_the_line() {
        let err = parse("width = 3\nheight = = 4\n").unwrap_err().to_string();
        assert!(err.starts_with("s.toml:2:"), "{err}");
    }

    #[test]
    fn degenerate_cameras_name_the_key_and_line() {
        let key = |extra: &str| {
            format!(
                "obj = \"a.obj\"\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [0, 0, 0]\ntarget = [0, 0, -1]\n[[camera.keys]]\ntime = 1\n{extra}"
            )
        };
        let err = |text: &str| parse(text).expect_err(text).to_string();
        let ok = key("position = [0, 1, 0]\ntarget = [0, 0, 0]\nfov_y_deg = 179\n");
        assert!(parse(&ok).is_ok());
        for (fov, why) in [
            ("180", "a vertical field of view of 180 degrees"),
            ("0", "a vertical field of view of 0 degrees"),
            ("-45", "a vertical field of view of -45 degrees"),
            ("nan", "nan is not a finite number"),
            ("inf", "inf is not a finite number"),
        ] {
            let e = err(&key(&format!(
                "position = [0, 1, 0]\ntarget = [0, 0, 0]\nfov_y_deg = {fov}\n"
            )));
            assert!(
                e.starts_with(&format!("s.toml:11: `camera.keys[1].fov_y_deg`: {why}")),
                "{e}"
            );
        }
        let e = err(&key("position = [1, 2, 3]\ntarget = [1, 2, 3]\n"));
        assert!(
            e.starts_with("s.toml:10: `camera.keys[1].target`: the target [1.0, 2.0, 3.0] is the camera's position"),
            "{e}"
        );
        let e = err(&key("position = [nan, 0, 0]\ntarget = [1, 2, 3]\n"));
        assert!(
            e.starts_with("s.toml:9: `camera.keys[1].position[0]`: nan is not a finite"),
            "{e}"
        );
        let e = err(
            &key("position = [0, 0, 0]\ntarget = [1, 2, 3]\ntime = inf\n")
                .replace("time = 1\n", ""),
        );
        assert!(
            e.contains("`camera.keys[1].time`: inf is not a finite number"),
            "{e}"
        );
        let e = err("obj = \"a.obj\"\n[camera]\nfov_y_deg = 180\n");
        assert!(e.starts_with("s.toml:3: `camera.fov_y_deg`"), "{e}");
        let e = err("obj = \"a.obj\"\n[camera]\nnear = 0\n");
        assert!(
            e.starts_with("s.toml:3: `camera.near`: a near plane at 0"),
            "{e}"
        );
    }

    #[test]
    fn non_finite_numbers_name_the_key_and_line() {
        let e = parse("obj = \"a.obj\"\nexposure = nan\n")
            .expect_err("nan")
            .to_string();
        assert_eq!(e, "s.toml:2: `exposure`: nan is not a finite number");
        let e = parse("obj = \"a.obj\"\n[[lights.point]]\nposition = [0, 0, 0]\n[[lights.point]]\nposition = [0,\n -inf, 0]\n")
            .expect_err("inf")
            .to_string();
        assert_eq!(
            e,
            "s.toml:6: `lights.point[1].position[1]`: -inf is not a finite number"
        );
    }

    #[test]
    fn positions_beyond_a_millimetre_of_f64_name_the_key_and_line() {
        for (text, want) in [
            (
                "[[lights.point]]\nposition = [0, 0, 0]\n[[lights.point]]\nposition = [1e13, 0, 0]\n",
                "s.toml:5: `lights.point[1].position`: the coordinate 1e13 is beyond what f64 holds at 1 mm precision",
            ),
            (
                "[camera]\n[[camera.keys]]\ntime = 0\nposition = [0, 0, -9e12]\ntarget = [0, 0, 0]\n",
                "s.toml:5: `camera.keys[0].position`: the coordinate -9e12 is beyond",
            ),
        ] {
            let e = parse(&format!("obj = \"a.obj\"\n{text}"))
                .expect_err("too far")
                .to_string();
            assert!(e.starts_with(want), "{e}");
        }
        // 10,000 km is well inside.
        assert!(parse("obj = \"a.obj\"\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [1e7, 0, 1e7]\ntarget = [1e7, 0, 9999990]\n[[lights.point]]\nposition = [1e7, 2, 1e7]\n").is_ok());
    }

    #[test]
    fn random_light_counts_are_bounded() {
        let text = |n: u64| format!("obj = \"a.obj\"\n[lights.random_points]\ncount = {n}\n");
        assert!(parse(&text(1 << 20)).is_ok());
        let e = parse(&text(4_000_000_000))
            .expect_err("too many")
            .to_string();
        assert_eq!(
            e,
            "s.toml:3: `lights.random_points.count`: 4000000000 lights; at most 1048576"
        );
    }

    #[test]
    fn anisotropy_is_one_to_sixteen_lookups() {
        let text = |n: i64| format!("obj = \"a.obj\"\nwidth = 64\nanisotropy = {n}\n");
        for n in [1, 2, 16] {
            let d = parse(&text(n)).expect("in range");
            assert_eq!(d.anisotropy.map(|a| *a.get_ref()), Some(n as u32));
        }
        for n in [0, 17] {
            let e = parse(&text(n)).expect_err("out of range").to_string();
            assert_eq!(
                e,
                format!(
                    "s.toml:3: `anisotropy`: {n} lookups; anisotropic filtering takes 1 \
                     (isotropic) to 16"
                )
            );
        }
        // Not a whole number of lookups: the reader's own error, with its line.
        let e = parse(&text(-1)).expect_err("negative").to_string();
        assert!(
            e.starts_with("s.toml:3: `anisotropy`: invalid value"),
            "{e}"
        );
    }

    #[test]
    fn full_description_parses() {
        let d = parse(
            "procedural = \"demo\"\nwidth = 64\nheight = 32\nframes = 3\n[camera]\n[[camera.keys]]\ntime = 1\nposition = [0,1,2]\ntarget = [0,0,0]\ncut = true\n[[camera.keys]]\ntime = 0\nposition = [0,1,3]\ntarget = [0,0,0]\n[lights.random_points]\ncount = 10\n[[animate]]\nobject = \"x\"\nspin_deg_per_s = 90\n",
        )
        .expect("parses");
        assert_eq!(d.width, Some(64));
        let path = camera_path(d.camera.as_ref()).expect("path");
        assert_eq!(path.keys[0].time, 0.0, "keys sorted by time");
        assert!(
            !path.keys[0].cut && path.keys[1].cut,
            "the cut stays with its key"
        );
        assert!(path.cut_between(0.5, 1.0));
        assert_eq!(
            d.lights
                .and_then(|l| l.random_points)
                .map(|r| *r.count.get_ref()),
            Some(10)
        );
    }
}
