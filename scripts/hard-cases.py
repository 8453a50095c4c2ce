#!/usr/bin/env python3
"""The hard-case gallery of docs/hard-cases.md: every technique on every built-in hard case.

Per case one `cbr bench builtin:CASE` against a supersampled reference (`ssaa:16` by default,
cached in $CBR_CACHE_DIR), then `cbr montage` strips (the reference and each technique on the
window of highest error, enlarged, over their FLIP maps), the reference frame, and the markdown:
a table per case (FLIP, edge and disocclusion FLIP against the named reference, frame time) and one
matrix of FLIP over all cases. The cases come from `cbr info --json`, so new ones join by
themselves; so do techniques added to TECHNIQUES below.

    python3 scripts/hard-cases.py --cbr ./target/release/cbr -o out/hard-cases --docs docs
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

from strips import worst_crop_strip

TECHNIQUES = [
    "native", "msaa:4", "checkerboard:rotated:ours", "checkerboard:split:ours",
    "checkerboard:rotated:pq4k", "checkerboard:rotated:fused", "upscale:bilinear", "interlaced",
    "native+fxaa", "native+taa", "checkerboard:rotated:ours+taa", "analytic", "deferred",
]
# Not here: `interleaved` (issue 15) shades VPL indirect light that the gallery's reference, a
# supersampled frame of the direct light, does not have, and needs a sun, which `specular` lacks;
# it is measured against `deferred:vpls=N` instead (docs/interleaved.md).
# Frames: warm-up (histories converge) and measured; `cut` is measured on the two frames after
# its cut (frame 8 is the first of the new shot).
FRAMES = {"cut": (8, 2)}
DEFAULT_FRAMES = (4, 2)
CROP = 48    # the window shown, around the reference row's worst-FLIP crop
SCALE = 3


def run(cmd):
    print("[hard-cases]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)


def cases(cbr):
    info = json.loads(subprocess.run([cbr, "info", "--json"], check=True, capture_output=True,
                                     text=True).stdout)
    return [(s["name"], s["about"]) for s in info["scenes"] if s["name"] != "demo"]


def f(v, d=4):
    return "–" if v is None else f"{v:.{d}f}"


def med(s):
    return (s or {}).get("median")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cbr", default="./target/release/cbr")
    ap.add_argument("-o", "--out", default="out/hard-cases")
    ap.add_argument("--docs", default="docs", help="writes hard-cases.md and images/hard-cases/")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--reference", default="ssaa:16")
    ap.add_argument("--only", help="comma-separated cases")
    ap.add_argument("--reuse", action="store_true", help="read finished bench runs")
    a = ap.parse_args()
    all_cases = cases(a.cbr)
    if a.only:
        keep = a.only.split(",")
        all_cases = [c for c in all_cases if c[0] in keep]
    img_dir = os.path.join(a.docs, "images", "hard-cases")
    os.makedirs(img_dir, exist_ok=True)
    sections, matrix, device = [], [], None
    for name, about in all_cases:
        out = os.path.join(a.out, name)
        done = os.path.join(out, "bench.json")
        warmup, frames = FRAMES.get(name, DEFAULT_FRAMES)
        if not (a.reuse and os.path.exists(done)):
            run([a.cbr, "bench", f"builtin:{name}", "--width", str(a.width), "--height",
                 str(a.height), "--warmup", str(warmup), "--frames", str(frames), "--reference",
                 a.reference, "--techniques", ",".join(TECHNIQUES), "-o", out])
        b = json.load(open(done))
        device = b["device"]
        rows = b["rows"]
        ref = next(r for r in rows if r.get("error") is None)
        techs = [r for r in rows if r.get("error") is not None]
        res = f"{a.width}x{a.height}"
        # The strip: the window around the worst crop, reference then each technique, over the
        # FLIP maps (blank under the reference).
        strip = os.path.join(img_dir, f"{name}.png")
        x, y = worst_crop_strip(a.cbr, out, ref, techs, (a.width, a.height), CROP, SCALE, strip,
                                "hard-cases")
        frame_png = os.path.join(img_dir, f"{name}-reference.png")
        shutil.copyfile(os.path.join(out, ref["images"]["image"]), frame_png)
        native_ms = next((med(r["frame_ms"]) for r in techs if r["spec"] == "native"), None)
        measured = [p["frame"] for p in techs[0]["error"]["per_frame"]]
        lines = [f"### `builtin:{name}`: {about}", "",
                 f"![{name}, reference frame](images/hard-cases/{name}-reference.png)", "",
                 f"![{name} strip](images/hard-cases/{name}.png)", "",
                 f"Left to right: `{ref['spec']}` (the reference), "
                 + ", ".join(f"`{r['spec']}`" for r in techs)
                 + f"; below each, its FLIP map against `{ref['spec']}`. Window {CROP}x{CROP} at "
                 f"({x}, {y}) around the worst crop, enlarged {SCALE}x; frame {ref['images']['frame']}.",
                 "",
                 f"{res}, {warmup} warm-up + {frames} measured frames ({measured}), error against "
                 f"`{ref['spec']}`; frame time is the median GPU time on {device['name']}.", "",
                 "| technique | FLIP | edge FLIP | disocclusion FLIP | PSNR dB | frame ms | time / native |",
                 "|---|---|---|---|---|---|---|"]
        best = min(r["error"]["flip_mean"] for r in techs)
        cells = {}
        for r in techs:
            e = r["error"]
            t = med(r["frame_ms"])
            psnr = [p.get("psnr") for p in e["per_frame"] if p.get("psnr") is not None]
            fl = e["flip_mean"]
            cells[r["spec"]] = fl
            mark = "**" if fl == best else ""
            lines.append(
                f"| `{r['spec']}` | {mark}{f(fl)}{mark} | {f(e.get('flip_edge_mean'))} | "
                f"{f(e.get('flip_disocc_mean'))} | {f(sum(psnr) / len(psnr) if psnr else None, 2)} | "
                f"{f(t, 2)} | {f(t / native_ms if t and native_ms else None, 2)} |")
        sections.append("\n".join(lines))
        matrix.append((name, cells))
    specs = TECHNIQUES
    head = ["| case | " + " | ".join(f"`{s}`" for s in specs) + " |",
            "|---|" + "---|" * len(specs)]
    for name, cells in matrix:
        vals = [cells.get(s) for s in specs]
        best = min(v for v in vals if v is not None)
        head.append(f"| `{name}` | " + " | ".join(
            ("**" + f(v) + "**") if v == best else f(v) for v in vals) + " |")
    gen = ("<!-- gallery:begin (written by scripts/hard-cases.py) -->\n"
           f"## FLIP on every case (against `{a.reference}`, lower is better; best in bold)\n\n"
           + "\n".join(head) + "\n\n## The cases\n\n" + "\n\n".join(sections)
           + "\n<!-- gallery:end -->")
    doc = os.path.join(a.docs, "hard-cases.md")
    text = open(doc).read() if os.path.exists(doc) else "# Hard cases\n\n"
    begin, end = text.find("<!-- gallery:begin"), text.find("<!-- gallery:end -->")
    if a.only:
        doc = os.path.join(a.out, "hard-cases-partial.md")
        text = gen + "\n"
    elif begin >= 0 and end > begin:
        text = text[:begin] + gen + text[end + len("<!-- gallery:end -->"):]
    else:
        text = text.rstrip("\n") + "\n\n" + gen + "\n"
    with open(doc + ".tmp", "w") as fh:
        fh.write(text)
    os.replace(doc + ".tmp", doc)
    print(f"[hard-cases] {doc}; strips in {img_dir}", file=sys.stderr)


if __name__ == "__main__":
    main()
