#!/usr/bin/env python3
"""Checkerboard layouts against native (issue 4): raster GPU time, fragment and vertex invocations,
target memory, each as a ratio to native from the same run, per scene and resolution.

    scripts/bench-layouts.py [--cbr ./target/release/cbr] [--frames 8] [--warmup 2] [-o out/bench/layouts]

Medians over the measured frames (after --warmup); timings are GPU timestamps of the raster pass.
Writes layouts.md and layouts.json into the output folder."""
import argparse
import json
import os
import statistics
import subprocess
import sys

SCENES = [("demo", "builtin:demo"), ("sibenik", "scenes/sibenik.toml")]
SIZES = [(1280, 720), (1920, 1080)]
LAYOUTS = ["masked", "split", "rotated", "msaa2x"]


def run(cbr, scene, w, h, frames, technique, layout, out):
    args = [cbr, "render", scene, "--width", str(w), "--height", str(h), "--frames", str(frames), "-o", out, "--technique", technique]
    if technique == "checkerboard":
        args += ["--layout", layout, "--resolve", "none"]
    p = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "failed"
    return json.load(open(os.path.join(out, "run.json"))), None


def summarize(run_json, warmup):
    frames = run_json["frames"][warmup:]
    raster = [next(x for x in f["passes"] if x["name"].endswith(".raster")) for f in frames]
    med = lambda xs: statistics.median(xs)
    stat = lambda k: med([r["stats"][k] for r in raster]) if raster[0]["stats"] else None
    return {
        "raster_ms": med([r["gpu_ms"] for r in raster]),
        "fragment_invocations": stat("fragment_invocations"),
        "vertex_invocations": stat("vertex_invocations"),
        "target_bytes": run_json["settings"]["target_bytes"],
        "device": run_json["device"]["name"],
        "driver": run_json["device"]["driver_info"],
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cbr", default="./target/release/cbr")
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("-o", "--out", default="out/bench/layouts")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows, notes = [], []
    for name, scene in SCENES:
        for w, h in SIZES:
            base, err = run(a.cbr, scene, w, h, a.frames, "native", "", os.path.join(a.out, f"{name}-{w}x{h}-native"))
            if base is None:
                sys.exit(f"native {name} {w}x{h}: {err}")
            nat = summarize(base, a.warmup)
            rows.append({"scene": name, "size": f"{w}x{h}", "technique": "native", **nat})
            for layout in LAYOUTS:
                r, err = run(a.cbr, scene, w, h, a.frames, "checkerboard", layout, os.path.join(a.out, f"{name}-{w}x{h}-{layout}"))
                if r is None:
                    notes.append(f"{layout} on {name} {w}x{h}: {err}")
                    continue
                s = summarize(r, a.warmup)
                rows.append({"scene": name, "size": f"{w}x{h}", "technique": layout, **s,
                             "ratios": {k: (s[k] / nat[k] if s[k] is not None and nat[k] else None) for k in ["raster_ms", "fragment_invocations", "vertex_invocations", "target_bytes"]}})
            print(f"[bench-layouts] {name} {w}x{h} done", file=sys.stderr)
    json.dump({"rows": rows, "notes": notes, "frames": a.frames, "warmup": a.warmup}, open(os.path.join(a.out, "layouts.json"), "w"), indent=1)
    lines = [f"Device: {rows[0]['device']} ({rows[0]['driver']}); medians of frames {a.warmup}..{a.frames - 1}.", "",
             "| scene | size | technique | raster ms | x native | fragment inv. | x native | vertex inv. | x native | target MiB | x native |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    fmt = lambda v, f="{:.2f}": "-" if v is None else f.format(v)
    for r in rows:
        q = r.get("ratios", {})
        lines.append(f"| {r['scene']} | {r['size']} | {r['technique']} | {r['raster_ms']:.1f} | {fmt(q.get('raster_ms'))} | {fmt(r['fragment_invocations'], '{:.0f}')} | {fmt(q.get('fragment_invocations'))} | {fmt(r['vertex_invocations'], '{:.0f}')} | {fmt(q.get('vertex_invocations'))} | {r['target_bytes'] / 1048576:.1f} | {fmt(q.get('target_bytes'))} |")
    for n in notes:
        lines.append(f"\nNot run: {n}")
    open(os.path.join(a.out, "layouts.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
