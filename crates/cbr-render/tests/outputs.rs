//! Frame outputs as named layers: every layer and statistic a frame carries is one its
//! technique's registration declares (name, channels, host and EXR types, in the declared
//! order), every layer the EXR gets has the frame's size, and the typed accessors read back
//! what the technique wrote.

mod common;

use cbr_render::registry::find;
use cbr_render::techniques::{IdPass, deferred, mask};
use cbr_render::{AnalyticLayers, Coverage, FrameOutput, InterleavedLayers, ResolveOutput, Spec};
use common::{assert_clean, demo, gpu, render_spec};

/// Checks `out` against the declarations of `spec`'s technique.
fn check_declared(spec: &str, out: &FrameOutput) {
    let spec_ = Spec::parse(spec).expect("spec");
    let reg = find(&spec_.technique.name).expect("registered");
    let decls = reg.outputs.layers;
    let mut last = None;
    for l in &out.layers {
        let Some(at) = decls.iter().position(|d| d.name == l.name) else {
            panic!("{spec}: layer `{}` is not declared", l.name);
        };
        let d = &decls[at];
        assert!(
            last.is_none_or(|p| p < at),
            "{spec}: layer `{}` out of the declared order",
            l.name
        );
        last = Some(at);
        assert_eq!(l.channels, d.channels, "{spec}: `{}` channels", l.name);
        assert_eq!(l.samples.sample_type(), d.samples, "{spec}: `{}`", l.name);
        assert_eq!(l.exr, d.exr, "{spec}: `{}` EXR type", l.name);
        let n = l.width as usize * l.height as usize * l.channels.len();
        assert_eq!(l.samples.len(), n, "{spec}: `{}` samples", l.name);
        if l.exr.is_some() {
            assert_eq!(
                (l.width, l.height),
                (out.width, out.height),
                "{spec}: `{}`",
                l.name
            );
        }
    }
    for name in out.stats.keys() {
        assert!(
            reg.outputs.stats.iter().any(|d| d.name == name),
            "{spec}: statistic `{name}` is not declared"
        );
    }
}

fn names(out: &FrameOutput) -> Vec<&str> {
    out.layers.iter().map(|l| l.name.as_str()).collect()
}

#[test]
fn frames_carry_the_layers_and_statistics_their_registrations_declare() {
    let gpu = gpu();
    let s = demo(48, 32);
    let cases: &[(&str, &[&str])] = &[
        ("native", &[]),
        ("upscale", &[]),
        ("taau", &[]),
        ("taau:debug", &["taau"]),
        ("msaa:4", &[]),
        ("ssaa:2", &["coverage"]),
        ("checkerboard:split:none", &["mask"]),
        (
            "checkerboard:rotated:ours:prepass:debug",
            &[
                "mask",
                "prepass_depth",
                "prepass_object_id",
                "prepass_primitive_id",
                "resolve_parity",
                "resolve_missing",
                "resolve_reprojected",
                "resolve_rejected_id",
                "resolve_rejected_depth",
                "resolve_clamped",
                "resolve_spatial",
                "resolve_still",
                "resolve_velocity",
            ],
        ),
        ("interlaced:debug", &["mask", "resolve_parity"]),
        ("analytic:seed:frags=4", &["coverage", "analytic"]),
        ("deferred:vpls=8:rsm=16", &["vpls"]),
        (
            "interleaved:2x2:vpls=8:rsm=16:debug",
            &["vpls", "interleaved", "interleaved_mosaic"],
        ),
    ];
    for &(spec, expected) in cases {
        let frames = render_spec(&gpu, &s, spec, &[0, 1]);
        for out in &frames {
            check_declared(spec, out);
            let got = names(out);
            for e in expected {
                assert!(got.contains(e), "{spec}: no layer `{e}` in {got:?}");
            }
            if expected.is_empty() {
                assert!(out.layers.is_empty() && out.stats.is_empty(), "{spec}");
            }
        }
        let [first, second] = &frames[..] else {
            unreachable!()
        };
        // The typed accessors of each technique read what it wrote.
        match spec.split(':').next() {
            Some("ssaa") => {
                let c = Coverage::from_frame(first).expect("coverage");
                assert!(c.fraction.iter().all(|f| (0.0..=1.0).contains(f)));
                assert!(c.edge.iter().any(|&e| e != 0), "{spec}: no edge pixel");
            }
            Some("checkerboard") | Some("interlaced") => {
                for (f, out) in [first, second].into_iter().enumerate() {
                    assert_eq!(out.count("parity"), Some(f as u64 % 2), "{spec}");
                    let m = mask(out).expect("mask");
                    assert_eq!(m.len(), 48 * 32);
                    assert!(m.contains(&1) && m.contains(&0));
                }
                if spec.contains("none") {
                    assert!(ResolveOutput::from_frame(first).is_none(), "{spec}");
                    continue;
                }
                let (r0, r1) = (
                    ResolveOutput::from_frame(first).expect("resolved"),
                    ResolveOutput::from_frame(second).expect("resolved"),
                );
                assert!(r0.reset && !r1.reset, "{spec}: the first frame resets");
                let bits = r1.debug_bits.expect("debug bits");
                // The parity view is the pixels this frame rendered: the mask.
                let m = mask(second).expect("mask");
                let rendered = cbr_render::resolve::DBG_RENDERED;
                assert!(
                    bits.iter()
                        .zip(m)
                        .all(|(b, &m)| (b & rendered != 0) == (m != 0)),
                    "{spec}: the debug bits disagree with the mask"
                );
                if spec.contains("prepass") {
                    let (depth, ids) = IdPass::from_frame(second).expect("prepass");
                    assert_eq!((depth.len(), ids.len()), (48 * 32, 48 * 32));
                    assert!(ids.iter().any(|i| i[0] != 0));
                    assert!(r1.velocity.is_some(), "{spec}: the debug velocity");
                }
            }
            Some("analytic") => {
                let a = AnalyticLayers::from_frame(first).expect("analytic");
                assert_eq!(a.kept_per_pixel, 4);
                assert_eq!(
                    first.count("analytic.fragments"),
                    Some(a.fragments.iter().map(|&f| u64::from(f)).sum())
                );
                let c = Coverage::from_frame(first).expect("coverage");
                let edge = c.edge.iter().filter(|&&e| e != 0).count() as u64;
                assert_eq!(first.count("analytic.edge_pixels"), Some(edge));
            }
            Some("deferred") => {
                let v = deferred::vpls(first).expect("VPLs");
                assert_eq!(v.len(), 8);
                assert!(
                    v.iter().any(|v| v.position[3] == 1.0),
                    "{spec}: no live VPL"
                );
            }
            Some("interleaved") => {
                let i = InterleavedLayers::from_frame(first).expect("debug views");
                assert_eq!(i.tile, (2, 2));
                assert_eq!(i.roundtrip_mismatches, 0);
                let (mw, mh, texels) = i.mosaic.expect("mosaic");
                assert_eq!(texels.len(), (mw * mh) as usize);
                assert_eq!(deferred::vpls(first).expect("VPLs").len(), 8);
            }
            _ => {}
        }
    }
    assert_clean(&gpu);
}
