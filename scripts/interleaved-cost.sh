#!/bin/bash
# Issue 57 (docs/interleaved.md, "Where the lighting pass's time goes"): `interleaved:4x4:vpls=1024`
# against `deferred:vpls=1024` on four scenes of different edge density (the demo, Sibenik,
# foliage, and the gallery's `specular` under a sun and 24 point lights) at 320x180 and 1280x720.
# Each run holds the reference (at 320x180 also without its light culling, `cull=0`), the default
# `interleaved`, the code before 2026-11-28 (`fallback=inline:window=fetch:cull=0`, the same
# frame), `exact-edges`, `search=1` and `exact-edges=2:band=object:search=1` (issue 57, part 2;
# `interleaved-goals.py ... --spec` tabulates them), both interleaved variants' `parts=` rows (the lighting pass by part) and
# a `:debug` row (the pixel classes). `uptime` is written beside each run: lavapipe's times are
# only comparable within a run. Usage: scripts/interleaved-cost.sh TAG [OUT] (then
# python3 scripts/interleaved-table.py OUT/bench/ic-TAG/*/bench.json).
set -e
tag=${1:?usage: interleaved-cost.sh TAG [OUT]}
out=${2:-out}
B=interleaved:4x4:vpls=1024
OLD=$B:fallback=inline:window=fetch:cull=0
T=$B,$OLD,$B:exact-edges,$B:search=1,$B:exact-edges=2:band=object:search=1,$B:parts=base,$B:parts=lights,$B:parts=filter,$OLD:parts=base,$OLD:parts=lights,$OLD:parts=filter,$B:debug
for r in 320x180 1280x720; do
    # 320x180: 6 measured frames and the reference without its light culling too; 1280x720: 3.
    case $r in
        320x180) frames=6; refs=deferred:vpls=1024,deferred:vpls=1024:cull=0 ;;
        *) frames=3; refs=deferred:vpls=1024 ;;
    esac
    for s in builtin:demo scenes/sibenik.toml scenes/foliage.toml scenes/specular-sun.toml; do
        n=$(basename "$s" .toml | sed 's/builtin://')
        o=$out/bench/ic-$tag/$n-$r
        mkdir -p "$o"
        uptime > "$o/uptime-before.txt"
        CBR_CACHE_DIR=${CBR_CACHE_DIR:-$out/cache} ./target/release/cbr bench "$s" \
            --width "${r%x*}" --height "${r#*x}" --warmup 1 --frames $frames \
            --reference deferred:vpls=1024 --techniques "$refs,$T" -o "$o" > "$o/log.txt" 2>&1
        uptime > "$o/uptime-after.txt"
        echo "$n $r: $(cat "$o/uptime-after.txt")"
    done
done
