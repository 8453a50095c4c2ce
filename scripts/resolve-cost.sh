#!/usr/bin/env bash
# Instructions per resolved pixel of each resolve mode's CPU reference (a deterministic cost figure
# beside the noisy GPU times; docs/resolve.md): the resolve_cost example under callgrind, counting
# only its `measured` function (4 frames of 256x256 resolved against their history).
set -euo pipefail
command -v valgrind >/dev/null || { echo "error: resolve-cost needs valgrind (apt-get install valgrind)" >&2; exit 1; }
cargo build --release -p cbr-render --example resolve_cost
bin=target/release/examples/resolve_cost
printf '| mode | instructions (4 x 256x256 px) | per resolved pixel |\n|---|---|---|\n'
for mode in ${*:-ours pq4k intel spatial temporal}; do
    out=$(mktemp)
    valgrind --tool=callgrind --toggle-collect='*measured*' --callgrind-out-file="$out" "$bin" "$mode" >/dev/null 2>"$out.log"
    ir=$(grep -E '^==[0-9]+== Collected' "$out.log" | awk '{print $4}')
    printf '| `%s` | %s | %.0f |\n' "$mode" "$ir" "$(awk -v ir="$ir" 'BEGIN { print ir / (4 * 256 * 256) }')"
    rm -f "$out" "$out.log"
done
