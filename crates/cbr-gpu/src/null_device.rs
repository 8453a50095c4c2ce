//! RADV's null device: AMD's real shader compiler (ACO) without an AMD GPU.
//!
//! With `RADV_FORCE_FAMILY=<family>` and the loader pointed at RADV's ICD, Mesa offers a device
//! named "Null hardware (RADV <FAMILY>)" that compiles pipelines for that GPU family but has no
//! memory and cannot execute (docs/PLATFORM.md). The driver reads both variables when the loader
//! enumerates devices, so a process opens one family's null device: set them on a child process
//! ([`set_env`]) to compile for several families.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{GpuError, Result};

/// Where Debian's `mesa-vulkan-drivers` installs RADV's ICD manifest.
pub const RADEON_ICD: &str = "/usr/share/vulkan/icd.d/radeon_icd.x86_64.json";

/// The families Mesa 22.3's RADV knows (`ac_get_family_name`), lower case. Mesa aborts the
/// process on any other name, so [`check_family`] refuses it first.
pub const FAMILIES: &[&str] = &[
    "tahiti",
    "pitcairn",
    "verde",
    "oland",
    "hainan",
    "bonaire",
    "kaveri",
    "kabini",
    "hawaii",
    "tonga",
    "iceland",
    "carrizo",
    "fiji",
    "stoney",
    "polaris10",
    "polaris11",
    "polaris12",
    "vegam",
    "vega10",
    "vega12",
    "vega20",
    "raven",
    "raven2",
    "renoir",
    "arcturus",
    "aldebaran",
    "navi10",
    "navi12",
    "navi14",
    "navi21",
    "navi22",
    "navi23",
    "navi24",
    "vangogh",
    "rembrandt",
    "gfx1036",
    "gfx1100",
    "gfx1101",
    "gfx1102",
    "gfx1103_r1",
    "gfx1103_r2",
];

/// Where RADV's ICD manifest is looked for: `$CBR_RADEON_ICD` (a Mesa installed elsewhere), else
/// [`RADEON_ICD`].
pub fn radeon_icd_path() -> PathBuf {
    std::env::var_os("CBR_RADEON_ICD")
        .filter(|p| !p.is_empty())
        .map_or_else(|| PathBuf::from(RADEON_ICD), PathBuf::from)
}

/// RADV's ICD manifest, when installed.
pub fn radeon_icd() -> Option<PathBuf> {
    let p = radeon_icd_path();
    Path::new(&p).is_file().then_some(p)
}

/// `Ok` when Mesa knows `family` (case-insensitive), else the error naming the known ones.
pub fn check_family(family: &str) -> Result<()> {
    if FAMILIES
        .iter()
        .any(|f| f.eq_ignore_ascii_case(family.trim()))
    {
        Ok(())
    } else {
        Err(GpuError::UnknownFamily {
            family: family.to_string(),
            known: FAMILIES.join(", "),
        })
    }
}

/// The environment that makes a process's Vulkan loader offer only `family`'s null device:
/// `RADV_FORCE_FAMILY` and `VK_DRIVER_FILES` (`./dev` also wants `CBR_ANY_DEVICE=1`, so it does
/// not pin lavapipe). Errors: an unknown family, or no RADV ICD on this machine.
pub fn env(family: &str) -> Result<Vec<(&'static str, String)>> {
    check_family(family)?;
    let icd = radeon_icd().ok_or_else(|| {
        GpuError::Other(format!(
            "RADV's ICD {} is not installed (Debian: `apt-get install mesa-vulkan-drivers`; \
             elsewhere: CBR_RADEON_ICD=PATH)",
            radeon_icd_path().display()
        ))
    })?;
    Ok(vec![
        ("RADV_FORCE_FAMILY", family.trim().to_lowercase()),
        ("VK_DRIVER_FILES", icd.display().to_string()),
    ])
}

/// Sets [`env`] on `cmd` (and clears `VK_ICD_FILENAMES`, which would otherwise compete).
pub fn set_env(cmd: &mut Command, family: &str) -> Result<()> {
    for (k, v) in env(family)? {
        cmd.env(k, v);
    }
    cmd.env_remove("VK_ICD_FILENAMES");
    Ok(())
}

/// Refuses a `RADV_FORCE_FAMILY` that Mesa would abort on, before any Vulkan call.
pub(crate) fn check_forced_family() -> Result<()> {
    match std::env::var("RADV_FORCE_FAMILY") {
        Ok(f) if !f.is_empty() => check_family(&f),
        _ => Ok(()),
    }
}

/// Whether a device can allocate and execute: RADV's null winsys has no memory heap or type and
/// names itself "Null hardware (RADV <FAMILY>)".
pub(crate) fn can_execute(name: &str, memory_heaps: u32, memory_types: u32) -> bool {
    memory_heaps > 0 && memory_types > 0 && !name.starts_with("Null hardware")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_are_checked_before_mesa_sees_them() {
        assert!(check_family("vega10").is_ok());
        assert!(check_family("NAVI21").is_ok());
        assert!(check_family("gfx1100").is_ok());
        let err = check_family("gfx900").unwrap_err().to_string();
        assert!(err.contains("RADV_FORCE_FAMILY=gfx900"), "{err}");
        assert!(err.contains("polaris10"), "{err}");
        assert!(check_family("").is_err());
    }

    #[test]
    fn a_device_without_memory_or_named_null_cannot_execute() {
        assert!(can_execute("llvmpipe (LLVM 15.0.6, 256 bits)", 1, 1));
        assert!(can_execute("AMD Radeon RX 6800 XT (RADV NAVI21)", 3, 11));
        assert!(!can_execute("Null hardware (RADV VEGA10)", 0, 0));
        assert!(!can_execute("Null hardware (RADV VEGA10)", 1, 1));
        assert!(!can_execute("some device", 0, 3));
        assert!(!can_execute("some device", 2, 0));
    }
}
