"""The `cbr montage` strip the gallery scripts share (hard-cases.py, bench-upsampling.py): the
reference and each row of a `cbr bench` run in a window around the reference's worst crop,
enlarged, over their FLIP maps (blank under the reference)."""
import os
import subprocess
import sys


def worst_crop_strip(cbr, out, ref, rows, size, crop, scale, png, tag):
    """Writes the strip of `rows` (bench.json rows of the run in folder `out`) beside `ref` to
    `png`; `size` is the frame's (width, height). Returns the window's corner (x, y)."""
    width, height = size
    cx, cy, cw, ch = ref["crops"][0]
    x = min(max(cx + cw // 2 - crop // 2, 0), width - crop)
    y = min(max(cy + ch // 2 - crop // 2, 0), height - crop)
    imgs = [os.path.join(out, ref["images"]["image"])]
    imgs += [os.path.join(out, r["images"]["image"]) for r in rows]
    flips = ["-"] + [os.path.join(out, r["images"]["flip"]) for r in rows]
    cmd = [cbr, "montage", *imgs, *flips, "--columns", str(len(imgs)), "--crop",
           f"{x},{y},{crop},{crop}", "--scale", str(scale), "--gap", "3", "-o", png]
    print(f"[{tag}]", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)
    return x, y
