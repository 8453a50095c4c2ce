#!/usr/bin/env bash
# Issue 17's GPU study, in one command on the lent GPU machine (docs/resolve.md, "The GPU study").
# Prepare here with scripts/gpu-pack.sh (just gpu-pack), then through the device tool:
#
#   run(command="bash scripts/gpu-study.sh", carry=[".gpu"], timeout_s=600)
#
# Stages, each with a deadline counted from the script's start (a stage that ends early leaves
# its time to the next), so that what finished comes back when a later one runs out (the tool
# allows 10 minutes a command and 15 minutes of device time a session):
#   1. unpack .gpu (binaries, ../shared, Debian's Vulkan loader and validation layers) and link the
#      paths the binaries were built under; `cbr info` of the device;
#   2. tests (until CBR_GPU_TESTS_END, default 190 s): every test binary of the workspace on the
#      GPU, validation layers on as always; the msaa2x and sample-location tests first;
#   3. bench (until CBR_GPU_BENCH_END, default 450 s): `cbr bench --timing-only` of builtin:demo at
#      3840x2160 and 1920x1080: rotated, split and (where the device has 2x MSAA) msaa2x, with and
#      without sample locations; `ours` and `pq4k` in every mapping (pixel, quad), group (8, 16)
#      and precision (fp32, fp16), the other modes at the defaults, each with its copy floor;
#      then Sibenik's frame against native at 1280x720 and 1920x1080;
#   4. goals (until CBR_GPU_GOALS_END, default 550 s): the frame-time goals of issues 14 and 15
#      that lavapipe's cost structure decides (docs/analytic.md, docs/interleaved.md), timed on
#      the GPU: interleaved:4x4 against every VPL at every pixel (deferred:vpls=1024) at 1280x720
#      on the demo and Sibenik; analytic against ssaa:16 at 320x180 and Sibenik at 160x90 too;
#   5. scripts/gpu-study-tables.py: the tables for the docs and references/README.md.
# What comes back in $OUT: gpu-study.md (the tables), tests.tsv (per test binary: passed, failed,
# skipped lines, VUID lines), study.log, results.tar.gz (every bench.json and test log).
#
# Arguments: `all` (default), `tests`, `bench` or `goals` (stage 1 always runs). CBR_GPU_STUDY_QUICK=1: a
# dry run on any device at tiny sizes (this is how the script is checked on lavapipe: `just
# gpu-study-dry-run`).
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
part=${1:-all}
quick=${CBR_GPU_STUDY_QUICK:-0}
out=${OUT:-$repo/out/gpu-study}
work=$repo/out/gpu-study-work
rm -rf "$work"
mkdir -p "$out" "$work/tests" "$work/bench"
log() { printf '[gpu-study %s] %s\n' "$(date +%T)" "$*" | tee -a "$out/study.log" >&2; }

# --- 1. unpack -------------------------------------------------------------------------------------
[ -f .gpu/bins.tar.xz ] || { log "error: .gpu/bins.tar.xz is missing: run scripts/gpu-pack.sh here first and carry .gpu"; exit 1; }
root=$(cat .gpu/root.txt)
log "pack of commit $(cat .gpu/commit.txt) built under $root; this tree: $repo ($(git rev-parse --verify -q HEAD || echo 'no commit'))"
if [ "${CBR_GPU_STUDY_KEEP_TARGET:-0}" != 1 ]; then
    tar -C "$repo" -xJf .gpu/bins.tar.xz || { log "error: cannot unpack the binaries"; exit 1; }
fi
# The binaries name files by the paths they were built under (env!("CARGO_MANIFEST_DIR"),
# CARGO_BIN_EXE_cbr); the scenes and tests read ../shared beside the checkout.
if [ "$root" != "$repo" ] && [ ! -e "$root" ]; then
    mkdir -p "$(dirname "$root")" && ln -s "$repo" "$root" && log "linked $root -> $repo"
fi
for s in "$(dirname "$repo")/shared" "$(dirname "$root")/shared"; do
    if [ ! -d "$s/scenes" ]; then
        mkdir -p "$(dirname "$s")" && tar -C "$(dirname "$s")" -xJf .gpu/shared.tar.xz && log "unpacked $s"
    fi
done
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1 '; then
    for f in .gpu/deb/libvulkan1_*.deb; do dpkg -x "$f" /; done
    ldconfig
    log "installed the Vulkan loader from .gpu/deb"
fi
if [ ! -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ]; then
    dpkg -x .gpu/deb/vulkan-validationlayers_*.deb "$work/vvl"
    export VK_LAYER_PATH=$work/vvl/usr/share/vulkan/explicit_layer.d
    export LD_LIBRARY_PATH=$work/vvl/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    log "validation layers from .gpu/deb (VK_LAYER_PATH=$VK_LAYER_PATH)"
fi
if [ -z "${VK_DRIVER_FILES:-}" ]; then
    for f in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json \
             /etc/vulkan/icd.d/nvidia_icd.json; do
        if [ -e "$f" ]; then export VK_DRIVER_FILES=$f; break; fi
    done
fi
log "VK_DRIVER_FILES=${VK_DRIVER_FILES:-<unset>}"
cbr=$repo/target/release/cbr
"$cbr" info >"$out/info.txt" 2>&1 || { log "error: cbr info failed:"; cat "$out/info.txt" >&2; exit 1; }
cp "$out/info.txt" "$work/info.txt"
cp .gpu/commit.txt "$work/commit.txt"
log "device: $(sed -n 's/^chosen: //p' "$out/info.txt"); $(grep -m1 'driver:' "$out/info.txt" | sed 's/^ *//')"
nproc=$(nproc)

# --- 2. tests --------------------------------------------------------------------------------------
run_tests() {
    local end=${CBR_GPU_TESTS_END:-190}
    printf 'test\tstatus\tpassed\tfailed\tskipped_lines\tvuid_lines\tseconds\n' >"$work/tests.tsv"
    # The GPU-only checks first (msaa2x, sample locations, 2x MSAA), then the rest in pack order.
    local list
    list=$( (grep -P '\t(layouts|msaa|resolve|timestamps)$' .gpu/tests.txt; grep -vP '\t(layouts|msaa|resolve|timestamps)$' .gpu/tests.txt) )
    [ -n "${CBR_GPU_STUDY_TESTS:-}" ] && list=$(grep -P "\t(${CBR_GPU_STUDY_TESTS})\$" <<<"$list")
    while IFS=$'\t' read -r bin crate name; do
        [ -n "$bin" ] || continue
        local left=$((end - SECONDS)) safe="$(basename "$crate")-${name// /_}"
        safe=${safe//[()]/}
        name="$(basename "$crate") $name"
        if [ "$left" -le 5 ]; then
            printf '%s\tnot run (test budget spent)\t\t\t\t\t\n' "$name" >>"$work/tests.tsv"
            continue
        fi
        local t0=$SECONDS rc
        (cd "$root/$crate" && CARGO_MANIFEST_DIR=$root/$crate timeout "$left" "$root/$bin" --test-threads="$nproc" --nocapture) \
            >"$work/tests/$safe.log" 2>&1
        rc=$?
        local passed failed status
        passed=$(grep -oP 'test result: \w+\. \K[0-9]+(?= passed)' "$work/tests/$safe.log" | awk '{s+=$1} END {print s+0}')
        failed=$(grep -oP '[0-9]+(?= failed;)' "$work/tests/$safe.log" | awk '{s+=$1} END {print s+0}')
        case $rc in 0) status=ok ;; 124) status="timed out" ;; *) status="rc $rc" ;; esac
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$status" "${passed:-0}" "${failed:-0}" \
            "$(grep -c 'SKIPPED' "$work/tests/$safe.log")" "$(grep -c 'VUID' "$work/tests/$safe.log")" \
            "$((SECONDS - t0))" >>"$work/tests.tsv"
        log "test $name: $status (${passed:-0} passed, ${failed:-0} failed) in $((SECONDS - t0)) s"
    done <<<"$list"
    cp "$work/tests.tsv" "$out/tests.tsv"
}

# --- 3. bench --------------------------------------------------------------------------------------
can() { grep -qP "^  $1 +yes" "$out/info.txt"; }
run_bench() {
    local big=3840x2160 hd=1920x1080 sib="1280x720,1920x1080"
    [ "$quick" = 1 ] && big=128x72 hd=64x36 sib=64x36
    local layouts="rotated split" core=() modes=()
    can msaa2x && layouts="msaa2x $layouts"
    for l in $layouts; do
        for m in ours pq4k; do core+=("checkerboard:$l:$m" "checkerboard:$l:$m:fp16"); done
        for m in intel spatial temporal; do modes+=("checkerboard:$l:$m"); done
    done
    if can 'msaa2x --msaa2x-sample-locations'; then
        for m in ours pq4k; do core+=("checkerboard:msaa2x:$m:locations"); done
    fi
    local core_csv modes_csv
    core_csv=$(IFS=,; echo "${core[*]}")
    modes_csv=$(IFS=,; echo "${modes[*]}")
    # name | scene | resolutions | techniques | extra
    local runs=(
        "core-$big|builtin:demo|$big|$core_csv|--mappings pixel,quad --groups 8,16"
        "core-$hd|builtin:demo|$hd|$core_csv|--mappings pixel,quad --groups 8,16"
        "modes-$big|builtin:demo|$big|$modes_csv|"
        "modes-$hd|builtin:demo|$hd|$modes_csv|"
        "sibenik|scenes/sibenik.toml|$sib|checkerboard:rotated:ours,checkerboard:split:ours,checkerboard:rotated:pq4k$(can msaa2x && echo ,checkerboard:msaa2x:ours)|"
    )
    bench_runs "${CBR_GPU_BENCH_END:-450}" "${runs[@]}"
}

# Runs `cbr bench --timing-only` for each "name|scene|resolutions|techniques|extra flags" until
# the deadline (seconds since the script's start).
bench_runs() {
    local end=$1 warmup=2 frames=8
    shift
    [ "$quick" = 1 ] && warmup=1 frames=2
    for r in "$@"; do
        IFS='|' read -r name scene res techs extra <<<"$r"
        local left=$((end - SECONDS))
        if [ "$left" -le 10 ]; then log "bench $name: not run (its stage's time is spent)"; continue; fi
        local t0=$SECONDS
        # shellcheck disable=SC2086
        timeout "$left" "$cbr" bench "$scene" --resolutions "$res" --warmup $warmup --frames $frames \
            --timing-only --techniques "$techs" $extra -o "$work/bench/$name" >"$work/bench/$name.log" 2>&1
        local rc=$?
        log "bench $name ($scene, $res): rc $rc in $((SECONDS - t0)) s$( [ $rc = 0 ] || echo ": $(tail -2 "$work/bench/$name.log" | tr '\n' ' ')")"
    done
}

# --- 4. goals --------------------------------------------------------------------------------------
run_goals() {
    local hd=1280x720 small=320x180 tiny=160x90
    [ "$quick" = 1 ] && hd=64x36 small=32x18 tiny=32x18
    local il="deferred:vpls=1024,deferred,interleaved:4x4:direct:box,interleaved:4x4:direct:seed,interleaved:4x4,interleaved:4x4:direct"
    bench_runs "${CBR_GPU_GOALS_END:-550}" \
        "goal-interleaved-demo|builtin:demo|$hd|$il|" \
        "goal-interleaved-sibenik|scenes/sibenik.toml|$hd|$il|" \
        "goal-analytic-demo|builtin:demo|$small|ssaa:16,analytic|--time-cached-rows --no-cache" \
        "goal-analytic-sibenik|scenes/sibenik.toml|$tiny,$small|ssaa:16,analytic|--time-cached-rows --no-cache"
}

case $part in
    all) run_tests; run_bench; run_goals ;;
    tests) run_tests ;;
    bench) run_bench ;;
    goals) run_goals ;;
    *) log "error: unknown part $part (all, tests, bench, goals)"; exit 2 ;;
esac

python3 scripts/gpu-study-tables.py "$work" >"$out/gpu-study.md" 2>>"$out/study.log" \
    || log "gpu-study-tables.py failed (the raw results are in results.tar.gz)"
cp "$out/study.log" "$work/" 2>/dev/null
tar --exclude vvl -C "$(dirname "$work")" -czf "$out/results.tar.gz" "$(basename "$work")"
log "done: $out (gpu-study.md, tests.tsv, info.txt, study.log, results.tar.gz)"
