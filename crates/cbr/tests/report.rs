//! The HTML report in headless Chromium (Debian's `chromium`, installed by `./dev`): generated
//! from a small bench run, opened from file://, it must load every image, log no error, sort its
//! table, zoom all panels together, move the wipe slider, answer keys 1-9, F and R and read
//! pixel values (the page's own `#selftest` script drives it and reports JSON into the DOM), and
//! a screenshot after zooming must differ from one before.

use std::path::Path;
use std::process::Command;

fn cbr(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cbr"))
        .args(args)
        .output()
        .expect("run cbr")
}

fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser"].into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn headless(browser: &str, extra: &[&str], url: &str) -> std::process::Output {
    let profile = tempfile::tempdir().expect("profile dir");
    let dir = format!("--user-data-dir={}", profile.path().display());
    Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=8000",
            &dir,
        ])
        .args(extra)
        .arg(url)
        .output()
        .expect("run chromium")
}

fn selftest(browser: &str, html: &Path, hash: &str) -> serde_json::Value {
    let url = format!("file://{}#{hash}", html.display());
    let o = headless(browser, &["--dump-dom"], &url);
    let dom = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    // Console errors reach stderr as CONSOLE lines; the page also collects its own.
    for line in stderr.lines().filter(|l| l.contains("CONSOLE")) {
        assert!(
            !line.contains("Uncaught") && !line.contains(":ERROR:CONSOLE"),
            "console: {line}"
        );
    }
    let start = dom
        .rfind("<pre id=\"selftest\">")
        .expect("the self-test ran")
        + 19;
    let end = start + dom[start..].find("</pre>").expect("end of the self-test");
    let json = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&amp;", "&");
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("self-test JSON {e}: {json}"))
}

#[test]
fn report_opens_in_headless_chromium_and_responds() {
    let Some(browser) = chromium() else {
        eprintln!(
            "SKIPPED: chromium is not installed (./dev installs it: apt-get install chromium)"
        );
        return;
    };
    let d = tempfile::tempdir().expect("tempdir");
    let bench = d.path().join("bench");
    let o = cbr(&[
        "bench",
        "builtin:demo",
        "--techniques",
        "native,checkerboard:rotated:ours,checkerboard:split:pq4k,upscale:bilinear",
        "--width",
        "96",
        "--height",
        "54",
        "--warmup",
        "1",
        "--frames",
        "3",
        "-o",
        bench.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = d.path().join("report.html");
    let o = cbr(&[
        "report",
        bench.to_str().expect("utf8"),
        "-o",
        html.to_str().expect("utf8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&html).expect("html");
    assert!(
        !text.contains("http://") && !text.contains("https://"),
        "no network references"
    );

    let r = selftest(browser, &html, "selftest");
    println!("{r}");
    assert_eq!(r["errors"], serde_json::json!([]), "page errors: {r}");
    let c = &r["checks"];
    assert!(c["images"].as_u64().unwrap_or(0) >= 8, "{r}");
    assert_eq!(c["images_broken"], serde_json::json!([]), "{r}");
    for k in [
        "sort_ascending",
        "sort_descending",
        "zoom_changed",
        "zoom_synchronised",
        "slider_moves",
        "key_selects",
        "hold_to_flip",
        "readout",
        "readout_values",
        "reset",
    ] {
        assert_eq!(c[k], true, "{k}: {r}");
    }
    assert_eq!(
        c["sorted_rows"], 3,
        "three configurations have a FLIP value: {r}"
    );

    // Screenshots before and after the scripted zoom differ.
    let shot = |name: &str, hash: &str| {
        let png = d.path().join(name);
        let url = format!("file://{}{hash}", html.display());
        let arg = format!("--screenshot={}", png.display());
        let o = headless(browser, &[&arg, "--window-size=1200,1400"], &url);
        assert!(png.is_file(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&png).expect("screenshot").to_rgba8()
    };
    let plain = shot("plain.png", "");
    let zoomed = shot("zoomed.png", "#selftest-zoomed");
    assert_eq!(plain.dimensions(), zoomed.dimensions());
    let differing = plain
        .pixels()
        .zip(zoomed.pixels())
        .filter(|(a, b)| a != b)
        .count();
    println!("{differing} screenshot pixels changed by the zoom");
    assert!(differing > 1000, "zooming changed only {differing} pixels");
    // Not blank: the page shows more than a handful of colours.
    let mut colours: Vec<[u8; 4]> = plain.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 200, "{} colours", colours.len());

    // Bad input: a folder without bench.json.
    let o = cbr(&[
        "report",
        d.path().to_str().expect("utf8"),
        "-o",
        "/dev/null",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("bench.json"));
}
