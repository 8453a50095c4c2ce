#!/usr/bin/env python3
"""The equal-budget comparison of docs/upsampling.md (issue 55): checkerboard against temporal
upsampling and spatial upscaling at the same shading budget.

Per scene one `cbr bench` against `ssaa:16` (cached in $CBR_CACHE_DIR): the moving demo,
Šibenik and foliage (their still and moving cameras) and the moving hard cases, rows ROWS (plus
the taau ablations on the demo); per scene the `cbr montage` strip (reference and each row around
the worst crop, over their FLIP maps) and the report's speed-against-error chart (`cbr report`,
its SVG); one cost run at 1280x720 without a reference (GPU time per pass). Writes the generated
part of docs/upsampling.md (between its markers) and docs/images/upsampling/; `--reuse` reads
finished runs.

    python3 scripts/bench-upsampling.py --cbr ./target/release/cbr -o out/bench/upsampling
"""
import argparse
import json
import os
import re
import subprocess
import sys

from strips import worst_crop_strip

ROWS = [
    "native", "native+taa", "checkerboard:rotated:ours", "checkerboard:rotated:ours+taa",
    "checkerboard:rotated:fused", "taau", "taau:0.5", "taau:0.77", "upscale:fsr1",
    "upscale:bilinear",
]
ABLATIONS = ["taau:without-locks", "taau:without-depth-clip", "taau:without-ids",
             "taau:without-reactive", "taau:without-rcas", "taau:without-stability",
             "taau:without-surface-velocity", "taau:lobes=2", "taau:bilinear", "taau:catmull",
             "taau:sharpness=0.2", "taau:lod=-1"]
# Scene, label, warm-up, measured frames. Warm-up 8: every history has had time to fill (taau's
# jitter has 16 phases at 1/sqrt(2); its history weight saturates in about 8 frames of motion).
SCENES = [
    ("builtin:demo", "demo (moving)", 8, 4),
    ("scenes/sibenik.toml", "Šibenik (still camera)", 8, 2),
    ("scenes/sibenik-moving.toml", "Šibenik (moving)", 8, 2),
    ("scenes/foliage.toml", "foliage (still camera)", 8, 2),
    ("scenes/foliage-moving.toml", "foliage (moving)", 8, 2),
]
# The gallery's cases with motion (camera or objects); `cut` is measured after its cut.
CASES = ["wires", "horizon", "foliage", "spinner", "texture", "slivers", "far", "specular",
         "thin-motion", "firefly", "zfight", "cut"]
CASE_FRAMES = {"cut": (8, 2)}
CROP, SCALE = 64, 3
CHECKERBOARD = [r for r in ROWS if r.startswith("checkerboard")]


def run(cmd):
    print("[upsampling]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)


def f(v, d=4):
    return "–" if v is None else f"{v:.{d}f}"


def med(s):
    return (s or {}).get("median")


def shaded(r):
    """Fragments shaded per frame (median, every raster pass of the row)."""
    v = r.get("fragment_invocations_median") or {}
    return sum(v.values()) if v else None


def bench(a, scene, out, rows, warmup, frames):
    done = os.path.join(out, "bench.json")
    if not (a.reuse and os.path.exists(done)):
        run([a.cbr, "bench", scene, "--width", str(a.width), "--height", str(a.height),
             "--warmup", str(warmup), "--frames", str(frames), "--reference", "ssaa:16",
             "--techniques", ",".join(rows), "-o", out])
    return json.load(open(done))


def strip(a, b, out, img_dir, name):
    rows = b["rows"]
    ref = next(r for r in rows if r.get("error") is None)
    techs = [r for r in rows if r.get("error") is not None and r["spec"] in ROWS]
    png = os.path.join(img_dir, f"{name}.png")
    x, y = worst_crop_strip(a.cbr, out, ref, techs, (a.width, a.height), CROP, SCALE, png,
                            "upsampling")
    return (f"![{name} strip](images/upsampling/{name}.png)\n\nLeft to right: `{ref['spec']}` "
            "(the reference), " + ", ".join(f"`{r['spec']}`" for r in techs)
            + f"; below each, its FLIP map against `{ref['spec']}`. Window {CROP}x{CROP} at "
            f"({x}, {y}) around the reference's worst crop, enlarged {SCALE}x; frame "
            f"{ref['images']['frame']}.")


def chart(a, out, img_dir, name):
    """The report's speed-against-error chart of this run, as an SVG file."""
    html = os.path.join(a.out, f"report-{name}.html")
    run([a.cbr, "report", out, "-o", html])
    text = open(html, encoding="utf-8").read()
    m = re.search(r'<svg class="chart".*?</svg>', text, re.S)
    if not m:
        return ""
    svg = m.group(0).replace("<svg ", '<svg xmlns="http://www.w3.org/2000/svg" ', 1)
    with open(os.path.join(img_dir, f"{name}-chart.svg"), "w", encoding="utf-8") as fh:
        fh.write(svg)
    return (f"![{name}: frame time against FLIP](images/upsampling/{name}-chart.svg)\n\n"
            f"The report's chart (`cbr report {out}`): median frame time against mean FLIP "
            "against `ssaa:16`, 320x180, lavapipe.")


def table(b, specs, native):
    lines = ["| configuration | FLIP | edge FLIP | disocclusion FLIP | flicker | shaded fragments "
             "(/ native) | frame ms (/ native) |", "|---|---|---|---|---|---|---|"]
    rows = {r["spec"]: r for r in b["rows"] if r.get("error") is not None}
    best = min(rows[s]["error"]["flip_mean"] for s in specs if s in rows)
    n_sh, n_ms = shaded(native), med(native["frame_ms"])
    for s in specs:
        if s not in rows:
            continue
        r = rows[s]
        e = r["error"]
        sh, ms = shaded(r), med(r["frame_ms"])
        mark = "**" if e["flip_mean"] == best else ""
        lines.append(
            f"| `{s}` | {mark}{f(e['flip_mean'])}{mark} | {f(e.get('flip_edge_mean'))} | "
            f"{f(e.get('flip_disocc_mean'))} | {f(e.get('flicker_mean'))} | "
            f"{int(sh) if sh is not None else '–'} ({f(sh / n_sh if sh and n_sh else None, 2)}) | "
            f"{f(ms, 1)} ({f(ms / n_ms if ms and n_ms else None, 2)}) |")
    return "\n".join(lines)


def verdict(b):
    """Best checkerboard row against taau at 1/sqrt(2) (equal shaded pixels)."""
    rows = {r["spec"]: r["error"]["flip_mean"] for r in b["rows"] if r.get("error") is not None}
    cb = min((rows[s], s) for s in CHECKERBOARD if s in rows)
    t = rows.get("taau")
    if t is None:
        return None
    win = "checkerboard" if cb[0] < t else "taau"
    return cb, t, win, rows.get("native")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cbr", default="./target/release/cbr")
    ap.add_argument("-o", "--out", default="out/bench/upsampling")
    ap.add_argument("--docs", default="docs")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--scenes", default=",".join(s[0] for s in SCENES))
    ap.add_argument("--cost-frames", type=int, default=8)
    ap.add_argument("--no-cost", action="store_true", help="skip the 1280x720 cost run")
    ap.add_argument("--reuse", action="store_true", help="read finished bench runs")
    a = ap.parse_args()
    img_dir = os.path.join(a.docs, "images", "upsampling")
    os.makedirs(img_dir, exist_ok=True)
    os.makedirs(a.out, exist_ok=True)
    keep = a.scenes.split(",")
    work = [(s, label, wu, n, re.sub(r"[^a-z0-9-]", "", os.path.basename(s).split(".")[0]
                                      .replace("builtin:", "")))
            for s, label, wu, n in SCENES if s in keep]
    work += [(f"builtin:{c}", f"hard case `{c}`", *CASE_FRAMES.get(c, (4, 2)), f"case-{c}")
             for c in a.cases.split(",") if c]
    sections, verdicts, goals, device = [], [], [], None
    for scene, label, wu, n, name in work:
        rows = ROWS + (ABLATIONS if scene == "builtin:demo" else [])
        out = os.path.join(a.out, name)
        b = bench(a, scene, out, rows, wu, n)
        device = b["device"]["name"]
        native = next(r for r in b["rows"] if r["spec"] == "native")
        measured = [p["frame"] for p in native["error"]["per_frame"]]
        text = [f"### {label} (`{scene}`)", "",
                f"{a.width}x{a.height}, {wu} warm-up + {n} measured frames {measured}, errors "
                f"against `ssaa:16`; flicker: mean |e_t - e_t-1| of the display error; frame "
                f"time: median GPU time at this size on {device} (noisy at 320x180; the cost "
                "run below is the one to read).", "", table(b, ROWS, native), ""]
        if scene == "builtin:demo":
            text += ["Ablations (taau's switches, same run):", "",
                     table(b, ["taau"] + ABLATIONS, native), ""]
        text += [strip(a, b, out, img_dir, name), "", chart(a, out, img_dir, name), ""]
        sections.append("\n".join(text))
        v = verdict(b)
        if v:
            (cbf, cbs), t, win, nat = v
            verdicts.append(f"| {label} | `{cbs}` {f(cbf)} | {f(t)} | {f(nat)} | {win} "
                            f"({f(abs(cbf - t) / max(cbf, t) * 100, 1)}% lower FLIP) |")
            if scene in ("builtin:demo", "scenes/sibenik.toml", "scenes/sibenik-moving.toml",
                         "scenes/foliage.toml", "scenes/foliage-moving.toml"):
                goals.append(f"| {label} | {f(t)} | {f(nat)} | {f(t / nat, 2)} | "
                             f"{'holds' if t <= nat else 'misses'} |")
    cost = ""
    if not a.no_cost:
        out = os.path.join(a.out, "cost-1280x720")
        done = os.path.join(out, "bench.json")
        specs = ["native", "taau", "taau:0.5", "taau:0.77", "upscale:fsr1",
                 "checkerboard:rotated:ours", "native+taa"]
        if not (a.reuse and os.path.exists(done)):
            run([a.cbr, "bench", "builtin:demo", "--width", "1280", "--height", "720",
                 "--warmup", "2", "--frames", str(a.cost_frames), "--timing-only",
                 "--techniques", ",".join(specs), "-o", out])
        b = json.load(open(done))
        nat = med(next(r for r in b["rows"] if r["spec"] == "native")["frame_ms"])
        lines = ["| configuration | frame ms (/ native) | its own passes after the raster, ms "
                 "(/ native's frame) |", "|---|---|---|"]
        for r in b["rows"]:
            ps = r.get("passes") or {}
            own = {k: med(v) for k, v in ps.items()
                   if not k.endswith("raster") and k != "readback"}
            tot = sum(v for v in own.values() if v)
            detail = ", ".join(f"`{k}` {f(v, 1)}" for k, v in sorted(own.items()))
            lines.append(f"| `{r['spec']}` | {f(med(r['frame_ms']), 1)} "
                         f"({f(med(r['frame_ms']) / nat, 2)}) | {f(tot, 1)} ({f(tot / nat, 3)})"
                         f"{': ' + detail if detail else ''} |")
        cost = ("## Cost (1280x720, demo, lavapipe)\n\n`" + " ".join(
            ["cbr", "bench", "builtin:demo", "--width", "1280", "--height", "720", "--warmup",
             "2", "--frames", str(a.cost_frames), "--timing-only", "--techniques",
             ",".join(specs)]) + "`: medians of the measured frames, one run.\n\n"
            + "\n".join(lines))
    gen = ["<!-- upsampling:begin (written by scripts/bench-upsampling.py) -->",
           "## Checkerboard against temporal upsampling at equal shading (verdict)", "",
           "Per scene the best checkerboard row (`checkerboard:rotated:ours`, `+taa` or `fused`) "
           "against `taau` at 1/sqrt(2) per axis (the same pixel count), FLIP against "
           "`ssaa:16`:", "",
           "| scene | best checkerboard | `taau` | `native` | lower FLIP |", "|---|---|---|---|---|",
           *verdicts, "", "## Goal: `taau` at most `native`'s FLIP", "",
           "| scene | `taau` | `native` | ratio | goal |", "|---|---|---|---|---|", *goals, "",
           cost, "", "## Per scene", "", "\n\n".join(sections),
           "<!-- upsampling:end -->"]
    gen = "\n".join(gen)
    doc = os.path.join(a.docs, "upsampling.md")
    text = open(doc, encoding="utf-8").read() if os.path.exists(doc) else "# Upsampling\n\n"
    begin, end = text.find("<!-- upsampling:begin"), text.find("<!-- upsampling:end -->")
    if begin >= 0 and end > begin:
        text = text[:begin] + gen + text[end + len("<!-- upsampling:end -->"):]
    else:
        text = text.rstrip("\n") + "\n\n" + gen + "\n"
    with open(doc + ".tmp", "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(doc + ".tmp", doc)
    print(f"[upsampling] {doc}; images in {img_dir}", file=sys.stderr)


if __name__ == "__main__":
    main()
