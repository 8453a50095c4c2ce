//! Issue 56: `cbr bench --shard K/N`, `--merge`, `cbr report` on shard folders, and `cbr slurm`
//! against a real single-node Slurm (Debian's slurm-wlm and munge) started and stopped here.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use serde_json::Value;

mod common;
use common::cbr;

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "cbr failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A clean failure (exit 1, one error, no panic) whose message holds every string of `expect`.
fn refused(o: &Output, expect: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "exit status; stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    for e in expect {
        assert!(err.contains(e), "expected `{e}` in:\n{err}");
    }
}

fn bench_json(dir: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("bench.json")).expect("bench.json"))
        .expect("json")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

/// Fields of a row that time the run (they differ between any two runs) or follow from times.
const TIMINGS: [&str; 9] = [
    "frame_ms",
    "passes",
    "setup_s",
    "frames_wall_s",
    "cached_frames",
    "copy_floor_ms",
    "fragment_invocations_median",
    "pareto",
    "equal_error_ssaa",
];

/// The rows of two bench.json files are the same rows in the same order, every field but the
/// timings equal (the errors bit for bit: serde_json reads floats back exactly).
fn same_rows(a: &Value, b: &Value) {
    let (ra, rb) = (a["rows"].as_array().unwrap(), b["rows"].as_array().unwrap());
    let names = |r: &[Value]| -> Vec<String> {
        r.iter()
            .map(|r| {
                format!(
                    "{} {}x{} {}",
                    r["scene"], r["width"], r["height"], r["config"]
                )
            })
            .collect()
    };
    assert_eq!(names(ra), names(rb));
    for (x, y) in ra.iter().zip(rb) {
        let strip = |r: &Value| {
            let mut r = r.clone();
            for t in TIMINGS {
                r.as_object_mut().unwrap().remove(t);
            }
            r
        };
        assert_eq!(strip(x), strip(y), "row {}", x["config"]);
        assert!(x["error"].is_null() || x["error"]["flip_mean"].is_f64());
    }
    assert_eq!(a["reference_images"], b["reference_images"]);
}

/// A sweep of two built-in scenes at 64x36 against ssaa:2.
fn sweep(dir: &Path, techniques: &str) -> PathBuf {
    let p = dir.join("sweep.toml");
    let text = format!(
        "scenes = [\"builtin:demo\", \"builtin:wires\"]\ntechniques = [{techniques}]\nresolutions = [\"64x36\"]\nwarmup = 1\nframes = 2\nreference = \"ssaa:2\"\n"
    );
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn shards_merge_into_the_unsharded_rows_and_bad_ones_are_named() {
    let d = tempfile::tempdir().unwrap();
    let sw = sweep(d.path(), "\"native\", \"upscale:bilinear\"");
    let cache = d.path().join("cache");
    let whole = d.path().join("whole");
    let base = ["bench", "--sweep", s(&sw), "--cache-dir", s(&cache)];
    ok(&cbr(&[&base[..], &["-o", s(&whole)]].concat(), &[]));
    // Shards share another cache: their references are rendered again, by their owners.
    let cache4 = d.path().join("cache4");
    let shard = |k: u32| d.path().join(format!("shard-{k}"));
    let mut owners = Vec::new();
    for k in 0..4 {
        let spec = format!("{k}/4");
        let o = cbr(
            &[
                "bench",
                "--sweep",
                s(&sw),
                "--cache-dir",
                s(&cache4),
                "--shard",
                &spec,
                "-o",
                s(&shard(k)),
            ],
            &[],
        );
        ok(&o);
        let j = bench_json(&shard(k));
        owners.push(j["shard"]["reference_frames"]["rendered"].as_u64().unwrap());
    }
    // A shard whose bench.json is missing (killed before the end) run again: its rows come
    // from rows/, its reference frames from the cache; nothing is measured again.
    let before = bench_json(&shard(1));
    std::fs::remove_file(shard(1).join("bench.json")).unwrap();
    let again = [
        "bench",
        "--sweep",
        s(&sw),
        "--cache-dir",
        s(&cache4),
        "--shard",
        "1/4",
    ];
    ok(&cbr(&[&again[..], &["-o", s(&shard(1))]].concat(), &[]));
    let after = bench_json(&shard(1));
    let rows = after["rows"].as_array().unwrap().len();
    assert!(rows > 0);
    assert_eq!(after["shard"]["rows_resumed"], rows);
    assert_eq!(after["shard"]["reference_frames"]["rendered"], 0);
    assert_eq!(
        after["rows"], before["rows"],
        "the same rows, timings included"
    );
    // 2 scenes x 2 measured frames of ssaa:2: each rendered once, by one shard or another.
    assert_eq!(owners.iter().sum::<u64>(), 4, "{owners:?}");
    let merged = d.path().join("merged");
    let all: Vec<PathBuf> = (0..4).map(shard).collect();
    let dirs: Vec<&str> = all.iter().map(|p| s(p)).collect();
    ok(&cbr(
        &[&["bench", "--merge"], &dirs[..], &["-o", s(&merged)]].concat(),
        &[],
    ));
    let (w, m) = (bench_json(&whole), bench_json(&merged));
    same_rows(&w, &m);
    assert!(m.get("shard").is_none());
    // All four shards ran here: one kind of machine, each shard's own load in merged_from.
    assert_eq!(
        m["machine"]["per_shard"],
        "hostname and load average: merged_from"
    );
    assert_eq!(m["machine"]["logical_cpus"], w["machine"]["logical_cpus"]);
    assert!(m["machine"].get("load_average").is_none());
    for f in m["merged_from"].as_array().unwrap() {
        assert!(f["machine"]["load_average"].is_object(), "{f}");
    }
    for r in m["rows"].as_array().unwrap() {
        if let Some(img) = r["images"]["image"].as_str() {
            assert!(merged.join(img).is_file(), "{img}");
        }
    }
    // The report straight from the shard folders.
    let html = d.path().join("report.html");
    ok(&cbr(
        &[&["report"], &dirs[..], &["-o", s(&html)]].concat(),
        &[],
    ));
    let text = std::fs::read_to_string(&html).unwrap();
    for r in m["rows"].as_array().unwrap() {
        let name = r["config"].as_str().unwrap();
        assert!(text.contains(name), "the report names {name}");
    }
    let scenes: Vec<&str> = m["scenes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(scenes.len(), 2);
    assert!(scenes.iter().all(|s| text.contains(s)), "{scenes:?}");

    // A missing shard is named; so is a folder of another run, by its field.
    let bad = d.path().join("bad");
    let o = cbr(
        &["bench", "--merge", dirs[0], dirs[1], dirs[3], "-o", s(&bad)],
        &[],
    );
    refused(&o, &["shard 2 of 4 missing"]);
    let other = d.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    let mut j = bench_json(&shard(2));
    j["protocol"]["measured_frames"] = 3.into();
    std::fs::write(other.join("bench.json"), j.to_string()).unwrap();
    let o = cbr(
        &[
            "bench",
            "--merge",
            dirs[0],
            dirs[1],
            s(&other),
            dirs[3],
            "-o",
            s(&bad),
        ],
        &[],
    );
    refused(&o, &["protocol.measured_frames"]);
    let o = cbr(
        &["bench", "--merge", dirs[0], s(&whole), "-o", s(&bad)],
        &[],
    );
    refused(&o, &["no `shard` section"]);
    assert!(!bad.exists(), "no output on a refused merge");
    for (spec, says) in [
        ("4/4", "K must be below N"),
        ("0/0", "N must be at least 1"),
    ] {
        let o = cbr(
            &["bench", "--sweep", s(&sw), "--shard", spec, "-o", s(&bad)],
            &[],
        );
        refused(&o, &[says]);
    }
    // cbr slurm: no shards, no scenes.
    let o = cbr(&["slurm", s(&sw), "--shards", "0", "-o", s(&bad)], &[]);
    refused(&o, &["--shards must be at least 1"]);
    let bare = d.path().join("bare.toml");
    std::fs::write(&bare, "techniques = [\"native\"]\n").unwrap();
    let o = cbr(&["slurm", s(&bare), "--shards", "2", "-o", s(&bad)], &[]);
    refused(&o, &["bare.toml", "`scenes`"]);
    std::fs::write(&sw, "scenes = [\"builtin:demo\", \"nowhere.toml\"]\n").unwrap();
    let o = cbr(&["bench", "--sweep", s(&sw), "-o", s(&bad)], &[]);
    refused(&o, &["sweep.toml:1", "scenes[1]", "nowhere.toml"]);
    assert!(!bad.exists());
}

/// A single-node Slurm on loopback, started for one test: munged, slurmctld and slurmd with
/// their state in a temporary folder; stopped by the pids in their pid files when dropped.
struct Slurm {
    dir: tempfile::TempDir,
    conf: PathBuf,
    pids: Vec<PathBuf>,
}

fn which(tool: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin".into(), "/sbin".into()])
        .map(|d| d.join(tool))
        .find(|p| p.is_file())
}

fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().port()
}

fn pid_of(file: &Path) -> Option<i32> {
    std::fs::read_to_string(file).ok()?.trim().parse().ok()
}

fn alive(pid: i32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
        && !std::fs::read_to_string(format!("/proc/{pid}/stat"))
            .is_ok_and(|s| s.split_whitespace().nth(2) == Some("Z"))
}

impl Slurm {
    /// None (with the reason) where Slurm or munge is not installed or this is not root.
    fn start() -> Result<Slurm, String> {
        let tools = ["munged", "slurmctld", "slurmd", "sbatch", "sinfo", "squeue"];
        let missing: Vec<&str> = tools
            .iter()
            .copied()
            .filter(|t| which(t).is_none())
            .collect();
        if !missing.is_empty() {
            return Err(format!(
                "not installed: {} (./dev test installs slurm-wlm and munge)",
                missing.join(", ")
            ));
        }
        let uid = Command::new("id")
            .arg("-u")
            .output()
            .map_err(|e| e.to_string())?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("slurmd runs its jobs as root here: run as root".into());
        }
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        let t = dir.path();
        let host =
            String::from_utf8_lossy(&Command::new("hostname").arg("-s").output().unwrap().stdout)
                .trim()
                .to_string();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        for sub in ["state", "spool", "munge"] {
            std::fs::create_dir_all(t.join(sub)).unwrap();
        }
        let key: Vec<u8> = (0..1024u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect();
        let key_file = t.join("munge/munge.key");
        std::fs::write(&key_file, key).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&key_file, std::fs::Permissions::from_mode(0o400)).unwrap();
        std::fs::set_permissions(t.join("munge"), std::fs::Permissions::from_mode(0o700)).unwrap();
        let socket = t.join("munge/munge.sock");
        let conf = t.join("slurm.conf");
        let text = format!(
            "ClusterName=cbrtest\nSlurmctldHost={host}(127.0.0.1)\nSlurmctldPort={}\nSlurmdPort={}\n\
             AuthType=auth/munge\nAuthInfo=socket={}\nCredType=cred/munge\nSlurmUser=root\nSlurmdUser=root\n\
             StateSaveLocation={}\nSlurmdSpoolDir={}\nSlurmctldPidFile={}\nSlurmdPidFile={}\n\
             SlurmctldLogFile={}\nSlurmdLogFile={}\nProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\nSelectType=select/cons_tres\nSelectTypeParameters=CR_Core\n\
             MpiDefault=none\nReturnToService=2\nSlurmdParameters=config_overrides\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=cbr Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            free_port(),
            free_port(),
            socket.display(),
            t.join("state").display(),
            t.join("spool").display(),
            t.join("slurmctld.pid").display(),
            t.join("slurmd.pid").display(),
            t.join("slurmctld.log").display(),
            t.join("slurmd.log").display(),
        );
        std::fs::write(&conf, text).unwrap();
        let mut slurm = Slurm {
            conf: conf.clone(),
            pids: Vec::new(),
            dir,
        };
        let t = slurm.dir.path().to_path_buf();
        let run = |cmd: &mut Command| -> Result<(), String> {
            let o = cmd.output().map_err(|e| e.to_string())?;
            if o.status.success() {
                Ok(())
            } else {
                Err(format!("{cmd:?}: {}", String::from_utf8_lossy(&o.stderr)))
            }
        };
        let munge_pid = t.join("munged.pid");
        slurm.pids.push(munge_pid.clone());
        run(Command::new(which("munged").unwrap())
            .args(["--force", "-S", s(&socket), "--key-file", s(&key_file)])
            .args([
                "--pid-file",
                s(&munge_pid),
                "--log-file",
                s(&t.join("munged.log")),
            ])
            .args(["--seed-file", s(&t.join("munge/seed"))]))?;
        slurm.pids.push(t.join("slurmctld.pid"));
        run(Command::new(which("slurmctld").unwrap()).args(["-f", s(&conf)]))?;
        slurm.pids.push(t.join("slurmd.pid"));
        run(Command::new(which("slurmd").unwrap()).args(["-f", s(&conf), "-N", &host]))?;
        let started = Instant::now();
        loop {
            let o = slurm.client("sinfo", &["-h", "-o", "%T"]);
            let state = String::from_utf8_lossy(&o.stdout).trim().to_string();
            if state == "idle" {
                break;
            }
            if started.elapsed() > Duration::from_secs(30) {
                let log = std::fs::read_to_string(t.join("slurmctld.log")).unwrap_or_default();
                return Err(format!(
                    "the node is `{state}` after 30 s; slurmctld.log:\n{log}"
                ));
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        eprintln!("slurm: up in {:.1} s", started.elapsed().as_secs_f64());
        Ok(slurm)
    }

    fn client(&self, tool: &str, args: &[&str]) -> Output {
        Command::new(which(tool).unwrap())
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .output()
            .unwrap()
    }

    /// Waits until no job is queued or running.
    fn wait_idle(&self, limit: Duration) -> bool {
        let started = Instant::now();
        while started.elapsed() < limit {
            let o = self.client("squeue", &["-h"]);
            if o.status.success() && o.stdout.iter().all(u8::is_ascii_whitespace) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(500));
        }
        false
    }
}

impl Drop for Slurm {
    /// Stops every daemon it started by the pid in its pid file (slurmd, slurmctld, munged):
    /// SIGTERM, then SIGKILL after 10 s.
    fn drop(&mut self) {
        for file in self.pids.iter().rev() {
            let Some(pid) = pid_of(file) else { continue };
            let _ = Command::new("kill").arg(pid.to_string()).status();
            let t = Instant::now();
            while alive(pid) && t.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_millis(100));
            }
            if alive(pid) {
                let _ = Command::new("kill").args(["-9", &pid.to_string()]).status();
            }
        }
    }
}

/// Issue 56: a 4-task sweep of 2 scenes through `cbr slurm --submit` on a Slurm started here
/// gives the unsharded run's rows (errors bit for bit, timings aside), bench.csv and a report;
/// every daemon started is stopped by pid, nothing left running.
#[test]
fn a_slurm_array_gives_the_unsharded_rows() {
    let slurm = match Slurm::start() {
        Ok(s) => s,
        Err(why) => {
            eprintln!("skipped: no single-node Slurm here: {why}");
            return;
        }
    };
    let d = tempfile::tempdir().unwrap();
    // CBR_SLURM_STUDY=SWEEP.toml: docs/cluster.md's measurement (`just cluster-study`).
    let study = std::env::var_os("CBR_SLURM_STUDY").map(PathBuf::from);
    let sw = study.clone().unwrap_or_else(|| {
        sweep(
            d.path(),
            "\"native\", \"upscale:bilinear\", \"checkerboard:rotated\"",
        )
    });
    let limit = Duration::from_secs(if study.is_some() { 3600 } else { 240 });
    let whole = d.path().join("whole");
    let cache = d.path().join("cache-whole");
    let started = Instant::now();
    let args = [
        "bench",
        "--sweep",
        s(&sw),
        "--cache-dir",
        s(&cache),
        "-o",
        s(&whole),
    ];
    ok(&cbr(&args, &[]));
    let whole_s = started.elapsed().as_secs_f64();
    let run = d.path().join("run");
    let conf = slurm.conf.to_string_lossy().into_owned();
    let started = Instant::now();
    let o = cbr(
        &["slurm", s(&sw), "--shards", "4", "--submit", "-o", s(&run)],
        &[("SLURM_CONF", &conf)],
    );
    ok(&o);
    let done = slurm.wait_idle(limit);
    let slurm_s = started.elapsed().as_secs_f64();
    let logs: String = std::fs::read_dir(run.join("logs"))
        .map(|r| {
            r.flatten()
                .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
                .collect()
        })
        .unwrap_or_default();
    assert!(done, "the jobs did not finish in {limit:?}; logs:\n{logs}");
    let script = std::fs::read_to_string(run.join("slurm/array.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=0-3"), "{script}");
    assert!(
        run.join("bench.json").is_file(),
        "no merged bench.json; logs:\n{logs}"
    );
    same_rows(&bench_json(&whole), &bench_json(&run));
    assert!(run.join("bench.csv").is_file() && run.join("report.html").is_file());
    let mut costs = Vec::new();
    for k in 0..4 {
        let j = bench_json(&run.join(format!("shard-{k}")));
        costs.push(j["shard"]["estimated_cost_s"][k].as_f64().unwrap());
        let wall = j["wall_s"].as_f64().unwrap();
        let refs = &j["shard"]["reference_frames"];
        eprintln!(
            "shard {k}: wall {wall:.1} s, estimated {:.1} s, reference frames {refs}",
            costs[k]
        );
    }
    let (lo, hi) = costs
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), c| (l.min(*c), h.max(*c)));
    eprintln!(
        "unsharded {whole_s:.1} s; 4-task Slurm array, merge and report {slurm_s:.1} s ({:.2}x); shard estimates within {:.2}x",
        slurm_s / whole_s,
        hi / lo
    );
    if study.is_some() {
        eprintln!("kept for a look: {}", d.keep().display());
    }
    let pids: Vec<i32> = slurm.pids.iter().filter_map(|p| pid_of(p)).collect();
    assert_eq!(pids.len(), 3, "three daemons started");
    drop(slurm);
    assert!(
        pids.iter().all(|p| !alive(*p)),
        "a daemon is still running: {pids:?}"
    );
}
