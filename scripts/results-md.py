#!/usr/bin/env python3
"""docs/results.md from `cbr bench` outputs: one table per scene and resolution.

    python3 scripts/results-md.py out/bench/standard/*/bench.json > docs/results.md
"""
import json
import sys


def f(v, d):
    return "–" if v is None else f"{v:.{d}f}"


def main(paths):
    out = ["# Results", "",
           "Written by `just bench` (scripts/results-md.py); do not edit by hand. Each table: one",
           "scene at one resolution, every configuration against native at the same frames.", ""]
    for p in paths:
        b = json.load(open(p))
        pr = b["protocol"]
        out += [f"## {b['scene']['name']} ({b['scene']['source']})", "",
                f"Device {b['device']['name']} ({b['device']['driver_info']}); git {b['git_commit']}; "
                f"{pr['warmup_frames']} warm-up + {pr['measured_frames']} measured frames; {pr['frame_ms']}; "
                f"metrics: {pr['metrics']}; display: {pr['display']}.", "",
                f"Command: `{' '.join(b['command'])}`", ""]
        groups = {}
        for r in b["rows"]:
            groups.setdefault((r["width"], r["height"]), []).append(r)
        for (w, h), rows in groups.items():
            native = next((r for r in rows if r["config"] == "native"), None)
            nat_ms = native["frame_ms"]["median"] if native else None
            # The temporal columns (bench.json from before them has none): disocclusion FLIP
            # over the last k frames, flicker, and the technique's and the reference's change.
            temporal = any((r["error"] or {}).get("flicker_mean") is not None
                           or (r["error"] or {}).get("flip_disocc_mean") is not None for r in rows)
            k = pr.get("disocclusion_frames")
            extra = f" disocclusion FLIP (k = {k}) | flicker | change | reference change |" if temporal else ""
            out += [f"### {w}x{h}", "",
                    "| configuration | GPU ms median [p5-p95] | vs native | resolve/upscale ms | copy floor ms | PSNR dB | SSIM | FLIP mean | relMSE | Pareto |" + extra,
                    "|---|---|---|---|---|---|---|---|---|---|" + ("---|" * 4 if temporal else "")]
            for r in rows:
                fm = r["frame_ms"]
                e = r["error"] or {}
                rec = (r["passes"].get("resolve") or r["passes"].get("upscale") or {}).get("median")
                floor = (r.get("copy_floor_ms") or {}) or {}
                ratio = f"{fm['median'] / nat_ms:.2f}x" if nat_ms else "–"
                out.append(
                    f"| {r['config']} | {f(fm['median'], 2)} [{f(fm['p5'], 2)}-{f(fm['p95'], 2)}] | {ratio} | "
                    f"{f(rec, 2)} | {f(floor.get('median') if floor else None, 2)} | {f(e.get('psnr_mean'), 2)} | "
                    f"{f(e.get('ssim_mean'), 4)} | {f(e.get('flip_mean'), 4)} | {f(e.get('relmse_mean'), 4)} | "
                    f"{'yes' if r.get('pareto') else ''} |"
                    + (f" {f(e.get('flip_disocc_mean'), 4)} | {f(e.get('flicker_mean'), 4)} | "
                       f"{f(e.get('change_mean'), 4)} | {f(e.get('ref_change_mean'), 4)} |" if temporal else ""))
            out.append("")
    print("\n".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
