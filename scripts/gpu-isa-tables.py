#!/usr/bin/env python3
"""Markdown tables for docs/gpu-isa.md from `cbr gpu-stats` output folders.

usage: gpu-isa-tables.py resolve DIR [FAMILY]   the resolve matrix (mode x mapping x group x precision)
       gpu-isa-tables.py check DIR1080          the pq4k check against the Stadia write-up
       gpu-isa-tables.py frames DIR             every frame by the model, per family
VMEM instructions are counted in the disassembly (DIR/disassembly/...) when it was written.
"""
import json
import os
import re
import sys

# The Stadia write-up's figures (docs/CHECKERBOARD.md, "Performance Considerations"): PorQue4K's
# resolve on Stadia's AMD GPU, measured with RGP.
STADIA_1080_PIXEL_US = 106.0
STADIA_1080_QUAD_US = 59.0
STADIA_4K_US = 410.0


def load(d):
    with open(os.path.join(d, "gpu-stats.json")) as f:
        return json.load(f)


def safe(name):
    return re.sub(r"[^A-Za-z0-9.\-]", "_", name)


def vmem(d, family, spec, pass_, stage, wave):
    p = os.path.join(d, "disassembly", family, safe(spec), f"{safe(pass_)}.{safe(stage)}.wave{wave}.s")
    if not os.path.exists(p):
        return None
    n = 0
    with open(p) as f:
        for line in f:
            op = line.strip().split(" ")[0]
            if re.match(r"^(image_|buffer_|global_|tbuffer_|flat_)", op):
                n += 1
    return n


def row(j, family, spec, pass_="resolve", wave=64):
    for r in j["rows"]:
        if (r["family"], r["spec"], r["pass"], r["wave"]) == (family, spec, pass_, wave) and r["stage"] == "compute":
            return r
    return None


def resolve(d, family="vega10"):
    j = load(d)
    w, h = j["width"], j["height"]
    print(f"| spec ({family}, {w}x{h}) | VGPRs | SGPRs | waves/SIMD | instr. | instr./px | VMEM | VMEM/px | inv. thr. | cycles/64 px | MB | ALU us | memory us | predicted us |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in j["rows"]:
        if r["family"] != family or r["pass"] != "resolve" or r["stage"] != "compute" or r["wave"] != 64:
            continue
        s, m = r["stats"], r["model"] or {}
        inv = r["invocations"]
        px_per_inv = (w * h) / inv if inv else 0
        instr = s["Instructions"]
        v = vmem(d, family, r["spec"], "resolve", "compute", 64)
        thr = s["Inverse Throughput"]
        print(
            f"| `{r['spec']}` | {s['VGPRs']} | {s['SGPRs']} | {s['Subgroups per SIMD']} | {instr} | "
            f"{instr / px_per_inv:.0f} | {v if v is not None else '-'} | "
            f"{(v / px_per_inv) if v is not None else 0:.1f} | {thr} | {thr * inv / (w * h):.0f} | "
            f"{r['bytes'] / 1e6:.1f} | {m.get('alu_us', '-')} | {m.get('memory_us', '-')} | {m.get('predicted_us', '-')} |"
        )


def check(d1080):
    """pq4k at 1080p against the write-up; 4K as 4x 1080p (the model is linear in pixels)."""
    j = load(d1080)
    print("| pq4k resolve on Vega 56 (model) | waves64 | ALU us | memory us | predicted us | ACO latency us/wave | published us | model / published |")
    print("|---|---|---|---|---|---|---|---|")
    got = {}
    for spec, size, scale, pub in [
        ("checkerboard:rotated:pq4k:pixel:16", "1080p", 1, STADIA_1080_PIXEL_US),
        ("checkerboard:rotated:pq4k:quad:8", "1080p", 1, STADIA_1080_QUAD_US),
        ("checkerboard:rotated:pq4k:pixel:16", "4K (4 x 1080p)", 4, STADIA_4K_US),
    ]:
        r = row(j, "vega10", spec)
        m = r["model"]
        pred = m["predicted_us"] * scale
        got[(spec, size)] = pred
        lat = r["stats"]["Latency"] / 1471.0
        print(f"| `{spec}` {size} | {r['invocations'] * scale // 64} | {m['alu_us'] * scale:.1f} | {m['memory_us'] * scale:.1f} | {pred:.1f} ({m['bound']}) | {lat:.2f} | {pub} | {pred / pub:.2f}x |")
    p = got[("checkerboard:rotated:pq4k:pixel:16", "1080p")]
    q = got[("checkerboard:rotated:pq4k:quad:8", "1080p")]
    print(f"\nquad / pixel at 1080p: model {q / p:.2f}, published {STADIA_1080_QUAD_US / STADIA_1080_PIXEL_US:.2f}")


def frames(d):
    j = load(d)
    print(f"| spec ({j['width']}x{j['height']}) | " + " | ".join(f"{f['gpu']} us" for f in j["families"] if f.get("gpu")) + " |")
    print("|---|" + "---|" * sum(1 for f in j["families"] if f.get("gpu")))
    specs = []
    for f in j["frames"]:
        if f["spec"] not in specs:
            specs.append(f["spec"])
    for spec in specs:
        cells = []
        for fam in j["families"]:
            fr = [f for f in j["frames"] if f["spec"] == spec and f["family"] == fam["family"] and f["wave"] == 64]
            if not fr:
                cells.append("-")
                continue
            f = fr[0]
            note = f" ({len(f['unmodelled'])} unmodelled)" if f["unmodelled"] else ""
            cells.append(f"{f['predicted_us']:.1f}{note}")
        print(f"| `{spec}` | " + " | ".join(cells) + " |")
    for c in j.get("crashed", []):
        print(f"\n{c['family']} `{c['spec']}`: {c['why']}")
    for c in j.get("refused", []):
        print(f"\n{c['family']} refuses `{c['spec']}`: {c['why']}")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    cmd = sys.argv[1]
    if cmd == "resolve":
        resolve(sys.argv[2], *(sys.argv[3:4]))
    elif cmd == "check":
        check(sys.argv[2])
    elif cmd == "frames":
        frames(sys.argv[2])
    else:
        sys.exit(__doc__)
