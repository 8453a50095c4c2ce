//! Loads scenes once each and prints, per scene, the load time, the process's peak resident memory
//! so far and a hash of what the renderer receives (every object's vertices, indices, material
//! and f64 origin; every material's numbers): two builds of the loader load a scene to the same
//! bits when their hashes agree.
//!
//! `cargo run --release -p cbr-scene --example load_time -- scenes/sibenik.toml`
//! (one process per load: interleave the runs of two builds and take medians; docs/scenes.md).

use std::hash::{Hash, Hasher};
use std::time::Instant;

fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let specs: Vec<String> = std::env::args().skip(1).collect();
    if specs.is_empty() {
        eprintln!("usage: load_time SCENE...");
        std::process::exit(2);
    }
    for spec in specs {
        let t = Instant::now();
        let scene = match cbr_scene::load(&spec, &cbr_scene::LoadOptions::default()) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        // SipHash with fixed keys: the same bits hash the same in every build.
        let mut h = std::hash::DefaultHasher::new();
        let mut recentred = 0;
        for o in &scene.objects {
            o.name.hash(&mut h);
            bytemuck::cast_slice::<_, u8>(&o.vertices).hash(&mut h);
            o.indices.hash(&mut h);
            o.material.hash(&mut h);
            o.origin.map(f64::to_bits).hash(&mut h);
            recentred += usize::from(o.origin != [0.0; 3]);
        }
        for m in &scene.materials {
            m.name.hash(&mut h);
            [m.kd, m.ks, m.ke]
                .concat()
                .iter()
                .map(|v| v.to_bits())
                .for_each(|b| b.hash(&mut h));
            m.ns.to_bits().hash(&mut h);
            m.bump_scale.to_bits().hash(&mut h);
        }
        println!(
            "{spec}: {ms:.1} ms, peak RSS {} KiB, {} objects ({recentred} recentred), {} triangles, hash {:016x}",
            peak_rss_kib().map_or("?".into(), |k| k.to_string()),
            scene.objects.len(),
            scene.triangle_count(),
            h.finish()
        );
    }
}
