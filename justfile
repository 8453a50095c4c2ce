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

# The demo: native frames of the built-in scene's camera path (960x540), then a bench at 320x180
# against the 256-sample ground truth (ssaa:16; frames 2-4 measured: each costs 256 native
# rasters, ~37 s on lavapipe, cached in out/demo/cache) of native, msaa:4, checkerboard (rotated
# and split with `ours`, rotated with `pq4k`), bilinear upscale, FXAA, TAA, checkerboard + TAA
# chained and fused, then the HTML report.
demo: setup
    @echo "[demo] native frames of builtin:demo (16 frames, 960x540) -> {{out}}/demo/native"
    ./target/release/cbr render builtin:demo --technique native -o {{out}}/demo/native
    @echo "[demo] bench at 320x180 against ssaa:16 (frames 2-4; ~2 min on 2 cores, cached after)"
    CBR_CACHE_DIR={{out}}/demo/cache ./target/release/cbr bench builtin:demo --width 320 --height 180 --warmup 2 --frames 3 --reference ssaa:16 --techniques native,msaa:4,checkerboard:rotated:ours,checkerboard:split:ours,checkerboard:rotated:pq4k,upscale:bilinear,native+fxaa,native+taa,checkerboard:rotated:ours+taa,checkerboard:rotated:fused -o {{out}}/demo/bench
    ./target/release/cbr report {{out}}/demo/bench -o {{out}}/demo/report.html
    @echo "[demo] report: $(realpath {{out}}/demo/report.html)"

# The standard benchmark set (DESIGN.md protocol: 4 warm-up + 50 measured frames, 1280x720):
# three scenes, eight configurations; bench.json/csv under {{out}}/bench/standard, the report
# next to them, and the tables in docs/results.md.
bench: setup
    for s in builtin:demo scenes/sibenik.toml scenes/foliage.toml; do \
        n=$(basename "$s" .toml | sed 's/builtin://'); \
        ./target/release/cbr bench "$s" --width 1280 --height 720 --warmup 4 --frames 50 \
            --techniques native,checkerboard:rotated:ours,checkerboard:split:ours,checkerboard:rotated:ours:prepass,checkerboard:rotated:pq4k,checkerboard:split:pq4k,upscale:bilinear,upscale:bicubic \
            -o {{out}}/bench/standard/$n || exit 1; \
    done
    ./target/release/cbr report {{out}}/bench/standard/*/ -o {{out}}/bench/standard/report.html
    python3 scripts/results-md.py {{out}}/bench/standard/*/bench.json > docs/results.md
    @echo "[bench] docs/results.md, $(realpath {{out}}/bench/standard/report.html)"
    @echo "[bench] anti-aliasing: every technique against native and ssaa:16 -> docs/antialiasing.md"
    python3 scripts/antialiasing.py --cbr ./target/release/cbr -o {{out}}/bench/aa
    @echo "[bench] temporal anti-aliasing: FXAA, TAA, checkerboard + TAA against ssaa:16, cost at 1280x720 -> docs/post-aa.md"
    python3 scripts/post-aa.py --cbr ./target/release/cbr -o {{out}}/bench/post-aa
    @echo "[bench] analytic coverage AA against ssaa:32 (demo and Sibenik at 320x180) -> docs/analytic.md"
    just bench-analytic
    @echo "[bench] interleaved many-light shading against every VPL at every pixel -> docs/interleaved.md"
    just bench-interleaved

# analytic coverage AA (its default mask of 64 samples, and 32 and 128; `aniso`: the single anisotropic texture filter in place of the box), its seed shortcut and the
# sample-based techniques against the 1024-sample ground truth (ssaa:32: ~3 min a frame of the
# demo at 320x180 on lavapipe, cached in out/cache); ssaa:16 is rendered and timed in the same run
# (--time-cached-rows), and so is a supersampling ladder (ssaa:6 ... ssaa:12) on which each row's
# edge error is placed (bench.json's equal_error_ssaa: the ssaa:N of equal error and its frame
# time). The demo and the demo without textures (geometric aliasing alone), frames
# 1-2; Sibenik and Sibenik without textures, frame 0 (each ssaa:32 frame about 2.5 min), all at
# 320x180; then Sibenik's frame times alone, warm (one warm-up frame, two measured), at 160x90 and
# 320x180.
bench-analytic: setup
    for s in builtin:demo scenes/demo-untextured.toml; do \
        n=$(basename "$s" .toml | sed 's/builtin://'); \
        CBR_CACHE_DIR={{out}}/cache ./target/release/cbr bench "$s" --width 320 --height 180 --warmup 1 --frames 2 --reference ssaa:32 --time-cached-rows --techniques native,msaa:4,ssaa:6,ssaa:8,ssaa:10,ssaa:12,ssaa:16,analytic,analytic:samples=32,analytic:samples=128,analytic:aniso,analytic:seed -o {{out}}/bench/analytic/$n || exit 1; \
    done
    for s in sibenik sibenik-untextured; do \
        CBR_CACHE_DIR={{out}}/cache ./target/release/cbr bench scenes/$s.toml --width 320 --height 180 --warmup 0 --frames 1 --reference ssaa:32 --time-cached-rows --techniques native,msaa:4,ssaa:6,ssaa:8,ssaa:10,ssaa:12,ssaa:16,analytic,analytic:samples=32,analytic:samples=128,analytic:aniso,analytic:seed -o {{out}}/bench/analytic/$s || exit 1; \
    done
    for r in 160x90 320x180; do \
        CBR_CACHE_DIR={{out}}/cache ./target/release/cbr bench scenes/sibenik.toml --width ${r%x*} --height ${r#*x} --warmup 1 --frames 2 --time-cached-rows --techniques native,ssaa:16,analytic,analytic:samples=32,analytic:samples=128,analytic:aniso -o {{out}}/bench/analytic/sibenik-time-$r || exit 1; \
    done
    python3 scripts/analytic-table.py {{out}}/bench/analytic/demo/bench.json {{out}}/bench/analytic/demo-untextured/bench.json {{out}}/bench/analytic/sibenik/bench.json {{out}}/bench/analytic/sibenik-untextured/bench.json {{out}}/bench/analytic/sibenik-time-160x90/bench.json {{out}}/bench/analytic/sibenik-time-320x180/bench.json

# Interleaved many-light shading (docs/interleaved.md): every VPL at every pixel
# (deferred:vpls=1024, the reference; ~3 s a frame at 1280x720 on lavapipe, cached in out/cache)
# against interleaved:4x4 with each filter, implicit, exact-edges, direct (the point lights
# interleaved too) with four filters, and the split+gather copy floor, on the demo
# and Sibenik at 1280x720 (1 warm-up + 2 frames); then the sweep over M x N (2x2, 4x4, 8x8) and
# the VPL count (256, 1024, 4096) on the demo at 320x180 against deferred:vpls=4096, with its
# report (the speed-vs-error chart). The tables: scripts/interleaved-table.py.
bench-interleaved: setup
    for s in builtin:demo scenes/sibenik.toml; do \
        n=$(basename "$s" .toml | sed 's/builtin://'); \
        CBR_CACHE_DIR={{out}}/cache ./target/release/cbr bench "$s" --width 1280 --height 720 --warmup 1 --frames 2 --reference deferred:vpls=1024 --techniques deferred,interleaved:4x4:floor,interleaved:4x4:implicit,interleaved:4x4:seed,interleaved:4x4:box,interleaved:4x4:none,interleaved:4x4:enough=8,interleaved:4x4:exact-edges,interleaved:4x4:exact-edges=2,interleaved:4x4:direct,interleaved:4x4:direct:seed,interleaved:4x4:direct:box,interleaved:4x4:direct:none,interleaved:4x4:direct:enough=8 -o {{out}}/bench/interleaved/$n || exit 1; \
    done
    CBR_CACHE_DIR={{out}}/cache ./target/release/cbr bench builtin:demo --width 320 --height 180 --warmup 1 --frames 2 --reference deferred:vpls=4096 --techniques deferred:vpls=256,deferred:vpls=1024,interleaved:2x2:vpls=256,interleaved:4x4:vpls=256,interleaved:8x8:vpls=256,interleaved:2x2:vpls=1024,interleaved:4x4:vpls=1024,interleaved:8x8:vpls=1024,interleaved:2x2:vpls=4096,interleaved:4x4:vpls=4096,interleaved:8x8:vpls=4096,interleaved:4x4:vpls=1024:seed,interleaved:4x4:vpls=1024:box -o {{out}}/bench/interleaved/sweep
    ./target/release/cbr report {{out}}/bench/interleaved/sweep -o {{out}}/bench/interleaved/sweep/report.html
    python3 scripts/interleaved-table.py {{out}}/bench/interleaved/demo/bench.json {{out}}/bench/interleaved/sibenik/bench.json {{out}}/bench/interleaved/sweep/bench.json
    @echo "[bench-interleaved] the sweep's report: $(realpath {{out}}/bench/interleaved/sweep/report.html)"

# Issue 57: `interleaved:4x4:vpls=1024` against `deferred:vpls=1024` on four scenes of different
# edge density at 320x180 and 1280x720, with the lighting pass attributed by part and pixel class
# and the code before the change in the same run (scripts/interleaved-cost.sh); then the tables.
bench-interleaved-cost tag="1": setup
    scripts/interleaved-cost.sh {{tag}} {{out}}
    python3 scripts/interleaved-table.py {{out}}/bench/ic-{{tag}}/*/bench.json

# Issue 57's goal in instructions (docs/interleaved.md, "Issue 57 in instructions"): lavapipe's JIT
# work per frame under callgrind (scripts/work-count.py), the same on any host, for the reference,
# `search=1` and the near-side depth band on four scenes. At 1280x720 about 75 minutes of one core
# (the reference's frame is 110-190 G instructions); `just interleaved-work 320 180` in about 15.
interleaved-work width="1280" height="720": setup
    for s in builtin:demo scenes/sibenik.toml scenes/foliage.toml scenes/specular-sun.toml; do \
        n=$(basename "$s" .toml | sed 's/builtin://'); \
        python3 scripts/work-count.py "$s" deferred:vpls=1024 interleaved:4x4:vpls=1024:search=1 interleaved:4x4:vpls=1024:exact-edges=2:band=depth:contrast=0.1:side=near:search=1 --width {{width}} --height {{height}} --entries 8 -o {{out}}/work/interleaved-$n-{{width}}x{{height}} || exit 1; \
    done

# The floor of FSR 2's passes on lavapipe (docs/upsampling.md, "The floor of FSR 2's passes"):
# `native,taau` at 1280x720 with the shipped accumulation and two stripped ones (through
# CBR_SHADER_DIR; measurements only, 3 runs, about a minute).
# The taau passes' floor against native's frame at 1280x720 on lavapipe (about a minute).
taau-floor: setup
    python3 scripts/taau-floor.py --runs 3 -o {{out}}/taau-floor

# The `taau` passes against `native`'s frame in instructions (docs/upsampling.md, the cost goal):
# 1280x720, 2 warm-up frames and one counted; about 10 minutes.
taau-work: setup
    python3 scripts/work-count.py builtin:demo native taau taau:0.5 native+taa upscale:fsr1 --against native --width 1280 --height 720 --warmup 2 --frames 1 --entries 12 -o {{out}}/work/taau

# Instructions per resolved pixel of each resolve mode's CPU reference under callgrind: a cost
# figure that does not move with the machine's load (docs/resolve.md).
resolve-cost:
    scripts/resolve-cost.sh

# The resolve shader's own instructions in lavapipe's JIT code under callgrind (demo, 256x144,
# 3 frames; about 1.5 min a technique): `ours` and `pq4k` in both thread mappings
# (docs/resolve.md, "A deterministic cost figure").
resolve-jit-cost: setup
    python3 scripts/resolve-jit-cost.py checkerboard:rotated:ours checkerboard:rotated:pq4k checkerboard:rotated:ours:pixel checkerboard:rotated:pq4k:pixel

# GPU evidence without a GPU (docs/gpu-isa.md): every pipeline compiled by ACO on RADV's null
# device for AMD families, the cost model's check against the Stadia write-up, the resolve
# matrix, modelled frames and the every-technique run, into out/gpu-isa (about 10 min on 2 cores).
gpu-isa: setup
    scripts/gpu-isa.sh {{out}}/gpu-isa

# The hard-case gallery (docs/hard-cases.md): every technique on every built-in hard case
# (`cbr info` lists them) at 320x180 against ssaa:16 (cached in out/cache; ~25 min cold on 2
# cores), strips by `cbr montage` into docs/images/hard-cases/.
hard-cases: setup
    CBR_CACHE_DIR={{out}}/cache python3 scripts/hard-cases.py --cbr ./target/release/cbr -o {{out}}/hard-cases --docs docs

# Checkerboard against temporal upsampling (`taau`) and FSR 1 at equal shading
# (docs/upsampling.md): the demo, Šibenik and foliage (still and moving cameras) and the moving
# hard cases at 320x180 against ssaa:16 (cached in out/cache), strips and charts into
# docs/images/upsampling/, and the 1280x720 cost run.
bench-upsampling: setup
    CBR_CACHE_DIR={{out}}/cache python3 scripts/bench-upsampling.py --cbr ./target/release/cbr -o {{out}}/bench/upsampling --docs docs

# The stability figures of docs/hard-cases.md (far from the origin, reverse-Z, 1000-frame drift).
stability:
    cargo test --release -p cbr-render --test stability -- --nocapture --test-threads 1
    CBR_DRIFT_FRAMES=1000 cargo test --release -p cbr-render --test stability drift -- --nocapture

# Format check, clippy, then the whole test suite on lavapipe with validation on.
test: lint
    @echo "[test] cargo test --workspace (GPU tests on ${VK_DRIVER_FILES:-the default Vulkan device}, validation layers on)"
    cargo test --workspace --no-fail-fast

# Issue 17's GPU study, prepared here for a session that is lent the GPU machine (docs/resolve.md,
# "The GPU study"): packs the release and test binaries, ../shared and Debian's Vulkan loader and
# validation layers into .gpu/ (git-ignored, about 25 MiB) for the device tool to carry; there,
# `bash scripts/gpu-study.sh` runs the test suite and the timing-only benches in one command.
gpu-pack:
    scripts/gpu-pack.sh

# The GPU study's script end to end on this machine's device at tiny sizes, in a copy of the tree
# the way the device tool sends it, with /work hidden (a private mount namespace, tmpfs over it:
# as root), so that the packed binaries, the link of the path they were built under and the
# unpacked ../shared are what runs, not this checkout (after `just gpu-pack`; about 2 minutes on
# lavapipe).
gpu-study-dry-run:
    #!/usr/bin/env bash
    set -euo pipefail
    [ -f .gpu/bins.tar.xz ] || { echo "run just gpu-pack first" >&2; exit 1; }
    d=$(mktemp -d); mkdir -p "$d/repo"
    git ls-files -z --cached --others --exclude-standard | xargs -0 -I{} cp --parents {} "$d/repo/"
    cp -r .gpu "$d/repo/"
    hide=$(dirname "$(cat .gpu/root.txt)")
    unshare -m bash -c "mount -t tmpfs none '$hide' && cd '$d/repo' && CBR_GPU_STUDY_QUICK=1 CBR_GPU_STUDY_TESTS='layouts|msaa|timestamps|real_scenes|cli' OUT='$d/OUT' bash scripts/gpu-study.sh"
    cat "$d/OUT/gpu-study.md"
    echo "[gpu-study-dry-run] $d/OUT"

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
    python3 scripts/bench-resolve.py moving --cbr ./target/release/cbr -o {{out}}/bench/resolve

# Formatting.
fmt:
    cargo fmt --all

# Format check and clippy with warnings as errors.
lint:
    cargo fmt --all -- --check
    cargo clippy --workspace --all-targets -- -D warnings
    python3 scripts/import-cycles.py crates/cbr-render/src

# Fuzz the loaders of untrusted files, each for SECONDS one after the other, one process each:
# obj (OBJ + MTL + texture, in memory), scene_toml, texture, image_input (`cbr compare`'s EXR/PNG
# reader). cargo-fuzz (libFuzzer + AddressSanitizer) wants nightly flags; RUSTC_BOOTSTRAP=1 lets
# stable Rust take them. Seeds: fuzz/seeds/TARGET; new inputs: fuzz/corpus/TARGET; a crash or hang
# (-timeout=10 s per input) stops the recipe and leaves its input in fuzz/artifacts/TARGET.
# Needs `cargo install cargo-fuzz`. Numbers of the last long runs: docs/fuzzing.md.
fuzz SECONDS="60":
    cd fuzz && for t in obj scene_toml texture image_input; do \
        mkdir -p corpus/$t; \
        echo "[fuzz] $t for {{SECONDS}} s"; \
        RUSTC_BOOTSTRAP=1 cargo fuzz run -O $t corpus/$t seeds/$t -- \
            -max_total_time={{SECONDS}} -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 || exit 1; \
        echo "[fuzz] $t: corpus $(ls corpus/$t | wc -l) files"; \
    done

# docs/cluster.md's measurement: the sweep of scripts/cluster-study.toml (2 scenes x 6
# configurations against ssaa:8) unsharded, then as a 4-task Slurm array with its merge and
# report on a one-node Slurm the test starts on this machine (as root, slurm-wlm and munge
# installed); prints both wall times and the shards' estimated costs.
cluster-study:
    CBR_SLURM_STUDY=$(realpath scripts/cluster-study.toml) cargo test -p cbr --test shards a_slurm_array -- --nocapture
