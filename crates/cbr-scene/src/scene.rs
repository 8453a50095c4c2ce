//! The scene as the renderer sees it: objects (one material each), materials, textures, camera
//! path, lights, rigid motions and render settings. Coordinates are Y-up, right-handed, metres.

use glam::{DMat4, DQuat, DVec3};
use serde::Serialize;

use crate::camera::CameraPath;

/// One vertex as uploaded to the GPU (8 floats; the shader reads it as a float array).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    /// Top-left origin (OBJ's V is flipped on load).
    pub uv: [f32; 2],
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Up {
    #[default]
    Y,
    Z,
}

impl Up {
    /// A point or direction given in this up convention, in cbr's (Y-up): Z-up rotates by -90
    /// degrees about X, (x, y, z) -> (x, z, -y).
    pub fn to_y_up<T: Copy + std::ops::Neg<Output = T>>(self, v: [T; 3]) -> [T; 3] {
        match self {
            Up::Y => v,
            Up::Z => [v[0], v[2], -v[1]],
        }
    }
}

/// Where a material's alpha-test mask comes from (alpha < 0.5 is discarded).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum AlphaSource {
    Opaque,
    /// A channel (0 = red for grey masks, 3 = alpha) of a texture.
    Texture {
        tex: u32,
        channel: u32,
    },
}

#[derive(Clone, Debug, Serialize)]
pub struct Material {
    pub name: String,
    /// Diffuse albedo (linear); multiplies `kd_tex`.
    pub kd: [f32; 3],
    pub ks: [f32; 3],
    /// Blinn-Phong exponent.
    pub ns: f32,
    /// Emitted radiance.
    pub ke: [f32; 3],
    pub kd_tex: Option<u32>,
    pub alpha: AlphaSource,
    pub bump_tex: Option<u32>,
    pub bump_scale: f32,
}

impl Material {
    /// A neutral grey, untextured, non-specular material.
    pub fn named(name: &str) -> Material {
        Material {
            name: name.to_string(),
            kd: [0.8, 0.8, 0.8],
            ks: [0.0; 3],
            ns: 32.0,
            ke: [0.0; 3],
            kd_tex: None,
            alpha: AlphaSource::Opaque,
            bump_tex: None,
            bump_scale: 1.0,
        }
    }
}

/// A drawable: one mesh with one material. Its object ID is its index + 1 (0 = background).
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub material: u32,
    /// Where the object's local coordinates are centred in the world (f64): vertices are stored
    /// in f32 relative to it, so geometry far from the world origin keeps its precision (the
    /// renderer forms camera-relative transforms in f64). Loaded OBJs: the centre of the object's
    /// bounds where that makes its f32 vertices meaningfully finer, zero otherwise
    /// ([`crate::obj::recentre`]).
    pub origin: [f64; 3],
}

impl Object {
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// Light travelling along `direction`; `color * intensity` is the irradiance on a surface facing it.
#[derive(Clone, Debug, Serialize)]
pub struct DirLight {
    pub direction: [f32; 3],
    pub color: [f32; 3],
    pub intensity: f32,
}

/// Point light: irradiance `color * intensity / d^2`, windowed smoothly to zero at `range`.
#[derive(Clone, Debug, Serialize)]
pub struct PointLight {
    pub position: [f64; 3],
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: f32,
}

/// Rigid motion of some objects: spin about `pivot` and translation, both from time 0.
#[derive(Clone, Debug, Serialize)]
pub struct Motion {
    pub name: String,
    pub objects: Vec<u32>,
    pub pivot: [f64; 3],
    pub spin_axis: [f64; 3],
    pub spin_rad_per_s: f64,
    pub velocity: [f64; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub fps: f64,
    pub seed: u64,
    /// Exposure in stops, applied by the display transform only.
    pub exposure: f32,
    pub ambient: [f32; 3],
    /// Radiance where no geometry is drawn (a constant sky).
    pub background: [f32; 3],
    /// Shade with `map_bump` height maps (screen-space derivative bump mapping). Off by default:
    /// it shows bright seams along triangle edges on Šibenik (docs/native.md).
    pub bump: bool,
    /// Anisotropic texture filtering: at most this many trilinear lookups along a texture
    /// footprint's longer side, each at its shorter side's level (shaders/inc/aniso.glsl); 1 (the
    /// default): one isotropic trilinear lookup, the sampler's own. The scene's `anisotropy`, or
    /// `--anisotropy N`.
    pub anisotropy: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 1280,
            height: 720,
            frames: 1,
            fps: 30.0,
            seed: 0,
            exposure: 0.0,
            ambient: [0.03; 3],
            background: [0.0; 3],
            bump: false,
            anisotropy: 1,
        }
    }
}

/// The largest distance from the origin (metres, per coordinate) a scene may place anything at:
/// 2^43 m, about 8.8e12 m. Below it an f64 resolves 2^-10 m (0.98 mm) or finer, so an object's
/// f64 `origin`, camera keys and point lights keep millimetre precision; OBJ vertices, camera
/// keys and point lights beyond it are refused.
pub const MAX_COORDINATE: f64 = 8_796_093_022_208.0;

/// Why a coordinate cannot be held at millimetre precision: it is not a finite number, or it is
/// beyond [`MAX_COORDINATE`].
pub fn check_coordinate(v: f64) -> Result<(), String> {
    if !v.is_finite() {
        Err(format!("the coordinate {v} is not a finite number"))
    } else if v.abs() >= MAX_COORDINATE {
        Err(format!(
            "the coordinate {v:e} is beyond what f64 holds at 1 mm precision (|x| < 2^43 m, about 8.8e12 m)"
        ))
    } else {
        Ok(())
    }
}

/// The largest image side cbr accepts (Vulkan implementations guarantee at least 4096; lavapipe and
/// current GPUs allow 16384).
pub const MAX_RESOLUTION: u32 = 16384;

pub fn check_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 || width > MAX_RESOLUTION || height > MAX_RESOLUTION {
        return Err(format!(
            "resolution {width}x{height} is outside 1..={MAX_RESOLUTION} per side"
        ));
    }
    Ok(())
}

/// What loading counted and noticed; reported in run.json.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LoadStats {
    pub triangles: usize,
    /// Faces with fewer than three distinct vertices.
    pub dropped_faces: usize,
    /// Objects whose normals were computed (smooth, area-weighted).
    pub computed_normals: usize,
    /// Faces without texture coordinates (they sample UV (0,0)).
    pub faces_without_uvs: usize,
    pub fallback_textures: usize,
    pub warnings: Vec<String>,
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The file it came from, or `builtin:NAME`.
    pub source: String,
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub textures: Vec<crate::Texture>,
    pub camera: CameraPath,
    pub directional: Vec<DirLight>,
    pub points: Vec<PointLight>,
    pub motions: Vec<Motion>,
    pub settings: Settings,
    pub stats: LoadStats,
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug)]
pub struct Bounds {
    pub min: DVec3,
    pub max: DVec3,
}

impl Bounds {
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }
    pub fn radius(&self) -> f64 {
        (self.max - self.min).length() * 0.5
    }
}

impl Scene {
    pub fn time_of_frame(&self, frame: u32) -> f64 {
        f64::from(frame) / self.settings.fps
    }

    /// The object ID (index + 1; 0 is the background) of the first object named `name`.
    pub fn object_id(&self, name: &str) -> Option<u32> {
        self.objects
            .iter()
            .position(|o| o.name == name)
            .map(|i| i as u32 + 1)
    }

    /// Object-to-world transform of object `index` at time `t` (seconds).
    pub fn object_transform(&self, index: usize, t: f64) -> DMat4 {
        let mut m = DMat4::from_translation(DVec3::from(self.objects[index].origin));
        for motion in &self.motions {
            if motion.objects.contains(&(index as u32)) {
                let pivot = DVec3::from(motion.pivot);
                let axis = DVec3::from(motion.spin_axis).normalize_or(DVec3::Y);
                let spin = DMat4::from_translation(pivot)
                    * DMat4::from_quat(DQuat::from_axis_angle(axis, motion.spin_rad_per_s * t))
                    * DMat4::from_translation(-pivot);
                m = DMat4::from_translation(DVec3::from(motion.velocity) * t) * spin * m;
            }
        }
        m
    }

    pub fn bounds(&self) -> Bounds {
        bounds_of(&self.objects)
    }

    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(Object::triangles).sum()
    }
}

pub fn bounds_of(objects: &[Object]) -> Bounds {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for (o, v) in objects
        .iter()
        .flat_map(|o| o.vertices.iter().map(move |v| (o, v)))
    {
        let p = DVec3::from(o.origin)
            + DVec3::new(
                f64::from(v.pos[0]),
                f64::from(v.pos[1]),
                f64::from(v.pos[2]),
            );
        min = min.min(p);
        max = max.max(p);
    }
    if !min.is_finite() {
        min = DVec3::ZERO;
        max = DVec3::ZERO;
    }
    Bounds { min, max }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_is_eight_floats() {
        assert_eq!(std::mem::size_of::<Vertex>(), 32);
    }

    #[test]
    fn coordinates_are_bounded_where_f64_keeps_a_millimetre() {
        assert_eq!(MAX_COORDINATE, 2f64.powi(43));
        // The f64 step just below the bound is 2^-10 m, at the bound 2^-9 m.
        let below = f64::from_bits(MAX_COORDINATE.to_bits() - 1);
        assert!(MAX_COORDINATE - below <= 1e-3);
        assert!(f64::from_bits(MAX_COORDINATE.to_bits() + 1) - MAX_COORDINATE > 1e-3);
        assert!(check_coordinate(-below).is_ok());
        assert!(check_coordinate(1e7).is_ok());
        let e = check_coordinate(-MAX_COORDINATE).expect_err("at the bound");
        assert!(e.contains("1 mm precision"), "{e}");
        let e = check_coordinate(f64::NAN).expect_err("nan");
        assert_eq!(e, "the coordinate NaN is not a finite number");
    }

    #[test]
    fn resolutions_are_bounded() {
        assert!(check_resolution(1920, 1080).is_ok());
        assert!(check_resolution(0, 1080).is_err());
        assert!(check_resolution(100_000, 10).is_err());
    }
}
