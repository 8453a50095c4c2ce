#!/usr/bin/env bash
# Peak memory of `cbr compare` on a 3840x2160 HDR pair (two frames of the demo), against the
# 600 MB target of issue 3. Usage: scripts/metrics-memory.sh [cbr binary]
set -euo pipefail
cbr=${1:-./target/release/cbr}
dir=out/bench/metrics-4k
if [ ! -f "$dir/frame_0001.exr" ]; then
  echo "[metrics-memory] rendering two 3840x2160 demo frames into $dir"
  "$cbr" render builtin:demo --width 3840 --height 2160 --frames 2 -o "$dir" >/dev/null
fi
for metrics in psnr,ssim,flip,mse,relmse psnr,ssim,flip,hdrflip,mse,relmse; do
  python3 - "$cbr" "$dir" "$metrics" <<'PY'
import resource, subprocess, sys, time
cbr, d, metrics = sys.argv[1:]
t = time.time()
subprocess.run([cbr, "compare", f"{d}/frame_0000.exr", f"{d}/frame_0001.exr", "--metrics", metrics], check=True, stdout=subprocess.DEVNULL)
peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
verdict = "PASS" if peak_mb <= 600 else "FAIL"
print(f"[metrics-memory] 3840x2160 HDR pair, {metrics}: peak RSS {peak_mb:.0f} MB, {time.time() - t:.2f} s wall: {verdict} (target 600 MB)")
PY
done
