//! A run split into shards (`--shard K/N`, docs/cluster.md): the work of a sweep as units
//! (reference frames, then one row per configuration, scene and resolution), each unit's
//! estimated cost, and a deterministic cost-balanced assignment of the units to N shards.

use anyhow::{Result, bail};
use cbr_render::RenderSettings;

/// Shard `index` of `count` (`--shard K/N`); `0/1` is the whole run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// `K/N` with N >= 1 and 0 <= K < N.
    pub fn parse(s: &str) -> Result<Shard> {
        let Some((k, n)) = s.split_once('/') else {
            bail!("--shard `{s}`: expected K/N, e.g. 0/4 (shard K of N, K from 0 to N-1)");
        };
        let num = |x: &str, what: &str| {
            x.trim()
                .parse::<u32>()
                .map_err(|e| anyhow::anyhow!("--shard `{s}`: {what} `{x}`: {e}"))
        };
        let (index, count) = (num(k, "K")?, num(n, "N")?);
        if count == 0 {
            bail!("--shard `{s}`: N must be at least 1");
        }
        if index >= count {
            bail!(
                "--shard `{s}`: K must be below N (0 to {} for N = {count})",
                count - 1
            );
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// What a unit of work is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// One frame of a group's cacheable reference, rendered into the shared frame cache
    /// (sharded runs only: the rows of other shards read it from there).
    RefFrame(u32),
    /// A row: 0 the reference's own, i the group's i-th configuration.
    Row(usize),
}

/// One unit: a group (scene x resolution, in the run's order), what, and its estimated cost.
#[derive(Clone, Debug)]
pub struct Unit {
    pub group: usize,
    pub work: Work,
    /// Estimated seconds on lavapipe (2 cores); only ratios matter.
    pub cost: f64,
}

/// Fixed cost of a row: the renderer's set-up (pipelines JIT-compiled by llvmpipe, the scene's
/// upload), about 1-2 s per row on lavapipe.
const SETUP_S: f64 = 1.5;
/// Seconds per rendered native sample (pixel x frame) on lavapipe.
const RENDER_S: f64 = 1.0e-6;
/// Seconds per compared pixel (PSNR, SSIM, FLIP, relMSE, masks), per measured frame.
const METRICS_S: f64 = 4.0e-6;

/// Rasters per frame relative to native: N^2 for `ssaa:N` (its sub-pixel passes), 1 otherwise.
pub fn samples_per_frame(s: &RenderSettings) -> f64 {
    match s.spec.technique.name.as_str() {
        "ssaa" => s
            .spec
            .technique
            .params
            .first()
            .and_then(|p| p.parse::<f64>().ok())
            .map_or(1.0, |n| n * n),
        _ => 1.0,
    }
}

/// Seconds of rendering `frames` frames of `s`.
pub fn render_cost(s: &RenderSettings, frames: u32) -> f64 {
    f64::from(s.width) * f64::from(s.height) * f64::from(frames) * samples_per_frame(s) * RENDER_S
}

/// Seconds of a row: set-up, `rendered` frames, and the metrics of `compared` frames.
pub fn row_cost(s: &RenderSettings, rendered: u32, compared: u32) -> f64 {
    SETUP_S
        + render_cost(s, rendered)
        + f64::from(s.width) * f64::from(s.height) * f64::from(compared) * METRICS_S
}

/// What a shard spends once on each group (scene x resolution) it has any unit of: building
/// the reference's renderer and reading its frames, and the native raster that stands in for
/// the object IDs of the warm-up frames a cached reference skips.
pub const GROUP_S: f64 = 2.0 * SETUP_S;

/// Cuts `units` (their group and cost, in the run's order) into at most `count` contiguous parts
/// none of which costs more than `limit` (a part pays [`GROUP_S`] once per group it holds
/// units of); `None` when that takes more parts.
fn cut(units: &[(usize, f64)], count: usize, limit: f64) -> Option<(Vec<u32>, Vec<f64>)> {
    let (mut owner, mut load) = (Vec::with_capacity(units.len()), vec![0.0f64]);
    let mut last_group = None;
    for &(group, cost) in units {
        let shard = load.len() - 1;
        let add = cost
            + if last_group == Some(group) {
                0.0
            } else {
                GROUP_S
            };
        if load[shard] > 0.0 && load[shard] + add > limit {
            if load.len() == count {
                return None;
            }
            load.push(cost + GROUP_S);
        } else {
            load[shard] += add;
        }
        last_group = Some(group);
        owner.push((load.len() - 1) as u32);
    }
    load.resize(count, 0.0);
    Some((owner, load))
}

/// Assigns units (their group and cost, in the run's order, a group's units together) to
/// `count` shards as contiguous runs of units, so that a shard holds few groups (each costs it
/// [`GROUP_S`]), with the least possible largest shard cost (binary search on that cost).
/// Deterministic: a function of the costs and groups only. Returns each unit's shard and each
/// shard's estimated total.
pub fn assign(units: &[(usize, f64)], count: u32) -> (Vec<u32>, Vec<f64>) {
    let count = count.max(1) as usize;
    let total: f64 = units.iter().map(|u| u.1 + GROUP_S).sum();
    let (mut lo, mut hi) = (0.0f64, total + GROUP_S);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if cut(units, count, mid).is_some() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    cut(units, count, hi).unwrap_or_else(|| (vec![0; units.len()], vec![total; count]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_bad_ones_are_refused() {
        assert_eq!(Shard::parse("0/1").unwrap(), Shard::WHOLE);
        assert_eq!(Shard::parse("3/4").unwrap(), Shard { index: 3, count: 4 });
        for (bad, says) in [
            ("4/4", "K must be below N"),
            ("0/0", "N must be at least 1"),
            ("1", "expected K/N"),
            ("a/2", "K `a`"),
            ("-1/2", "K `-1`"),
        ] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    #[test]
    fn assignment_is_balanced_and_deterministic() {
        // Two groups of 10 units: a few large (reference frames), then smaller rows.
        let units: Vec<(usize, f64)> = (0..20)
            .map(|i| {
                (
                    i / 10,
                    if i % 10 < 3 {
                        4.0
                    } else {
                        1.0 + (i * 7 % 5) as f64
                    },
                )
            })
            .collect();
        let (owner, load) = assign(&units, 4);
        assert_eq!((owner.clone(), load.clone()), assign(&units, 4));
        assert!(
            owner.windows(2).all(|w| w[0] <= w[1]),
            "contiguous: {owner:?}"
        );
        let total: f64 = units.iter().map(|u| u.1).sum();
        // Each shard pays its groups once on top of the units' costs.
        let touched: usize = (0..4u32)
            .map(|s| {
                let mut g: Vec<usize> = (0..units.len())
                    .filter(|&i| owner[i] == s)
                    .map(|i| units[i].0)
                    .collect();
                g.dedup();
                g.len()
            })
            .sum();
        let sum: f64 = load.iter().sum();
        assert!((sum - total - touched as f64 * GROUP_S).abs() < 1e-9);
        let (lo, hi) = (
            load.iter().copied().fold(f64::INFINITY, f64::min),
            load.iter().copied().fold(0.0, f64::max),
        );
        assert!(hi / lo <= 1.5, "{load:?}");
        // One shard takes everything; more shards than units leaves some empty.
        assert!(assign(&units, 1).0.iter().all(|&o| o == 0));
        assert_eq!(assign(&[(0, 5.0), (0, 4.0)], 4).0, vec![0, 1]);
        assert_eq!(assign(&[(0, 5.0), (0, 4.0)], 4).1[2..], [0.0, 0.0]);
        // Rows of one group stay together while the balance allows.
        let same: Vec<(usize, f64)> = vec![(0, 1.0), (0, 1.0), (1, 1.0), (1, 1.0)];
        let (o, l) = assign(&same, 2);
        assert_eq!(o, vec![0, 0, 1, 1]);
        assert_eq!(l, vec![2.0 + GROUP_S, 2.0 + GROUP_S]);
    }
}
