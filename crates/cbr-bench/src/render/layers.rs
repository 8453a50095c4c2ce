//! What `cbr render` writes of a frame beyond its four common layers, for any technique: its
//! layers as EXR parts (each as its declaration says: cbr_render::LayerDecl), its statistics in
//! run.json's per-frame record, and its registration's entry in run.json's `settings`. Nothing
//! here names a technique: each declares its layers and statistics in its registration
//! (cbr_render::technique::Outputs). PNGs: crate::render::pngs.

use anyhow::{Result, bail};
use cbr_metrics::io::{ChannelSamples, ExtraLayer};
use cbr_render::registry::{TECHNIQUES, find};
use cbr_render::{ExrType, FrameOutput, Layer, Samples, Spec};
use half::f16;
use serde_json::{Value, json};

/// The frame's layers that go into its EXR, in the frame's order, each channel converted to
/// the EXR type its declaration names.
pub fn exr_layers(out: &FrameOutput) -> Result<Vec<ExtraLayer>> {
    let mut layers = Vec::new();
    for l in &out.layers {
        if let Some(e) = exr_layer(l)? {
            layers.push(e);
        }
    }
    Ok(layers)
}

/// One layer as an EXR part (`None`: the layer is on the host only).
pub fn exr_layer(l: &Layer) -> Result<Option<ExtraLayer>> {
    let Some(exr) = l.exr else {
        return Ok(None);
    };
    let n = l.width as usize * l.height as usize;
    let mut channels = Vec::new();
    for (c, name) in l.channels.iter().enumerate() {
        let range = c * n..(c + 1) * n;
        let samples = match (&l.samples, exr) {
            (Samples::U8(v), ExrType::Half) => {
                ChannelSamples::F16(v[range].iter().map(|&x| f16::from(x)).collect())
            }
            (Samples::U8(v), ExrType::Float) => {
                ChannelSamples::F32(v[range].iter().map(|&x| f32::from(x)).collect())
            }
            (Samples::U8(v), ExrType::Uint) => {
                ChannelSamples::U32(v[range].iter().map(|&x| u32::from(x)).collect())
            }
            (Samples::U32(v), ExrType::Half) => {
                ChannelSamples::F16(v[range].iter().map(|&x| f16::from_f32(x as f32)).collect())
            }
            (Samples::U32(v), ExrType::Float) => {
                ChannelSamples::F32(v[range].iter().map(|&x| x as f32).collect())
            }
            (Samples::U32(v), ExrType::Uint) => ChannelSamples::U32(v[range].to_vec()),
            (Samples::F16(v), ExrType::Half) => ChannelSamples::F16(v[range].to_vec()),
            (Samples::F16(v), ExrType::Float) => {
                ChannelSamples::F32(v[range].iter().map(|x| x.to_f32()).collect())
            }
            (Samples::F32(v), ExrType::Half) => {
                ChannelSamples::F16(v[range].iter().map(|&x| f16::from_f32(x)).collect())
            }
            (Samples::F32(v), ExrType::Float) => ChannelSamples::F32(v[range].to_vec()),
            (Samples::F16(_) | Samples::F32(_), ExrType::Uint) => {
                bail!(
                    "layer `{}`: float samples declared as uint in the EXR",
                    l.name
                )
            }
        };
        channels.push((name.clone(), samples));
    }
    Ok(Some((l.name.clone(), channels)))
}

/// Adds the frame's statistics to its run.json record: `a.b` as entry `b` of object `a`, a
/// name without a dot as a field; every statistic a registered technique declares is there,
/// `null` where this frame has none (so every record has the same fields).
pub fn add_stats(out: &FrameOutput, record: &mut Value) {
    for d in TECHNIQUES.iter().flat_map(|r| r.outputs.stats) {
        let key = d.name.split_once('.').map_or(d.name, |(a, _)| a);
        if record.get(key).is_none() {
            record[key] = Value::Null;
        }
    }
    for (name, s) in &out.stats {
        match name.split_once('.') {
            Some((a, b)) => {
                if !record[a].is_object() {
                    record[a] = json!({});
                }
                record[a][b] = json!(s);
            }
            None => record[name.as_str()] = json!(s),
        }
    }
}

/// Adds run.json's `settings.<technique>` entries: the spec's technique's (its registration's
/// `outputs.settings`), `null` for every other registration that has one.
pub fn add_settings(spec: &Spec, settings: &mut Value) {
    for r in TECHNIQUES.iter().filter(|r| r.outputs.settings.is_some()) {
        settings[r.name] = Value::Null;
    }
    let Some(r) = find(&spec.technique.name) else {
        return;
    };
    if let Some(f) = r.outputs.settings {
        settings[r.name] = f(&spec.technique.params()).unwrap_or(Value::Null);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cbr_render::Stat;

    /// run.json keeps the fields it had before the layers were generic: every record has
    /// `parity`, `resolve_reset`, `analytic` and `interleaved` (null where the frame has none),
    /// a dotted statistic lands in its object, and `settings.checkerboard` is null but for
    /// checkerboard specs.
    #[test]
    fn every_record_has_the_same_fields_and_statistics_nest_by_their_dots() {
        let mut out = FrameOutput::new(1, 1, vec![], vec![], vec![], vec![]);
        let mut record = json!({"index": 0});
        add_stats(&out, &mut record);
        for key in ["parity", "resolve_reset", "analytic", "interleaved"] {
            assert_eq!(record.get(key), Some(&Value::Null), "{key} in {record}");
        }
        out.set_stat("parity", Stat::Count(1));
        out.set_stat("resolve_reset", Stat::Flag(true));
        out.set_stat("analytic.tail_fragments", Stat::Count(7));
        out.set_stat("analytic.seed_differs_edge_fraction", Stat::Real(0.0));
        out.set_stat("interleaved.tile", Stat::Counts(vec![4, 2]));
        let mut record = json!({"index": 0});
        add_stats(&out, &mut record);
        assert_eq!(record["index"], 0);
        assert_eq!(record["parity"], 1);
        assert_eq!(record["resolve_reset"], true);
        assert_eq!(record["analytic"]["tail_fragments"], 7);
        assert!(record["analytic"]["seed_differs_edge_fraction"].is_f64());
        assert_eq!(record["interleaved"]["tile"], json!([4, 2]));

        let mut settings = json!({"technique": "native"});
        add_settings(&Spec::parse("native").expect("spec"), &mut settings);
        assert_eq!(settings.get("checkerboard"), Some(&Value::Null));
        let mut settings = json!({});
        let spec = Spec::parse("checkerboard:split:pq4k:prepass").expect("spec");
        add_settings(&spec, &mut settings);
        let cb = &settings["checkerboard"];
        assert_eq!(cb["layout"], "split");
        assert_eq!(cb["id_prepass"], true);
        assert_eq!(cb["resolve"]["mode"], "pq4k");
    }

    /// Each sample type goes to the EXR type its layer declares; host-only layers stay out.
    #[test]
    fn layers_convert_to_their_declared_exr_types() {
        let decl = |name, samples, exr| cbr_render::LayerDecl {
            name,
            channels: &["Y"],
            samples,
            exr,
            about: "",
        };
        let mut out = FrameOutput::new(2, 1, vec![], vec![], vec![], vec![]);
        let mask = decl("mask", cbr_render::SampleType::U8, Some(ExrType::Half));
        out.layers
            .push(mask.layer(2, 1, vec![vec![0u8, 1]]).expect("mask"));
        let count = decl("n", cbr_render::SampleType::U32, Some(ExrType::Float));
        out.layers
            .push(count.layer(2, 1, vec![vec![3u32, 9]]).expect("n"));
        let host = decl("host", cbr_render::SampleType::F32, None);
        out.layers
            .push(host.layer(2, 1, vec![vec![1.0f32, 2.0]]).expect("host"));
        let exr = exr_layers(&out).expect("converted");
        assert_eq!(exr.len(), 2, "the host-only layer is not written");
        assert_eq!(
            exr[0],
            (
                "mask".to_string(),
                vec![(
                    "Y".to_string(),
                    ChannelSamples::F16(vec![f16::ZERO, f16::ONE])
                )]
            )
        );
        assert_eq!(exr[1].1[0].1, ChannelSamples::F32(vec![3.0, 9.0]));
        let bad = decl("bad", cbr_render::SampleType::F32, Some(ExrType::Uint));
        out.layers
            .push(bad.layer(2, 1, vec![vec![0.5f32, 1.0]]).expect("bad"));
        assert!(exr_layers(&out).is_err(), "floats as uint are refused");
    }
}
