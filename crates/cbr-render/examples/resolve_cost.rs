//! A deterministic cost figure for the resolve modes: the CPU reference of the resolve
//! (crate::resolve::reference, operation for operation the shader's fp32 path) run on a synthetic
//! moving frame, to be counted by callgrind. Instructions per resolved pixel do not depend on
//! the machine's load, so a change to a mode can be judged on a 2-core machine where GPU times
//! (lavapipe) are noisy. It counts the reference's instructions on x86-64, not the shader's on a
//! GPU: read it as the relative algorithmic work of the modes (docs/resolve.md).
//!
//! `scripts/resolve-cost.sh` runs it under `valgrind --tool=callgrind
//! --toggle-collect='*measured*'` for each mode. Alone it prints the pixels it resolved:
//! `cargo run --release -p cbr-render --example resolve_cost -- ours`.

use cbr_render::resolve::reference::{HistoryRef, Inputs, Sample, resolve};
use cbr_render::resolve::{ResolveMode, ResolveSettings};

const W: u32 = 256;
const H: u32 = 256;
/// Frames resolved inside the counted function.
const FRAMES: u32 = 4;

/// SplitMix64: deterministic texture noise.
fn hash(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Frame `f` of the synthetic scene: a textured background panning 1.5 px/frame right and a
/// textured disc (object 2, nearer) moving 3.5 px/frame down-left over it, so that the disc's
/// trailing edge disoccludes background every frame (about 3% of the pixels) and the rest
/// reprojects at sub-pixel offsets.
fn frame(f: u32) -> Vec<Sample> {
    let (bg_v, disc_v) = ([1.5f32, 0.0], [-3.5f32, 3.5]);
    let t = f as f32;
    let centre = [96.0 - 3.5 * t + 60.0, 80.0 + 3.5 * t];
    (0..W * H)
        .map(|i| {
            let (x, y) = ((i % W) as f32 + 0.5, (i / W) as f32 + 0.5);
            let (dx, dy) = (x - centre[0], y - centre[1]);
            if dx * dx + dy * dy < 48.0 * 48.0 {
                let (u, v) = ((dx + 256.0) as u64, (dy + 256.0) as u64);
                let n = hash(u / 3 * 977 + v / 3) % 1000;
                Sample {
                    c: [0.8, 0.3 + n as f32 * 1e-4, 0.2],
                    v: disc_v,
                    d: 0.2,
                    ids: [2, 0],
                }
            } else {
                let u = (x - 1.5 * t + 1024.0) as u64;
                let v = y as u64;
                let n = hash(u / 4 * 131 + v / 4) % 1000;
                let g = 0.1 + n as f32 * 8e-4;
                Sample {
                    c: [g, g * 0.9, g * 0.7],
                    v: bg_v,
                    d: 0.05,
                    ids: [1, 0],
                }
            }
        })
        .collect()
}

/// The counted work: FRAMES resolves, each reading the previous one's output as history.
#[inline(never)]
fn measured(
    frames: &[Vec<Sample>],
    settings: &ResolveSettings,
    first: (Vec<[f32; 3]>, Vec<f32>, Vec<u32>),
) -> u64 {
    let (mut color, mut depth, mut ids) = first;
    let mut checksum = 0u64;
    for (k, cur) in frames.iter().enumerate() {
        let out = resolve(
            &Inputs {
                width: W,
                height: H,
                parity: (k as u32 + 1) & 1,
                current: cur,
                history: Some(HistoryRef {
                    color: &color,
                    depth: &depth,
                    ids: &ids,
                }),
                prepass: None,
                reproj: [
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
                ],
            },
            settings,
        );
        checksum = checksum.wrapping_add(out.debug.iter().map(|&d| u64::from(d)).sum::<u64>());
        (color, depth, ids) = (out.color, out.depth, out.ids);
    }
    checksum
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "ours".into());
    let mode = match mode.as_str() {
        "ours" => ResolveMode::Ours,
        "pq4k" => ResolveMode::Pq4k,
        "intel" => ResolveMode::Intel,
        "spatial" => ResolveMode::Spatial,
        "temporal" => ResolveMode::Temporal,
        other => {
            eprintln!("error: `{other}`: give ours, pq4k, intel, spatial or temporal");
            std::process::exit(1);
        }
    };
    let settings = ResolveSettings {
        mode,
        ..ResolveSettings::default()
    };
    // Warm-up (not counted): frame 0 resolved without history gives the first history.
    let f0 = frame(0);
    let first = resolve(
        &Inputs {
            width: W,
            height: H,
            parity: 0,
            current: &f0,
            history: None,
            prepass: None,
            reproj: [0.0; 16],
        },
        &settings,
    );
    let frames: Vec<Vec<Sample>> = (1..=FRAMES).map(frame).collect();
    let sum = measured(&frames, &settings, (first.color, first.depth, first.ids));
    println!(
        "{} pixels resolved ({FRAMES} frames of {W}x{H}), mode {:?}, checksum {sum}",
        u64::from(W * H * FRAMES),
        settings.mode
    );
}
