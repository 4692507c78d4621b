#!/usr/bin/env bash
# The GPU verification of the CUDA backend (issue 5) in as few device calls as possible: the GPU
# machine lacks our Debian libraries, so the programs are built here and carried there
# (../shared/GPU.md), and device time counts from the machine's start, so all steps go in one call
# (each step has its own time limit; a call may take 600 s).
#
#   On the build machine:  scripts/gpu-check.sh bundle
#       builds build-gpu for sm_90 (H100, H200) and packs .gpu/ (programs, libraries, Panda data, FCL's meshes).
#   On the GPU machine (device `run` with carry [".gpu"]), from the repository root:
#       scripts/gpu-check.sh run tests bench sanitize
#   (all three took 86 s on an H200 on 2026-11-26, each step well inside its limit below; a step
#   may also run alone)
#   The script sets LD_LIBRARY_PATH, RASTERCHECK_DATA and RASTERCHECK_SOURCE to the bundle and this
#   checkout unless they are set, and RASTERCHECK_REQUIRE_GPU, so a GPU test fails rather than
#   skips when the backend cannot use the device. Every step writes its log under $OUT (else
#   ./gpu-results) and ends with a line giving its exit status; a step whose program fell back to
#   the CPU gets status 4; a failing step does not stop the others.
set -uo pipefail
cd "$(dirname "$0")/.."

bundle() {
    set -e
    command -v cpio >/dev/null || { echo "gpu-check: gpu-bundle needs cpio (apt-get install cpio)" >&2; exit 1; }
    cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DRASTERCHECK_WITH_CUDA=ON \
        -DCMAKE_CUDA_ARCHITECTURES=90
    cmake --build build-gpu --target test_gpu_backend test_staged_pipeline rastercheck_bench_backends
    mkdir -p "$(git rev-parse --git-dir)/info"  # gpu-bundle appends to info/exclude, absent in some checkouts
    ../shared/tools/gpu-bundle build-gpu --bin test_gpu_backend --bin test_staged_pipeline \
        --bin rastercheck_bench_backends --data mbm/panda --data meshes/fcl
}

run() {
    export LD_LIBRARY_PATH=$PWD/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export RASTERCHECK_DATA=${RASTERCHECK_DATA:-$PWD/.gpu/data} RASTERCHECK_SOURCE=${RASTERCHECK_SOURCE:-$PWD}
    export RASTERCHECK_REQUIRE_GPU=1 PATH=$PATH:/usr/local/cuda/bin
    local out=${OUT:-$PWD/gpu-results}
    mkdir -p "$out"
    local steps=("$@")
    ((${#steps[@]})) || steps=(tests sanitize bench)
    local summary=()
    step() {  # step NAME SECONDS COMMAND...: run with a time limit, log to $out/NAME.log
        local name=$1 limit=$2
        shift 2
        local start=$SECONDS
        timeout -k 10 "$limit" "$@" >"$out/$name.log" 2>&1
        local rc=$?
        # The checker's warning when CUDA was asked for but could not be used.
        if ((rc == 0)) && grep -q "using the CPU backend" "$out/$name.log"; then rc=4; fi
        summary+=("$name: rc $rc, $((SECONDS - start)) s")
        echo "gpu-check: $name: rc $rc, $((SECONDS - start)) s"
    }
    {
        date -u +"%Y-%m-%d %H:%M UTC"
        nvidia-smi -L
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
        nvcc --version | tail -2
        nproc
    } >"$out/machine.txt" 2>&1
    cat "$out/machine.txt"
    for s in "${steps[@]}"; do
        case $s in
            tests)
                step gpu-tests 300 .gpu/bin/test_gpu_backend
                step staged-pipeline 200 .gpu/bin/test_staged_pipeline ;;
            sanitize)
                # Every kernel on small batches (the million-state test would take too long).
                step memcheck 240 compute-sanitizer --tool memcheck --error-exitcode 3 .gpu/bin/test_gpu_backend \
                    --gtest_filter='*AccuracySuites*:*To1000States*'
                # initcheck: reads of device memory no one wrote (what HostScratch::Poisoned mimics).
                step initcheck 240 compute-sanitizer --tool initcheck --error-exitcode 3 .gpu/bin/test_gpu_backend \
                    --gtest_filter='*To1000States*:*DeviceMemoryLimit*' ;;
            bench)
                # The Panda scenes, the crane and FCL's env/rob meshes, FCL in the same run.
                step bench-safe 280 .gpu/bin/rastercheck_bench_backends 1000000 safe
                step bench-raster 200 .gpu/bin/rastercheck_bench_backends 100000 raster ;;
            *) echo "gpu-check: unknown step $s (tests, sanitize, bench)" >&2; return 2 ;;
        esac
    done
    printf '%s\n' "${summary[@]}" >"$out/summary.txt"
}

case ${1:-} in
    bundle) bundle ;;
    run) shift; run "$@" ;;
    *) sed -n '2,16p' "$0"; exit 2 ;;
esac
