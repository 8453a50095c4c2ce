//! Pooling of per-pixel errors: mean, FLIP's weighted percentiles, min, max.

use serde::Serialize;

/// Statistics of an error map over the valid pixels.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Pooled {
    pub mean: f64,
    /// FLIP's weighted percentiles: the smallest error e whose errors <= e hold the given share of
    /// the total error (each pixel weighted by its own error).
    pub weighted_median: f64,
    pub weighted_q1: f64,
    pub weighted_q3: f64,
    pub min: f64,
    pub max: f64,
}

pub fn pool(values: &[f32], valid: Option<&[bool]>) -> Option<Pooled> {
    let mut v: Vec<f32> = match valid {
        Some(m) => values
            .iter()
            .zip(m)
            .filter(|(_, ok)| **ok)
            .map(|(x, _)| *x)
            .collect(),
        None => values.to_vec(),
    };
    if v.is_empty() {
        return None;
    }
    let sum: f64 = v.iter().map(|&x| f64::from(x)).sum();
    let mean = sum / v.len() as f64;
    v.sort_unstable_by(f32::total_cmp);
    let weighted = |q: f64| {
        let target = q * sum;
        let mut acc = 0.0f64;
        for &x in &v {
            acc += f64::from(x);
            if acc >= target {
                return f64::from(x);
            }
        }
        f64::from(v[v.len() - 1])
    };
    Some(Pooled {
        mean,
        weighted_median: weighted(0.5),
        weighted_q1: weighted(0.25),
        weighted_q3: weighted(0.75),
        min: f64::from(v[0]),
        max: f64::from(v[v.len() - 1]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_percentiles_weigh_by_value() {
        // Total 10: 1 + 2 + 3 + 4. Half (5) is reached at 3; a quarter (2.5) at 2; 7.5 at 4.
        let p = pool(&[4.0, 1.0, 3.0, 2.0], None).expect("pooled");
        assert_eq!(p.mean, 2.5);
        assert_eq!(
            (p.weighted_q1, p.weighted_median, p.weighted_q3),
            (2.0, 3.0, 4.0)
        );
        assert_eq!((p.min, p.max), (1.0, 4.0));
        let masked =
            pool(&[4.0, 1.0, 3.0, 2.0], Some(&[true, false, false, true])).expect("pooled");
        assert_eq!(masked.mean, 3.0);
        assert!(pool(&[1.0], Some(&[false])).is_none());
    }
}
