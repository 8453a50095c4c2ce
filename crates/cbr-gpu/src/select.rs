//! Device selection as plain data, so the rules are testable without a GPU.

use std::fmt::Write as _;

/// What selection needs to know about one physical device.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub index: usize,
    pub name: String,
    pub kind: DeviceKind,
    /// Vulkan API version as (major, minor).
    pub api: (u32, u32),
    pub has_graphics_compute_queue: bool,
    /// Required features this device lacks, by name.
    pub missing: Vec<&'static str>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DeviceKind {
    Discrete,
    Integrated,
    Virtual,
    Cpu,
    Other,
}

impl DeviceKind {
    fn preference(self) -> u32 {
        match self {
            DeviceKind::Discrete => 4,
            DeviceKind::Integrated => 3,
            DeviceKind::Virtual => 2,
            DeviceKind::Cpu => 1,
            DeviceKind::Other => 0,
        }
    }
}

/// The minimum API version cbr is written against (dynamic rendering, synchronization2 in core).
pub const MIN_API: (u32, u32) = (1, 3);

impl Candidate {
    /// Why this device cannot run cbr, or `None` when it can.
    pub fn rejection(&self) -> Option<String> {
        let mut why = Vec::new();
        if self.api < MIN_API {
            why.push(format!(
                "Vulkan {}.{} < required {}.{}",
                self.api.0, self.api.1, MIN_API.0, MIN_API.1
            ));
        }
        if !self.has_graphics_compute_queue {
            why.push("no queue family with both graphics and compute".to_string());
        }
        if !self.missing.is_empty() {
            why.push(format!("missing features: {}", self.missing.join(", ")));
        }
        (!why.is_empty()).then(|| why.join("; "))
    }
}

/// Picks a device. `pick` is an index (`"0"`) or a case-insensitive substring of the device name
/// (`"llvmpipe"`). Without one the most capable kind wins (discrete > integrated > virtual > CPU),
/// ties going to the lower index. The error lists every device with the reason it was rejected.
pub fn choose(candidates: &[Candidate], pick: Option<&str>) -> Result<usize, String> {
    let matches_pick = |c: &Candidate| match pick {
        None => true,
        Some(p) => match p.trim().parse::<usize>() {
            Ok(i) => c.index == i,
            Err(_) => c.name.to_lowercase().contains(&p.trim().to_lowercase()),
        },
    };
    let best = candidates
        .iter()
        .filter(|c| matches_pick(c) && c.rejection().is_none())
        .max_by_key(|c| (c.kind.preference(), std::cmp::Reverse(c.index)));
    if let Some(c) = best {
        return Ok(c.index);
    }
    let mut report = String::new();
    for c in candidates {
        let reason = if !matches_pick(c) {
            format!("does not match --device {:?}", pick.unwrap_or_default())
        } else {
            c.rejection().unwrap_or_default()
        };
        let _ = writeln!(
            report,
            "  [{}] {} ({:?}): {}",
            c.index, c.name, c.kind, reason
        );
    }
    if candidates.is_empty() {
        report.push_str("  (no devices)\n");
    }
    Err(report.trim_end().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(index: usize, name: &str, kind: DeviceKind) -> Candidate {
        Candidate {
            index,
            name: name.into(),
            kind,
            api: (1, 3),
            has_graphics_compute_queue: true,
            missing: vec![],
        }
    }

    #[test]
    fn prefers_discrete_then_lowest_index() {
        let c = [
            cand(0, "llvmpipe (LLVM 15.0.6, 256 bits)", DeviceKind::Cpu),
            cand(1, "NVIDIA H100", DeviceKind::Discrete),
            cand(2, "NVIDIA H100", DeviceKind::Discrete),
        ];
        assert_eq!(choose(&c, None), Ok(1));
    }

    #[test]
    fn picks_by_index_and_by_name() {
        let c = [
            cand(0, "llvmpipe", DeviceKind::Cpu),
            cand(1, "NVIDIA H100", DeviceKind::Discrete),
        ];
        assert_eq!(choose(&c, Some("0")), Ok(0));
        assert_eq!(choose(&c, Some("LLVMPIPE")), Ok(0));
        assert_eq!(choose(&c, Some("nvidia")), Ok(1));
    }

    #[test]
    fn explains_every_rejection() {
        let mut old = cand(0, "old", DeviceKind::Discrete);
        old.api = (1, 1);
        old.missing = vec!["dynamicRendering"];
        let mut noq = cand(1, "noqueue", DeviceKind::Integrated);
        noq.has_graphics_compute_queue = false;
        let err = choose(&[old, noq], None).unwrap_err();
        assert!(err.contains("[0] old"), "{err}");
        assert!(err.contains("Vulkan 1.1 < required 1.3"), "{err}");
        assert!(err.contains("missing features: dynamicRendering"), "{err}");
        assert!(
            err.contains("no queue family with both graphics and compute"),
            "{err}"
        );
        let err = choose(&[cand(0, "a", DeviceKind::Cpu)], Some("7")).unwrap_err();
        assert!(err.contains("does not match --device \"7\""), "{err}");
        assert!(choose(&[], None).unwrap_err().contains("no devices"));
    }
}
