//! `deferred`'s parameters (`vpls=N`, `points=N`, `rsm=R`, `reach=D`, `clamp=D`), shared by its
//! passes and by `interleaved`.

use crate::technique::unknown_param;

pub const MAX_VPLS: u32 = 16384;
/// The most extra point lights (each pixel sums them all too).
pub const MAX_POINTS: u32 = 16384;
/// The reflective shadow map's side unless `rsm=R` says otherwise, and its bounds.
pub const DEFAULT_RSM: u32 = 512;
pub const MIN_RSM: u32 = 16;
pub const MAX_RSM: u32 = 4096;
/// How far from the camera (metres, a cube's half-side) the map frames the scene unless
/// `reach=D` says otherwise.
pub const DEFAULT_REACH: f32 = 32.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeferredConfig {
    /// VPLs from the sun's reflective shadow map (0: no indirect light).
    pub vpls: u32,
    /// Random point lights added to the scene's (deterministic per scene seed).
    pub points: u32,
    /// The reflective shadow map's side in texels.
    pub rsm: u32,
    /// The map frames the scene within this many metres of the camera (a cube's half-side); the
    /// random point lights fill the scene within this many metres of the camera path.
    pub reach: f32,
    /// The VPL clamp distance in metres (1/max(d^2, clamp^2)); `None`: the VPLs' mean spacing,
    /// sqrt(map area / N).
    pub clamp: Option<f32>,
    /// The lighting pass skips a point light where no pixel of a SIMD group is within its range
    /// (its term is exactly 0 there; shaders/deferred/lighting.comp). `cull=0` shades every
    /// light at every pixel, as before 2026-11-28 (the same frame; for timing it).
    pub cull: bool,
}

fn count(key: &str, value: &str, max: u32, what: &str) -> std::result::Result<u32, String> {
    let n: u64 = value
        .parse()
        .map_err(|_| format!("deferred {key}=`{value}`: give a whole number from 0 to {max}"))?;
    if n > u64::from(max) {
        return Err(format!(
            "deferred {key}={n}: at most {max} {what} (every pixel sums every one)"
        ));
    }
    Ok(n as u32)
}

fn metres(key: &str, value: &str) -> std::result::Result<f32, String> {
    value
        .parse()
        .ok()
        .filter(|d: &f32| d.is_finite() && *d > 0.0 && *d <= 1e9)
        .ok_or_else(|| {
            format!("deferred {key}=`{value}`: a distance in metres, above 0, at most 1e9")
        })
}

pub fn parse(params: &[&str]) -> std::result::Result<DeferredConfig, String> {
    let mut c = DeferredConfig {
        vpls: 0,
        points: 0,
        rsm: DEFAULT_RSM,
        reach: DEFAULT_REACH,
        clamp: None,
        cull: true,
    };
    for p in params {
        let (key, value) = p.split_once('=').unwrap_or((p, ""));
        match key {
            "vpls" => c.vpls = count(key, value, MAX_VPLS, "VPLs")?,
            "points" => c.points = count(key, value, MAX_POINTS, "point lights")?,
            "rsm" => {
                c.rsm = value
                    .parse()
                    .ok()
                    .filter(|r| (MIN_RSM..=MAX_RSM).contains(r))
                    .ok_or_else(|| {
                        format!("deferred rsm=`{value}`: a side from {MIN_RSM} to {MAX_RSM} texels")
                    })?
            }
            "clamp" => c.clamp = Some(metres(key, value)?),
            "reach" => c.reach = metres(key, value)?,
            "cull" => {
                c.cull = match value {
                    "0" => false,
                    "1" => true,
                    _ => return Err(format!("deferred cull=`{value}`: cull=0 or cull=1")),
                }
            }
            _ => {
                return Err(unknown_param(
                    "deferred",
                    p,
                    "vpls=N, points=N, rsm=R, reach=D, clamp=D, cull=0|1",
                ));
            }
        }
    }
    if u64::from(c.vpls) > u64::from(c.rsm) * u64::from(c.rsm) {
        return Err(format!(
            "deferred vpls={}: more VPLs than the {}x{} reflective shadow map has texels",
            c.vpls, c.rsm, c.rsm
        ));
    }
    Ok(c)
}
