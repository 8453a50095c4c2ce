//! The checkerboard technique's spec parameters:
//! `checkerboard[:LAYOUT][:MODE|none][:pixel|quad][:8|16][:fp16][:f32history][:debug][:prepass]`
//! `[:locations][:gradients][:tol=T][:without-velocity|depth|ids|clamp|prepass]`.
//! Every `cbr render` flag of the technique is one of these, so run.json's spec says it all.

use cbr_gpu::{GpuError, Layout};

use crate::resolve::{Mapping, ResolveMode, ResolveSettings};
use crate::spec::Spec;
use crate::technique::unknown_param;

/// How texture LOD follows the sample spacing of a layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LodMode {
    /// A LOD bias (`lod_bias`, default per layout).
    Bias,
    /// `textureGrad` with the derivatives turned into full-res screen derivatives (then scaled by
    /// 2^`lod_bias`, default 0).
    Gradients,
}

impl LodMode {
    /// Each layout's default. Split and msaa2x space their samples 2 px apart on both axes, so a
    /// bias of -1 gives exactly the full-res footprint. The rotated lattice's neighbours are
    /// diagonal, sqrt(2) px apart: no isotropic bias matches its footprint, and on alpha-tested
    /// foliage (1280x720, against native) a bias of -0.5 left the rotated layout at 3.8x split's
    /// FLIP where gradients bring it to 0.86x (docs/resolve.md). Masked keeps native's quads and
    /// derivatives.
    pub fn default_for(layout: Layout) -> LodMode {
        match layout {
            Layout::Rotated => LodMode::Gradients,
            Layout::Masked | Layout::Split | Layout::Msaa2x => LodMode::Bias,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LodMode::Bias => "bias",
            LodMode::Gradients => "gradients",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckerboardConfig {
    pub layout: Layout,
    pub lod_mode: LodMode,
    /// `None` (`:none`): the raw checkerboard frame, missing pixels alpha 0, a mask layer.
    pub resolve: Option<ResolveSettings>,
    /// A native-resolution depth + ID pass before the checkerboard raster, no shading (what
    /// PS4 Pro hardware gives Decima).
    pub prepass: bool,
    /// msaa2x only: odd frames move the samples (VK_EXT_sample_locations) instead of shifting
    /// the viewport.
    pub locations: bool,
}

const EXPECTED: &str = "a layout (rotated, split, masked, msaa2x) first, then a resolve mode \
    (ours, fused, pq4k, intel, spatial, temporal, none) and options pixel, quad, 8, 16, fp16, \
    f32history, debug, prepass, locations, bias, gradients, tol=T, without-velocity|depth|ids|clamp|prepass";

/// run.json's `settings.checkerboard`: layout, LOD mode, resolve settings, prepass and sample
/// locations of these parameters (`None` where they do not parse).
pub fn settings_json(params: &[&str]) -> Option<serde_json::Value> {
    let c = CheckerboardConfig::parse(params).ok()?;
    Some(serde_json::json!({
        "layout": c.layout.name(),
        "lod_mode": c.lod_mode,
        "resolve": c.resolve,
        "id_prepass": c.prepass,
        "sample_locations": c.locations,
    }))
}

impl CheckerboardConfig {
    pub fn new(layout: Layout, resolve: Option<ResolveSettings>) -> CheckerboardConfig {
        CheckerboardConfig {
            layout,
            lod_mode: LodMode::default_for(layout),
            resolve,
            prepass: false,
            locations: false,
        }
    }

    pub fn parse(params: &[&str]) -> Result<CheckerboardConfig, String> {
        let mut it = params.iter().copied().peekable();
        let layout = match it.peek() {
            None => Layout::Rotated,
            Some(p) => match Layout::ALL.into_iter().find(|l| l.name() == *p) {
                Some(l) => {
                    it.next();
                    l
                }
                None => return Err(unknown_param("checkerboard", p, EXPECTED)),
            },
        };
        let mut r = ResolveSettings::default();
        let mut c = CheckerboardConfig::new(layout, None);
        let mut none = false;
        for p in it {
            let a = &mut r.ablation;
            match p {
                "none" => none = true,
                "fused" => {
                    r.mode = ResolveMode::Ours;
                    r.fused = true;
                }
                "pixel" => r.mapping = Mapping::Pixel,
                "quad" => r.mapping = Mapping::Quad,
                "8" => r.group = 8,
                "16" => r.group = 16,
                "fp16" => r.fp16 = true,
                "f32history" => r.f32_history = true,
                "debug" => r.debug = true,
                "prepass" => c.prepass = true,
                "locations" => c.locations = true,
                "bias" => c.lod_mode = LodMode::Bias,
                "gradients" => c.lod_mode = LodMode::Gradients,
                "without-velocity" => a.velocity = false,
                "without-depth" => a.depth = false,
                "without-ids" => a.ids = false,
                "without-clamp" => a.clamp = false,
                "without-prepass" => a.prepass = false,
                _ => {
                    if let Some(t) = p.strip_prefix("tol=") {
                        r.depth_tolerance = t
                            .parse()
                            .map_err(|_| format!("`{p}`: the depth tolerance is a number"))?;
                    } else if let Some(m) = ResolveMode::ALL.into_iter().find(|m| m.name() == p) {
                        r.mode = m;
                    } else {
                        return Err(unknown_param("checkerboard", p, EXPECTED));
                    }
                }
            }
        }
        r.validate()?;
        if c.locations && layout != Layout::Msaa2x {
            return Err("`locations` applies to the msaa2x layout".into());
        }
        c.resolve = (!none).then_some(r);
        Ok(c)
    }

    /// The canonical parameters (defaults left out), the inverse of `parse`.
    pub fn params(&self) -> Vec<String> {
        let mut p = vec![self.layout.name().to_string()];
        let d = ResolveSettings::default();
        match &self.resolve {
            None => p.push("none".into()),
            Some(r) => {
                p.push(if r.fused { "fused" } else { r.mode.name() }.into());
                if r.mapping != d.mapping {
                    p.push("pixel".into());
                }
                if r.group != d.group {
                    p.push(r.group.to_string());
                }
                for (on, name) in [(r.fp16, "fp16"), (r.f32_history, "f32history")] {
                    if on {
                        p.push(name.into());
                    }
                }
            }
        }
        if self.prepass {
            p.push("prepass".into());
        }
        if self.locations {
            p.push("locations".into());
        }
        if self.lod_mode != LodMode::default_for(self.layout) {
            p.push(self.lod_mode.name().into());
        }
        if let Some(r) = &self.resolve {
            if r.debug {
                p.push("debug".into());
            }
            if r.depth_tolerance != d.depth_tolerance {
                p.push(format!("tol={}", r.depth_tolerance));
            }
            let a = &r.ablation;
            for (on, name) in [
                (a.velocity, "velocity"),
                (a.depth, "depth"),
                (a.ids, "ids"),
                (a.clamp, "clamp"),
                (a.prepass, "prepass"),
            ] {
                if !on {
                    p.push(format!("without-{name}"));
                }
            }
        }
        p
    }

    /// The spec `checkerboard:...` of this configuration.
    pub fn spec(&self) -> crate::spec::Spec {
        crate::spec::Spec {
            technique: crate::spec::Part {
                name: "checkerboard".into(),
                params: self.params(),
            },
            post: Vec::new(),
        }
    }

    /// The mip bias that matches the layout's sample spacing: 2 px (split, msaa2x) is one level,
    /// sqrt(2) px (rotated) half a level; none with gradients, which already are full-res
    /// pixels'. `fused` (jittered, accumulated) looks up one level finer, as `+taa` does.
    pub fn default_lod_bias(&self) -> f32 {
        let layout = match (self.lod_mode, self.layout) {
            (LodMode::Gradients, _) | (_, Layout::Masked) => 0.0,
            (_, Layout::Split | Layout::Msaa2x) => -1.0,
            (_, Layout::Rotated) => -0.5,
        };
        let fused = self.resolve.is_some_and(|r| r.fused);
        layout
            + if fused {
                crate::post::taa::TaaConfig::OURS.lod_bias
            } else {
                0.0
            }
    }
}

/// The checkerboard technique's `cbr render` shorthand flags (`--layout`, `--resolve`,
/// `--resolve-mapping`, ...), each an edit of the spec's parameters; run.json records the result.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckerboardShorthand {
    pub layout: Option<Layout>,
    /// `Some(None)`: `--resolve none`, the raw checkerboard frame.
    pub resolve: Option<Option<ResolveMode>>,
    pub mapping: Option<Mapping>,
    pub group: Option<u32>,
    pub fp16: bool,
    pub f32_history: bool,
    pub debug: bool,
    /// `--resolve-without`: inputs of `ours` switched off (velocity, depth, ids, clamp, prepass).
    pub without: Vec<String>,
    pub depth_tolerance: Option<f32>,
    pub prepass: bool,
    pub locations: bool,
    pub lod_mode: Option<LodMode>,
}

impl CheckerboardShorthand {
    /// The flags given, by their command-line names.
    pub fn given(&self) -> Vec<&'static str> {
        [
            ("--layout", self.layout.is_some()),
            ("--resolve", self.resolve.is_some()),
            ("--resolve-mapping", self.mapping.is_some()),
            ("--resolve-group", self.group.is_some()),
            ("--resolve-fp16", self.fp16),
            ("--resolve-f32-history", self.f32_history),
            ("--resolve-debug", self.debug),
            ("--resolve-without", !self.without.is_empty()),
            ("--depth-tolerance", self.depth_tolerance.is_some()),
            ("--id-prepass", self.prepass),
            ("--msaa2x-sample-locations", self.locations),
            ("--lod-mode", self.lod_mode.is_some()),
        ]
        .into_iter()
        .filter_map(|(flag, set)| set.then_some(flag))
        .collect()
    }

    /// Edits a `checkerboard` spec's parameters into their canonical form with the flags applied.
    /// A flag that contradicts a parameter the spec names, or any flag on another technique, is a
    /// [`GpuError::Config`] naming the spec.
    pub fn apply(&self, spec: &mut Spec) -> Result<(), GpuError> {
        let text = spec.to_string();
        let refuse = |message: String| GpuError::Config {
            spec: text.clone(),
            message,
        };
        let name = &spec.technique.name;
        if name != "checkerboard" {
            return match self.given().first() {
                Some(flag) => Err(refuse(format!(
                    "{flag} applies to the checkerboard technique, not `{name}`"
                ))),
                None => Ok(()),
            };
        }
        let params = spec.technique.params();
        let mut c = CheckerboardConfig::parse(&params).map_err(refuse)?;
        if let Some(layout) = self.layout {
            if !params.is_empty() && c.layout != layout {
                return Err(refuse(format!(
                    "--layout {} contradicts the spec's layout `{}`",
                    layout.name(),
                    c.layout.name()
                )));
            }
            if c.layout != layout {
                c.lod_mode = LodMode::default_for(layout);
            }
            c.layout = layout;
        }
        if let Some(mode) = self.resolve {
            if params.len() > 1 && c.resolve.map(|r| r.mode) != mode {
                return Err(refuse(
                    "--resolve contradicts the spec's resolve mode".to_string(),
                ));
            }
            c.resolve = mode.map(|mode| ResolveSettings {
                mode,
                ..c.resolve.unwrap_or_default()
            });
        }
        if let Some(r) = c.resolve.as_mut() {
            r.mapping = self.mapping.unwrap_or(r.mapping);
            r.group = self.group.unwrap_or(r.group);
            r.fp16 |= self.fp16;
            r.f32_history |= self.f32_history;
            r.debug |= self.debug;
            r.depth_tolerance = self.depth_tolerance.unwrap_or(r.depth_tolerance);
            let a = &mut r.ablation;
            for w in &self.without {
                match w.as_str() {
                    "velocity" => a.velocity = false,
                    "depth" => a.depth = false,
                    "ids" => a.ids = false,
                    "clamp" => a.clamp = false,
                    "prepass" => a.prepass = false,
                    _ => {
                        return Err(refuse(format!(
                            "--resolve-without {w} (velocity, depth, ids, clamp or prepass)"
                        )));
                    }
                }
            }
            r.validate().map_err(refuse)?;
        }
        c.prepass |= self.prepass;
        c.locations |= self.locations;
        c.lod_mode = self.lod_mode.unwrap_or(c.lod_mode);
        // The edited configuration must still read back (e.g. locations on msaa2x only).
        let edited = c.params();
        CheckerboardConfig::parse(&edited.iter().map(String::as_str).collect::<Vec<_>>())
            .map_err(refuse)?;
        spec.technique.params = edited;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_round_trip_through_the_canonical_form() {
        for s in [
            "rotated:ours",
            "split:pq4k:prepass",
            "masked:none",
            "rotated:ours:pixel:16:fp16:f32history:prepass:bias:debug:tol=0.1:without-ids:without-clamp",
            "split:ours:gradients",
            "msaa2x:intel:locations",
            "rotated:fused:prepass",
        ] {
            let p: Vec<&str> = s.split(':').collect();
            let c = CheckerboardConfig::parse(&p).unwrap_or_else(|e| panic!("{s}: {e}"));
            assert_eq!(c.params().join(":"), s);
        }
        let c = CheckerboardConfig::parse(&[]).expect("defaults");
        assert_eq!(c.params(), ["rotated", "ours"]);
        assert_eq!(
            (c.lod_mode, c.default_lod_bias()),
            (LodMode::Gradients, 0.0)
        );
        let b = CheckerboardConfig::parse(&["rotated", "bias"]).expect("bias");
        assert_eq!((b.lod_mode, b.default_lod_bias()), (LodMode::Bias, -0.5));
        let s = CheckerboardConfig::parse(&["split"]).expect("split");
        assert_eq!((s.lod_mode, s.default_lod_bias()), (LodMode::Bias, -1.0));
        let r = CheckerboardConfig::parse(&["split", "temporal", "quad", "8"])
            .expect("parse")
            .resolve
            .expect("resolve");
        assert_eq!(
            (r.mode, r.mapping, r.group),
            (ResolveMode::Temporal, Mapping::Quad, 8)
        );
        for bad in [
            &["hexagon"][..],
            &["rotated", "magic"],
            &["rotated", "tol=x"],
            &["rotated", "tol=-1"],
            &["rotated", "locations"],
        ] {
            assert!(CheckerboardConfig::parse(bad).is_err(), "{bad:?}");
        }
    }
}
