#!/usr/bin/env bash
# The GPU verification of the CUDA backend (issue 5) in as few device calls as possible: the GPU
# machine lacks our Debian libraries, so the programs are built here and carried there
# (../shared/GPU.md), and device time counts from the machine's start, so all steps go in one call
# (each step has its own time limit; a call may take 600 s).
#
#   On the build machine:  scripts/gpu-check.sh bundle
#       builds build-gpu for sm_90 (H100, H200) and packs .gpu/ (programs, libraries, Panda data, FCL's meshes).
#   Optionally, after bundle (which replaces .gpu/):  scripts/gpu-check.sh baseline REV
#       builds the benchmark at git revision REV (a temporary worktree, build-gpu-base) into
#       .gpu/baseline/, so that the step "baseline" measures old and new code on the same device.
#   On the GPU machine (device `run` with carry [".gpu"]), from the repository root:
#       scripts/gpu-check.sh run tests bench sanitize [plan] [profile] [latency] [throughput] [blocks] [baseline]
#   (all three took 86 s on an H200 on 2026-11-26, each step well inside its limit below; a step
#   may also run alone)
#   On the build machine, no GPU needed:  scripts/gpu-check.sh registers
#       compiles build-gpu's CUDA file again with ptxas's report and prints registers per thread,
#       stack frame and spills of every stage kernel, largest first (what limits occupancy).
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
    cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DRASTERCHECK_WITH_CUDA=ON -DRASTERCHECK_UNITY_BUILD=ON \
        -DCMAKE_CUDA_ARCHITECTURES=90
    cmake --build build-gpu --target test_gpu_backend test_staged_pipeline rastercheck_bench_backends \
        rastercheck_bench_planners
    mkdir -p "$(git rev-parse --git-dir)/info"  # gpu-bundle appends to info/exclude, absent in some checkouts
    ../shared/tools/gpu-bundle build-gpu --bin test_gpu_backend --bin test_staged_pipeline \
        --bin rastercheck_bench_backends --bin rastercheck_bench_planners --data mbm/panda --data meshes/fcl
}

baseline() {
    set -e
    local rev=${1:?baseline needs a git revision}
    local tree=build-gpu-base/src
    rm -rf build-gpu-base/src
    git worktree prune
    git worktree add --detach "$tree" "$rev"
    cmake -S "$tree" -B build-gpu-base/build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRASTERCHECK_WITH_CUDA=ON \
        -DCMAKE_CUDA_ARCHITECTURES=90
    cmake --build build-gpu-base/build --target rastercheck_bench_backends
    rm -rf .gpu/baseline
    mkdir -p .gpu/baseline/lib
    cp build-gpu-base/build/bench/rastercheck_bench_backends .gpu/baseline/
    # The project's own libraries at that revision; the rest comes from the bundle's lib/.
    cp -L build-gpu-base/build/librastercheck*.so.0 .gpu/baseline/lib/  # by their SONAME
    git -C "$tree" rev-parse --short HEAD >.gpu/baseline/revision
    git worktree remove --force "$tree"
}

run() {
    export LD_LIBRARY_PATH=$PWD/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export RASTERCHECK_DATA=${RASTERCHECK_DATA:-$PWD/.gpu/data} RASTERCHECK_SOURCE=${RASTERCHECK_SOURCE:-$PWD}
    export RASTERCHECK_REQUIRE_GPU=1 PATH=$PATH:/usr/local/cuda/bin
    local out=${OUT:-$PWD/gpu-results}
    local bench_states=${BENCH_STATES:-1000000}  # the largest batch of the safe-mode benches
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
                    --gtest_filter='*AccuracySuites*:*To1000States*:*PairPaddings*:*EightThreads*:*MeshObstacle*'
                # initcheck: reads of device memory no one wrote (what HostScratch::Poisoned mimics), the
                # outcome downloads of a guessed length among them.
                step initcheck 240 compute-sanitizer --tool initcheck --error-exitcode 3 .gpu/bin/test_gpu_backend \
                    --gtest_filter='*To1000States*:*DeviceMemoryLimit*:*WaitsOnce*' ;;
            bench)
                # The Panda scenes, the crane and FCL's env/rob meshes, FCL in the same run; "GPU per
                # call" gives a call's time, waits, launches and allocations.
                step bench-safe 280 .gpu/bin/rastercheck_bench_backends "$bench_states" safe
                step bench-exact 200 .gpu/bin/rastercheck_bench_backends 100000 exact
                step bench-raster 200 .gpu/bin/rastercheck_bench_backends 100000 raster
                # Small calls without CUDA graphs (each kernel launched, as before they were
                # replayed), for the per-call columns side by side.
                step bench-safe-nographs 200 env RASTERCHECK_CUDA_GRAPHS=0 .gpu/bin/rastercheck_bench_backends 1000 safe
                # And with each stage kernel launched only once the one before it has ended (no
                # programmatic dependent launch), graphs on.
                step bench-safe-nopdl 200 env RASTERCHECK_CUDA_PDL=0 .gpu/bin/rastercheck_bench_backends 1000 safe ;;
            plan)
                # BatchRRTConnect on Panda problems 1-10 of every scenario, certified edges, 1 s: the
                # checker on the GPU, rounds of 256 samples, every batch of 32 states or more on the
                # device, a round's candidates decided together (the default there: fewer, larger
                # calls) and one at a time (their small rakes on the CPU), and together with every
                # call on the device; the library's defaults (samples by the backend, the automatic
                # device threshold, which on 16 threads keeps rounds of 8 on the CPU); every CPU core.
                step plan-cuda-256 100 .gpu/bin/rastercheck_bench_planners panda 10 1 256 1 batch 2 0 300 cuda 0
                step plan-cuda-256-one 100 .gpu/bin/rastercheck_bench_planners panda 10 1 256 1 batch 2 0 300 cuda 0 bisection 0 32 0
                step plan-cuda-256-every 100 .gpu/bin/rastercheck_bench_planners panda 10 1 256 1 batch 2 0 300 cuda 0 bisection 0 1
                step plan-cuda-auto 100 .gpu/bin/rastercheck_bench_planners panda 10 1 0 1 batch 2 0 300 cuda 0 bisection 0 0
                step plan-cpu 100 .gpu/bin/rastercheck_bench_planners panda 10 1 8 1 batch 2 0 300 cpu 0 ;;
            profile)
                # Registers per thread and occupancy of every kernel of a few small and large Panda batches.
                step profile 200 ncu --clock-control none --section SpeedOfLight --section LaunchStats --section Occupancy --launch-count 120 \
                    .gpu/bin/test_gpu_backend --gtest_filter='*To1000States*' ;;
            latency)
                # Two calls of 32 Panda states past the first ones (22 kernels a call, from the third
                # call on in one CUDA graph; ncu profiles a graph's kernels one by one): which kernels
                # a small call's latency is made of.
                step profile-32 120 ncu --clock-control none --section SpeedOfLight --section LaunchStats --section Occupancy \
                    --launch-skip 230 --launch-count 46 .gpu/bin/test_gpu_backend --gtest_filter='*ABatchOf32States*' ;;
            throughput)
                # Every kernel of the first chunks of a million random Panda states: where a large
                # batch's device time goes (the 10x-the-CPU target is at 10^5 states and more).
                step profile-large 240 ncu --clock-control none --section SpeedOfLight --section LaunchStats --section Occupancy \
                    --launch-count 60 .gpu/bin/test_gpu_backend --gtest_filter='*AMillionRandomStates*' ;;
            blocks)
                # The light kernels at 256 threads a block, as before 64 was the default: the same
                # benchmark, so the block size is measured on its own (the baseline step changes more).
                step bench-safe-blocks256 200 env RASTERCHECK_CUDA_BLOCK_THREADS=256 \
                    .gpu/bin/rastercheck_bench_backends 100000 safe ;;
            baseline)
                # The same benchmark at an earlier revision (scripts/gpu-check.sh baseline REV), same device.
                step "baseline-$(cat .gpu/baseline/revision)" 280 env LD_LIBRARY_PATH=$PWD/.gpu/baseline/lib:$LD_LIBRARY_PATH \
                    .gpu/baseline/rastercheck_bench_backends "$bench_states" safe ;;
            *) echo "gpu-check: unknown step $s (tests, sanitize, bench, plan, profile, latency, throughput, blocks, baseline)" >&2; return 2 ;;
        esac
    done
    printf '%s\n' "${summary[@]}" >"$out/summary.txt"
}

registers() {
    set -e
    [[ -f build-gpu/build.ninja ]] || { echo "gpu-check: configure build-gpu first (scripts/gpu-check.sh bundle)" >&2; exit 1; }
    local command report
    # The object's own compile command, without ccache (its hit would print nothing) and writing elsewhere.
    command=$(ninja -C build-gpu -t commands rastercheck | grep -m1 'CudaStageRunner\.cu\.o')
    command=${command#ccache }
    command=$(sed -E 's# -MD -MT [^ ]+ -MF [^ ]+##; s# -o [^ ]+# -o /dev/null -Xptxas -v#' <<<"$command")
    report=$(mktemp)
    (cd build-gpu && eval "$command") >"$report" 2>&1
    python3 - "$report" <<'PY'
import re, subprocess, sys
rows, entry, frame = [], None, None
for line in open(sys.argv[1]):
    m = re.search(r"Compiling entry function '(\S+)'", line)
    if m:
        entry, frame = m.group(1), None
        continue
    m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
    if m and entry:
        frame = m.groups()
    m = re.search(r"Used (\d+) registers", line)
    if m and entry:
        name = subprocess.run(["c++filt", entry], capture_output=True, text=True).stdout.strip()
        stage = re.search(r"device::(\w+)<", name)
        lam = re.search(r"\{lambda\(unsigned long\)#(\d+)\}", name)
        if stage and "cub::" not in name:
            label = stage.group(1) + (" lambda #" + lam.group(1) if lam else "")
            rows.append((int(m.group(1)), label, frame or ("?", "?", "?")))
        entry = None
print("| kernel (stage, lambda in source order) | registers | stack frame B | spill stores B | spill loads B |")
print("|---|---:|---:|---:|---:|")
for registers, label, (stack, stores, loads) in sorted(rows, reverse=True):
    print(f"| {label} | {registers} | {stack} | {stores} | {loads} |")
PY
    rm -f "$report"
}

case ${1:-} in
    bundle) bundle ;;
    registers) registers ;;
    baseline) shift; baseline "$@" ;;
    run) shift; run "$@" ;;
    *) sed -n '2,22p' "$0"; exit 2 ;;
esac
