#!/usr/bin/env bash
# Records the golden EXRs of references/goldens/configs.txt with a cbr binary (default
# ./target/release/cbr): builtin:demo, 96x54, frames 0-2, lavapipe. Only the EXRs are kept.
# The test crates/cbr/tests/goldens.rs renders the same configurations and compares every layer
# bit for bit. Re-record only when a change is meant to alter the pixels, and say so in the commit.
set -euo pipefail
cd "$(dirname "$0")/.."
cbr=${1:-./target/release/cbr}
root=references/goldens
grep -v '^#' "$root/configs.txt" | while IFS=$'\t' read -r name spec flags; do
  [ -n "$name" ] || continue
  tmp=$(mktemp -d)
  # shellcheck disable=SC2086
  "$cbr" render builtin:demo --width 96 --height 54 --frames 3 $flags -o "$tmp" >/dev/null
  rm -rf "${root:?}/$name"; mkdir -p "$root/$name"
  cp "$tmp"/frame_000?.exr "$root/$name/"
  rm -rf "$tmp"
  echo "$name ($spec): $(du -sh "$root/$name" | cut -f1)"
done
