#!/usr/bin/env bash
# Packs what the GPU study (scripts/gpu-study.sh, issue 17) needs on the lent GPU machine, which
# has a GPU and its driver but no Vulkan loader, no Rust, no network and no ../shared:
#
#   .gpu/bins.tar.xz    the release `cbr`, the debug `cbr` and every test binary of `cargo test
#                       --workspace` (the ones ./dev test runs), stripped, at their target/ paths
#   .gpu/tests.txt      the test binaries: path, crate folder (cargo runs a test there) and name
#   .gpu/src-hash.txt  a hash of crates/, shaders/ and Cargo.*: the study warns when the tree differs
#   .gpu/root.txt       the checkout's path here: the binaries hold paths under it (env!), so the
#                       study links it to the device's copy of the tree
#   .gpu/shared.tar.xz  ../shared/scenes and ../shared/testdata (the real-scene tests, Sibenik)
#   .gpu/deb/           Debian 12's Vulkan loader and validation layers, unpacked there (and in
#                       deb/fallback/ its libstdc++ and libgcc, unpacked only where they are missing)
#
# .gpu/ is git-ignored; the device tool carries it (`carry: [".gpu"]`). The tree plus .gpu must
# stay under the tool's 64 MiB: this script checks it. Run it here (after ./dev has installed the
# system packages):  scripts/gpu-pack.sh   (or: just gpu-pack)
set -euo pipefail
cd "$(dirname "$0")/.."
say() { printf '[gpu-pack] %s\n' "$*" >&2; }

[ -d ../shared/scenes ] || { say "error: ../shared/scenes is absent: the study's scenes come from there"; exit 1; }
command -v xz >/dev/null || { say "error: xz is not installed (apt-get install xz-utils)"; exit 1; }

say "building the release binary and the test binaries (debug, as ./dev test builds them)"
cargo build --release -p cbr >&2
cargo build -p cbr >&2
tests_json=$(mktemp)
cargo test --workspace --no-run --message-format=json 2>/dev/null >"$tests_json"

rm -rf .gpu
mkdir -p .gpu/deb
stage=$(mktemp -d)
trap 'rm -rf "$stage" "$tests_json"' EXIT
mkdir -p "$stage/target/release" "$stage/target/debug/deps"
cp target/release/cbr "$stage/target/release/cbr"
cp target/debug/cbr "$stage/target/debug/cbr"
python3 - "$tests_json" "$stage" "$PWD" >.gpu/tests.txt <<'EOF'
import json, os, shutil, sys
src, stage, root = sys.argv[1:]
seen = set()
for line in open(src):
    m = json.loads(line)
    if m.get("reason") != "compiler-artifact" or not m.get("executable") or not m["profile"]["test"]:
        continue
    exe = m["executable"]
    if exe in seen:
        continue
    seen.add(exe)
    rel = os.path.relpath(exe, root)
    shutil.copy(exe, os.path.join(stage, rel))
    kind = m["target"]["kind"][0]
    name = m["target"]["name"] if kind == "test" else f"{m['target']['name']} (unit tests)"
    crate = os.path.relpath(os.path.dirname(m["manifest_path"]), root)
    print(f"{rel}\t{crate}\t{name}")
EOF
say "$(wc -l <.gpu/tests.txt) test binaries"
strip "$stage"/target/release/cbr "$stage"/target/debug/cbr "$stage"/target/debug/deps/*
say "compressing the binaries (xz, 256 MiB dictionary: the test binaries share most of their code)"
tar -C "$stage" -cf - target | xz -T0 --lzma2=preset=6,dict=256MiB >.gpu/bins.tar.xz
tar -C .. -cf - shared/scenes shared/testdata | xz -T0 -6 >.gpu/shared.tar.xz
say "downloading Debian's Vulkan loader, validation layers and GL vendor-neutral dispatch"
(cd .gpu/deb && apt-get download libvulkan1 vulkan-validationlayers >&2)
# NVIDIA's Vulkan driver is libGLX_nvidia.so.0, which needs libglvnd's libGLdispatch: without
# these the loader found no physical device on the H100 machine (first call, 2026-11-27).
mkdir -p .gpu/deb/glvnd
(cd .gpu/deb/glvnd && apt-get download libglvnd0 libglx0 libegl1 libgl1 libopengl0 libgles2 >&2)
# libstdc++ and libgcc for a device whose userland lacks them (used only then).
mkdir -p .gpu/deb/fallback
(cd .gpu/deb/fallback && apt-get download libstdc++6 libgcc-s1 >&2)
git rev-parse HEAD >.gpu/commit.txt
# The same list and hash as gpu-study.sh's src_hash: the files under crates/ and shaders/ and the
# Cargo files that the device tool sends (tracked, and untracked but not ignored).
git ls-files -z --cached --others --exclude-standard -- crates shaders Cargo.toml Cargo.lock \
    | xargs -0 -I{} sh -c '[ -f "$1" ] && printf "%s\n" "$1"' _ {} | LC_ALL=C sort \
    | xargs -d '\n' sha256sum | sha256sum | cut -c1-16 >.gpu/src-hash.txt
echo "$PWD" >.gpu/root.txt
git status --porcelain >.gpu/dirty.txt

tree_kib=$(git ls-files -z --cached --others --exclude-standard | du -ck --files0-from=- 2>/dev/null | tail -1 | cut -f1)
pack_kib=$(du -sk .gpu | cut -f1)
total_mib=$(( (tree_kib + pack_kib) / 1024 ))
say "packed: .gpu $(( pack_kib / 1024 )) MiB + working tree $(( tree_kib / 1024 )) MiB = ${total_mib} MiB (the device tool carries at most 64)"
if [ "$total_mib" -ge 62 ]; then
    say "error: too large to carry"
    exit 1
fi
