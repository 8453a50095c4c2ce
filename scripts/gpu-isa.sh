#!/bin/bash
# The measurements of docs/gpu-isa.md: `cbr gpu-stats` runs (RADV's null device per AMD family,
# the frame traced on lavapipe) and their tables (scripts/gpu-isa-tables.py).
# usage: scripts/gpu-isa.sh OUT_DIR [CBR]     (just gpu-isa)
set -euo pipefail
O=${1:-out/gpu-isa}
CBR=${2:-./target/release/cbr}
mkdir -p "$O"
T=scripts/gpu-isa-tables.py
P=checkerboard:rotated:pq4k

# 1. The check against the Stadia write-up: pq4k's resolve at 1080p, pixel/16 and quad/8.
$CBR gpu-stats --techniques $P:pixel:16,$P:quad:8 --families vega10 --width 1920 --height 1080 \
    --model-only --disassembly -o "$O/check-1080" > "$O/check-1080.txt"

# 2. Pixel against quad: every resolve mode x pixel/quad x group 8/16 x f32/fp16, GCN and RDNA 2.
S=""
for m in ours pq4k intel spatial temporal; do for map in pixel quad; do for g in 8 16; do
    for p in "" ":fp16"; do S="$S,checkerboard:rotated:$m:$map:$g$p"; done
done; done; done
$CBR gpu-stats --techniques "${S#,}" --families vega10,navi21 --width 1920 --height 1080 \
    --model-only --disassembly -o "$O/resolve" > "$O/resolve.txt"

# 3. Frames by the model: every layout's checkerboard against native on Šibenik at 1080p (the
#    checkerboard's raw-frame readback does not fit lavapipe's 128 MiB storage buffers at 4K:
#    4K is 4x, the model being linear in pixels; native at 4K is traced to show it), and the
#    questions of the earlier issues on the demo.
SIB=scenes/sibenik.toml
if [ -f ../shared/scenes/sibenik/sibenik.obj ] || [ -d ../shared/scenes ]; then
    $CBR gpu-stats $SIB --techniques native,checkerboard:masked:ours,checkerboard:split:ours,checkerboard:rotated:ours,checkerboard:msaa2x:ours,checkerboard:rotated:pq4k,checkerboard:rotated:ours+taa \
        --families polaris10,vega10,navi21,gfx1100 --width 1920 --height 1080 -o "$O/sibenik-1080" > "$O/sibenik-1080.txt"
    $CBR gpu-stats $SIB --techniques native --families vega10,navi21 --width 3840 --height 2160 \
        -o "$O/sibenik-native-4k" > "$O/sibenik-native-4k.txt"
else
    echo "../shared/scenes is absent: the Šibenik frames are skipped" >&2
fi
$CBR gpu-stats builtin:demo --techniques analytic,ssaa:16,msaa:4 --families vega10,navi21 \
    --width 320 --height 180 -o "$O/analytic-320" > "$O/analytic-320.txt"
$CBR gpu-stats builtin:demo --techniques deferred:vpls=1024,interleaved:4x4:vpls=1024,interleaved:4x4:vpls=1024:direct \
    --families vega10,navi21 --width 1280 --height 720 -o "$O/interleaved-720" > "$O/interleaved-720.txt"

# 4. Every registered technique, layout and post pass on four families at 1080p (timed).
SP="native,ssaa:4,msaa:4,checkerboard,upscale,interlaced,analytic,deferred,interleaved:4x4,flicker"
for l in masked split rotated msaa2x; do SP="$SP,checkerboard:$l:ours"; done
for m in ours fused pq4k intel spatial temporal none; do SP="$SP,checkerboard:rotated:$m:quad:8"; done
SP="$SP,checkerboard:msaa2x:ours:locations,checkerboard:rotated:ours:prepass+taa,ssaa:2,msaa:4:sample:hdr"
SP="$SP,analytic:seed:aniso,deferred:vpls=64,interleaved:4x4:vpls=64:seed:direct:debug:floor"
SP="$SP,interleaved:3x2:vpls=48:implicit,interlaced:debug,upscale:bicubic,native+taa+sharpen,native+taa:inside+fxaa"
SP="$SP,upscale:fsr1:0.5,taau,taau:0.5:without-locks:debug"
start=$(date +%s)
$CBR gpu-stats --techniques "$SP" --width 1920 --height 1080 -o "$O/all" > "$O/all.txt"
echo "every registered technique, 4 families, 1920x1080: $(( $(date +%s) - start )) s" | tee "$O/all.time"

python3 $T check "$O/check-1080"
python3 $T resolve "$O/resolve" vega10
python3 $T resolve "$O/resolve" navi21
for d in sibenik-1080 sibenik-native-4k analytic-320 interleaved-720 all; do
    [ -f "$O/$d/gpu-stats.json" ] && python3 $T frames "$O/$d"
done
