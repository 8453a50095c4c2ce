//! `upscale[:bilinear|bicubic|fsr1][:SCALE][:sharpness=S][:lod=B]`: the filter, the low
//! resolution's size per axis, FSR 1's RCAS sharpness and the texture LOD bias, each read once
//! with its default; parameters in any
//! order, each at most once.

/// The scale per axis when none is given: 1/sqrt(2), the checkerboard's pixel count.
pub const DEFAULT_SCALE: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// RCAS sharpness in stops (0 the sharpest, each stop halves the sharpening): 0.2, the value
/// AMD's FSR 1 integration guide recommends (FidelityFX-CLI's example uses it too).
pub const DEFAULT_SHARPNESS: f32 = 0.2;

/// The sharpness range AMD documents for RCAS (FidelityFX-CLI: "from maximum (0.0) to minimum
/// (2.0)").
pub const MAX_SHARPNESS: f32 = 2.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UpscaleFilter {
    Bilinear,
    Bicubic,
    /// AMD FidelityFX Super Resolution 1: EASU then RCAS (docs/upscale.md).
    Fsr1,
}

impl UpscaleFilter {
    pub const ALL: [UpscaleFilter; 3] = [
        UpscaleFilter::Bilinear,
        UpscaleFilter::Bicubic,
        UpscaleFilter::Fsr1,
    ];

    pub fn name(self) -> &'static str {
        match self {
            UpscaleFilter::Bilinear => "bilinear",
            UpscaleFilter::Bicubic => "bicubic",
            UpscaleFilter::Fsr1 => "fsr1",
        }
    }

    fn from_name(s: &str) -> Option<UpscaleFilter> {
        UpscaleFilter::ALL.into_iter().find(|f| f.name() == s)
    }
}

/// What an `upscale` spec says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpscaleConfig {
    pub filter: UpscaleFilter,
    /// The low resolution per axis, in (0, 1].
    pub scale: f64,
    /// RCAS sharpness in stops (fsr1 only).
    pub sharpness: f32,
    /// The texture LOD bias (`lod=B`); `None`: log2(SCALE) for fsr1 (AMD's FSR 1 guide: the
    /// output's mip levels, detail for RCAS to keep), 0 for bilinear and bicubic (the low
    /// resolution's own levels). docs/upscale.md measures both.
    pub lod_bias: Option<f32>,
}

impl Default for UpscaleConfig {
    fn default() -> UpscaleConfig {
        UpscaleConfig {
            filter: UpscaleFilter::Bilinear,
            scale: DEFAULT_SCALE,
            sharpness: DEFAULT_SHARPNESS,
            lod_bias: None,
        }
    }
}

impl UpscaleConfig {
    /// The low resolution for a W x H output: W x SCALE by H x SCALE, rounded, at least 1.
    pub fn low_resolution(&self, width: u32, height: u32) -> (u32, u32) {
        let f = |v: u32| ((f64::from(v) * self.scale).round() as u32).max(1);
        (f(width), f(height))
    }

    /// The texture LOD bias: `lod=B`, else log2(SCALE) for fsr1 and 0 for the others.
    pub fn lod_bias(&self) -> f32 {
        self.lod_bias.unwrap_or(match self.filter {
            UpscaleFilter::Fsr1 => self.scale.log2() as f32,
            _ => 0.0,
        })
    }

    /// RCAS's weight scale: 2^-sharpness.
    pub fn sharpness_linear(&self) -> f32 {
        (-self.sharpness).exp2()
    }
}

const EXPECTED: &str =
    "a filter (bilinear, bicubic, fsr1), a scale in (0, 1], sharpness=S or lod=B";

pub fn parse(params: &[&str]) -> std::result::Result<UpscaleConfig, String> {
    let mut c = UpscaleConfig::default();
    let (mut filter, mut scale, mut sharpness, mut lod) = (None, None, None, None);
    let once = |slot: bool, p: &str, what: &str| match slot {
        true => Err(format!("`{p}`: upscale takes one {what}")),
        false => Ok(()),
    };
    for &p in params {
        if let Some(f) = UpscaleFilter::from_name(p) {
            once(filter.is_some(), p, "filter")?;
            filter = Some(f);
        } else if let Some(s) = p.strip_prefix("sharpness=") {
            once(sharpness.is_some(), p, "sharpness")?;
            sharpness = Some(match s.parse::<f32>() {
                Ok(v) if (0.0..=MAX_SHARPNESS).contains(&v) => v,
                _ => {
                    return Err(format!(
                        "sharpness `{s}` (RCAS stops from 0, the sharpest, to {MAX_SHARPNESS})"
                    ));
                }
            });
        } else if let Some(s) = p.strip_prefix("lod=") {
            once(lod.is_some(), p, "lod")?;
            lod = Some(match s.parse::<f32>() {
                Ok(v) if (-4.0..=4.0).contains(&v) => v,
                _ => return Err(format!("lod `{s}` (a texture LOD bias from -4 to 4)")),
            });
        } else if p.starts_with(|ch: char| ch.is_ascii_digit() || ch == '.' || ch == '-') {
            once(scale.is_some(), p, "scale")?;
            scale = Some(match p.parse::<f64>() {
                Ok(v) if v > 0.0 && v <= 1.0 => v,
                _ => {
                    return Err(format!(
                        "scale `{p}` (the low resolution per axis: a number in (0, 1])"
                    ));
                }
            });
        } else {
            return Err(crate::technique::unknown_param("upscale", p, EXPECTED));
        }
    }
    c.filter = filter.unwrap_or(c.filter);
    c.scale = scale.unwrap_or(c.scale);
    c.lod_bias = lod.or(c.lod_bias);
    if let Some(s) = sharpness {
        if c.filter != UpscaleFilter::Fsr1 {
            return Err(format!(
                "`sharpness={s}` is RCAS's, fsr1 only (the filter is {})",
                c.filter.name()
            ));
        }
        c.sharpness = s;
    }
    Ok(c)
}

/// `cbr render --filter`: the filter of an `upscale` spec (which always names one afterwards,
/// bilinear by default, first); a filter contradicting the spec's, or the flag on another
/// technique, is a [`cbr_gpu::GpuError::Config`] naming the spec.
pub fn apply_shorthand(
    spec: &mut crate::spec::Spec,
    filter: Option<UpscaleFilter>,
) -> std::result::Result<(), cbr_gpu::GpuError> {
    let refuse = |message: String| cbr_gpu::GpuError::Config {
        spec: spec.to_string(),
        message,
    };
    let name = &spec.technique.name;
    if name != "upscale" {
        return match filter {
            Some(_) => Err(refuse(format!(
                "--filter applies to the upscale technique, not `{name}`"
            ))),
            None => Ok(()),
        };
    }
    let params = &spec.technique.params;
    let named = params.iter().position(|p| UpscaleFilter::from_name(p).is_some());
    match (named, filter.map(UpscaleFilter::name)) {
        (Some(i), Some(f)) if params[i] != f => {
            return Err(refuse(format!("--filter {f} contradicts `{}`", params[i])));
        }
        (Some(_), _) => {}
        (None, f) => {
            let f = f.unwrap_or(UpscaleFilter::Bilinear.name());
            spec.technique.params.insert(0, f.to_string());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_bilinear_at_one_over_root_two_and_rcas_at_two_tenths_of_a_stop() {
        let c = parse(&[]).expect("default");
        assert_eq!(c, UpscaleConfig::default());
        assert_eq!(c.filter, UpscaleFilter::Bilinear);
        // The old fixed W/sqrt(2) x H/sqrt(2), rounded.
        assert_eq!(c.low_resolution(320, 180), (226, 127));
        assert_eq!(c.low_resolution(64, 36), (45, 25));
        assert_eq!(c.low_resolution(1, 1), (1, 1));
        let f = parse(&["fsr1"]).expect("fsr1");
        assert_eq!((f.filter, f.sharpness), (UpscaleFilter::Fsr1, 0.2));
        assert!((f.sharpness_linear() - 2f32.powf(-0.2)).abs() < 1e-6);
    }

    #[test]
    fn scale_and_sharpness_are_read_in_any_order() {
        let c = parse(&["fsr1", "0.5", "sharpness=1"]).expect("spec");
        assert_eq!((c.filter, c.scale, c.sharpness), (UpscaleFilter::Fsr1, 0.5, 1.0));
        assert_eq!(parse(&["sharpness=0", "0.77", "fsr1"]).expect("spec").scale, 0.77);
        assert_eq!(parse(&["fsr1", "lod=0.25"]).expect("lod").lod_bias(), 0.25);
        assert_eq!(parse(&[]).expect("default").lod_bias(), 0.0);
        assert_eq!(parse(&["bicubic", "0.5"]).expect("bicubic").lod_bias(), 0.0);
        assert_eq!(parse(&["fsr1", "0.5"]).expect("fsr1").lod_bias(), -1.0);
        assert!((parse(&["fsr1"]).expect("fsr1").lod_bias() + 0.5).abs() < 1e-6);
        assert_eq!(c.low_resolution(320, 180), (160, 90));
        let b = parse(&["0.77"]).expect("bare scale");
        assert_eq!((b.filter, b.low_resolution(320, 180)), (UpscaleFilter::Bilinear, (246, 139)));
        assert_eq!(parse(&["bicubic", "1"]).expect("scale 1").low_resolution(7, 5), (7, 5));
        assert_eq!(parse(&["0.001"]).expect("tiny").low_resolution(64, 36), (1, 1));
    }

    #[test]
    fn bad_parameters_are_one_sentence_naming_them() {
        for (params, needle) in [
            (&["2"][..], "scale `2`"),
            (&["0"], "scale `0`"),
            (&["-0.5"], "scale `-0.5`"),
            (&["0.5x"], "scale `0.5x`"),
            (&["nan"], "`nan` is not a parameter of upscale"),
            (&["fsr1", "sharpness=3"], "sharpness `3`"),
            (&["fsr1", "sharpness=-1"], "sharpness `-1`"),
            (&["fsr1", "sharpness="], "sharpness ``"),
            (&["bicubic", "sharpness=0.5"], "fsr1 only"),
            (&["sharpness=0.5"], "fsr1 only"),
            (&["fsr1", "0.5", "0.7"], "one scale"),
            (&["fsr1", "bicubic"], "one filter"),
            (&["fsr1", "sharpness=1", "sharpness=1"], "one sharpness"),
            (&["lanczos"], "`lanczos` is not a parameter of upscale"),
            (&["lod=-9"], "lod `-9`"),
            (&["lod=0", "lod=1"], "one lod"),
        ] {
            let e = parse(params).expect_err(needle);
            assert!(e.contains(needle), "{params:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn the_filter_flag_names_the_filter_first_and_refuses_a_contradiction() {
        let apply = |text: &str, f: Option<UpscaleFilter>| {
            let mut s = crate::spec::Spec::parse(text).expect("spec");
            apply_shorthand(&mut s, f).map(|()| s.to_string())
        };
        assert_eq!(apply("upscale", None).expect("ok"), "upscale:bilinear");
        assert_eq!(apply("upscale:0.5", None).expect("ok"), "upscale:bilinear:0.5");
        let fsr = Some(UpscaleFilter::Fsr1);
        assert_eq!(apply("upscale:0.5", fsr).expect("ok"), "upscale:fsr1:0.5");
        assert_eq!(apply("upscale:0.5:fsr1", fsr).expect("ok"), "upscale:0.5:fsr1");
        let e = apply("upscale:0.5:bicubic", fsr).expect_err("contradiction");
        assert!(e.to_string().contains("--filter fsr1 contradicts `bicubic`"), "{e}");
        assert!(apply("native", fsr).is_err());
        assert_eq!(apply("native", None).expect("ok"), "native");
    }
}
