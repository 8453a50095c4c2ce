# cbr's recipes. Run them through ./dev on a fresh machine (it installs what is missing first):
#   ./dev demo    ./dev test    ./dev lint
# VK_DRIVER_FILES is pinned to lavapipe by ./dev unless set (CBR_ANY_DEVICE=1 lifts the pin).

set shell := ["bash", "-euo", "pipefail", "-c"]

out := "out"

# List the recipes.
default:
    @just --list

# Build the release binary (after ./dev has installed the system packages).
setup:
    cargo build --release -p cbr

# Render the built-in demo's camera path: EXR + PNG per frame and run.json under out/demo/native.
demo: setup
    @echo "[demo] rendering builtin:demo (16 frames, 960x540) with the native technique"
    ./target/release/cbr render builtin:demo --technique native -o {{out}}/demo/native
    @echo "[demo] done: {{out}}/demo/native (frame_*.exr, frame_*.png, run.json)"

# Format check, clippy, then the whole test suite on lavapipe with validation on.
test: lint
    @echo "[test] cargo test --workspace (GPU tests on ${VK_DRIVER_FILES:-the default Vulkan device}, validation layers on)"
    cargo test --workspace --no-fail-fast

# Criterion benchmarks of the metrics on 1080p pairs, then peak memory on a 4K HDR pair
# (figures in docs/metrics.md).
bench-metrics: setup
    cargo bench -p cbr-metrics --bench metrics
    scripts/metrics-memory.sh ./target/release/cbr

# Checkerboard layouts against native: raster time, invocations, memory (docs/checkerboard-layouts.md).
bench-layouts: setup
    python3 scripts/bench-layouts.py --cbr ./target/release/cbr -o {{out}}/bench/layouts

# The resolve: quality against native over camera paths (every mode, layouts, upscale) and cost at
# 1080p per thread mapping and group size next to a copy-kernel floor (docs/resolve.md).
bench-resolve: setup
    python3 scripts/bench-resolve.py cost --cbr ./target/release/cbr -o {{out}}/bench/resolve
    python3 scripts/bench-resolve.py quality --cbr ./target/release/cbr -o {{out}}/bench/resolve

# Formatting.
fmt:
    cargo fmt --all

# Format check and clippy with warnings as errors.
lint:
    cargo fmt --all -- --check
    cargo clippy --workspace --all-targets -- -D warnings
