//! What a bench run measures: the sweep file, configurations (a spec with sweep values filled
//! in), resolutions.

use anyhow::{Context, Result};
use cbr_render::{CheckerboardConfig, Mapping, RenderSettings};
use cbr_scene::check_resolution;
use serde::{Deserialize, Serialize};

/// The sweep file (`--sweep FILE.toml`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Scenes the run measures one after the other (paths relative to the sweep file; a scene
    /// named on the command line replaces them).
    pub scenes: Option<Vec<String>>,
    pub techniques: Option<Vec<String>>,
    pub resolutions: Option<Vec<String>>,
    pub mappings: Option<Vec<String>>,
    pub groups: Option<Vec<u32>>,
    pub lod_biases: Option<Vec<f32>>,
    pub warmup: Option<u32>,
    pub frames: Option<u32>,
    pub reference: Option<String>,
}

/// One configuration to measure.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// The spec as written, with sweep values appended (e.g. `checkerboard:rotated:ours:pixel:16`).
    pub name: String,
    #[serde(skip)]
    pub settings: RenderSettings,
}

pub fn parse_resolution(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("resolution `{s}`: expected WxH, e.g. 1920x1080"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("resolution `{s}`"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("resolution `{s}`"))?;
    check_resolution(w, h).map_err(anyhow::Error::msg)?;
    Ok((w, h))
}

/// Parses one configuration spec for a resolution (any registered technique and post chain).
/// Returns the settings and whether a checkerboard spec named a mapping and a group (sweeps
/// fill the others).
pub fn parse_spec(spec: &str, w: u32, h: u32) -> Result<(RenderSettings, bool, bool)> {
    let mut s = RenderSettings::parse(w, h, spec).map_err(anyhow::Error::msg)?;
    // Benchmarks also time the resolve's copy-kernel floor.
    s.instrument = true;
    let named = |p: &[&str]| {
        s.spec
            .technique
            .params
            .iter()
            .any(|x| p.contains(&x.as_str()))
    };
    let is_cb = s.spec.technique.name == "checkerboard";
    Ok((
        s.clone(),
        is_cb && named(&["pixel", "quad"]),
        is_cb && named(&["8", "16"]),
    ))
}

/// The checkerboard configuration of settings, if they are a checkerboard spec.
pub fn checkerboard(s: &RenderSettings) -> Option<CheckerboardConfig> {
    (s.spec.technique.name == "checkerboard")
        .then(|| CheckerboardConfig::parse(&s.spec.technique.params()).ok())
        .flatten()
}

/// The cross product of specs and sweeps at one resolution.
pub fn expand(
    specs: &[String],
    w: u32,
    h: u32,
    mappings: &[Mapping],
    groups: &[u32],
    lod_biases: &[f32],
) -> Result<Vec<Config>> {
    let mut out = Vec::new();
    for spec in specs {
        let (base, named_mapping, named_group) = parse_spec(spec, w, h)?;
        let cb = checkerboard(&base);
        let is_resolved = cb.is_some_and(|c| c.resolve.is_some());
        let maps: Vec<Option<Mapping>> = if is_resolved && !named_mapping && !mappings.is_empty() {
            mappings.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        let grps: Vec<Option<u32>> = if is_resolved && !named_group && !groups.is_empty() {
            groups.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        let biases: Vec<Option<f32>> = if cb.is_some() && !lod_biases.is_empty() {
            lod_biases.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        for m in &maps {
            for g in &grps {
                for b in &biases {
                    let mut s = base.clone();
                    let mut name = spec.clone();
                    if let Some(mut c) = cb {
                        if let (Some(r), Some(m)) = (c.resolve.as_mut(), m) {
                            r.mapping = *m;
                            name += if *m == Mapping::Pixel {
                                ":pixel"
                            } else {
                                ":quad"
                            };
                        }
                        if let (Some(r), Some(g)) = (c.resolve.as_mut(), g) {
                            r.group = *g;
                            name += &format!(":{g}");
                        }
                        s.spec.technique.params = c.params();
                    }
                    if let Some(b) = b {
                        s.lod_bias = Some(*b);
                        name += &format!(":lod{b}");
                    }
                    out.push(Config { name, settings: s });
                }
            }
        }
    }
    Ok(out)
}
