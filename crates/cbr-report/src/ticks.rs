//! Axis ticks for the log-log speed-vs-error chart, and their labels in plain numbers.

/// At least this many labelled ticks on an axis whose range is not degenerate.
pub(crate) const MIN_TICKS: usize = 3;
/// More 1-2-5 ticks than this (over about five decades) thin to 1 x 10^k.
const MAX_TICKS: usize = 15;

/// `m` x 10^`e`, correctly rounded (10^k is exact in f64 up to k = 22, so dividing by it rounds
/// once: 2 x 10^-2 is the same f64 as the literal 0.02).
fn scaled(m: f64, e: i32) -> f64 {
    if e >= 0 {
        m * 10f64.powi(e)
    } else {
        m / 10f64.powi(-e)
    }
}

/// The values `mantissas` x 10^k inside [lo, hi] (with a relative tolerance of 1e-4).
fn decade_ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut t = Vec::new();
    let mut e = lo.log10().floor() as i32 - 1;
    while scaled(1.0, e) <= hi * 1.0001 {
        for &m in mantissas {
            let v = scaled(m, e);
            if v >= lo * 0.9999 && v <= hi * 1.0001 {
                t.push(v);
            }
        }
        e += 1;
    }
    t
}

/// Evenly spaced ticks inside [lo, hi]: the largest step 1, 2 or 5 x 10^k that fits at least
/// three times into the range, so at least [`MIN_TICKS`] multiples of it lie inside.
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let target = (hi - lo) / MIN_TICKS as f64;
    let mut e = target.log10().floor() as i32;
    let m = [5.0, 2.0, 1.0]
        .into_iter()
        .find(|&m| scaled(m, e) <= target)
        .unwrap_or_else(|| {
            e -= 1;
            5.0
        });
    let step = scaled(m, e);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    // k x m x 10^e rounds once, so 0.3 is 0.3 and not 3 x 0.1.
    (first..=last).map(|k| scaled(k as f64 * m, e)).collect()
}

/// Ticks for a log10 axis over [lo, hi] (positive): 1, 2, 5 x 10^k; when fewer than
/// [`MIN_TICKS`] of those lie in the range, the finer 1, 1.5, 2, 3, 4, 5, 6, 8 x 10^k; when
/// still fewer (a range under a factor of about 1.5), evenly spaced 1-2-5 steps. A degenerate
/// range (lo = hi) gets the one tick lo; a range with no positive finite end gets none.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    if !(lo > 0.0 && hi.is_finite()) {
        return Vec::new();
    }
    if hi <= lo * (1.0 + 1e-9) {
        return vec![lo];
    }
    let t = decade_ticks(lo, hi, &[1.0, 2.0, 5.0]);
    if t.len() > MAX_TICKS {
        return decade_ticks(lo, hi, &[1.0]);
    }
    if t.len() >= MIN_TICKS {
        return t;
    }
    let t = decade_ticks(lo, hi, &[1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0]);
    if t.len() >= MIN_TICKS {
        return t;
    }
    linear_ticks(lo, hi)
}

/// A tick value in plain decimal notation with no more decimals than it needs
/// (0.0005, 1.5, 20).
pub(crate) fn label(v: f64) -> String {
    for d in 0..=12 {
        let s = format!("{v:.d$}");
        if s.parse::<f64>()
            .is_ok_and(|x| (x - v).abs() <= v.abs() * 1e-9)
        {
            return s;
        }
    }
    format!("{v}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= y.abs() * 1e-12)
    }

    fn check(lo: f64, hi: f64) -> Vec<f64> {
        let t = log_ticks(lo, hi);
        assert!(t.len() >= MIN_TICKS, "{lo}..{hi}: {t:?}");
        assert!(
            t.iter().all(|&v| v >= lo * 0.9999 && v <= hi * 1.0001),
            "{lo}..{hi}: {t:?}"
        );
        assert!(t.windows(2).all(|w| w[0] < w[1]), "{lo}..{hi}: {t:?}");
        t
    }

    #[test]
    fn log_ticks_at_least_three_and_nice() {
        // Over decades: 1-2-5 x 10^k.
        let t = check(0.01, 10.0);
        let want = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0];
        assert!(close(&t, &want), "{t:?}");
        assert!(close(&check(0.8, 30.0), &[1.0, 2.0, 5.0, 10.0, 20.0]));
        // Less than a decade: finer mantissas.
        assert!(close(&check(0.9, 3.0), &[1.0, 1.5, 2.0, 3.0]));
        let t = check(0.023, 0.117);
        assert!(close(&t, &[0.03, 0.04, 0.05, 0.06, 0.08, 0.1]), "{t:?}");
        // Less than a factor 1.5: evenly spaced nice values.
        let t = check(3.2, 5.1);
        assert!(close(&t, &[3.5, 4.0, 4.5, 5.0]), "{t:?}");
        let t = check(1.0, 1.02);
        assert!(close(&t, &[1.0, 1.005, 1.01, 1.015, 1.02]), "{t:?}");
        // A single point padded by 1.3 either way, as the chart does.
        for v in [0.0123, 0.77, 1.0, 2.5, 4.2, 9.99, 13.0, 420.0] {
            check(v / 1.3, v * 1.3);
        }
        for i in 0..200 {
            let lo = 10f64.powf(-3.0 + i as f64 * 0.031);
            for f in [1.001, 1.01, 1.1, 1.5, 2.0, 3.0, 7.0] {
                check(lo, lo * f);
            }
        }
        // Many decades thin to powers of ten.
        let t = check(1e-3, 1e3);
        assert!(
            close(&t, &[1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1000.0]),
            "{t:?}"
        );
        // Degenerate and invalid ranges.
        assert_eq!(log_ticks(2.5, 2.5), vec![2.5]);
        assert!(close(&log_ticks(5.1, 3.2), &[3.5, 4.0, 4.5, 5.0]));
        assert!(log_ticks(0.0, 1.0).is_empty());
        assert!(log_ticks(f64::NAN, 1.0).is_empty());
    }

    #[test]
    fn tick_labels_are_plain_numbers() {
        assert_eq!(label(0.0005), "0.0005");
        assert_eq!(label(1.5), "1.5");
        assert_eq!(label(20.0), "20");
        assert_eq!(label(0.1 + 0.2), "0.3");
        assert_eq!(label(1.015), "1.015");
        assert_eq!(label(1e-7), "0.0000001");
        for v in log_ticks(0.0001, 1.0) {
            assert!(!label(v).contains('e'), "{v}");
        }
    }
}
