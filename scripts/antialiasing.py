#!/usr/bin/env python3
"""The anti-aliasing tables of docs/antialiasing.md: every technique's error against `native` and
against `ssaa:16` (whole frame and edge pixels) beside its cost, per scene, from two `cbr bench`
runs per scene (reference ssaa:16, then reference native; the second reads the first's cached
ssaa:16 frames, so the ssaa:16 cost comes from the first). Rewrites the block between the
results markers of docs/antialiasing.md.

    python3 scripts/antialiasing.py --cbr ./target/release/cbr -o out/bench/aa
"""
import argparse
import json
import os
import re
import subprocess
import sys

TECHNIQUES = ["native", "ssaa:4", "msaa:4", "msaa:4:sample", "msaa:4:hdr",
              "checkerboard:rotated:ours", "checkerboard:split:pq4k", "upscale:bilinear",
              "ssaa:16"]
SCENES = ["builtin:demo", "scenes/sibenik.toml", "scenes/foliage.toml"]
# Measured frames per scene where --frames is too many: Šibenik's ssaa:16 frames take ~5 min
# each on lavapipe at 320x180 (64 point lights, mip 0 of large textures at LOD bias -4).
FRAMES = {"scenes/sibenik.toml": 3}


def bench(cbr, scene, out, reference, a, env):
    done = os.path.join(out, "bench.json")
    if a.reuse and os.path.exists(done):
        print(f"[aa] reusing {done}", file=sys.stderr)
        return json.load(open(done))
    techs = [t for t in TECHNIQUES if t != reference]
    frames = FRAMES.get(scene, a.frames)
    cmd = [cbr, "bench", scene, "--width", str(a.width), "--height", str(a.height),
           "--warmup", str(a.warmup), "--frames", str(frames), "--reference", reference,
           "--techniques", ",".join(techs), "-o", out]
    print("[aa]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True, env=env)
    return json.load(open(os.path.join(out, "bench.json")))


def f(v, d):
    return "–" if v is None else f"{v:.{d}f}"


def table(vs_ssaa, vs_native):
    rows_n = {r["config"]: r for r in vs_native["rows"]}
    # Costs from the ssaa:16 run only: ratios within one run.
    native_ms = next(r for r in vs_ssaa["rows"] if r["config"] == "native")["frame_ms"]["median"]
    out = ["| technique | frame ms (median) | x native | FLIP vs native | edge FLIP vs native "
           "| FLIP vs ssaa:16 | edge FLIP vs ssaa:16 | PSNR vs ssaa:16 |",
           "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in vs_ssaa["rows"]:
        c = r["config"]
        n = rows_n.get(c, {})
        ms = r["frame_ms"]["median"] if r["frame_ms"] else None
        e_s = r["error"] or {}
        e_n = n.get("error") or {}
        out.append(f"| `{c}` | {f(ms, 1)} | {f(ms / native_ms if ms else None, 2)} | "
                   f"{f(e_n.get('flip_mean'), 4) if c != 'native' else 'reference'} | "
                   f"{f(e_n.get('flip_edge_mean'), 4) if c != 'native' else '–'} | "
                   f"{f(e_s.get('flip_mean'), 4) if c != 'ssaa:16' else 'reference'} | "
                   f"{f(e_s.get('flip_edge_mean'), 4) if c != 'ssaa:16' else '–'} | "
                   f"{f(e_s.get('psnr_mean'), 2) if c != 'ssaa:16' else '–'} |")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cbr", default="./target/release/cbr")
    ap.add_argument("-o", "--out", default="out/bench/aa")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--doc", default="docs/antialiasing.md")
    ap.add_argument("--reuse", action="store_true",
                    help="keep bench runs whose bench.json exists (resume an interrupted run)")
    a = ap.parse_args()
    env = dict(os.environ, CBR_CACHE_DIR=os.path.join(a.out, "cache"))
    lines = [f"Written by `just bench` (scripts/antialiasing.py); do not edit by hand. "
             f"{a.width}x{a.height}, {a.warmup} warm-up + {a.frames} measured frames of each "
             f"scene's camera path (fewer where a table says so); FLIP = mean LDR-FLIP over the measured frames; edge = mean "
             f"over the reference's edge pixels (ssaa:16: more than one object ID among the "
             f"pixel's 256 samples; native: an object ID that differs from a 4-neighbour's); "
             f"frame ms = GPU time of the technique's passes (lavapipe: ratios travel, "
             f"absolute times do not).", ""]
    for scene in SCENES:
        if scene.startswith("scenes/") and not os.path.isdir("../shared/scenes"):
            print(f"[aa] SKIPPED {scene}: ../shared/scenes is absent", file=sys.stderr)
            continue
        name = os.path.basename(scene).replace(".toml", "").replace("builtin:", "")
        s = bench(a.cbr, scene, os.path.join(a.out, name, "vs-ssaa16"), "ssaa:16", a, env)
        n = bench(a.cbr, scene, os.path.join(a.out, name, "vs-native"), "native", a, env)
        rows = {r["config"]: r for r in s["rows"]}
        ssaa_ms = rows["ssaa:16"]["frame_ms"]["median"]
        native_ms = rows["native"]["frame_ms"]["median"]
        cached = rows["ssaa:16"].get("cached_frames", 0)
        lines += [f"### {s['scene']['name']} ({s['scene']['source']})", "",
                  f"Device {s['device']['name']} ({s['device']['driver_info']}); git "
                  f"{s['git_commit']}; {s['protocol']['measured_frames']} measured frames. "
                  f"ssaa:16 / (256 x native) = {ssaa_ms / (256 * native_ms):.3f} "
                  f"(target <= 1.1), same run"
                  + (f" (ssaa:16 timed on {rows['ssaa:16']['frame_ms']['n']} frame(s); "
                     f"{cached} came from the cache, untimed)" if cached else "") + ".", ""]
        lines += table(s, n) + [""]
    doc = open(a.doc).read()
    block = "<!-- results:begin -->\n" + "\n".join(lines) + "\n<!-- results:end -->"
    doc = re.sub(r"<!-- results:begin -->.*<!-- results:end -->", lambda _: block, doc,
                 flags=re.S)
    open(a.doc, "w").write(doc)
    print(f"[aa] {a.doc} updated", file=sys.stderr)


if __name__ == "__main__":
    main()
