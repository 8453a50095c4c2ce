//! Bad input to every command (render, bench and its sweep file, compare, report, info): one
//! clear error naming the file and line or the option, exit status 1 (`compare`: 2, its error
//! status), no panic, and nothing written. Renders that cannot fit the device are refused with
//! the estimate and the device's limit before anything is allocated. More cases: cli.rs,
//! compare_cli.rs.

mod common;
use common::{cbr, s};

use std::path::{Path, PathBuf};
use std::process::Output;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

/// Checks a clean failure: `status`, one `error:` line first (clap adds a usage hint after its
/// own), no panic, every string of `expect` in the message. Problems are collected, so that one
/// run lists every case that fails.
#[derive(Default)]
struct Cases(Vec<String>);

impl Cases {
    fn fails(&mut self, o: &Output, status: i32, expect: &[&str]) {
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        let mut why = Vec::new();
        if o.status.code() != Some(status) {
            why.push(format!("exit status {:?}, not {status}", o.status.code()));
        }
        if err.contains("panicked") {
            why.push("a panic".into());
        }
        if !err.starts_with("error: ") || err.matches("error:").count() != 1 {
            why.push("not one `error:` first".into());
        }
        for e in expect {
            if !err.contains(e) {
                why.push(format!("no `{e}`"));
            }
        }
        if !why.is_empty() {
            self.0
                .push(format!("{expect:?}: {}\n{err}", why.join(", ")));
        }
    }

    fn check(&mut self, ok: bool, what: &str) {
        if !ok {
            self.0.push(what.to_string());
        }
    }
}

impl Drop for Cases {
    fn drop(&mut self) {
        if !self.0.is_empty() && !std::thread::panicking() {
            panic!(
                "{} case(s) failed:\n{}",
                self.0.len(),
                self.0.join("\n---\n")
            );
        }
    }
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n";

#[test]
fn render_refuses_bad_options_and_degenerate_cameras() {
    let mut c = Cases::default();
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("out");
    // Small, so that a case that wrongly succeeds costs little.
    let o = |extra: &[&str]| {
        let mut args = vec!["render", "builtin:demo", "-o", s(&out)];
        args.extend_from_slice(extra);
        if !extra.contains(&"--width") {
            args.extend_from_slice(&["--width", "16", "--height", "16", "--frames", "1"]);
        }
        cbr(&args, &[])
    };
    c.fails(&o(&["--width", "abc"]), 1, &["'abc'", "--width"]);
    c.fails(
        &o(&["--exposure", "nan"]),
        1,
        &["--exposure", "not a finite number"],
    );
    c.fails(
        &o(&["--lod-bias", "inf"]),
        1,
        &["--lod-bias", "not a finite number"],
    );
    c.fails(
        &o(&["--technique", "checkerboard", "--depth-tolerance", "NaN"]),
        1,
        &["--depth-tolerance", "not a finite number"],
    );
    c.fails(&o(&["--technique", "bogus"]), 1, &["bogus"]);
    c.fails(&o(&["--no-such-flag"]), 1, &["--no-such-flag"]);
    c.check(!out.exists(), "render: nothing written");

    let obj = write(d.path(), "t.obj", TRI);
    let key = |k: &str| {
        format!(
            "obj = \"t.obj\"\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [0, 0, 2]\ntarget = [0, 0, 0]\n{k}"
        )
    };
    let cases: &[(&str, String, &[&str])] = &[
        ("fov180.toml", key("fov_y_deg = 180\n"), &["fov180.toml:7:", "`camera.keys[0].fov_y_deg`", "180 degrees"]),
        ("fov0.toml", key("fov_y_deg = 0\n"), &["fov0.toml:7:", "0 degrees"]),
        ("fovneg.toml", key("fov_y_deg = -20\n"), &["fovneg.toml:7:", "-20 degrees"]),
        (
            "same.toml",
            "obj = \"t.obj\"\n[camera]\n[[camera.keys]]\ntime = 0\nposition = [1, 2, 3]\ntarget = [1, 2, 3]\n".into(),
            &["same.toml:6:", "`camera.keys[0].target`", "looks nowhere"],
        ),
        (
            "camfov.toml",
            "obj = \"t.obj\"\n[camera]\nfov_y_deg = 180.0\n".into(),
            &["camfov.toml:3:", "`camera.fov_y_deg`"],
        ),
        ("nan.toml", "obj = \"t.obj\"\nexposure = nan\n".into(), &["nan.toml:2:", "`exposure`", "not a finite number"]),
        (
            "lights.toml",
            "obj = \"t.obj\"\n[lights.random_points]\ncount = 4000000000\n".into(),
            &["lights.toml:3:", "at most 1048576"],
        ),
    ];
    for (name, text, expect) in cases {
        let p = write(d.path(), name, text);
        c.fails(&cbr(&["render", s(&p), "-o", s(&out)], &[]), 1, expect);
        c.check(!out.exists(), &format!("{name}: nothing written"));
        let _ = std::fs::remove_dir_all(&out);
    }
    drop(obj);

    // Textures: the path once, and a directory said to be one.
    std::fs::create_dir(d.path().join("maps")).expect("mkdir");
    write(d.path(), "bad.png", "\u{89}PNG not really");
    for (tex, expect) in [
        ("maps", "is a directory"),
        ("bad.png", "cannot decode texture"),
    ] {
        write(d.path(), "m.mtl", &format!("newmtl m\nmap_Kd {tex}\n"));
        let p = write(d.path(), "m.obj", &format!("mtllib m.mtl\nusemtl m\n{TRI}"));
        let o = cbr(&["render", s(&p), "-o", s(&out)], &[]);
        c.fails(&o, 1, &[expect]);
        let err = String::from_utf8_lossy(&o.stderr);
        c.check(
            err.matches(tex).count() == 1,
            &format!("the texture named once:\n{err}"),
        );
        c.check(!out.exists(), &format!("{tex}: nothing written"));
        let _ = std::fs::remove_dir_all(&out);
    }

    // An output path that is a file.
    let file = write(d.path(), "afile", "x");
    c.fails(
        &cbr(
            &[
                "render",
                "builtin:demo",
                "-o",
                s(&file),
                "--width",
                "8",
                "--height",
                "8",
                "--frames",
                "1",
            ],
            &[],
        ),
        1,
        &["afile"],
    );
}

#[test]
fn bench_refuses_bad_options_and_sweep_files_naming_the_line() {
    let mut c = Cases::default();
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("out");
    let bench = |extra: &[&str]| {
        let mut args = vec!["bench", "builtin:demo", "-o", s(&out)];
        args.extend_from_slice(extra);
        cbr(&args, &[])
    };
    let cases: &[(&[&str], &[&str])] = &[
        (&["--techniques", "native,bogus"], &["--techniques `bogus`"]),
        (&["--reference", "ssaa:x"], &["--reference `ssaa:x`"]),
        (&["--resolutions", "64x36,10"], &["--resolutions", "`10`"]),
        (&["--resolutions", "0x36"], &["--resolutions", "0x36"]),
        (&["--groups", "12"], &["--groups 12"]),
        (&["--mappings", "diagonal"], &["--mappings `diagonal`"]),
        (
            &["--lod-biases", "0,nan"],
            &["--lod-biases", "not a finite number"],
        ),
        (&["--frames", "0"], &["--frames must be at least 1"]),
        (&["--disocclusion-frames", "0"], &["--disocclusion-frames"]),
        (&["--crop", "1,2,3"], &["--crop 1,2,3"]),
        // Found before anything is rendered (cbr-bench itself finds out after measuring).
        (
            &["--width", "32", "--height", "18", "--crop", "0,0,40,10"],
            &["--crop 0,0,40,10 does not fit in 32x18"],
        ),
        (
            &["--sweep", "/nonexistent/sweep.toml"],
            &["/nonexistent/sweep.toml", "cannot read"],
        ),
    ];
    for (extra, expect) in cases {
        c.fails(&bench(extra), 1, expect);
        c.check(!out.exists(), &format!("{extra:?}: nothing written"));
        let _ = std::fs::remove_dir_all(&out);
    }
    let sweeps: &[(&str, &str, &[&str])] = &[
        (
            "syntax.toml",
            "frames = 3\ngroups = [8,\n",
            &["syntax.toml:2:"],
        ),
        (
            "unknown.toml",
            "frames = 3\nframe_count = 2\n",
            &["unknown.toml:2:", "frame_count"],
        ),
        (
            "type.toml",
            "frames = 3\ngroups = \"eight\"\n",
            &["type.toml:2:", "`groups`"],
        ),
        (
            "group.toml",
            "groups = [8,\n  12]\n",
            &["group.toml:2:", "`groups[1]`", "12"],
        ),
        (
            "res.toml",
            "resolutions = [\"64x36\", \"64by36\"]\n",
            &["res.toml:1:", "`resolutions[1]`", "64by36"],
        ),
        (
            "map.toml",
            "\nmappings = [\"quad\", \"tile\"]\n",
            &["map.toml:2:", "`mappings[1]`", "tile"],
        ),
        (
            "tech.toml",
            "techniques = [\"native\",\n\"upscale:nope\"]\n",
            &["tech.toml:2:", "`techniques[1]`"],
        ),
        (
            "frames.toml",
            "frames = 0\n",
            &["frames.toml:1:", "`frames`", "at least 1"],
        ),
        (
            "ref.toml",
            "reference = \"bogus\"\n",
            &["ref.toml:1:", "`reference`"],
        ),
        (
            "lod.toml",
            "lod_biases = [0.0, -inf]\n",
            &["lod.toml:1:", "`lod_biases[1]`", "not a finite number"],
        ),
    ];
    for (name, text, expect) in sweeps {
        let p = write(d.path(), name, text);
        c.fails(
            &cbr(
                &["bench", "builtin:demo", "-o", s(&out), "--sweep", s(&p)],
                &[],
            ),
            1,
            expect,
        );
        c.check(!out.exists(), &format!("{name}: nothing written"));
        let _ = std::fs::remove_dir_all(&out);
    }
}

#[test]
fn render_and_bench_refuse_what_cannot_fit_before_allocating() {
    let mut c = Cases::default();
    let d = tempfile::tempdir().expect("tempdir");
    let out = d.path().join("out");
    // The test device's limits decide the sizes and which limit is named (lavapipe: a 2 GiB heap
    // and 2 GiB per allocation: 16384, 16384 and 5000; the H100 of the GPU study, 80 GiB and 4 GiB
    // an allocation: 16384, 24576 and 12288 by this check with its limits); the limit is named,
    // with the estimate, before anything is allocated or written.
    let gpu = cbr_gpu::Gpu::new(&cbr_gpu::GpuOptions {
        device: None,
        validation: false,
    })
    .expect("device");
    // The first side at which `spec` is refused (and, with `native_fits`, native is not).
    let refused = |spec: &str, sides: &[u32], native_fits: bool| -> Option<String> {
        sides
            .iter()
            .find(|&&n| !fits(&gpu, spec, n) && (!native_fits || fits(&gpu, "native", n)))
            .map(|n| n.to_string())
    };
    // On lavapipe every case must run (its 2 GiB heap refuses all three); elsewhere a device too
    // large for every side is a skip, said as such.
    let lavapipe = gpu.info().driver_name == "llvmpipe";
    let skip = |what: &str| {
        assert!(!lavapipe, "{what}: lavapipe must refuse one of the sizes");
        println!("SKIPPED: {what}: no size up to the device's largest image is refused there");
    };
    let limit = |c: &mut Cases, o: &Output| {
        let err = String::from_utf8_lossy(&o.stderr);
        c.check(
            ["device-local heap is", "(maxMemoryAllocationSize)"]
                .iter()
                .any(|l| err.contains(l)),
            &format!("no device limit named:\n{err}"),
        );
    };
    let started = std::time::Instant::now();
    let Some(n) = refused("ssaa:16", &[16384, 24576, 32768], false) else {
        return skip("`ssaa:16`");
    };
    let o = cbr(
        &[
            "render",
            "builtin:demo",
            "--width",
            &n,
            "--height",
            &n,
            "--frames",
            "1",
            "--technique",
            "ssaa:16",
            "-o",
            s(&out),
        ],
        &[],
    );
    c.fails(
        &o,
        1,
        &[
            &format!("`ssaa:16` at {n}x{n} needs about "),
            " GiB of GPU memory",
            "the largest one `ssaa.accum` ",
            "Nothing was allocated",
        ],
    );
    limit(&mut c, &o);
    c.check(!out.exists(), "render: nothing written");

    // bench: the reference (native) is refused at this size before anything renders.
    let bench = |extra: &[&str]| {
        let mut args = vec!["bench", "builtin:demo", "--warmup", "0", "--frames", "1"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", s(&out)]);
        cbr(&args, &[])
    };
    match refused("native", &[16384, 24576, 32768], false) {
        Some(n) => {
            let o = bench(&["--width", &n, "--height", &n, "--techniques", "ssaa:16"]);
            c.fails(
                &o,
                1,
                &[
                    &format!("`native` at {n}x{n} needs about "),
                    "Nothing was allocated",
                ],
            );
            limit(&mut c, &o);
            c.check(!out.exists(), "bench: nothing written");
        }
        None => skip("`native` in bench"),
    }
    // A row that cannot fit where the reference can: refused before the reference renders.
    let Some(n) = refused("msaa:4", &[5000, 8192, 12288, 16384], true) else {
        return skip("`msaa:4` where native fits");
    };
    let o = bench(&["--width", &n, "--height", &n, "--techniques", "msaa:4"]);
    c.fails(
        &o,
        1,
        &[
            &format!("`msaa:4` at {n}x{n} needs about "),
            "Nothing was allocated",
        ],
    );
    limit(&mut c, &o);
    // The bench's own check, not a renderer set up after the reference rendered (whose error
    // says `setting up ...`).
    let err = String::from_utf8_lossy(&o.stderr);
    c.check(
        err.starts_with(&format!("error: `msaa:4` at {n}x{n}")),
        &format!("refused before the reference rendered:\n{err}"),
    );
    c.check(!out.exists(), "bench row: nothing written");
    let took = started.elapsed().as_secs();
    c.check(took < 60, &format!("refusals took {took} s"));
}

/// Whether `spec` at `side` x `side` on the demo fits `gpu` by the check `render` and `bench` make
/// before allocating (`cbr_render::memory::check`); sides beyond the device's largest image are
/// never taken (that is another refusal).
fn fits(gpu: &cbr_gpu::Gpu, spec: &str, side: u32) -> bool {
    if side > gpu.caps().max_image_dimension_2d {
        return true;
    }
    let mut scene = cbr_scene::builtin("demo").expect("demo");
    (scene.settings.width, scene.settings.height) = (side, side);
    let settings = cbr_render::RenderSettings::parse(side, side, spec).expect("spec");
    let e = cbr_render::Renderer::estimate(gpu.caps(), &scene, &settings).expect("estimate");
    cbr_render::memory::check(spec, side, side, &e, gpu.caps(), &gpu.info().name).is_ok()
}

#[test]
fn report_info_and_compare_refuse_bad_input() {
    let mut c = Cases::default();
    let d = tempfile::tempdir().expect("tempdir");
    let html = d.path().join("r.html");
    c.fails(&cbr(&["report", "-o", s(&html)], &[]), 1, &["at least one"]);
    c.fails(
        &cbr(
            &["report", s(&d.path().join("absent")), "-o", s(&html)],
            &[],
        ),
        1,
        &["absent", "bench.json", "cannot read"],
    );
    let b = d.path().join("b");
    std::fs::create_dir(&b).expect("mkdir");
    write(
        &b,
        "bench.json",
        "{\n  \"schema\": \"cbr.bench/1\",\n  \"rows\": [\n}\n",
    );
    c.fails(
        &cbr(&["report", s(&b), "-o", s(&html)], &[]),
        1,
        &["bench.json", "line 4"],
    );
    write(
        &b,
        "bench.json",
        "{\"schema\": \"cbr.bench/9\", \"rows\": []}",
    );
    c.fails(
        &cbr(&["report", s(&b), "-o", s(&html)], &[]),
        1,
        &["bench.json", "cbr.bench/9"],
    );
    c.fails(&cbr(&["report", "--bogus"], &[]), 1, &["--bogus"]);
    c.check(!html.exists(), "no report written");

    c.fails(
        &cbr(&["info", "--device", "no-such-device"], &[]),
        1,
        &["no-such-device"],
    );
    c.fails(&cbr(&["info", "--jsn"], &[]), 1, &["--jsn"]);

    // compare: 2 is its error status (1 means a threshold failed).
    let img = d.path().join("a.png");
    image::RgbImage::from_pixel(8, 8, image::Rgb([40, 90, 200]))
        .save(&img)
        .expect("png");
    let heat = d.path().join("heat.png");
    let cmp = |extra: &[&str]| {
        let mut args = vec!["compare", s(&img), s(&img), "--heatmap", s(&heat)];
        args.extend_from_slice(extra);
        cbr(&args, &[])
    };
    c.fails(
        &cmp(&["--exposure", "nan"]),
        2,
        &["--exposure", "not a finite number"],
    );
    c.fails(
        &cmp(&["--fail-above", "psnr=nan"]),
        2,
        &["psnr=nan", "not a finite number"],
    );
    c.fails(&cmp(&["--warmup", "x"]), 2, &["'x'", "--warmup"]);
    c.fails(
        &cbr(&["compare", s(&img), s(d.path())], &[]),
        2,
        &["not one of each"],
    );
    c.check(!heat.exists(), "no heatmap written");
}
