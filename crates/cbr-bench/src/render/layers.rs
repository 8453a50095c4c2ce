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
