#!/usr/bin/env python3
"""The GPU study's tables (issue 17), from the folder scripts/gpu-study.sh fills:

    scripts/gpu-study-tables.py out/gpu-study-work > gpu-study.md

Reads info.txt, tests.tsv and bench/*/bench.json (`cbr bench --timing-only` runs). Prints:
the device and driver; the test binaries' results; per resolution, the resolve's GPU time for
every layout, mode (`ours`, `pq4k`), precision, mapping and group with its copy floor from the
same frames; the other resolve modes at the defaults; Sibenik's checkerboard frame against
native's; and the 1080p pixel/quad times beside the Stadia write-up's on an AMD Vega. Every
time is the median over the measured frames of GPU timestamps. Nothing is printed for what was
not measured."""
import glob
import json
import os
import sys

STADIA = "106 us (one pixel per thread) and 59 us (2x2 quad per thread), 1080p, AMD Vega (../shared/seeds/002)"


def med(summary):
    return summary.get("median") if isinstance(summary, dict) else None


def ms(v):
    return "-" if v is None else (f"{v * 1000:.1f} us" if v < 1 else f"{v:.3f} ms")


def ratio(a, b):
    return "-" if a is None or b in (None, 0) else f"{a / b:.2f}"


def load(work):
    runs = {}
    for p in sorted(glob.glob(os.path.join(work, "bench", "*", "bench.json"))):
        runs[os.path.basename(os.path.dirname(p))] = json.load(open(p))
    return runs


def layout_of(row):
    spec = row["spec"].split(":")
    return spec[1] + (":locations" if "locations" in spec else "") if len(spec) > 1 else ""


def mode_of(row):
    return row.get("resolve") or "-"


def resolve_rows(runs, prefix):
    out = {}
    for name, b in runs.items():
        if not name.startswith(prefix):
            continue
        for r in b["rows"]:
            if r["technique"] != "checkerboard" or not r.get("resolve"):
                continue
            out.setdefault(f"{r['width']}x{r['height']}", []).append(r)
    return out


def tsv_table(path, title, columns):
    """Prints a tab-separated file with a header line as a markdown table; returns its rows."""
    if not os.path.exists(path):
        return None
    lines = [l.rstrip("\n").split("\t") for l in open(path)][1:]
    print(f"## {title}\n")
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for l in lines:
        print("| " + " | ".join((l + [""] * len(columns))[:len(columns)]) + " |")
    print()
    return lines


def goals(runs):
    """Issues 14 and 15's frame-time goals, timed on this device (no error: --timing-only)."""
    for scene in ("demo", "sibenik"):
        b = runs.get(f"goal-interleaved-{scene}")
        if not b:
            continue
        rows = b["rows"]
        ref = next((med(r["frame_ms"]) for r in rows if r["config"] == "deferred:vpls=1024"), None)
        r0 = rows[0]
        print(f"## Interleaved shading against every VPL at every pixel, {scene}, {r0['width']}x{r0['height']} "
              f"({b['protocol']['warmup_frames']} warm-up + {b['protocol']['measured_frames']} measured frames)\n")
        print("Issue 15's goal: 4x4 with 1024 VPLs at least 10x faster than `deferred:vpls=1024` at FLIP at "
              "most 0.05. FLIP is not measured here (`--timing-only`); docs/interleaved.md has lavapipe's.\n")
        print("| configuration | frame | x faster than `deferred:vpls=1024` | passes |")
        print("|---|---|---|---|")
        for r in rows:
            f = med(r["frame_ms"])
            passes = ", ".join(f"{k} {ms(med(v))}" for k, v in r["passes"].items() if k != "readback")
            print(f"| `{r['config']}` | {ms(f)} | {ratio(ref, f)} | {passes} |")
        print()
    for scene in ("demo", "sibenik"):
        b = runs.get(f"goal-analytic-{scene}")
        if not b:
            continue
        print(f"## `analytic` against `ssaa:16`, {scene} ({b['protocol']['warmup_frames']} warm-up + "
              f"{b['protocol']['measured_frames']} measured frames)\n")
        print("Issue 14's goal: the frame at most 1/20 of `ssaa:16`'s at the same resolution.\n")
        print("| resolution | `native` | `ssaa:16` | `analytic` | `analytic` / `ssaa:16` |")
        print("|---|---|---|---|---|")
        by_res = {}
        for r in b["rows"]:
            by_res.setdefault(f"{r['width']}x{r['height']}", {})[r["config"]] = med(r["frame_ms"])
        for res, t in by_res.items():
            a, s = t.get("analytic"), t.get("ssaa:16")
            frac = f"1/{s / a:.1f}" if a and s else "-"
            print(f"| {res} | {ms(t.get('native'))} | {ms(s)} | {ms(a)} | {frac} |")
        print()


def main():
    work = sys.argv[1]
    runs = load(work)
    info = open(os.path.join(work, "info.txt")).read() if os.path.exists(os.path.join(work, "info.txt")) else ""
    device = next((l.split(":", 1)[1].strip() for l in info.splitlines() if l.startswith("chosen:")), "?")
    driver = next((l.split(":", 1)[1].strip() for l in info.splitlines() if l.strip().startswith("driver:")), "?")
    cf = os.path.join(work, "commit.txt")
    commits = {open(cf).read().strip()} if os.path.exists(cf) else {b.get("git_commit") for b in runs.values()}
    print(f"# GPU study: {device}, {driver}\n")
    print(f"Binaries of commit {', '.join(sorted(c or '?' for c in commits))}. `cbr bench --timing-only`: GPU "
          "timestamps per pass, medians over the measured frames (warm-up and frame counts in each "
          "table's heading); the copy floor is a compute kernel moving the resolve's minimum bytes, "
          "timed in the same frames.\n")

    lines = tsv_table(os.path.join(work, "tests.tsv"), "Tests (validation layers on)",
                      ["test binary", "status", "passed", "failed", "SKIPPED lines", "VUID lines", "s"])
    if lines is not None:
        tot = lambda i: sum(int(l[i]) for l in lines if len(l) > i and l[i].isdigit())
        print(f"Total: {tot(2)} passed, {tot(3)} failed, {tot(5)} VUID lines.\n")
    tsv_table(os.path.join(work, "runs.tsv"), "Bench runs (`cbr bench --timing-only`)",
              ["run", "scene", "resolutions", "status", "s"])
    # Where each finished run's wall clock went (bench.json's setup_s and frames_wall_s per row;
    # absent from binaries before they were written). A killed run writes no bench.json: its
    # log holds one line per row that finished.
    walls = [(n, b["rows"]) for n, b in runs.items() if any("setup_s" in r for r in b["rows"])]
    if walls:
        print("## Wall clock of the finished runs\n")
        print("| run | rows | set-up s (sum) | frames s (sum) | slowest set-up |")
        print("|---|---|---|---|---|")
        for n, rows in walls:
            su = sum(r.get("setup_s") or 0.0 for r in rows)
            fr = sum(r.get("frames_wall_s") or 0.0 for r in rows)
            top = max(rows, key=lambda r: r.get("setup_s") or 0.0)
            print(f"| {n} | {len(rows)} | {su:.1f} | {fr:.1f} | `{top['config']}` {top.get('setup_s') or 0.0:.1f} s |")
        print()

    for res, rows in resolve_rows(runs, "core-").items():
        b = next(b for n, b in runs.items()
                 if n.startswith("core-") and any(f"{r['width']}x{r['height']}" == res for r in b["rows"]))
        p = b["protocol"]
        print(f"## Resolve cost, builtin:demo, {res} ({p['warmup_frames']} warm-up + "
              f"{p['measured_frames']} measured frames)\n")
        print("| layout | mode | precision | pixel/8 | pixel/16 | quad/8 | quad/16 | floor (quad/8) | "
              "quad/8 / floor | best / its floor | quad / pixel (8) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        keyed = {}
        for r in rows:
            keyed.setdefault((layout_of(r), mode_of(r), "fp16" if r["fp16"] else "fp32"), {})[
                (r["mapping"], r["group"])] = r
        for (layout, mode, prec), cells in sorted(keyed.items()):
            t = {k: med(v["passes"].get("resolve")) for k, v in cells.items()}
            f = {k: med(v["copy_floor_ms"]) for k, v in cells.items()}
            best = min((k for k in t if t[k] is not None), key=lambda k: t[k], default=None)
            q8, p8 = t.get(("quad", 8)), t.get(("pixel", 8))
            print(f"| {layout} | {mode} | {prec} | {ms(p8)} | {ms(t.get(('pixel', 16)))} | {ms(q8)} | "
                  f"{ms(t.get(('quad', 16)))} | {ms(f.get(('quad', 8)))} | {ratio(q8, f.get(('quad', 8)))} | "
                  f"{ratio(t[best], f[best]) + ' (' + best[0] + '/' + str(best[1]) + ')' if best else '-'} | "
                  f"{ratio(q8, p8)} |")
        print()

    for res, rows in resolve_rows(runs, "modes-").items():
        print(f"## The other resolve modes, builtin:demo, {res} (quad/8, fp32)\n")
        print("| layout | mode | resolve | floor | resolve / floor | raster | frame |")
        print("|---|---|---|---|---|---|---|")
        for r in sorted(rows, key=lambda r: (layout_of(r), mode_of(r))):
            raster = next((med(v) for k, v in r["passes"].items() if k.endswith(".raster")), None)
            t, fl = med(r["passes"].get("resolve")), med(r["copy_floor_ms"])
            print(f"| {layout_of(r)} | {mode_of(r)} | {ms(t)} | {ms(fl)} | {ratio(t, fl)} | {ms(raster)} | "
                  f"{ms(med(r['frame_ms']))} |")
        print()

    sib = [(n, b) for n, b in runs.items() if n.startswith("sibenik")]
    if sib:
        by_res = {}
        for n, b in sib:
            for r in b["rows"]:
                rows = by_res.setdefault(f"{r['width']}x{r['height']}", [])
                if not any(x["config"] == r["config"] for x in rows):
                    rows.append(r)
        p = sib[0][1]["protocol"]
        for res, rows in by_res.items():
            native = next((med(r["frame_ms"]) for r in rows if r["config"] == "native"), None)
            print(f"## Šibenik's frame, {res} ({p['warmup_frames']} warm-up + "
                  f"{p['measured_frames']} measured frames; native from the first run)\n")
            print("| configuration | frame | / native | raster | / native's | resolve (share of frame) |")
            print("|---|---|---|---|---|---|")
            for r in rows:
                f = med(r["frame_ms"])
                raster = next((med(v) for k, v in r["passes"].items() if k.endswith(".raster")), None)
                res_ms = med(r["passes"].get("resolve")) if "resolve" in r["passes"] else None
                share = f" ({100 * res_ms / f:.1f}%)" if res_ms is not None and f else ""
                print(f"| `{r['config']}` | {ms(f)} | {ratio(f, native)} | {ms(raster)} | {ratio(raster, native)} | "
                      f"{ms(res_ms)}{share} |")
            print()

    goals(runs)

    hd = resolve_rows(runs, "core-").get("1920x1080", [])
    if hd:
        print(f"## Beside the Stadia write-up ({STADIA})\n")
        print("| layout | mode | pixel/8 | quad/8 | quad / pixel |")
        print("|---|---|---|---|---|")
        for r in hd:
            if r["fp16"] or r["group"] != 8 or r["mapping"] != "quad":
                continue
            p = next((x for x in hd if x["mapping"] == "pixel" and x["group"] == 8 and not x["fp16"]
                      and layout_of(x) == layout_of(r) and mode_of(x) == mode_of(r)), None)
            q, pp = med(r["passes"].get("resolve")), med(p["passes"].get("resolve")) if p else None
            print(f"| {layout_of(r)} | {mode_of(r)} | {ms(pp)} | {ms(q)} | {ratio(q, pp)} |")
        print("| Stadia write-up, AMD Vega | theirs | 106.0 us | 59.0 us | 0.56 |\n")


if __name__ == "__main__":
    main()
