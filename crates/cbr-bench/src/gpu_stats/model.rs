//! The static cost model of `cbr gpu-stats`, stated as one (docs/gpu-isa.md): per pass, on a
//! named GPU with its published figures,
//! - ALU time = waves64 x ACO's "Inverse Throughput" / (CUs x SIMDs per CU) / clock, where waves64
//!   = invocations / 64 (ACO states its inverse throughput in busy cycles per 64 invocations,
//!   wave32 programs included, with the occupancy's latency hiding already counted);
//! - memory time = bytes / bandwidth, the bytes being those the pass's declared reads and writes
//!   touch, each image or buffer once in full (cbr_gpu::Traffic: compulsory traffic, perfect
//!   caches);
//! - predicted = the larger of the two, and which bound it is.
//!
//! No calibration constant: nothing is fitted to any measurement.

use serde::Serialize;

/// A GPU the model predicts for: one per family, with its published figures.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct GpuModel {
    pub name: &'static str,
    /// Mesa's family name of its chip.
    pub family: &'static str,
    pub cus: u32,
    /// SIMDs per CU: 4 SIMD16 on GCN, 2 SIMD32 on RDNA.
    pub simds_per_cu: u32,
    /// Boost clock.
    pub clock_mhz: f64,
    /// DRAM bandwidth.
    pub bandwidth_gb_s: f64,
    pub source: &'static str,
}

/// The GPUs of the model, one per family (docs/gpu-isa.md cites each figure).
pub const GPUS: &[GpuModel] = &[
    GpuModel {
        name: "Radeon RX 480",
        family: "polaris10",
        cus: 36,
        simds_per_cu: 4,
        clock_mhz: 1266.0,
        bandwidth_gb_s: 256.0,
        source: "AMD Radeon RX 480 specifications: 36 CUs, 1266 MHz boost, 8 Gbps GDDR5 on 256 bits",
    },
    GpuModel {
        name: "Radeon RX Vega 56",
        family: "vega10",
        cus: 56,
        simds_per_cu: 4,
        clock_mhz: 1471.0,
        bandwidth_gb_s: 410.0,
        source: "AMD Radeon RX Vega 56 specifications (the Stadia write-up's reference GPU): 56 CUs, 1471 MHz boost, 410 GB/s HBM2",
    },
    GpuModel {
        name: "Radeon RX 6800 XT",
        family: "navi21",
        cus: 72,
        simds_per_cu: 2,
        clock_mhz: 2250.0,
        bandwidth_gb_s: 512.0,
        source: "AMD Radeon RX 6800 XT specifications: 72 CUs, 2250 MHz boost, 512 GB/s GDDR6 (its 128 MB Infinity Cache is not modelled)",
    },
    GpuModel {
        name: "Radeon RX 7900 XTX",
        family: "gfx1100",
        cus: 96,
        simds_per_cu: 2,
        clock_mhz: 2500.0,
        bandwidth_gb_s: 960.0,
        source: "AMD Radeon RX 7900 XTX specifications: 96 CUs, 2500 MHz boost, 960 GB/s GDDR6 (Infinity Cache not modelled)",
    },
];

/// The model's GPU for `family`.
pub fn gpu_for(family: &str) -> Option<&'static GpuModel> {
    GPUS.iter().find(|g| g.family == family)
}

/// One prediction (a row's `model`).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Prediction {
    pub gpu: String,
    pub width: u32,
    pub height: u32,
    pub alu_us: f64,
    pub memory_us: f64,
    pub predicted_us: f64,
    /// `alu` or `memory`.
    pub bound: String,
}

/// Microseconds of ALU time for `invocations` of a program whose ACO inverse throughput is
/// `inverse_throughput` (busy cycles per 64 invocations on one SIMD).
pub fn alu_us(gpu: &GpuModel, invocations: u64, inverse_throughput: f64) -> f64 {
    let waves64 = invocations as f64 / 64.0;
    let simds = f64::from(gpu.cus * gpu.simds_per_cu);
    // cycles / MHz = microseconds.
    waves64 * inverse_throughput / simds / gpu.clock_mhz
}

/// Microseconds to move `bytes` at the GPU's DRAM bandwidth.
pub fn memory_us(gpu: &GpuModel, bytes: u64) -> f64 {
    // bytes / (GB/s) = ns.
    bytes as f64 / gpu.bandwidth_gb_s / 1e3
}

/// Rounds to 0.01 us: the JSON stays byte-identical across reruns and machines (the inputs are
/// integers; this keeps float formatting from mattering).
fn round(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

pub fn predict(gpu: &GpuModel, size: (u32, u32), alu: f64, memory: f64) -> Prediction {
    let (alu, memory) = (round(alu), round(memory));
    Prediction {
        gpu: gpu.name.to_string(),
        width: size.0,
        height: size.1,
        alu_us: alu,
        memory_us: memory,
        predicted_us: alu.max(memory),
        bound: if alu >= memory { "alu" } else { "memory" }.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_formulas_by_hand() {
        let vega = gpu_for("vega10").expect("vega56");
        // 1920x1080 invocations, 556 cycles per wave64: 32400 waves x 556 / 224 SIMDs / 1471 MHz.
        let a = alu_us(vega, 1920 * 1080, 556.0);
        assert!((a - 32400.0 * 556.0 / 224.0 / 1471.0).abs() < 1e-9, "{a}");
        assert!((a - 54.67).abs() < 0.01, "{a}");
        // 100 MB at 410 GB/s: 243.9 us (the write-up's 244 us floor at 4K).
        let m = memory_us(vega, 100_000_000);
        assert!((m - 243.9).abs() < 0.01, "{m}");
        let p = predict(vega, (1920, 1080), a, m);
        assert_eq!(p.bound, "memory");
        assert_eq!(p.predicted_us, 243.9);
        // RDNA: 2 SIMD32 per CU.
        let navi = gpu_for("navi21").expect("6800 XT");
        let a = alu_us(navi, 64 * 144, 2250.0);
        assert!((a - 1.0).abs() < 1e-12, "{a}");
        assert!(gpu_for("gfx900").is_none());
    }
}
