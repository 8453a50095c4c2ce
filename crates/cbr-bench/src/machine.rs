//! The machine a bench ran on (bench.json's `machine`): its CPU, how many logical CPUs it
//! offered, which vector extensions the CPU has, its memory, and the load average at the run's
//! start and end. On lavapipe the CPU is the device, and its name says nothing of the CPU: two
//! 2-core hosts that both report `llvmpipe (LLVM 15.0.6, 256 bits)` gave `interleaved:4x4`'s
//! ratio to `deferred:vpls=1024` 1.7 times apart, with the code unchanged (docs/interleaved.md,
//! "Issue 57 on a second host"). The load average says whether other work shared the cores.
//! Read from Linux's /proc; where a file is missing or unreadable its fields are null.

use serde_json::{Value, json};

/// What /proc/cpuinfo says of the first CPU.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cpu {
    /// `model name` (x86) or `Hardware` / `CPU part` (Arm); empty if none.
    pub name: String,
    /// Vendor, family, model and stepping (x86: `GenuineIntel family 6 model 167 stepping 1`;
    /// Arm: `implementer 0x41 part 0xd0c`); empty if none.
    pub id: String,
    /// Of [`SIMD`], those the CPU's `flags` (x86) or `Features` (Arm) list, in that order.
    pub simd: Vec<&'static str>,
}

/// The vector extensions worth naming beside a CPU timing: what llvmpipe's JIT may use.
pub const SIMD: [&str; 10] = [
    "sse4_2", "avx", "avx2", "fma", "avx512f", "avx512bw", "avx512vl", "asimd", "sve", "sve2",
];

/// The first processor's entry of /proc/cpuinfo's text.
pub fn parse_cpuinfo(text: &str) -> Cpu {
    let first = text.split("\n\n").next().unwrap_or("");
    let field = |key: &str| {
        first.lines().find_map(|l| {
            let (k, v) = l.split_once(':')?;
            (k.trim() == key).then(|| v.trim().to_string())
        })
    };
    let name = field("model name")
        .or_else(|| field("Hardware"))
        .or_else(|| field("CPU part"))
        .unwrap_or_default();
    let id = match (field("vendor_id"), field("CPU implementer")) {
        (Some(vendor), _) => {
            let mut id = vendor;
            for (label, key) in [
                ("family", "cpu family"),
                ("model", "model"),
                ("stepping", "stepping"),
            ] {
                if let Some(v) = field(key) {
                    id.push_str(&format!(" {label} {v}"));
                }
            }
            id
        }
        (None, Some(implementer)) => {
            let part = field("CPU part").unwrap_or_default();
            format!("implementer {implementer} part {part}")
        }
        (None, None) => String::new(),
    };
    let flags = field("flags")
        .or_else(|| field("Features"))
        .unwrap_or_default();
    let has: std::collections::HashSet<&str> = flags.split_whitespace().collect();
    let simd = SIMD.iter().copied().filter(|s| has.contains(s)).collect();
    Cpu { name, id, simd }
}

/// /proc/loadavg's text: the 1, 5 and 15 minute load averages.
pub fn parse_loadavg(text: &str) -> Option<[f64; 3]> {
    let mut it = text.split_whitespace().map(|v| v.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// /proc/meminfo's `MemTotal`, in GiB.
pub fn parse_memtotal_gib(text: &str) -> Option<f64> {
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / (1024.0 * 1024.0))
}

/// The load average now (null where /proc/loadavg is not there).
pub fn load_average() -> Option<[f64; 3]> {
    parse_loadavg(&std::fs::read_to_string("/proc/loadavg").ok()?)
}

/// bench.json's `machine`, with the load average taken at the run's start and now.
pub fn describe(load_at_start: Option<[f64; 3]>) -> Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .map(|t| parse_cpuinfo(&t));
    let memory = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| parse_memtotal_gib(&t));
    let nonempty = |s: &str| (!s.is_empty()).then(|| s.to_string());
    json!({
        "hostname": cbr_metrics::io::hostname(),
        "cpu": cpu.as_ref().and_then(|c| nonempty(&c.name)),
        "cpu_id": cpu.as_ref().and_then(|c| nonempty(&c.id)),
        "simd": cpu.as_ref().map(|c| c.simd.clone()),
        "logical_cpus": std::thread::available_parallelism().ok().map(|n| n.get()),
        "memory_gib": memory.map(|m| (m * 10.0).round() / 10.0),
        "load_average": {
            "what": "1, 5 and 15 minute load averages (/proc/loadavg) when the run started and ended",
            "start": load_at_start,
            "end": load_average(),
        },
    })
}

/// `machine` without what differs from run to run on one machine (hostname aside): the fields
/// that must agree for two runs' times to be compared as one machine's.
pub fn identity(machine: &Value) -> Value {
    json!({
        "cpu": machine["cpu"],
        "cpu_id": machine["cpu_id"],
        "simd": machine["simd"],
        "logical_cpus": machine["logical_cpus"],
        "memory_gib": machine["memory_gib"],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const XEON: &str = "processor\t: 0\nvendor_id\t: GenuineIntel\ncpu family\t: 6\nmodel\t\t: 167\n\
        model name\t: Intel(R) Xeon(R) Processor\nstepping\t: 1\nflags\t\t: fpu sse sse2 sse4_2 avx \
        avx2 fma avx512f avx512bw avx512vl avx512cd\n\nprocessor\t: 1\nvendor_id\t: OtherVendor\n\
        model name\t: not the first\n";
    const EPYC: &str = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 1\n\
        model name\t: AMD EPYC 7B13\nstepping\t: 1\nflags\t\t: fpu sse4_2 avx avx2 fma\n";
    const ARM: &str = "processor\t: 0\nBogoMIPS\t: 50.00\nFeatures\t: fp asimd evtstrm sve\n\
        CPU implementer\t: 0x41\nCPU part\t: 0xd0c\n";

    #[test]
    fn the_first_cpu_is_read_with_its_vector_extensions() {
        let x = parse_cpuinfo(XEON);
        assert_eq!(x.name, "Intel(R) Xeon(R) Processor");
        assert_eq!(x.id, "GenuineIntel family 6 model 167 stepping 1");
        assert_eq!(
            x.simd,
            [
                "sse4_2", "avx", "avx2", "fma", "avx512f", "avx512bw", "avx512vl"
            ]
        );
        let e = parse_cpuinfo(EPYC);
        assert_eq!(e.name, "AMD EPYC 7B13");
        assert_eq!(e.id, "AuthenticAMD family 25 model 1 stepping 1");
        assert_eq!(e.simd, ["sse4_2", "avx", "avx2", "fma"]);
        let a = parse_cpuinfo(ARM);
        assert_eq!(a.name, "0xd0c");
        assert_eq!(a.id, "implementer 0x41 part 0xd0c");
        assert_eq!(a.simd, ["asimd", "sve"]);
        assert_eq!(parse_cpuinfo(""), Cpu::default());
    }

    #[test]
    fn load_and_memory_are_parsed_or_refused() {
        assert_eq!(
            parse_loadavg("0.03 0.63 1.10 1/123 4567\n"),
            Some([0.03, 0.63, 1.10])
        );
        assert_eq!(parse_loadavg("0.03 x 1.10"), None);
        assert_eq!(parse_loadavg(""), None);
        let m = parse_memtotal_gib("MemTotal:       24523608 kB\nMemFree: 1 kB\n").expect("memory");
        assert!((m - 23.387).abs() < 1e-3, "{m}");
        assert_eq!(parse_memtotal_gib("MemFree: 1 kB\n"), None);
    }

    #[test]
    fn the_identity_leaves_out_the_load_and_the_hostname() {
        let m = json!({"hostname": "h", "cpu": "c", "cpu_id": "i", "simd": ["avx2"], "logical_cpus": 2,
            "memory_gib": 23.4, "load_average": {"start": [0.1, 0.1, 0.1], "end": null}});
        assert_eq!(identity(&m)["logical_cpus"], 2);
        assert!(identity(&m).get("load_average").is_none());
        assert!(identity(&m).get("hostname").is_none());
    }
}
