//! `cbr compare`'s text output: one pair's metrics, or a sequence's per-frame and summary lines.

use cbr_metrics::{CompareOptions, PairResult};

fn fmt(v: f64) -> String {
    if v.is_infinite() {
        "inf".into()
    } else if v != 0.0 && v.abs() < 1e-3 {
        format!("{v:.4e}")
    } else {
        format!("{v:.6}")
    }
}

pub fn pair(r: &PairResult, o: &CompareOptions) {
    let src = |s: &cbr_metrics::compare::Source| {
        if s.layer.is_empty() {
            format!("{} ({:?})", s.path.display(), s.encoding)
        } else {
            format!(
                "{} (layer {} [{}], {:?})",
                s.path.display(),
                s.layer,
                s.channels.join(","),
                s.encoding
            )
        }
    };
    println!(
        "reference {}\ntest      {}",
        src(&r.reference),
        src(&r.test)
    );
    println!(
        "{}x{}, non-finite pixels: reference {}, test {} ({} excluded)",
        r.width, r.height, r.reference.nonfinite_pixels, r.test.nonfinite_pixels, r.excluded_pixels
    );
    if let Some(p) = r.psnr {
        println!(
            "  PSNR      {} dB          (display values, peak 1)",
            fmt(p.0)
        );
    }
    if let Some(s) = r.ssim {
        println!(
            "  SSIM      {}            (display, per RGB channel, averaged)",
            fmt(s)
        );
    }
    if let Some(f) = &r.flip {
        println!(
            "  FLIP      mean {}  weighted median {}  quartiles {} / {}  min {}  max {}  ({:.2} ppd)",
            fmt(f.mean),
            fmt(f.weighted_median),
            fmt(f.weighted_q1),
            fmt(f.weighted_q3),
            fmt(f.min),
            fmt(f.max),
            o.ppd
        );
    }
    if let Some(h) = &r.hdrflip {
        println!(
            "  HDR-FLIP  mean {}  weighted median {}  max {}  (exposures {:.3} .. {:.3}, {} steps)",
            fmt(h.pooled.mean),
            fmt(h.pooled.weighted_median),
            fmt(h.pooled.max),
            h.exposures.start,
            h.exposures.stop,
            h.exposures.count
        );
    }
    if let Some(m) = r.mse {
        println!("  MSE       {}            (linear)", fmt(m));
    }
    if let Some(m) = r.relmse {
        println!(
            "  relMSE    {}            (linear, eps {})",
            fmt(m),
            o.relmse_eps
        );
    }
    println!("display transform: {}", o.display.describe());
}

pub fn sequence(s: &cbr_metrics::SequenceResult, o: &CompareOptions) {
    let names: Vec<&str> = o.metrics.iter().map(|m| m.name()).collect();
    println!(
        "{:<20} {}  flicker",
        "frame",
        names.iter().map(|n| format!("{n:>12}")).collect::<String>()
    );
    for f in &s.frames {
        let vals: String = o
            .metrics
            .iter()
            .map(|m| {
                format!(
                    "{:>12}",
                    f.result.value(*m).map(fmt).unwrap_or_else(|| "-".into())
                )
            })
            .collect();
        let fl = f.flicker.map(fmt).unwrap_or_else(|| "-".into());
        println!(
            "{:<20} {vals}  {fl}{}",
            f.frame,
            if f.warmup { "  (warm-up)" } else { "" }
        );
    }
    let means: String = o
        .metrics
        .iter()
        .map(|m| {
            format!(
                "{:>12}",
                s.mean
                    .get(m.name())
                    .map(|d| fmt(d.0))
                    .unwrap_or_else(|| "-".into())
            )
        })
        .collect();
    println!(
        "{:<20} {means}  {}",
        format!("mean (after {})", s.warmup),
        s.flicker.map(fmt).unwrap_or_else(|| "-".into())
    );
    println!("display transform: {}", o.display.describe());
}
