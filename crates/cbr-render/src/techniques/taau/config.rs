//! `taau[:SCALE][:OPTION...]`: temporal upsampling's parameters (docs/upsampling.md), each read
//! once with its default; parameters in any order, each at most once.

use crate::techniques::upscale::config::DEFAULT_SCALE;
use crate::techniques::upscale::config::MAX_SHARPNESS;

/// RCAS sharpness in stops: 1, RCAS's lobe at half strength (`upscale:fsr1`'s 0.2 keeps 87%):
/// sharpening an accumulated frame also sharpens what is left of the jitter's noise (measured
/// in docs/upsampling.md; FSR 2 makes its sharpening optional).
pub const DEFAULT_SHARPNESS: f32 = 1.0;

/// The reconstruction kernel of the current frame's samples and of the history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// Separable tent of one render pixel (the current frame) and one output pixel (the
    /// history): bilinear interpolation.
    Bilinear,
    /// Catmull-Rom (radius 2), radial on the current samples, separable on the history.
    Catmull,
    /// Lanczos-2, radial on the current samples with its radius sized to the upscale ratio,
    /// separable on the history (FSR 2).
    Lanczos,
}

impl Kernel {
    pub const ALL: [Kernel; 3] = [Kernel::Bilinear, Kernel::Catmull, Kernel::Lanczos];

    pub fn name(self) -> &'static str {
        match self {
            Kernel::Bilinear => "bilinear",
            Kernel::Catmull => "catmull",
            Kernel::Lanczos => "lanczos",
        }
    }
}

/// The parts `without-X` switches off.
pub const ABLATIONS: [&str; 7] = [
    "locks",
    "depth-clip",
    "ids",
    "reactive",
    "rcas",
    "stability",
    "surface-velocity",
];

/// What a `taau` spec says.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TaauConfig {
    /// The render resolution per axis, in (0, 1].
    pub scale: f64,
    pub kernel: Kernel,
    /// Thin-feature locks (FSR 2): a locked history is not rectified.
    pub locks: bool,
    /// Depth clip (FSR 2): the disocclusion a reconstructed previous depth shows drops the
    /// history.
    pub depth_clip: bool,
    /// The object test: a history texel of another object than the pixel's nearest sample,
    /// moving at least [`SPEED`] output pixels a frame faster or slower than that sample, is a
    /// disocclusion (`without-ids`: FSR 2's depth clip alone, which does not see a surface
    /// that turned away).
    pub ids: bool,
    /// FSR 2's reactive mask, made from the scene's own motion: a turning object (its own
    /// rotation this frame over 10 degrees, at most 1: `gpu_scene::turn`) keeps (1 - turn) of
    /// the history's cap, at rest as at speed, and its fragments withdraw the LOD bias as much
    /// (its shading changes every frame, so the history cannot average the sharper level).
    pub reactive: bool,
    /// RCAS on the accumulated output.
    pub rcas: bool,
    /// Luminance stability: an oscillating current luma weighs less.
    pub stability: bool,
    /// The dilation keeps a surface's own velocity (the 3x3 one plane, as `+taa`'s): the
    /// nearest texel of a receding floor moves faster, and the history lagged by the difference.
    pub surface_velocity: bool,
    /// RCAS sharpness in stops (0 the sharpest).
    pub sharpness: f32,
    /// The lobes of the history's Lanczos resampling (with the `lanczos` kernel): 3 (6x6 taps),
    /// or 2 (4x4, FSR 2's). Every reprojection resamples the history and the blur compounds
    /// over the frames it holds (docs/upsampling.md).
    pub history_lobes: u32,
    /// The history's weight cap where the pixel is still, in sample weights (a sample exactly on
    /// the output pixel weighs 1).
    pub accumulation: f32,
    /// The history's weight cap at [`SPEED`] output pixels per frame and faster (every
    /// reprojection resamples the history and softens it). 1 since 2026-12-07 (0.5 before):
    /// Šibenik moving 1.024x -> 0.988x `native`'s FLIP, the moving demo 1.086x -> 1.094x
    /// (docs/upsampling.md).
    pub moving_accumulation: f32,
    /// Rectification box: mean +- gamma sigma of the current 3x3 (perceptual YCoCg).
    pub gamma: f32,
    /// Relative depth separation that counts as a disocclusion.
    pub depth_tolerance: f32,
    /// The texture LOD bias; `None`: log2(SCALE) - 1 (FSR 2's recommendation).
    pub lod_bias: Option<f32>,
    /// `debug`: the disocclusion, lock and sample-weight layers read back each frame.
    pub debug: bool,
}

impl Default for TaauConfig {
    fn default() -> TaauConfig {
        TaauConfig {
            scale: DEFAULT_SCALE,
            kernel: Kernel::Lanczos,
            locks: true,
            depth_clip: true,
            ids: true,
            reactive: true,
            rcas: true,
            stability: true,
            surface_velocity: true,
            sharpness: DEFAULT_SHARPNESS,
            history_lobes: 3,
            accumulation: 8.0,
            moving_accumulation: 1.0,
            gamma: 1.0,
            depth_tolerance: 0.05,
            lod_bias: None,
            debug: false,
        }
    }
}

/// Output pixels per frame at which the history's cap falls linearly from `accum` to `moving`,
/// and the current frame's kernel widens linearly from W / w to 1 (the render grid's own).
pub const SPEED: f32 = 2.0;

impl TaauConfig {
    /// The render resolution for a W x H output: W x SCALE by H x SCALE, rounded, at least 1.
    pub fn render_resolution(&self, width: u32, height: u32) -> (u32, u32) {
        let f = |v: u32| ((f64::from(v) * self.scale).round() as u32).max(1);
        (f(width), f(height))
    }

    /// Jitter phases: 8 x (output width / render width)^2, truncated (FSR 2's count), at
    /// least 8.
    pub fn phases(&self, width: u32, height: u32) -> u32 {
        let (w, _) = self.render_resolution(width, height);
        let ratio = f64::from(width) / f64::from(w);
        ((8.0 * ratio * ratio) as u32).max(8)
    }

    /// The texture LOD bias: `lod=B`, else log2(SCALE) - 1.
    pub fn lod_bias(&self) -> f32 {
        self.lod_bias
            .unwrap_or_else(|| (self.scale.log2() - 1.0) as f32)
    }

    /// RCAS's weight scale: 2^-sharpness.
    pub fn sharpness_linear(&self) -> f32 {
        (-self.sharpness).exp2()
    }
}

const EXPECTED: &str = "a scale in (0, 1], bilinear|catmull|lanczos, without-X (X: locks, \
                        depth-clip, ids, reactive, rcas, stability, surface-velocity), sharpness=S, lobes=2|3, accum=A, moving=A, gamma=G, \
                        tol=T, lod=B or debug";

pub fn parse(params: &[&str]) -> std::result::Result<TaauConfig, String> {
    let mut c = TaauConfig::default();
    let mut seen: Vec<String> = Vec::new();
    let mut once = |key: &str, p: &str| {
        if seen.iter().any(|s| s == key) {
            return Err(format!("`{p}`: taau takes one {key}"));
        }
        seen.push(key.to_string());
        Ok(())
    };
    let num = |p: &str, v: &str, lo: f32, hi: f32| match v.parse::<f32>() {
        Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        _ => Err(format!("`{p}`: a number from {lo} to {hi}")),
    };
    for &p in params {
        if let Some(k) = Kernel::ALL.into_iter().find(|k| k.name() == p) {
            once("kernel", p)?;
            c.kernel = k;
        } else if let Some(x) = p.strip_prefix("without-") {
            once(p, p)?;
            match x {
                "locks" => c.locks = false,
                "depth-clip" => c.depth_clip = false,
                "ids" => c.ids = false,
                "reactive" => c.reactive = false,
                "rcas" => c.rcas = false,
                "stability" => c.stability = false,
                "surface-velocity" => c.surface_velocity = false,
                _ => {
                    return Err(format!(
                        "`{p}`: taau can go without {}",
                        ABLATIONS.join(", ")
                    ));
                }
            }
        } else if p == "debug" {
            once("debug", p)?;
            c.debug = true;
        } else if let Some((k, v)) = p.split_once('=') {
            once(k, p)?;
            match k {
                "sharpness" => c.sharpness = num(p, v, 0.0, MAX_SHARPNESS)?,
                "accum" => c.accumulation = num(p, v, 1.0, 1024.0)?,
                "moving" => c.moving_accumulation = num(p, v, 0.0, 1024.0)?,
                "gamma" => c.gamma = num(p, v, 0.25, 16.0)?,
                "tol" => c.depth_tolerance = num(p, v, 0.0, 1.0)?,
                "lod" => c.lod_bias = Some(num(p, v, -4.0, 4.0)?),
                "lobes" => {
                    c.history_lobes = match v {
                        "2" => 2,
                        "3" => 3,
                        _ => return Err(format!("`{p}`: the history's Lanczos lobes, 2 or 3")),
                    }
                }
                _ => return Err(crate::technique::unknown_param("taau", p, EXPECTED)),
            }
        } else if p.starts_with(|ch: char| ch.is_ascii_digit() || ch == '.' || ch == '-') {
            once("scale", p)?;
            c.scale = match p.parse::<f64>() {
                Ok(v) if v > 0.0 && v <= 1.0 => v,
                _ => {
                    return Err(format!(
                        "scale `{p}` (the render resolution per axis: a number in (0, 1])"
                    ));
                }
            };
        } else {
            return Err(crate::technique::unknown_param("taau", p, EXPECTED));
        }
    }
    if c.kernel != Kernel::Lanczos && seen.iter().any(|s| s == "lobes") {
        return Err(format!(
            "`lobes` is the Lanczos history's; taau `{}` resamples with its own kernel",
            c.kernel.name()
        ));
    }
    if !c.rcas && seen.iter().any(|s| s == "sharpness") {
        return Err("`sharpness` is RCAS's; taau `without-rcas` has none".into());
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_follow_fsr2_at_the_checkerboards_pixel_count() {
        let c = parse(&[]).expect("default");
        assert_eq!(c, TaauConfig::default());
        assert_eq!(c.render_resolution(320, 180), (226, 127));
        // 8 x (320 / 226)^2 = 16.04: 16 phases; at 0.5, 32.
        assert_eq!(c.phases(320, 180), 16);
        let h = parse(&["0.5"]).expect("half");
        assert_eq!((h.render_resolution(320, 180), h.phases(320, 180)), ((160, 90), 32));
        assert!((c.lod_bias() - (-1.5)).abs() < 1e-6);
        assert!((h.lod_bias() - (-2.0)).abs() < 1e-6);
        assert_eq!(parse(&["lod=-0.5"]).expect("lod").lod_bias(), -0.5);
        assert_eq!(parse(&["1"]).expect("1").phases(64, 36), 8);
    }

    #[test]
    fn options_are_read_in_any_order() {
        let c = parse(&["without-locks", "0.77", "catmull", "without-rcas", "debug"]).expect("ok");
        assert!(!c.locks && !c.rcas && c.depth_clip && c.stability && c.debug);
        assert_eq!((c.scale, c.kernel), (0.77, Kernel::Catmull));
        let d = parse(&["accum=16", "gamma=1.5", "tol=0.1", "without-depth-clip"]).expect("ok");
        assert_eq!((d.accumulation, d.gamma, d.depth_tolerance), (16.0, 1.5, 0.1));
        assert!(!d.depth_clip);
        assert!(!parse(&["without-stability"]).expect("ok").stability);
        assert!(TaauConfig::default().ids && !parse(&["without-ids"]).expect("ok").ids);
        assert_eq!(TaauConfig::default().history_lobes, 3);
        assert!(TaauConfig::default().reactive && !parse(&["without-reactive"]).expect("ok").reactive);
        assert_eq!(parse(&["lobes=2", "lanczos"]).expect("ok").history_lobes, 2);
    }

    #[test]
    fn bad_parameters_are_one_sentence_naming_them() {
        for (params, needle) in [
            (&["2"][..], "scale `2`"),
            (&["0"], "scale `0`"),
            (&["nan"], "`nan` is not a parameter of taau"),
            (&["without-clip"], "taau can go without"),
            (&["lanczos", "catmull"], "one kernel"),
            (&["0.5", "0.7"], "one scale"),
            (&["accum=0"], "`accum=0`"),
            (&["gamma=inf"], "`gamma=inf`"),
            (&["sharpness=3"], "`sharpness=3`"),
            (&["without-rcas", "sharpness=1"], "RCAS's"),
            (&["debug", "debug"], "one debug"),
            (&["lobes=4"], "2 or 3"),
            (&["catmull", "lobes=2"], "Lanczos history's"),
            (&["speed=2"], "`speed=2` is not a parameter of taau"),
        ] {
            let e = parse(params).expect_err(needle);
            assert!(e.contains(needle), "{params:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
