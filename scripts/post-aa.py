#!/usr/bin/env python3
"""The temporal anti-aliasing study of docs/post-aa.md (issue 13's goals).

Quality: per scene, one `cbr bench` against `ssaa:16` on the scene's moving camera (320x180 by
default; 8 warm-up frames so the histories have converged, then N measured frames) of native, FXAA,
TAA (ours, INSIDE, each ablation), checkerboard + TAA chained and fused, msaa:4 + TAA and, when
registered, interlaced + TAA. Cost: one `cbr bench` at 1280x720 without a reference (GPU time per
pass, medians). Prints the markdown tables and the goal checks; `--reuse` reads finished runs.

    python3 scripts/post-aa.py --cbr ./target/release/cbr -o out/bench/post-aa
"""
import argparse
import json
import os
import subprocess
import sys

QUALITY = [
    "native", "native+fxaa", "native+taa", "native+taa:inside",
    "native+taa:without-dilation", "native+taa:without-clip", "native+taa:without-ids",
    "native+taa:without-depth", "native+taa:without-catmull",
    "native+taa:without-ids:without-depth", "native+taa:without-speed", "native+taa:filter",
    "checkerboard:rotated:ours", "checkerboard:rotated:ours+taa", "checkerboard:split:ours+taa",
    "checkerboard:rotated:ours:prepass+taa", "checkerboard:rotated:fused",
    "checkerboard:split:fused", "checkerboard:rotated:fused:prepass",
    "checkerboard:rotated:ours+taa:inside", "checkerboard:rotated:pq4k+taa",
    "checkerboard:split:pq4k+taa", "checkerboard:split:spatial+taa", "upscale:bicubic+taa",
    "msaa:4+taa", "interlaced", "interlaced+taa",
]
COST = ["native", "native+fxaa", "native+taa", "native+taa:inside",
        "checkerboard:rotated:ours", "checkerboard:rotated:ours+taa",
        "checkerboard:split:ours+taa", "checkerboard:rotated:fused", "checkerboard:split:fused",
        "checkerboard:split:pq4k+taa", "checkerboard:split:spatial+taa", "interlaced",
        "interlaced+taa", "checkerboard:rotated:ours:prepass+taa",
        "checkerboard:split:ours:prepass+taa"]
SCENES = {"builtin:demo": "demo", "scenes/sibenik.toml": "sibenik", "scenes/foliage.toml": "foliage"}


def run(cbr, scene, out, techs, a, reference=None, width=None, height=None, warmup=None,
        frames=None):
    done = os.path.join(out, "bench.json")
    if a.reuse and os.path.exists(done):
        print(f"[post-aa] reusing {done}", file=sys.stderr)
        return json.load(open(done))
    cmd = [cbr, "bench", scene, "--width", str(width), "--height", str(height),
           "--warmup", str(warmup), "--frames", str(frames), "--techniques", ",".join(techs),
           "-o", out]
    if reference:
        cmd += ["--reference", reference]
    print("[post-aa]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)
    return json.load(open(done))


def f(v, d=4):
    return "–" if v is None else f"{v:.{d}f}"


def err(r, k):
    e = r.get("error") or {}
    return e.get(k)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--cbr", default="./target/release/cbr")
    p.add_argument("-o", "--out", default="out/bench/post-aa")
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=180)
    p.add_argument("--warmup", type=int, default=8)
    p.add_argument("--frames", default="builtin:demo=8,scenes/sibenik.toml=2,scenes/foliage.toml=4",
                   help="measured frames per scene (the ssaa:16 reference costs 256 rasters each)")
    p.add_argument("--cost-frames", type=int, default=10)
    p.add_argument("--extra", default="", help="more specs, comma-separated (e.g. interlaced+taa)")
    p.add_argument("--reuse", action="store_true")
    p.add_argument("--no-cost", action="store_true", help="skip the 1280x720 cost run")
    a = p.parse_args()
    frames = dict(kv.split("=") for kv in a.frames.split(","))
    quality = QUALITY + [t for t in a.extra.split(",") if t]
    out = []
    goals = []
    for scene in a.scenes.split(","):
        name = SCENES.get(scene, os.path.basename(scene))
        b = run(a.cbr, scene, os.path.join(a.out, name), quality, a, "ssaa:16", a.width, a.height,
                a.warmup, int(frames.get(scene, 4)))
        rows = {r["config"]: r for r in b["rows"]}
        n = int(frames.get(scene, 4))
        out.append(f"\n**{name}** ({a.width}x{a.height}, frames {a.warmup}-{a.warmup + n - 1} "
                   f"measured after {a.warmup} warm-up, against `ssaa:16`):\n")
        has_ghost = any(err(r, "flip_disocc_mean") is not None for r in b["rows"])
        head = "| configuration | FLIP | edge FLIP |" + (" disocclusion FLIP |" if has_ghost else "")
        head += " flicker | change (reference's) | FLIP / native |"
        out.append(head)
        out.append("|" + "---|" * (head.count("|") - 1))
        nat = err(rows["native"], "flip_mean")
        for t in quality:
            r = rows.get(t)
            if r is None:
                continue
            fl = err(r, "flip_mean")
            line = f"| `{t}` | {f(fl)} | {f(err(r, 'flip_edge_mean'))} |"
            if has_ghost:
                line += f" {f(err(r, 'flip_disocc_mean'))} |"
            line += (f" {f(err(r, 'flicker_mean'))} | {f(err(r, 'change_mean'))} "
                     f"({f(err(r, 'ref_change_mean'))}) |")
            line += f" {f(fl / nat if fl and nat else None, 3)} |"
            out.append(line)
        taa = err(rows["native+taa"], "flip_mean")
        inside = err(rows["native+taa:inside"], "flip_mean")
        cbs = [t for t in quality if t.startswith("checkerboard") and ("taa" in t or "fused" in t)
               and "inside" not in t]
        best = min(cbs, key=lambda t: err(rows[t], "flip_mean") if t in rows else 9)
        goals.append((name, taa / nat, best, err(rows[best], "flip_mean") / taa, taa / inside,
                      (err(rows["native+taa"], "flip_disocc_mean"),
                       err(rows["native+taa:inside"], "flip_disocc_mean"))))
    print("\n".join(out))
    print("\n**Goals**:\n")
    for name, r_taa, best, r_cb, r_inside, ghost in goals:
        print(f"- {name}: native+taa / native FLIP = {r_taa:.3f} (goal <= 0.7); best checkerboard "
              f"under TAA `{best}`: {r_cb:.3f}x native+taa's FLIP (goal <= 1.15); ours / INSIDE "
              f"= {r_inside:.3f} (goal <= 0.85); disocclusion FLIP ours {f(ghost[0])}, INSIDE "
              f"{f(ghost[1])}")
    if a.no_cost:
        return
    out = []
    # Cost at 1280x720 on the demo.
    c = run(a.cbr, "builtin:demo", os.path.join(a.out, "cost"), COST, a, None, 1280, 720, 3,
            a.cost_frames)
    crow = {r["config"]: r for r in c["rows"]}
    native_ms = crow["native"]["frame_ms"]["median"]
    out.append(f"\n**Cost** (builtin:demo, 1280x720, 3 warm-up + {a.cost_frames} frames, GPU "
               f"medians, {c['rows'][0]['device']}):\n")
    out.append("| configuration | frame ms | x native | x native+taa | post passes (ms) |")
    out.append("|---|---|---|---|---|")
    taa_ms = crow["native+taa"]["frame_ms"]["median"]
    for t in COST:
        r = crow[t]
        ms = r["frame_ms"]["median"]
        post = ", ".join(f"{k} {v['median']:.1f}" for k, v in r["passes"].items()
                         if k.startswith("taa") or k.startswith("fxaa"))
        out.append(f"| `{t}` | {ms:.1f} | {ms / native_ms:.3f} | {ms / taa_ms:.3f} | {post or '–'} |")
    print("\n".join(out))
    for t in COST[1:]:
        if "+" in t:
            r = crow[t]
            post = sum(v["median"] for k, v in r["passes"].items()
                       if k.startswith("taa") or k.startswith("fxaa"))
            print(f"- `{t}`: post passes {post:.1f} ms = {post / native_ms:.3f}x native's frame")
    for t in [t for t in COST if t.startswith("checkerboard") and t != "checkerboard:rotated:ours"]:
        print(f"- `{t}`: {crow[t]['frame_ms']['median'] / taa_ms:.3f}x native+taa's frame cost "
              f"(goal <= 0.65)")


if __name__ == "__main__":
    main()
