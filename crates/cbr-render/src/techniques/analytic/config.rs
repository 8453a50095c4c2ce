//! `analytic`'s parameters (`analytic[:seed][:frags=K][:samples=N][:aniso]`) and the device
//! features it needs.

use cbr_gpu::Caps;

use crate::technique::unknown_param;

/// The visibility mask's sample counts (`samples=N`; shaders/analytic/mask.glsl) and the default.
pub const MASK_SAMPLE_COUNTS: [u32; 3] = [32, 64, 128];
pub const DEFAULT_SAMPLES: u32 = 64;

/// Fragments kept per pixel unless `frags=K` says otherwise (lowered to what fits).
pub const DEFAULT_FRAGS: u32 = 32;
/// The most `frags=K` may ask for: resolve.comp holds the set of a pixel's kept fragments it
/// composites as the bits of two 32-bit words.
pub const MAX_FRAGS: u32 = 64;
/// The key's identity field: object IDs below 2^12, primitive IDs below 2^20.
pub const MAX_OBJECTS: usize = (1 << 12) - 1;
pub const MAX_PRIMITIVES: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnalyticConfig {
    pub seed: bool,
    /// Fragments kept per pixel asked for (`None`: the default, fitted to the device).
    pub frags: Option<u32>,
    /// The visibility mask's samples (one of [`MASK_SAMPLE_COUNTS`]).
    pub samples: u32,
    /// The albedo texture integrated over the footprint as a box (the default; `aniso`: one
    /// anisotropic trilinear filter).
    pub box_filter: bool,
}

pub fn parse(params: &[&str]) -> std::result::Result<AnalyticConfig, String> {
    let mut c = AnalyticConfig {
        seed: false,
        frags: None,
        samples: DEFAULT_SAMPLES,
        box_filter: true,
    };
    for p in params {
        match *p {
            "seed" => c.seed = true,
            "aniso" => c.box_filter = false,
            _ => {
                if let Some(n) = p.strip_prefix("frags=") {
                    let n: u32 = n
                        .parse()
                        .ok()
                        .filter(|&n| (1..=MAX_FRAGS).contains(&n))
                        .ok_or_else(|| format!("analytic frags=`{n}` (1 to {MAX_FRAGS})"))?;
                    c.frags = Some(n);
                } else if let Some(n) = p.strip_prefix("samples=") {
                    c.samples = n
                        .parse()
                        .ok()
                        .filter(|n| MASK_SAMPLE_COUNTS.contains(n))
                        .ok_or_else(|| format!("analytic samples=`{n}` (32, 64 or 128)"))?;
                } else {
                    return Err(unknown_param(
                        "analytic",
                        p,
                        "seed, frags=K, samples=N, aniso",
                    ));
                }
            }
        }
    }
    Ok(c)
}

pub(super) fn needs(_: &[&str], caps: &Caps) -> Option<String> {
    if !caps.geometry_shader {
        return Some("the geometryShader feature (the conservative raster)".into());
    }
    if !caps.int64_atomics {
        return Some(
            "64-bit storage-buffer atomics (shaderInt64, shaderBufferInt64Atomics: the K nearest)"
                .into(),
        );
    }
    (!caps.fragment_stores_and_atomics)
        .then(|| "the fragmentStoresAndAtomics feature (fragment lists)".into())
}
