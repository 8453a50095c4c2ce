#!/usr/bin/env python3
"""The tables of docs/interleaved.md from `cbr bench` runs of `interleaved` (just bench-interleaved).

For each bench.json given: one row per configuration with the frame time, the VPL work (the passes
that deal with the VPLs: the reference's lighting pass less `deferred`'s lighting pass of the same
run, i.e. the VPL sum; interleaved's split, shade, gather or implicit, the seed's blur, and its
lighting pass less `deferred`'s), both as ratios to the reference's, FLIP (mean, edge pixels,
interior pixels and their ratio) and PSNR against the reference; then, for rows run with `floor`,
the split and gather passes against their copy kernel. Rows with `direct` have no VPL work
figure (their lighting pass no longer shades the point lights, which `deferred`'s does, so the
difference would not be the VPLs' work). Every number comes from the one run named
in its heading: ratios are taken within a run, never across runs.
"""
import json
import sys

VPL_PASSES = ("split", "shade", "gather", "implicit", "seed_blur_h", "seed_blur_v", "fallback",
              "finish")


def med(row, name):
    for k, v in (row.get("passes") or {}).items():
        if k.split(".")[-1] == name:
            return v["median"]
    return None


def lighting(row):
    for k, v in (row.get("passes") or {}).items():
        if k.endswith(".lighting"):
            return v["median"]
    return None


CLASSES = ("interior", "edge_found", "fallback_1_4", "fallback_5_8", "fallback_9_16",
           "fallback_17_plus")


def attribution(rows):
    """The lighting pass by part (bench.json's `interleaved_parts`, from the `parts=` rows) and the
    per-pixel classes (`interleaved_attribution`, from `:debug` rows)."""
    parts = [(c, r["interleaved_parts"]) for c, r in rows.items() if r.get("interleaved_parts")]
    if parts:
        print("\n| spec | lighting ms | base | point lights | filter | fallback (in the pass) | "
              "`interleaved.fallback` | `interleaved.finish` |")
        print("|---|---|---|---|---|---|---|---|")
        for c, p in parts:
            r = rows[c]
            print(f"| `{c}` | {f(p['lighting_ms'], 1)} | {f(p['base_ms'], 1)} | "
                  f"{f(p['lights_ms'], 1)} | {f(p['filter_ms'], 1)} | {f(p['fallback_ms'], 1)} | "
                  f"{f(med(r, 'fallback'), 1)} | {f(med(r, 'finish'), 1)} |")
    for c, r in rows.items():
        a = (r.get("error") or {}).get("interleaved_attribution")
        if not a:
            continue
        v, e = a["visible"], a["edge"]
        print(f"\n`{c}`: subsets shaded in the fallback per visible pixel "
              f"{v['subsets_per_pixel']:.3f}, per reference edge pixel {e['subsets_per_pixel']:.2f}; "
              f"lane use of the inline loop (8-pixel row groups, model) {f(a['lane_use'], 2)}, "
              f"listed apart {f(a['lane_use_compacted'], 2)}\n")
        print("| class | visible pixels | their fallback subsets | error share | mean FLIP | "
              "reference edge pixels | error share there | mean FLIP there |")
        print("|---|---|---|---|---|---|---|---|")
        for k in CLASSES:
            x, y = v[k], e[k]
            if x["pixels"] == 0 and y["pixels"] == 0:
                continue
            print(f"| {k} | {x['pixels']:.3f} | {x['subsets']:.3f} | {x['error']:.3f} | "
                  f"{f(x['flip_mean'])} | {y['pixels']:.3f} | {y['error']:.3f} | "
                  f"{f(y['flip_mean'])} |")


def vpl_work(row, base_lighting):
    light = lighting(row)
    if light is None or base_lighting is None:
        return None
    extra = sum(med(row, p) or 0.0 for p in VPL_PASSES)
    return extra + light - base_lighting


def f(v, d=4):
    return "–" if v is None else f"{v:.{d}f}"


def table(path):
    b = json.load(open(path))
    rows = {r["config"]: r for r in b["rows"]}
    ref = b["reference"]
    r0 = rows.get(ref)
    base = rows.get("deferred")
    base_light = lighting(base) if base else None
    ref_frame = r0["frame_ms"]["median"] if r0 else None
    ref_vpl = vpl_work(r0, base_light) if r0 else None
    w, h = r0["width"], r0["height"]
    frames = r0["frames"]
    scene = b["scene"]["name"] if isinstance(b["scene"], dict) else b["scene"]
    print(f"\n#### {scene}, {w}x{h}, against `{ref}` ({r0['warmup']} warm-up + {frames} "
          f"measured frames, medians; {r0['device']})\n")
    print(f"`{' '.join(b['command'][1:] if isinstance(b['command'], list) else [b['command']])}`\n")
    print("| spec | frame ms | x faster (frame) | VPL work ms | x faster (VPL work) | FLIP | "
          "edge FLIP | interior FLIP | edge / interior | PSNR dB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    floors = []
    for cfg, r in rows.items():
        e = r.get("error") or {}
        frame = r["frame_ms"]["median"]
        many = cfg.startswith(("interleaved", "deferred:")) and ":direct" not in cfg
        vw = vpl_work(r, base_light) if many else None
        ratio = ref_frame / frame if ref_frame and cfg != ref else None
        vratio = ref_vpl / vw if (ref_vpl and vw and cfg != ref) else None
        edge, interior = e.get("flip_edge_mean"), e.get("flip_interior_mean")
        er = edge / interior if edge is not None and interior else None
        name = f"`{cfg}`" + (" (reference)" if cfg == ref else "")
        print(f"| {name} | {f(frame, 1)} | {f(ratio, 2)} | {f(vw, 1)} | {f(vratio, 2)} | "
              f"{f(e.get('flip_mean'))} | {f(edge)} | {f(interior)} | {f(er, 2)} | "
              f"{f(e.get('psnr_mean'), 2)} |")
        copy = med(r, "copy_floor")
        if copy:
            sg = (med(r, "split") or 0.0) + (med(r, "gather") or 0.0)
            floors.append((cfg, sg, copy))
    attribution(rows)
    for cfg, sg, copy in floors:
        print(f"\n`{cfg}`: split + gather {sg:.2f} ms, their copy kernel (48 bytes read and 48 "
              f"written a pixel) {copy:.2f} ms: **{sg / copy:.2f}x** the floor.")


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: interleaved-table.py BENCH.json...")
    for p in sys.argv[1:]:
        table(p)


if __name__ == "__main__":
    main()
