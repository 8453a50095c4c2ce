#!/usr/bin/env python3
"""Instructions per frame on lavapipe, counted by callgrind: a work figure that does not depend on
how fast the host is.

    scripts/work-count.py [--cbr BIN] [--shaders DIR] [--width W --height H] [--warmup 0]
                          [--frames 1] [--against SPEC] [--entries N] [--keep-dumps]
                          [--reparse] [-o DIR] SCENE TECHNIQUE [TECHNIQUE ...]

Runs `cbr bench SCENE --timing-only --no-cache --techniques TECHNIQUE,...` once under callgrind,
with llvmpipe on the calling thread (LP_NUM_THREADS=0) and a dump at the start and at the end of
every call of `cbr_bench::measure::counted_frame` (one rendered frame: on lavapipe the frame's
GPU work runs inside it; the end is `counted_frame_end`, which it calls last). Each frame's dump
is split by object:

- `jit`: lavapipe's JIT code, the compiled shaders and the raster's generated code: the GPU work;
- `driver`: libvulkan_lvp.so (binning, rasterisation, dispatch) and the Vulkan loader;
- `llvm`: LLVM compiling a shader variant that lavapipe builds at its first use, inside a frame
  (in the first frame of a row; zero once warm);
- `host`: everything else the frame ran (cbr's command recording and readback, and libc, whose
  memset and memcpy also carry lavapipe's buffer fills and copies).

`jit` is deterministic to a few instructions in tens of millions: the same binary, driver, shaders
and inputs give the same count on every run (checked 2026-12-02: two runs of the demo at 160x90
agreed on every frame's count of three techniques to the instruction; four runs of the test's
held box agreed to the instruction, and one more, under a heavy load of the machine, counted 2
instructions more in one frame of 38.6 M, cause not found).
The other parts move by a few per cent between runs (waits and allocator paths). Valgrind presents
its own CPU to the program (AVX2, no AVX-512), so LLVM compiles the same code on any x86-64 host
valgrind runs on; a count is a count of 8-lane (256-bit) instructions, not a time: memory
latency, gathers and caches, which make one host's ratios differ from another's, are not in it.

Prints a table per technique and resolution (the measured frames' median, the lower middle one
of an even count; the warm-up frames are counted too, and left out), with the ratio of
`--against`'s count to each row's (how many times less work than it, `jit` and `jit + driver`),
and writes DIR/work.json. Without --against the first technique is the base. The bench's own
native row is in the table as well.

A 320x180 frame of `deferred:vpls=1024` on the demo takes about 40 s under callgrind, a 1280x720
one about 10 minutes (a 7 G and a 110 G instruction frame)."""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARKER = "*counted_frame*"


def classify(obj):
    """The part an object's instructions count in: jit, driver, llvm or host."""
    if obj in ("???", ""):
        return "jit"
    base = os.path.basename(obj)
    if base.startswith("libvulkan_lvp") or base.startswith("libvulkan.so"):
        return "driver"
    if base.startswith("libLLVM"):
        return "llvm"
    return "host"


def compressed_name(line, table):
    """The name of an `ob=`/`cob=` or `fn=`/`cfn=` line under callgrind's name compression:
    `(id) name` defines id in `table` (objects and functions have a table each), `(id)` alone
    refers to it."""
    m = re.match(r"c?(?:ob|fn)=(?:\((\d+)\))?\s*(.*)$", line.rstrip("\n"))
    ident, name = m.group(1), m.group(2)
    if ident is not None:
        if name:
            table[ident] = name
        else:
            name = table.get(ident, "")
    return name


def parse_dump(path):
    """(trigger, {jit, driver, llvm, host}, entries) of one callgrind dump. The parts: the self cost of
    every cost line, by the object of the function it belongs to (a call's inclusive cost line is
    not self cost). The entries: {JIT function: [calls, inclusive instructions]} of the JIT
    functions that code outside the JIT calls (the compute passes' shaders, the raster's
    fragment and setup functions), with how often lavapipe entered each (a compute pass of this
    build's: once per workgroup, so a full-resolution pass at W x H in 8 x 8 groups has
    W H / 64 calls) and its instructions inclusive of everything it calls (its texel fetch
    functions, and any libc or driver helper they call): that pass's work."""
    names = {}
    fn_names = {}
    parts = {"jit": 0, "driver": 0, "llvm": 0, "host": 0}
    self_cost = {}
    inclusive_calls = {}
    entry_calls = {}
    trigger = ""
    summary = None
    obj = ""
    fn = ""
    callee_obj = None
    callee_fn = ""
    pending_call = None  # (callee object, callee function, calls) until its cost line
    with open(path) as f:
        for line in f:
            c = line[:1]
            if c.isdigit() or c in "+-*":
                fields = line.split()
                cost = int(fields[1]) if len(fields) >= 2 else 0
                if pending_call is not None:
                    cob, cfn, n = pending_call
                    pending_call = None
                    callee_obj, callee_fn = None, ""
                    inclusive_calls[fn] = inclusive_calls.get(fn, 0) + cost
                    if classify(cob) == "jit" and classify(obj) != "jit":
                        e = entry_calls.setdefault(cfn, [0, 0])
                        e[0] += n
                    continue
                parts[classify(obj)] += cost
                if classify(obj) == "jit":
                    self_cost[fn] = self_cost.get(fn, 0) + cost
                continue
            if line.startswith("ob=") or line.startswith("cob="):
                name = compressed_name(line, names)
                if line.startswith("ob="):
                    obj = name
                else:
                    callee_obj = name
            elif line.startswith("fn=") or line.startswith("cfn="):
                name = compressed_name(line, fn_names)
                if line.startswith("fn="):
                    fn = name
                else:
                    callee_fn = name
            elif line.startswith("calls="):
                n = int(line.split("=", 1)[1].split()[0])
                pending_call = (callee_obj if callee_obj is not None else obj, callee_fn, n)
            elif line.startswith("desc: Trigger:"):
                trigger = line.split(":", 2)[2].strip()
            elif line.startswith("summary:"):
                summary = int(line.split()[1])
    # The parts must add up to callgrind's own total of the dump: a cost line counted twice or
    # missed (a call's inclusive line taken as self cost) shows here.
    if summary is not None and sum(parts.values()) != summary:
        sys.exit(f"{path}: the objects' instructions add up to {sum(parts.values())}, "
                 f"callgrind's summary says {summary}")
    for name, e in entry_calls.items():
        e[1] = self_cost.get(name, 0) + inclusive_calls.get(name, 0)
    return trigger, parts, entry_calls


def frame_dumps(prefix):
    """The per-frame dumps, in the order they were written: those the frame's end triggered."""
    d = os.path.dirname(prefix)
    base = os.path.basename(prefix)
    files = []
    for name in os.listdir(d):
        m = re.fullmatch(re.escape(base) + r"\.(\d+)", name)
        if m:
            files.append((int(m.group(1)), os.path.join(d, name)))
    out = []
    for _, path in sorted(files):
        trigger, parts, entries = parse_dump(path)
        if trigger.endswith("counted_frame_end"):
            parts["entries"] = entries
            out.append(parts)
    return out


def rows_rendered(log):
    """[(config, width, height, frames rendered)] in the order the bench ran them (its log)."""
    out = []
    for line in log.splitlines():
        m = re.match(r"(\S+) (\d+)x(\d+): set up in [\d.]+ s, (\d+) frames in", line.strip())
        if m:
            out.append((m.group(1), int(m.group(2)), int(m.group(3)), int(m.group(4))))
    return out


def ratio(x):
    """A ratio for the table, or a dash where the row did no work to divide by."""
    return "–" if x is None else f"{x:.2f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("techniques", nargs="+")
    ap.add_argument("--cbr", default=os.path.join(ROOT, "target/release/cbr"))
    ap.add_argument("--shaders", help="CBR_SHADER_DIR for the run (a variant without rebuilding)")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--warmup", type=int, default=0)
    ap.add_argument("--frames", type=int, default=1)
    ap.add_argument("--against", help="the row every ratio is against (default: the first)")
    ap.add_argument("--entries", type=int, default=0,
                    help="also print each row's N costliest JIT entry points (work.json has all)")
    ap.add_argument("--keep-dumps", action="store_true",
                    help="keep callgrind's dumps and the bench's log in DIR/dumps")
    ap.add_argument("--reparse", action="store_true",
                    help="read DIR/dumps of an earlier --keep-dumps run instead of running (its "
                         "scene, techniques, size and frames, whatever the command line says)")
    ap.add_argument("-o", "--out", help="folder for work.json and the bench's output")
    a = ap.parse_args()
    against = a.against or a.techniques[0]
    if a.frames < 1:
        sys.exit("--frames must be at least 1")
    if a.reparse and not a.out:
        sys.exit("--reparse needs -o DIR (the folder of the --keep-dumps run)")
    out = a.out or tempfile.mkdtemp(prefix="work-count-")
    os.makedirs(out, exist_ok=True)
    env = dict(os.environ, LP_NUM_THREADS="0")
    env.setdefault("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json")
    if a.shaders:
        env["CBR_SHADER_DIR"] = os.path.abspath(a.shaders)
    cmd = None
    dumps = os.path.join(out, "dumps")
    saved = ("scene", "techniques", "width", "height", "warmup", "frames", "shaders")
    if a.reparse:
        # The kept dumps of an earlier run (--keep-dumps): its arguments, log and callgrind files.
        try:
            with open(os.path.join(dumps, "args.json")) as f:
                args = json.load(f)
            with open(os.path.join(dumps, "bench.log")) as f:
                log = f.read()
            with open(os.path.join(dumps, "command")) as f:
                cmd = f.read().split("\0")
        except OSError as e:
            sys.exit(f"--reparse: {e} (run once with --keep-dumps -o {out})")
        for k in saved:
            setattr(a, k, args[k])
        against = a.against or a.techniques[0]
        frames = frame_dumps(os.path.join(dumps, "callgrind.out"))
    else:
        if a.keep_dumps:
            os.makedirs(dumps, exist_ok=True)
            for name in os.listdir(dumps):
                os.remove(os.path.join(dumps, name))
        tmp = dumps if a.keep_dumps else tempfile.mkdtemp(prefix="work-count-", dir=out)
        try:
            prefix = os.path.join(tmp, "callgrind.out")
            cmd = ["valgrind", "--tool=callgrind", "--smc-check=all-non-file",
                   f"--dump-before={MARKER}",
                   f"--callgrind-out-file={prefix}", a.cbr, "bench", a.scene,
                   "--width", str(a.width), "--height", str(a.height),
                   "--warmup", str(a.warmup), "--frames", str(a.frames),
                   "--timing-only", "--no-cache", "--techniques", ",".join(a.techniques),
                   "-o", os.path.join(out, "bench")]
            p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
            if p.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr[-3000:]}")
            log = p.stdout + "\n" + p.stderr
            # The counts are lavapipe's: refuse another device (VK_DRIVER_FILES set elsewhere).
            with open(os.path.join(out, "bench", "bench.json")) as f:
                device = json.load(f).get("device") or {}
            if device.get("driver_name") != "llvmpipe":
                sys.exit(f"the bench ran on {device.get('name')!r}, not lavapipe: the counts "
                         f"are of lavapipe's JIT code (unset VK_DRIVER_FILES or point it at "
                         f"lvp_icd)")
            if a.keep_dumps:
                with open(os.path.join(dumps, "bench.log"), "w") as f:
                    f.write(log)
                with open(os.path.join(dumps, "command"), "w") as f:
                    f.write("\0".join(cmd))
                with open(os.path.join(dumps, "args.json"), "w") as f:
                    json.dump({k: getattr(a, k) for k in saved}, f)
            frames = frame_dumps(prefix)
        finally:
            if not a.keep_dumps:
                shutil.rmtree(tmp, ignore_errors=True)
    rows = rows_rendered(log)
    if not rows:
        sys.exit("the bench's log names no configuration (its 'set up in' lines)")
    if sum(r[3] for r in rows) != len(frames):
        sys.exit(f"{len(frames)} frame dumps for {sum(r[3] for r in rows)} rendered frames "
                 f"({rows}): is the binary built with `counted_frame`?")
    results = []
    k = 0
    for name, w, h, n in rows:
        mine = frames[k:k + n]
        k += n
        measured = mine[-a.frames:]
        entry = {"spec": name, "width": w, "height": h, "frames_rendered": n,
                 "frames_counted": len(measured)}
        for part in ("jit", "driver", "llvm", "host"):
            entry[part] = statistics.median_low(f[part] for f in measured)
            entry[part + "_per_frame"] = [f[part] for f in mine]
        # The JIT entry points of the median frame: one per dispatch or raster function.
        median = next(f for f in measured if f["jit"] == entry["jit"])
        entry["jit_entries"] = [
            {"function": fn, "calls": c, "inclusive": inc}
            for fn, (c, inc) in sorted(median["entries"].items(), key=lambda e: -e[1][1])]
        results.append(entry)
    base = next((r for r in results if r["spec"] == against), None)
    if base is None:
        sys.exit(f"--against {against}: not a row ({[r['spec'] for r in results]})")
    for r in results:
        r["jit_ratio"] = base["jit"] / r["jit"] if r["jit"] else None
        both = r["jit"] + r["driver"]
        r["jit_driver_ratio"] = (base["jit"] + base["driver"]) / both if both else None
    doc = {
        "what": "instructions per frame under callgrind (valgrind's CPU: AVX2), llvmpipe on the "
                "calling thread; jit = lavapipe's JIT code (deterministic), driver = "
                "libvulkan_lvp.so and the loader, llvm = shaders compiled at first use, host = "
                "the rest of the frame's call (libc's fills and copies among it); the "
                "median of the measured frames (the lower middle one of an even count)",
        "command": cmd,
        "scene": a.scene,
        "warmup": a.warmup,
        "frames": a.frames,
        "against": against,
        "shaders": os.path.abspath(a.shaders) if a.shaders else None,
        "rows": results,
    }
    path = os.path.join(out, "work.json")
    with open(path + ".tmp", "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(path + ".tmp", path)
    print(f"{a.scene}, {a.width}x{a.height}, {a.warmup} warm-up + {a.frames} counted frame(s), "
          f"instructions per frame (G), ratios: {against} over the row")
    print("| spec | jit | driver | llvm | host | x less jit work | x less jit + driver |")
    print("|---|---|---|---|---|---|---|")
    for r in results:
        print(f"| `{r['spec']}` | {r['jit'] / 1e9:.3f} | {r['driver'] / 1e9:.3f} | "
              f"{r['llvm'] / 1e9:.3f} | {r['host'] / 1e9:.3f} | {ratio(r['jit_ratio'])} | "
              f"{ratio(r['jit_driver_ratio'])} |")
    for r in results if a.entries else []:
        print(f"\n`{r['spec']}`: the JIT entry points of its median frame (calls: how often "
              f"lavapipe entered each, a compute pass once per workgroup), instructions "
              f"inclusive of what they call, their texel fetches among it")
        print("| function | calls | instructions (G) | share of jit |")
        print("|---|---|---|---|")
        for e in r["jit_entries"][:a.entries]:
            print(f"| {e['function']} | {e['calls']} | {e['inclusive'] / 1e9:.3f} | "
                  f"{e['inclusive'] / r['jit']:.3f} |")
    print(f"written: {path}")


if __name__ == "__main__":
    main()
