#!/usr/bin/env python3
"""The resolve shader's own instruction count on lavapipe: a deterministic cost figure.

    scripts/resolve-jit-cost.py [--cbr BIN] [--shaders DIR] [--scene SCENE]
                                [--width 256 --height 144] [--frames 3] TECHNIQUE [TECHNIQUE ...]

Runs `cbr render SCENE --technique TECHNIQUE` under callgrind with llvmpipe on the calling thread
(LP_NUM_THREADS=0), then reads the instructions of lavapipe's JIT code out of the profile: each
compiled shader function is an unnamed `???:0x...` entry, and every texel fetch of a shader is a
call into a fetch function generated per texture. The resolve is the JIT function that calls
five or more JIT functions (its sample, history and geometry fetches) and is called once per
8-lane vector of its dispatch in every frame. Works for the checkerboard resolve in both
mappings and for `interlaced`'s resolve. Prints, per technique, its inclusive count
(fetch functions included), the fetch functions' share, and the count per resolved pixel.

Same binary, driver and inputs give the same count (valgrind runs one thread; the JIT is
deterministic), so a shader change is judged by it on a 2-core machine whose times drift.
The count depends on the CPU features LLVM compiles for: compare counts from one machine.
--shaders loads the shaders from DIR (CBR_SHADER_DIR), to count a variant without rebuilding.
A run takes about 1.5 minutes (256x144, 3 frames)."""
import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def jit_functions(profile):
    """{address: (inclusive, calls, [(callee address, inclusive, calls)])} of the JIT code."""
    out = subprocess.run(["callgrind_annotate", "--threshold=100", "--inclusive=yes",
                          "--tree=calling", profile], capture_output=True, text=True,
                         check=True).stdout
    funcs = {}
    calls_to = {}
    for block in out.split("\n\n"):
        lines = block.strip().split("\n")
        head = [l for l in lines if re.search(r"\*\s+\?\?\?:0x[0-9a-f]+ \[\?\?\?\]", l)]
        if not head:
            continue
        total = int(re.match(r"\s*([\d,]+)", head[0]).group(1).replace(",", ""))
        addr = re.search(r"\?\?\?:(0x[0-9a-f]+)", head[0]).group(1)
        callees = []
        for l in lines:
            m = re.match(r"\s*([\d,]+) .*>\s+\?\?\?:(0x[0-9a-f]+) \(([\d,]+)x\) \[\?\?\?\]", l)
            if m:
                n = int(m.group(3).replace(",", ""))
                callees.append((m.group(2), int(m.group(1).replace(",", "")), n))
                calls_to[m.group(2)] = calls_to.get(m.group(2), 0) + n
        funcs[addr] = [total, 0, callees]
    for a, n in calls_to.items():
        if a in funcs:
            funcs[a][1] = n
    return funcs


def vectors(technique, width, height):
    """8-lane vectors of the resolve's dispatch per frame: llvmpipe calls the shader function
    once per vector of every workgroup, padding included. The checkerboard's quad mapping (its
    default) has one invocation per 2x2 quad, `:pixel` one per pixel, groups of 8 x 8 or (`:16`)
    16 x 16; `interlaced` one per vertical pair of pixels, groups of 8 x 8."""
    parts = technique.split("+")[0].split(":")
    if parts[0] == "interlaced":
        ux, uy, g = width, (height + 1) // 2, 8
    else:
        pixel = "pixel" in parts
        ux, uy = (width, height) if pixel else ((width + 1) // 2, (height + 1) // 2)
        g = 16 if "16" in parts else 8
    return -(-ux // g) * -(-uy // g) * g * g // 8


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("techniques", nargs="+")
    ap.add_argument("--cbr", default=os.path.join(ROOT, "target/release/cbr"))
    ap.add_argument("--shaders", help="CBR_SHADER_DIR for the run")
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes/demo.toml"))
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=144)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--min-fetches", type=int, default=5,
                    help="fetch functions the resolve calls at least (a variant may call fewer)")
    a = ap.parse_args()
    env = dict(os.environ, LP_NUM_THREADS="0")
    if a.shaders:
        env["CBR_SHADER_DIR"] = os.path.abspath(a.shaders)
    pixels = a.width * a.height * a.frames
    for t in a.techniques:
        with tempfile.TemporaryDirectory(prefix="resolve-jit-") as tmp:
            prof = os.path.join(tmp, "callgrind.out")
            cmd = ["valgrind", "--tool=callgrind", "--smc-check=all",
                   f"--callgrind-out-file={prof}", a.cbr, "render", a.scene, "--width",
                   str(a.width), "--height", str(a.height), "--frames", str(a.frames),
                   "--technique", t, "-o", os.path.join(tmp, "out")]
            p = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True)
            if p.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}")
            funcs = jit_functions(prof)
        expected = a.frames * vectors(t, a.width, a.height)
        cands = [(v[0], k) for k, v in funcs.items()
                 if v[1] == expected and len(v[2]) >= a.min_fetches]
        if not cands:
            sys.exit(f"{t}: no JIT function with {a.min_fetches}+ fetch callees "
                     f"called {expected} times; is it a resolve technique?")
        # Another per-pixel compute pass of the frame has 4 fetch functions and the pixel
        # mapping's call count: the resolve is the largest candidate.
        total, addr = max(cands)
        fetch = sum(c[1] for c in funcs[addr][2])
        print(f"{t}: {total / 1e6:.2f} M instructions (fetch functions {fetch / 1e6:.2f} M, "
              f"the shader's own code {(total - fetch) / 1e6:.2f} M), "
              f"{total / pixels:.1f} per resolved pixel, {a.width}x{a.height}, {a.frames} frames")
        for c in sorted(funcs[addr][2], key=lambda c: -c[1]):
            print(f"    fetch {c[0]}: {c[2]} calls, {c[1] / 1e6:.2f} M")


if __name__ == "__main__":
    main()
