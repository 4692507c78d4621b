#!/usr/bin/env bash
# Fuzzes every loader with libFuzzer: bench/fuzz.sh [executions]   (default 100000 per harness)
#
# Builds the harnesses (fuzz/) with clang and -fsanitize=fuzzer,address,undefined in build-fuzz/,
# seeds each one's corpus from the shared data (RASTERCHECK_DATA, else ../shared/data), the
# committed seeds (fuzz/seeds/) and the inputs that once failed (tests/data/fuzz-regressions/),
# then runs the harnesses one after the other (the machine has 2 shared cores) for that many
# executions each, leaks detected. Prints executions, exec/s, time and result per harness and
# exits nonzero when one found a crash, hang, leak or unexpected exception; the input that did it
# is in build-fuzz/fuzz-artifacts/<harness>/ and the log in build-fuzz/fuzz-logs/<harness>.log.
#
# Environment: FUZZ_TARGETS="urdf mesh" runs a subset; FUZZ_BUILD_DIR (default build-fuzz);
# FUZZ_SEED (default 1) for libFuzzer's -seed; FUZZ_JOBS (default 2) build jobs.
set -euo pipefail
cd "$(dirname "$0")/.."
source_dir=$PWD
runs=${1:-100000}
build=${FUZZ_BUILD_DIR:-build-fuzz}
data=${RASTERCHECK_DATA:-$source_dir/../shared/data}
targets=${FUZZ_TARGETS:-urdf srdf scene request cfg csv mesh}
seed=${FUZZ_SEED:-1}

[[ -d $data ]] || { echo "fuzz.sh: data root '$data' not found (set RASTERCHECK_DATA)" >&2; exit 2; }
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (libFuzzer needs clang)" >&2; exit 2; }

# -O1 -g without NDEBUG: assertions (Eigen's index checks included) stay on and stacks are readable.
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DRASTERCHECK_BUILD_FUZZERS=ON \
    -DRASTERCHECK_BUILD_TESTS=OFF -DRASTERCHECK_BUILD_BENCH=OFF -DRASTERCHECK_BUILD_EXAMPLES=OFF -DRASTERCHECK_WITH_CUDA=OFF \
    -DBUILD_SHARED_LIBS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" >/dev/null
# shellcheck disable=SC2046
cmake --build "$build" -j "${FUZZ_JOBS:-2}" --target $(printf 'fuzz_%s ' $targets)

# ---- corpora, rebuilt from the data at every run (nothing from the data is committed) ----------
corpus=$build/fuzz-corpus
rm -rf "$corpus" "$build/fuzz-work" "$build/fuzz-artifacts" "$build/fuzz-logs" "$build/fuzz-tmp"
mkdir -p "$corpus" "$build/fuzz-work" "$build/fuzz-artifacts" "$build/fuzz-logs" "$build/fuzz-tmp"
for t in $targets; do
    mkdir -p "$corpus/$t" "$build/fuzz-work/$t" "$build/fuzz-artifacts/$t"
    if [[ $t != mesh && -d fuzz/seeds/$t ]]; then cp fuzz/seeds/$t/* "$corpus/$t/"; fi  # mesh: below
    if [[ -d tests/data/fuzz-regressions/$t ]]; then cp tests/data/fuzz-regressions/$t/* "$corpus/$t/"; fi
done
problems() { find "$data/mbm" -path '*/problems/*' -name "$1" | sort; }
if [[ -d $corpus/urdf ]]; then
    # Mesh references point at the harness's scratch mesh, so the seeds build whole models; what the
    # loader does not read (comments, inertia, materials, transmissions) is left out, which makes the
    # seeds 40 % smaller and the executions faster.
    for f in $(find "$data" -name '*.urdf' | sort); do
        perl -0pe 's/<!--.*?-->//gs; s/<inertial>.*?<\/inertial>//gs; s/<material\b[^>]*\/>//gs;
                   s/<material\b.*?<\/material>//gs;
                   s/<(safety_controller|dynamics|calibration|transmission|gazebo)\b.*?(\/>|<\/\1>)//gs;
                   s#filename="[^"]*"#filename="mesh.stl"#g; s/\n\s*\n/\n/g' "$f" \
            >"$corpus/urdf/$(echo "${f#$data/}" | tr / _)"
    done
fi
if [[ -d $corpus/srdf ]]; then
    for f in $(find "$data" -name '*.srdf' | sort); do cp "$f" "$corpus/srdf/$(echo "${f#$data/}" | tr / _)"; done
fi
if [[ -d $corpus/scene ]]; then
    for f in $(problems scene0001.yaml); do cp "$f" "$corpus/scene/$(basename "$(dirname "$f")").yaml"; done
fi
if [[ -d $corpus/request ]]; then
    for f in $(problems request0001.yaml); do cp "$f" "$corpus/request/$(basename "$(dirname "$f")").yaml"; done
fi
if [[ -d $corpus/csv ]]; then
    # The goal configurations of 20 Panda problems as rows, plus an extra column CSV readers skip.
    {
        echo "panda_joint1,panda_joint2,panda_joint3,panda_joint4,panda_joint5,panda_joint6,panda_joint7,problem"
        for f in $(find "$data/mbm/panda/problems/box_panda" -name 'request*.yaml' | sort | head -20); do
            awk '/^goal_constraints:/ {g = 1; next} /^[a-z]/ {g = 0}
                 g && /joint_name:/ {n = $NF} g && /position:/ {p = $NF}
                 g && n != "" && p != "" {v[n] = p; n = ""; p = ""}
                 END {for (j = 1; j <= 7; ++j) printf "%s,", v["panda_joint" j]; f = FILENAME; sub(/.*\//, "", f); print f}' "$f"
        done
    } >"$corpus/csv/panda-goals.csv"
fi
if [[ -d $corpus/mesh ]]; then
    # The first byte picks assimp's format hint (FuzzTargets.h): 0 obj, 1 stl, 2 dae, 3 ply.
    selector() { case "${1,,}" in *.obj) echo '\x00' ;; *.stl) echo '\x01' ;; *.dae) echo '\x02' ;; *.ply) echo '\x03' ;; esac; }
    for f in fuzz/seeds/mesh/* $(find "$data" -type f \( -iname '*.obj' -o -iname '*.stl' -o -iname '*.dae' \) -size -20k | sort); do
        out=$corpus/mesh/$(echo "${f#$data/}" | tr / _)
        { printf "$(selector "$f")"; cat "$f"; } >"$out"
    done
fi

# ---- run, one harness at a time ---------------------------------------------------------------
declare -A max_len=([urdf]=16384 [srdf]=20000 [scene]=8192 [request]=4096 [cfg]=2048 [csv]=2048 [mesh]=20000)
failed=0
summary=$(printf '%-8s %10s %8s %8s  %s' harness executions exec/s seconds result)
for t in $targets; do
    log=$build/fuzz-logs/$t.log
    dict=()
    case $t in
        urdf) dict=(-dict=fuzz/dict/urdf.dict) ;;
        srdf) dict=(-dict=fuzz/dict/srdf.dict) ;;
        scene | request) dict=(-dict=fuzz/dict/yaml.dict) ;;
        *) dict=(-dict=fuzz/dict/$t.dict) ;;
    esac
    echo "fuzz.sh: $t: $runs executions (log $log)"
    start=$(date +%s%N)
    status=0
    # TMPDIR: the harnesses' scratch folder (fuzz/FuzzTargets.cpp) in the build tree.
    TMPDIR=$(cd "$build/fuzz-tmp" && pwd) ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1 \
        "$build/fuzz/fuzz_$t" -runs="$runs" -seed="$seed" -max_len="${max_len[$t]}" -timeout=10 \
        -rss_limit_mb=2048 -detect_leaks=1 -print_final_stats=1 "${dict[@]}" \
        -artifact_prefix="$build/fuzz-artifacts/$t/" "$build/fuzz-work/$t" "$corpus/$t" >"$log" 2>&1 || status=$?
    elapsed_ns=$(($(date +%s%N) - start))
    executed=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    seconds=$(awk -v ns=$elapsed_ns 'BEGIN {printf "%.1f", ns / 1e9}')
    # Over the whole run, start-up and seed corpus included (libFuzzer's own figure is whole seconds).
    rate=$(awk -v n="${executed:-0}" -v ns=$elapsed_ns 'BEGIN {printf "%.0f", n / (ns / 1e9)}')
    if [[ $status -eq 0 ]]; then
        result=ok
    else
        failed=1
        artifact=$(ls "$build/fuzz-artifacts/$t/" 2>/dev/null | head -1)
        result="FAILED (exit $status; $(grep -m1 -E 'ERROR: |runtime error|uncaught|what\(\)' "$log" | cut -c1-120); input ${artifact:+$build/fuzz-artifacts/$t/$artifact})"
    fi
    summary+=$'\n'$(printf '%-8s %10s %8s %8s  %s' "$t" "${executed:--}" "${rate:--}" "$seconds" "$result")
done
echo "$summary"
exit $failed
