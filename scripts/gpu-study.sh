#!/usr/bin/env bash
# Issue 17's GPU study, in one command on the lent GPU machine (docs/resolve.md, "The GPU study").
# Prepare here with scripts/gpu-pack.sh (just gpu-pack) in the same session, then through the
# device tool:
#
#   run(command="bash scripts/gpu-study.sh", carry=[".gpu"], timeout_s=600)
#
# Stages, each with a deadline counted from the script's start (a stage that ends early leaves
# its time to the next; no single bench run takes more than CBR_GPU_RUN_CAP_S, default 120 s),
# so that what finished comes back when a later one runs out (the tool allows 10 minutes a
# command and 15 minutes of device time a session):
#   1. unpack .gpu (binaries, ../shared, Debian's Vulkan loader and validation layers) and link the
#      paths the binaries were built under; check that the tree is the one packed; `cbr info` of
#      the device; a 64x36 frame with the validation layers on;
#   2. tests (until CBR_GPU_TESTS_END, default 190 s): every test binary of the workspace on the
#      GPU, validation layers on as always, CBR_GPU_TESTS_PAR (3) binaries at a time; the
#      filtering, readback, msaa2x and sample-location tests first;
#   3. bench (until CBR_GPU_BENCH_END, default 450 s): `cbr bench --timing-only` of builtin:demo at
#      1920x1080 and then 3840x2160: rotated and split, then (where the device has 2x MSAA)
#      msaa2x with and without sample locations, in separate runs; `ours` and `pq4k` in every
#      mapping (pixel, quad), group (8, 16) and precision (fp32, fp16), the other modes at the
#      defaults, each with its copy floor; then Sibenik's frame against native at 1280x720 and
#      1920x1080;
#   4. goals (until CBR_GPU_GOALS_END, default 550 s): the frame-time goals of issues 14 and 15
#      that lavapipe's cost structure decides (docs/analytic.md, docs/interleaved.md), timed on
#      the GPU: interleaved:4x4 against every VPL at every pixel (deferred:vpls=1024) at 1280x720
#      on the demo and Sibenik; analytic against ssaa:16 at 320x180 and Sibenik at 160x90 too;
#   5. scripts/gpu-study-tables.py: the tables for the docs and references/README.md.
# What comes back in $OUT: gpu-study.md (the tables), tests.tsv (per test binary: passed, failed,
# SKIPPED lines, VUID lines), runs.tsv (per bench run: exit status, seconds), info.txt, study.log,
# results.tar.gz (every bench.json and log; rebuilt after each run, so it survives a kill).
#
# Arguments: `all` (default), `tests`, `bench` or `goals` (stage 1 always runs). CBR_GPU_STUDY_QUICK=1: a
# dry run on any device at tiny sizes (this is how the script is checked on lavapipe: `just
# gpu-study-dry-run`).
set -uo pipefail
# Physical paths: the binaries resolve `..` in the paths they hold physically.
cd -P "$(dirname "$0")/.." || exit 1
repo=$(pwd -P)
part=${1:-all}
quick=${CBR_GPU_STUDY_QUICK:-0}
cap=${CBR_GPU_RUN_CAP_S:-120}
out=${OUT:-$repo/out/gpu-study}
work=$repo/out/gpu-study-work
rm -rf "$work"
mkdir -p "$out" "$work/tests" "$work/bench"
log() { printf '[gpu-study %s] %s\n' "$(date +%T)" "$*" | tee -a "$out/study.log" >&2; }
pack_results() {
    cp "$out/study.log" "$work/" 2>/dev/null
    tar --exclude vvl --exclude fallback -C "$(dirname "$work")" -czf "$out/results.tar.gz" "$(basename "$work")" 2>/dev/null
}
# The source files whose build the pack holds: scripts/gpu-pack.sh hashes the same list.
src_hash() {
    find crates shaders Cargo.toml Cargo.lock -type f 2>/dev/null | LC_ALL=C sort | xargs -d '\n' sha256sum | sha256sum | cut -c1-16
}

# --- 1. unpack -------------------------------------------------------------------------------------
[ -f .gpu/bins.tar.xz ] || { log "error: .gpu/bins.tar.xz is missing: run scripts/gpu-pack.sh here first and carry .gpu"; exit 1; }
root=$(cat .gpu/root.txt)
log "pack of commit $(cat .gpu/commit.txt) built under $root; this tree: $repo"
if [ "$(src_hash)" != "$(cat .gpu/src-hash.txt 2>/dev/null)" ]; then
    log "WARNING: crates/, shaders/ or Cargo.* differ from what the pack was built from (run just gpu-pack again): the binaries are the pack's"
fi
tar -C "$repo" -xJf .gpu/bins.tar.xz || { log "error: cannot unpack the binaries"; exit 1; }
if ! "$repo/target/release/cbr" --version >/dev/null 2>"$work/version.err"; then
    log "cbr does not start here ($(head -1 "$work/version.err")): Debian's libstdc++ and libgcc from .gpu/deb/fallback"
    for f in .gpu/deb/fallback/*.deb; do dpkg -x "$f" "$work/fallback"; done
    export LD_LIBRARY_PATH=$work/fallback/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    "$repo/target/release/cbr" --version >/dev/null 2>&1 || log "error: cbr still does not start"
fi
# The binaries name files by the paths they were built under (env!("CARGO_MANIFEST_DIR"),
# CARGO_BIN_EXE_cbr): make $root this tree.
if [ ! "$root/target/debug/cbr" -ef "$repo/target/debug/cbr" ]; then
    if [ ! -e "$root" ] && [ ! -L "$root" ]; then
        mkdir -p "$(dirname "$root")" && ln -s "$repo" "$root"
    else
        mkdir -p "$root" && mount --bind "$repo" "$root"
    fi
    if [ "$root/target/debug/cbr" -ef "$repo/target/debug/cbr" ]; then
        log "$root is now this tree"
    else
        log "error: cannot make $root this tree (the test binaries look there); the tests will fail"
    fi
fi
# The scenes and tests read ../shared beside the checkout, resolved physically: beside this tree
# (scenes/*.toml) and beside $root's target (the tests' ../../../shared from a crate).
for s in "$(dirname "$repo")/shared" "$(cd -P "$root/.." 2>/dev/null && pwd -P)/shared"; do
    if [ ! -d "$s/scenes" ]; then
        mkdir -p "$(dirname "$s")" && tar -C "$(dirname "$s")" -xJf .gpu/shared.tar.xz && log "unpacked $s"
    fi
done
for s in "$repo/scenes/../../shared/scenes" "$root/crates/cbr-render/../../../shared/scenes"; do
    [ -d "$s" ] || log "error: $s is missing: the real-scene tests will skip and the Sibenik runs fail"
done
# `grep >/dev/null`, not `grep -q`: with pipefail, ldconfig could die of SIGPIPE when grep quits.
if ! ldconfig -p 2>/dev/null | grep 'libvulkan.so.1 ' >/dev/null; then
    for f in .gpu/deb/libvulkan1_*.deb; do dpkg -x "$f" /; done
    ldconfig
    log "installed the Vulkan loader from .gpu/deb"
fi
# NVIDIA's ICD (libGLX_nvidia.so.0) needs libglvnd: without it the loader sees no device.
if ! ldconfig -p 2>/dev/null | grep 'libGLdispatch.so.0 ' >/dev/null; then
    for f in .gpu/deb/glvnd/*.deb; do dpkg -x "$f" /; done
    ldconfig
    log "installed libglvnd from .gpu/deb/glvnd"
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
# Loaders before 1.3.207 read only the older name.
[ -n "${VK_DRIVER_FILES:-}" ] && export VK_ICD_FILENAMES=$VK_DRIVER_FILES
log "VK_DRIVER_FILES=${VK_DRIVER_FILES:-<unset>}"
cbr=$repo/target/release/cbr
"$cbr" info >"$out/info.txt" 2>&1 || { log "error: cbr info failed:"; cat "$out/info.txt" >&2; pack_results; exit 1; }
cp "$out/info.txt" "$work/info.txt"
cp .gpu/commit.txt "$work/commit.txt"
log "device: $(sed -n 's/^chosen: //p' "$out/info.txt"); $(grep -m1 'driver:' "$out/info.txt" | sed 's/^ *//')"
timeout -k 5 60 "$cbr" bench builtin:demo --width 64 --height 36 --warmup 0 --frames 1 --timing-only \
    --validation -o "$work/bench/validation-check" >"$work/bench/validation-check.log" 2>&1
log "validation check (64x36, native, layers on): rc $?, $(grep -o '"messages": [0-9]*' "$work/bench/validation-check/bench.json" 2>/dev/null || echo 'no bench.json') $(tail -1 "$work/bench/validation-check.log")"
nproc=$(nproc)

# --- 2. tests --------------------------------------------------------------------------------------
# One test binary: its log, and its row of tests.tsv in $work/tests/row-IDX (rows are joined in
# list order at the end, since binaries run side by side).
run_test_binary() {
    local idx=$1 bin=$2 crate=$3 name=$4 left=$5 safe t0=$SECONDS rc counts passed failed skipped vuid status
    safe=${name// /_}
    safe=${safe//[()]/}
    (cd "$root/$crate" && CARGO_MANIFEST_DIR=$root/$crate timeout -k 10 "$left" "$root/$bin" \
        --test-threads="$nproc" --nocapture) >"$work/tests/$safe.log" 2>&1
    rc=$?
    counts=$(awk '/^test result:/ { for (i = 2; i <= NF; i++) { if ($i ~ /^passed;?$/) p += $(i-1); if ($i ~ /^failed;?$/) f += $(i-1) } } END { print p + 0, f + 0 }' "$work/tests/$safe.log")
    read -r passed failed <<<"$counts"
    skipped=$(grep -c 'SKIPPED' "$work/tests/$safe.log")
    vuid=$(grep -c 'VUID' "$work/tests/$safe.log")
    case $rc in 0) status=ok ;; 124|137) status="timed out" ;; *) status="rc $rc" ;; esac
    [ "$skipped" -gt 0 ] && status="$status ($skipped SKIPPED lines)"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$status" "$passed" "$failed" "$skipped" "$vuid" \
        "$((SECONDS - t0))" >"$work/tests/row-$idx"
    log "test $name: $status ($passed passed, $failed failed) in $((SECONDS - t0)) s"
}

run_tests() {
    # CBR_GPU_TESTS_PAR binaries at a time (default 3; each runs its tests on every core): on the
    # H100 machine one at a time took 185 s for 23 of the 33 binaries (2026-11-27).
    local end=${CBR_GPU_TESTS_END:-190} par=${CBR_GPU_TESTS_PAR:-3} idx=0 i
    local first='^(filtering|readback|layouts|msaa|resolve|timestamps)$' list
    printf 'test\tstatus\tpassed\tfailed\tSKIPPED lines\tVUID lines\tseconds\n' >"$out/tests.tsv"
    # The GPU-only checks first (msaa2x, sample locations, 2x MSAA), then the rest in pack order.
    list=$(awk -F'\t' -v re="$first" '$3 ~ re' .gpu/tests.txt; awk -F'\t' -v re="$first" '$3 !~ re' .gpu/tests.txt)
    if [ -n "${CBR_GPU_STUDY_TESTS:-}" ]; then
        list=$(awk -F'\t' -v re="^(${CBR_GPU_STUDY_TESTS})\$" '$3 ~ re' <<<"$list")
    fi
    rm -f "$work"/tests/row-*
    while IFS=$'\t' read -r bin crate name; do
        [ -n "$bin" ] || continue
        idx=$((idx + 1))
        name="$(basename "$crate") $name"
        # Wait for a free place; the deadline is checked when the binary would start.
        while [ "$(jobs -rp | wc -l)" -ge "$par" ]; do wait -n; done
        local left=$((end - SECONDS))
        if [ "$left" -le 5 ]; then
            printf '%s\tnot run (test time spent)\t\t\t\t\t\n' "$name" >"$work/tests/row-$idx"
            continue
        fi
        run_test_binary "$idx" "$bin" "$crate" "$name" "$left" &
    done <<<"$list"
    wait
    for i in $(seq 1 "$idx"); do cat "$work/tests/row-$i" >>"$out/tests.tsv" 2>/dev/null; done
    cp "$out/tests.tsv" "$work/tests.tsv"
    pack_results
}

# --- 3. bench --------------------------------------------------------------------------------------
can() { grep -E "^  $1 +yes" "$out/info.txt" >/dev/null; }
run_bench() {
    local sizes="1920x1080 3840x2160" sib="1280x720,1920x1080"
    [ "$quick" = 1 ] && sizes="64x36 128x72" sib=64x36
    local portable=() msaa=() pmodes=() mmodes=()
    for m in ours pq4k; do
        for l in rotated split; do portable+=("checkerboard:$l:$m" "checkerboard:$l:$m:fp16"); done
        msaa+=("checkerboard:msaa2x:$m" "checkerboard:msaa2x:$m:fp16")
    done
    for m in intel spatial temporal; do
        pmodes+=("checkerboard:rotated:$m" "checkerboard:split:$m")
        mmodes+=("checkerboard:msaa2x:$m")
    done
    if can 'msaa2x --msaa2x-sample-locations'; then
        for m in ours pq4k; do msaa+=("checkerboard:msaa2x:$m:locations"); done
    fi
    local csv_p csv_m csv_pm csv_mm runs=() sweep="--mappings pixel,quad --groups 8,16"
    csv_p=$(IFS=,; echo "${portable[*]}")
    csv_m=$(IFS=,; echo "${msaa[*]}")
    csv_pm=$(IFS=,; echo "${pmodes[*]}")
    csv_mm=$(IFS=,; echo "${mmodes[*]}")
    # name | scene | resolutions | techniques | extra flags; 1080p first (the Stadia comparison),
    # msaa2x apart (one configuration a device refuses refuses its whole run).
    # The largest size gets the fp32 `ours` and `pq4k`, pixel and quad, 8x8 only: on the H100 the
    # whole sweep took 89 s at 1080p (mostly pipeline builds and readbacks, ~2.7 s a
    # configuration) and did not finish in 81 s at 4K (2026-11-27); its other modes go last.
    local big=${sizes##* } small_sizes=${sizes% *} four_p four_m
    four_p=$(printf 'checkerboard:%s,' rotated:ours rotated:pq4k split:ours split:pq4k)
    four_m=$(printf 'checkerboard:%s,' msaa2x:ours msaa2x:pq4k)
    for res in $small_sizes; do
        runs+=("core-$res-portable|builtin:demo|$res|$csv_p|$sweep")
        can msaa2x && runs+=("core-$res-msaa2x|builtin:demo|$res|$csv_m|$sweep")
        runs+=("modes-$res-portable|builtin:demo|$res|$csv_pm|")
        can msaa2x && runs+=("modes-$res-msaa2x|builtin:demo|$res|$csv_mm|")
    done
    runs+=("core-$big-portable|builtin:demo|$big|${four_p%,}|--mappings pixel,quad --groups 8")
    can msaa2x && runs+=("core-$big-msaa2x|builtin:demo|$big|${four_m%,}|--mappings pixel,quad --groups 8")
    runs+=("sibenik-portable|scenes/sibenik.toml|$sib|checkerboard:rotated:ours,checkerboard:split:ours,checkerboard:rotated:pq4k|")
    can msaa2x && runs+=("sibenik-msaa2x|scenes/sibenik.toml|$sib|checkerboard:msaa2x:ours|")
    runs+=("modes-$big-portable|builtin:demo|$big|$csv_pm|")
    can msaa2x && runs+=("modes-$big-msaa2x|builtin:demo|$big|$csv_mm|")
    bench_runs "${CBR_GPU_BENCH_END:-450}" "${runs[@]}"
}

# Runs `cbr bench --timing-only` for each "name|scene|resolutions|techniques|extra flags" until
# the deadline (seconds since the script's start), each run at most $cap seconds.
bench_runs() {
    local end=$1 warmup=2 frames=8
    shift
    [ "$quick" = 1 ] && warmup=1 frames=2
    [ -f "$out/runs.tsv" ] || printf 'run\tscene\tresolutions\tstatus\tseconds\n' >"$out/runs.tsv"
    for r in "$@"; do
        local name scene res techs extra left t0 rc status
        IFS='|' read -r name scene res techs extra <<<"$r"
        left=$((end - SECONDS))
        if [ "$left" -le 10 ]; then
            log "bench $name: not run (its stage's time is spent)"
            printf '%s\t%s\t%s\tnot run (time spent)\t\n' "$name" "$scene" "$res" >>"$out/runs.tsv"
            continue
        fi
        [ "$left" -gt "$cap" ] && left=$cap
        t0=$SECONDS
        # shellcheck disable=SC2086
        timeout -k 10 "$left" "$cbr" bench "$scene" --resolutions "$res" --warmup $warmup --frames $frames \
            --timing-only --techniques "$techs" $extra -o "$work/bench/$name" >"$work/bench/$name.log" 2>&1
        rc=$?
        case $rc in 0) status=ok ;; 124|137) status="timed out after $left s" ;; *) status="rc $rc: $(tail -1 "$work/bench/$name.log" | tr '\t' ' ')" ;; esac
        printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$scene" "$res" "$status" "$((SECONDS - t0))" >>"$out/runs.tsv"
        log "bench $name ($scene, $res): $status in $((SECONDS - t0)) s"
        cp "$out/runs.tsv" "$work/runs.tsv"
        pack_results
    done
}

# --- 4. goals --------------------------------------------------------------------------------------
run_goals() {
    local hd=1280x720 small=320x180 tiny=160x90
    [ "$quick" = 1 ] && hd=64x36 small=32x18 tiny=24x14
    local il="deferred:vpls=1024,deferred,interleaved:4x4:direct:box,interleaved:4x4:direct:seed,interleaved:4x4,interleaved:4x4:direct"
    bench_runs "${CBR_GPU_GOALS_END:-550}" \
        "goal-interleaved-demo|builtin:demo|$hd|$il|" \
        "goal-interleaved-sibenik|scenes/sibenik.toml|$hd|$il|" \
        "goal-analytic-demo|builtin:demo|$small|ssaa:16,analytic|" \
        "goal-analytic-sibenik|scenes/sibenik.toml|$tiny,$small|ssaa:16,analytic|"
}

case $part in
    all) run_tests; run_bench; run_goals ;;
    tests) run_tests ;;
    bench) run_bench ;;
    goals) run_goals ;;
    *) log "error: unknown part $part (all, tests, bench, goals)"; exit 2 ;;
esac

cp "$out/tests.tsv" "$work/tests.tsv" 2>/dev/null
cp "$out/runs.tsv" "$work/runs.tsv" 2>/dev/null
python3 scripts/gpu-study-tables.py "$work" >"$out/gpu-study.md" 2>>"$out/study.log" \
    || log "gpu-study-tables.py failed (the raw results are in results.tar.gz)"
log "done: $out (gpu-study.md, tests.tsv, runs.tsv, info.txt, study.log, results.tar.gz)"
pack_results
