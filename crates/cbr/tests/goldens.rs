//! Golden EXRs (references/goldens, recorded before techniques became pass chains): every
//! technique, layout and resolve mode of builtin:demo at 96x54, frames 0-2, must reproduce every
//! layer bit for bit. Each configuration runs twice: through its technique spec and through the
//! shorthand flags it was recorded with. Re-record only on purpose (scripts/make-goldens.sh).
//! The goldens are lavapipe's bits: on another driver (a GPU) every configuration still renders
//! with zero validation messages and the comparison is skipped with a message.

mod common;

use std::path::{Path, PathBuf};

use exr::prelude::*;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../references/goldens")
}

struct Config {
    name: String,
    spec: String,
    flags: Vec<String>,
}

fn configs() -> Vec<Config> {
    let text = std::fs::read_to_string(root().join("configs.txt")).expect("configs.txt");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            assert_eq!(c.len(), 3, "configs.txt line `{l}`");
            Config {
                name: c[0].into(),
                spec: c[1].into(),
                flags: c[2].split_whitespace().map(String::from).collect(),
            }
        })
        .collect()
}

/// (layer name, channel name) -> raw sample bits, in file order.
fn layers(path: &Path) -> Vec<(String, String, Vec<u32>)> {
    let img = read_all_flat_layers_from_file(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut out = Vec::new();
    for l in &img.layer_data {
        let lname = l
            .attributes
            .layer_name
            .as_ref()
            .map(|t| t.to_string())
            .unwrap_or_default();
        for c in &l.channel_data.list {
            let bits: Vec<u32> = match &c.sample_data {
                FlatSamples::F16(v) => v.iter().map(|x| u32::from(x.to_bits())).collect(),
                FlatSamples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
                FlatSamples::U32(v) => v.clone(),
            };
            out.push((lname.clone(), c.name.to_string(), bits));
        }
    }
    out
}

/// Renders into `out` with the validation layers on; returns the device's driver name.
fn render(args: &[String], out: &Path) -> std::result::Result<String, String> {
    let mut all = vec!["--validation"];
    all.extend(args.iter().map(String::as_str));
    let run = common::render_demo(out, (96, 54), 3, &all)
        .map_err(|e| format!("cbr render {args:?}: {}", e.trim()))?;
    if run["validation"]["messages"] != 0 {
        return Err(format!("{args:?}: validation {}", run["validation"]));
    }
    let driver = run["device"]["driver_name"].as_str().unwrap_or_default();
    // The bits are compared on lavapipe only: a driver name that goes missing, or another driver
    // where the environment pins lavapipe (./dev, CI), must not turn the comparison off.
    let pinned = std::env::var("VK_DRIVER_FILES").is_ok_and(|f| f.contains("lvp_icd"));
    if driver.is_empty() || (pinned && driver != "llvmpipe") {
        return Err(format!(
            "{args:?}: run.json's device.driver_name is `{driver}` (VK_DRIVER_FILES pins lavapipe: {pinned})"
        ));
    }
    Ok(driver.to_string())
}

/// Differences between a rendered folder and the golden one, as readable lines.
fn diff(name: &str, how: &str, dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    for f in 0..3 {
        let file = format!("frame_{f:04}.exr");
        let (want, got) = (
            layers(&root().join(name).join(&file)),
            layers(&dir.join(&file)),
        );
        let names = |v: &[(String, String, Vec<u32>)]| -> Vec<String> {
            v.iter().map(|(l, c, _)| format!("{l}.{c}")).collect()
        };
        if names(&want) != names(&got) {
            bad.push(format!(
                "{name} ({how}) {file}: layers {:?} != golden {:?}",
                names(&got),
                names(&want)
            ));
            continue;
        }
        for ((l, c, w), (_, _, g)) in want.iter().zip(&got) {
            let n = w.iter().zip(g).filter(|(a, b)| a != b).count();
            if n > 0 {
                bad.push(format!("{name} ({how}) {file} {l}.{c}: {n} samples differ"));
            }
        }
    }
    bad
}

#[test]
fn every_technique_reproduces_its_golden_exrs_bit_for_bit() {
    let configs = configs();
    assert!(
        configs.len() >= 20,
        "configs.txt lists every technique and mode"
    );
    let tmp = tempfile::tempdir().expect("tempdir");
    // Two workers: the machine has two cores, each render is single-threaded setup + lavapipe.
    let jobs: Vec<(usize, bool)> = (0..configs.len())
        .flat_map(|i| [(i, true), (i, false)])
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failures = std::sync::Mutex::new(Vec::new());
    let other_driver = std::sync::Mutex::new(None::<String>);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&(i, by_spec)) = jobs.get(k) else {
                        break;
                    };
                    let c = &configs[i];
                    let (how, args) = if by_spec {
                        // The spec carries the technique; flags that are not part of the spec
                        // grammar (debug views, LOD mode) stay flags.
                        let extra = c.flags.iter().filter(|f| {
                            ["--resolve-debug", "--lod-mode", "gradients", "bias"]
                                .contains(&f.as_str())
                        });
                        let mut a = vec!["--technique".to_string(), c.spec.clone()];
                        a.extend(extra.cloned());
                        ("spec", a)
                    } else {
                        ("flags", c.flags.clone())
                    };
                    let dir = tmp.path().join(format!("{}-{how}", c.name));
                    // The goldens are lavapipe's bits: on another driver every configuration
                    // still renders with zero validation messages, and the bits are not compared.
                    let d = match render(&args, &dir) {
                        Ok(driver) if driver == "llvmpipe" => diff(&c.name, how, &dir),
                        Ok(driver) => {
                            other_driver.lock().expect("lock").replace(driver);
                            Vec::new()
                        }
                        Err(e) => vec![e],
                    };
                    failures.lock().expect("lock").extend(d);
                }
            });
        }
    });
    let failures = failures.into_inner().expect("lock");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    if let Some(driver) = other_driver.into_inner().expect("lock") {
        eprintln!(
            "SKIPPED the bit-for-bit comparison on driver {driver}: the goldens are lavapipe's (every configuration rendered with zero validation messages)"
        );
    }
}
