#!/usr/bin/env python3
"""The tables of docs/analytic.md from `just bench-analytic`'s bench.json files: per scene, each
technique's error against the reference (named), its edge-pixel FLIP, frame time and the ratios
the issue's goals ask for (edge FLIP / ssaa:16's, frame time / ssaa:16's), all from one run; and
where the run measured a supersampling ladder (ssaa:6 ... ssaa:16), the supersampling of equal
edge error (bench.json's equal_error_ssaa: N per side, interpolated between the rungs) and how
many times faster the row is than it."""
import json
import sys


def med(summary):
    return summary.get("median") if summary else None


def fmt(v, spec="{:.4f}"):
    return "n/a" if v is None else spec.format(v)


def equal_error(r):
    """The equal-edge-error supersampling of a row and its speed-up over it, as table cells."""
    p = (r.get("equal_error_ssaa") or {}).get("flip_edge")
    if p is None:
        return "–", "–"
    if "better_than" in p:
        return f"better than `ssaa:{p['better_than']:.0f}`", "–"
    if "worse_than" in p:
        return f"worse than `ssaa:{p['worse_than']:.0f}`", "–"
    return (f"`ssaa:{p['n']:.1f}` ({p['samples_per_pixel']:.0f} spp)",
            fmt(p.get("speedup"), "{:.1f}x"))


for path in sys.argv[1:]:
    b = json.load(open(path))
    rows = b["rows"]
    ref = next((r["spec"] for r in rows if r.get("error") is None), "?")
    first = rows[0]
    print(f"\n### {b['scene']['name']} ({first['width']}x{first['height']}, "
          f"{b['protocol']['warmup_frames']} warm-up + {b['protocol']['measured_frames']} measured frames, "
          + ("timing only" if ref == "native" else f"reference `{ref}`") + f", {b['device']['name']})\n")
    by = {r["spec"]: r for r in rows}
    s16 = by.get("ssaa:16")
    e16 = s16["error"]["flip_edge_mean"] if s16 and s16.get("error") else None
    t16 = med(s16["frame_ms"]) if s16 else None
    if ref == "native":
        # A timing run (no ground truth): frame times and their ratio to ssaa:16's only.
        print("| technique | frame ms (median) | time / ssaa:16's |")
        print("|---|---|---|")
        for r in rows:
            t = med(r["frame_ms"])
            print(f"| `{r['spec']}` | {fmt(t, '{:.2f}')} | {fmt(t16 / t if t and t16 else None, '1/{:.0f}')} |")
        continue
    print("| technique | FLIP | edge-pixel FLIP | edge FLIP / ssaa:16's | frame ms (median) | time / ssaa:16's "
          "| supersampling of equal edge FLIP | faster than it |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        e = r.get("error")
        if e is None:
            continue
        t = med(r["frame_ms"])
        ef = e.get("flip_edge_mean")
        print(f"| `{r['spec']}` | {fmt(e.get('flip_mean'))} | {fmt(ef)} | "
              f"{fmt(ef / e16 if ef is not None and e16 else None, '{:.2f}x')} | {fmt(t, '{:.2f}')} | "
              f"{fmt(t16 / t if t and t16 else None, '1/{:.0f}')} | {' | '.join(equal_error(r))} |")
