//! The checkerboard technique's spec parameters:
//! `checkerboard[:LAYOUT][:MODE|none][:pixel|quad][:8|16][:fp16][:f32history][:debug][:prepass]`
//! `[:locations][:gradients][:tol=T][:without-velocity|depth|ids|clamp|prepass]`.
//! Every `cbr render` flag of the technique is one of these, so run.json's spec says it all.

use cbr_gpu::Layout;

use crate::resolve::{Mapping, ResolveMode, ResolveSettings};
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
