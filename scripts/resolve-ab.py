#!/usr/bin/env python3
"""A/B the resolve's GPU time: two or more (binary, technique) entries, run in alternation.

    scripts/resolve-ab.py SCENE BIN@TECHNIQUE [BIN@TECHNIQUE ...]
                          [--width 1280 --height 720] [--frames 8] [--rounds 3] [--skip 2]
                          [--pass resolve]

Each round renders SCENE once per entry (`cbr render ... --technique TECHNIQUE`), in the order
given, so slow drifts of a shared machine fall on every entry alike; per entry it prints the
median `resolve` pass time over all rounds' frames from --skip on (the first frames reset the
history and touch textures for the first time), and its ratio to the first entry; the median over rounds of each round's ratio to the first entry
(paired, so that a drift of the machine's speed cancels: prefer many short rounds), each
round's median; and the best of the rounds: for each frame its fastest round, summed over the
frames, and that sum's ratio to the first entry's (interference only adds time, so on a shared
machine this is the steadiest of the three). Build each
version of cbr into its own file (e.g. `cp target/release/cbr /tmp/cbr-before`) and never
compile while this runs. Times are lavapipe's GPU timestamps: compare entries of one run only."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("entries", nargs="+", metavar="BIN@TECHNIQUE")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--skip", type=int, default=2)
    ap.add_argument("--pass", dest="pass_name", default="resolve",
                    help="the pass to time (e.g. interlaced.resolve)")
    a = ap.parse_args()
    if a.frames <= a.skip:
        sys.exit("--frames must exceed --skip")
    entries = []
    for e in a.entries:
        if "@" not in e:
            sys.exit(f"{e}: expected BIN@TECHNIQUE")
        entries.append(tuple(e.split("@", 1)))
    times = {e: [] for e in entries}
    rounds = {e: [] for e in entries}
    per_frame = {e: [] for e in entries}
    with tempfile.TemporaryDirectory(prefix="resolve-ab-") as tmp:
        for _ in range(a.rounds):
            for k, (cbr, technique) in enumerate(entries):
                out = os.path.join(tmp, str(k))
                cmd = [cbr, "render", a.scene, "--width", str(a.width), "--height",
                       str(a.height), "--frames", str(a.frames), "--technique", technique,
                       "-o", out]
                p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   text=True)
                if p.returncode != 0:
                    sys.exit(f"{' '.join(cmd)}: {p.stderr.strip()}")
                run = json.load(open(os.path.join(out, "run.json")))
                ms = [t["gpu_ms"] for f in run["frames"][a.skip:] for t in f["passes"]
                      if t["name"] == a.pass_name]
                if not ms:
                    sys.exit(f"{technique}: no `{a.pass_name}` pass in {out}/run.json")
                times[(cbr, technique)] += ms
                rounds[(cbr, technique)].append(statistics.median(ms))
                per_frame[(cbr, technique)].append(ms)
    first = statistics.median(times[entries[0]])
    print(f"{a.scene}, {a.width}x{a.height}, frames {a.skip}-{a.frames - 1}, {a.rounds} rounds")
    for e in entries:
        cbr, technique = e
        m = statistics.median(times[e])
        # Each round's median over the first entry's in the same round: a slow drift of the
        # machine's speed (2 cores shared with other tenants; rounds of one binary have differed
        # by 1.5x within one run) falls on both and cancels.
        paired = sorted(r / f for r, f in zip(rounds[e], rounds[entries[0]]))
        # Best of the rounds, frame by frame: interference only ever adds time, so each frame's
        # fastest round is its least disturbed measurement; summed over the frames.
        best = sum(min(f) for f in zip(*per_frame[e]))
        best_first = sum(min(f) for f in zip(*per_frame[entries[0]]))
        print(f"{cbr} {technique}: best of rounds {best:.1f} ms over {len(per_frame[e][0])} "
              f"frames, {best / best_first:.3f}x the first's")
        print(f"{cbr} {technique}: resolve median {m:.2f} ms over {len(times[e])} frames "
              f"({m / first:.2f}x the first); paired ratio to the first {statistics.median(paired):.3f} "
              f"(rounds {paired[0]:.3f}-{paired[-1]:.3f}); rounds' medians "
              + " ".join(f"{r:.1f}" for r in rounds[e]))

if __name__ == "__main__":
    main()
