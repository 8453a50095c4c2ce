//! Speed of the metrics on 1920x1080 pairs (docs/metrics.md). Run: `just bench-metrics`.
//! Targets (issue 3, 2-core machine): LDR-FLIP <= 0.3 s; all the metrics of a pair <= 0.6 s.

use cbr_metrics::flip::{Flip, default_ppd};
use cbr_metrics::planes::Rgb;
use cbr_metrics::{CompareOptions, Encoding, InputImage, Metric, compare_images};
use criterion::{Criterion, criterion_group, criterion_main};

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

const W: usize = 1920;
const H: usize = 1080;

/// A textured image and a noisy, shifted copy: every metric has work to do.
fn pair(hdr: bool) -> (InputImage, InputImage) {
    let make = |noise: f32, shift: usize| {
        let v: Vec<f32> = (0..W * H * 3)
            .map(|i| {
                let (p, c) = (i / 3, i % 3);
                let (x, y) = ((p % W + shift) as f32, (p / W) as f32);
                let base = 0.5 + 0.25 * ((x / 17.0).sin() + (y / 23.0 + c as f32).cos());
                let n = ((i as u64 * 2_654_435_761) % 1000) as f32 / 1000.0 - 0.5;
                let v = (base + noise * n).clamp(0.0, 1.0);
                if hdr { (v * 10.0 - 5.0).exp2() } else { v }
            })
            .collect();
        InputImage {
            path: "bench".into(),
            layer: String::new(),
            channels: vec![],
            rgb: Rgb::from_interleaved(W, H, &v),
            encoding: if hdr {
                Encoding::Linear
            } else {
                Encoding::Srgb
            },
        }
    };
    (make(0.02, 0), make(0.1, 1))
}

fn bench(c: &mut Criterion) {
    let (r, t) = pair(false);
    let mut g = c.benchmark_group("1920x1080");
    g.sample_size(10);
    g.bench_function("ldr_flip", |b| {
        b.iter(|| Flip::new(default_ppd()).ldr(&r.rgb, &t.rgb))
    });
    let five = CompareOptions {
        metrics: vec![
            Metric::Psnr,
            Metric::Ssim,
            Metric::Flip,
            Metric::Mse,
            Metric::RelMse,
        ],
        ..Default::default()
    };
    g.bench_function("psnr_ssim_flip_mse_relmse", |b| {
        b.iter(|| compare_images(&r, &t, &five).expect("compare"))
    });
    let (hr, ht) = pair(true);
    let hdr = CompareOptions {
        metrics: vec![Metric::HdrFlip],
        ..Default::default()
    };
    g.bench_function("hdr_flip", |b| {
        b.iter(|| compare_images(&hr, &ht, &hdr).expect("compare"))
    });
    let all = CompareOptions::default();
    g.bench_function("all_six_hdr_pair", |b| {
        b.iter(|| compare_images(&hr, &ht, &all).expect("compare"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
