#!/usr/bin/env python3
"""Issue 57's goal table from scripts/interleaved-cost.sh runs (docs/interleaved.md, "Where the
lighting pass's time goes"): per scene and resolution, `interleaved:4x4:vpls=1024` (and the code
before the change, and `exact-edges`) against `deferred:vpls=1024` of the same run: frame times,
speed-up, FLIP, edge FLIP over interior FLIP, and the load average before and after the run
(uptime-*.txt beside bench.json). Usage: interleaved-goals.py OUT/bench/ic-TAG/*/bench.json
[--spec SPEC ...]: with --spec, one row per scene and spec instead (each spec's frame time,
speed-up, FLIP, edge / interior FLIP and whether the three goals hold); rows a run lacks are
skipped."""
import json
import os
import sys

B = "interleaved:4x4:vpls=1024"
OLD = B + ":fallback=inline:window=fetch:cull=0"
REF = "deferred:vpls=1024"


def load(path):
    """bench.json and the 1-minute load average before and after the run: from uptime-*.txt
    beside it where a script wrote them, else from bench.json's `machine` (since 2026-12-02)."""
    d = os.path.dirname(path)
    b = json.load(open(path))
    recorded = (b.get("machine") or {}).get("load_average") or {}
    up = []
    for n, k in (("uptime-before.txt", "start"), ("uptime-after.txt", "end")):
        try:
            up.append(open(os.path.join(d, n)).read().split("load average:")[1].split(",")[0].strip())
        except (OSError, IndexError):
            v = recorded.get(k)
            up.append(f"{v[0]:.2f}" if v else "?")
    return b, up


def specs_table(paths, specs):
    print("| scene | size | spec | reference ms | ms | x faster | FLIP | edge / interior FLIP "
          "| goals (6x, FLIP, edge) | load avg (before, after) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for p in paths:
        b, up = load(p)
        rows = {r["config"]: r for r in b["rows"]}
        ref = rows[REF]["frame_ms"]["median"]
        size = f"{rows[REF]['width']}x{rows[REF]['height']}"
        for spec in specs:
            r = rows.get(spec)
            if r is None:
                continue
            e = r.get("error") or {}
            ms = r["frame_ms"]["median"]
            x = ref / ms
            er = e["flip_edge_mean"] / e["flip_interior_mean"] if e.get("flip_interior_mean") else float("nan")
            flip = e.get("flip_mean")
            ok = lambda c: "yes" if c else "no"
            print(f"| {rows[REF]['scene']} | {size} | `{spec.replace(B, 'B')}` | {ref:.1f} | {ms:.1f} | "
                  f"**{x:.2f}** | {flip:.4f} | {er:.2f} | {ok(x >= 6)}, {ok(flip <= 0.05)}, "
                  f"{ok(er <= 1.5)} | {up[0]}, {up[1]} |")


def main():
    if "--spec" in sys.argv:
        i = sys.argv.index("--spec")
        return specs_table(sys.argv[1:i], sys.argv[i + 1:])
    print("| scene | size | reference ms | `interleaved:4x4` ms | x faster | before the change: ms, x faster "
          "| FLIP | edge / interior FLIP | `exact-edges`: x faster, FLIP, edge / interior | load avg (before, after) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for p in sys.argv[1:]:
        b, up = load(p)
        rows = {r["config"]: r for r in b["rows"]}
        ref = rows[REF]["frame_ms"]["median"]
        scene = rows[REF]["scene"]
        size = f"{rows[REF]['width']}x{rows[REF]['height']}"

        def fig(cfg):
            r = rows[cfg]
            e = r.get("error") or {}
            ms = r["frame_ms"]["median"]
            ratio = e["flip_edge_mean"] / e["flip_interior_mean"] if e.get("flip_interior_mean") else float("nan")
            return ms, ref / ms, e.get("flip_mean"), ratio

        ms, x, flip, er = fig(B)
        oms, ox, _, _ = fig(OLD)
        _, ex, eflip, eer = fig(B + ":exact-edges")
        print(f"| {scene} | {size} | {ref:.1f} | {ms:.1f} | **{x:.2f}** | {oms:.1f}, {ox:.2f} | {flip:.4f} | "
              f"{er:.2f} | {ex:.2f}, {eflip:.4f}, {eer:.2f} | {up[0]}, {up[1]} |")
        cull = rows.get(REF + ":cull=0")
        if cull:
            print(f"|  | (reference `cull=0`: {cull['frame_ms']['median']:.1f} ms; old interleaved "
                  f"against it {cull['frame_ms']['median'] / oms:.2f}x) |||||||||")


if __name__ == "__main__":
    main()
