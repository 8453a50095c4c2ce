//! What `cbr render` writes for particular techniques beyond the frame's own layers: EXR layers
//! (coverage, analytic, interleaved, the resolve's debug views) and run.json's per-frame
//! summaries and per-technique settings. PNGs of the same: crate::render::pngs.

use cbr_render::resolve::DEBUG_VIEWS;
use cbr_render::{CheckerboardConfig, FrameOutput, Spec};
use serde_json::json;

/// run.json's per-frame summaries of the technique's extra outputs (`null` where none), by key.
pub fn frame_summaries(out: &FrameOutput) -> [(&'static str, serde_json::Value); 2] {
    [
        ("analytic", analytic_summary(out)),
        ("interleaved", interleaved_summary(out)),
    ]
}

/// run.json's `settings` entries of the spec's technique (`null` where not that technique), by
/// key.
pub fn settings(spec: &Spec) -> [(&'static str, serde_json::Value); 1] {
    [("checkerboard", checkerboard_json(spec))]
}

/// The checkerboard configuration of a spec, for run.json (layout, LOD mode, resolve settings).
fn checkerboard_json(spec: &Spec) -> serde_json::Value {
    if spec.technique.name != "checkerboard" {
        return json!(null);
    }
    match CheckerboardConfig::parse(&spec.technique.params()) {
        Ok(c) => json!({
            "layout": c.layout.name(),
            "lod_mode": c.lod_mode,
            "resolve": c.resolve,
            "id_prepass": c.prepass,
            "sample_locations": c.locations,
        }),
        Err(_) => json!(null),
    }
}

/// The resolve's debug views as EXR layers: one 0/1 layer per bit (`resolve_parity`,
/// `resolve_missing`, ...), `resolve_velocity` (X, Y) and `resolve_object_id` is the raw layer.
pub fn exr_layers(out: &FrameOutput) -> Vec<cbr_metrics::io::ExtraLayer> {
    let mut layers = Vec::new();
    if let Some(c) = &out.coverage {
        // `coverage`: edge (1 where the pixel's samples saw several object IDs) and fraction (of
        // the samples on geometry).
        layers.push((
            "coverage".to_string(),
            vec![
                (
                    "edge".to_string(),
                    c.edge.iter().map(|&e| f32::from(e)).collect(),
                ),
                ("fraction".to_string(), c.fraction.clone()),
            ],
        ));
    }
    if let Some(a) = &out.analytic {
        // `analytic`: per pixel the fragments that touched it, those beyond the K kept
        // (overflow), those that contributed, (analytic:seed) where the shortcut is off by more
        // than 1e-3, and where a kept fragment's shading was not finite.
        let f = |v: &[u32]| v.iter().map(|&x| x as f32).collect();
        layers.push((
            "analytic".to_string(),
            vec![
                ("fragments".to_string(), f(&a.fragments)),
                ("overflow".to_string(), f(&a.overflow)),
                ("visible".to_string(), f(&a.visible)),
                (
                    "seed_differs".to_string(),
                    a.seed_differs.iter().map(|&x| f32::from(x)).collect(),
                ),
                (
                    "nonfinite".to_string(),
                    a.nonfinite.iter().map(|&x| f32::from(x)).collect(),
                ),
            ],
        ));
    }
    if let Some(i) = &out.interleaved {
        // `interleaved:...:debug`: per pixel its VPL subset, the edge mask (the filter's window
        // holds another surface; `seed`: the seed's edge test) and the subsets it shaded itself.
        let f = |v: &[u8]| v.iter().map(|&x| f32::from(x)).collect();
        layers.push((
            "interleaved".to_string(),
            vec![
                ("subset".to_string(), f(&i.subset)),
                ("edge".to_string(), f(&i.edge)),
                ("fallback".to_string(), f(&i.fallback)),
            ],
        ));
    }
    let Some(r) = &out.resolve else {
        return layers;
    };
    if let Some(bits) = &r.debug_bits {
        for (name, bit) in DEBUG_VIEWS {
            let v = bits
                .iter()
                .map(|b| f32::from(u8::from(b & bit != 0)))
                .collect();
            layers.push((format!("resolve_{name}"), vec![("Y".to_string(), v)]));
        }
    }
    if let Some(v) = &r.velocity {
        layers.push((
            "resolve_velocity".to_string(),
            vec![
                ("X".to_string(), v.iter().map(|v| v[0]).collect()),
                ("Y".to_string(), v.iter().map(|v| v[1]).collect()),
            ],
        ));
    }
    layers
}

/// `analytic` frames in run.json: fragments kept per pixel (K), fragments that touched pixels,
/// and pixel counts: edge pixels (a visible fragment covers part of the pixel or the background
/// shows), overflow (more fragments than K), non-finite shading, and with `analytic:seed` where
/// the shortcut's area is off by more than 1e-3 and that count's share of the edge pixels.
fn analytic_summary(out: &FrameOutput) -> serde_json::Value {
    let (Some(a), Some(c)) = (&out.analytic, &out.coverage) else {
        return json!(null);
    };
    let count = |v: &[u8]| v.iter().filter(|&&x| x != 0).count();
    let edge = count(&c.edge);
    let seed = a
        .seed_differs
        .iter()
        .zip(&c.edge)
        .filter(|&(&s, &e)| s != 0 && e != 0)
        .count();
    json!({
        "kept_per_pixel": a.kept_per_pixel,
        "tail_fragments": a.tail_fragments,
        "albedo_jobs": a.albedo_jobs,
        "fragments": a.fragments.iter().map(|&f| u64::from(f)).sum::<u64>(),
        "edge_pixels": edge,
        "overflow_pixels": a.overflow.iter().filter(|&&o| o > 0).count(),
        "nonfinite_pixels": count(&a.nonfinite),
        "seed_differs_pixels": count(&a.seed_differs),
        "seed_differs_edge_fraction": if edge > 0 { seed as f64 / edge as f64 } else { 0.0 },
    })
}

/// `interleaved:...:debug` frames in run.json: M x N, pixels on a surface, edge pixels, pixels
/// that shaded a subset themselves and the mean number of subsets they shaded, and the pixels where
/// the split G-buffer gathered back differs from the G-buffer (0 unless the passes are broken).
fn interleaved_summary(out: &FrameOutput) -> serde_json::Value {
    let Some(i) = &out.interleaved else {
        return json!(null);
    };
    let drawn: Vec<bool> = out.ids.iter().map(|id| id[0] != 0).collect();
    let count = |v: &[u8]| v.iter().zip(&drawn).filter(|&(&x, &d)| x != 0 && d).count();
    let visible = drawn.iter().filter(|&&d| d).count();
    let shaded: u64 = i.fallback.iter().map(|&x| u64::from(x)).sum();
    json!({
        "tile": [i.tile.0, i.tile.1],
        "visible_pixels": visible,
        "edge_pixels": count(&i.edge),
        "fallback_pixels": count(&i.fallback),
        "fallback_subsets_per_visible_pixel":
            if visible > 0 { shaded as f64 / visible as f64 } else { 0.0 },
        "roundtrip_mismatches": i.roundtrip_mismatches,
    })
}
