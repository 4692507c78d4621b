#!/usr/bin/env bash
# The tests again under sanitizers (CI runs this after the Release tests; see .ci/run):
#   asan  build-asan: the whole test suite, built by GCC with AddressSanitizer (and LeakSanitizer)
#         and UndefinedBehaviorSanitizer; every report fails the test.
#   tsan  build-tsan: the tests labelled concurrency (test_concurrency, test_batch_planners), built by clang
#         with ThreadSanitizer. Clang, because LLVM's OpenMP runtime with its Archer tool tells TSan
#         about OpenMP's barriers and locks, so the OpenMP batch path runs as it ships; GCC's
#         libgomp is not instrumented and TSan would report races in every parallel region.
# Both: unity builds (RASTERCHECK_UNITY_BUILD: the libraries' sources in batches),
# -O1 -g1 (the test programs and the command line -O0: tests/CMakeLists.txt's
# RASTERCHECK_TEST_OPTIMIZATION, CMakeLists.txt's RASTERCHECK_CLI_OPTIMIZATION), assertions on (ours, Eigen's, and libstdc++'s bounds checks), no benchmarks,
# examples or CUDA (sanitizers check host code). -g1 (line tables, no variables) gives the reports'
# stack traces the same functions, files, lines and inlined frames as -g, in less compile time. Both run tests/test_concurrency.cpp at a tenth of
# its size (RASTERCHECK_CONCURRENCY_STATES), and asan the accuracy and property tests' samples at a
# quarter (RASTERCHECK_SAMPLE_SCALE: tests/test_nonconvex.cpp, test_staged_pipeline.cpp,
# test_motion_bound.cpp), the viewer's load tests at a twentieth (RASTERCHECK_VIEW_LOAD_SCALE)
# and the long-running tests at a fiftieth (RASTERCHECK_SOAK_SCALE): the sanitizers slow the
# checker 10 to 50 times. asan leaves out the tests labelled slurm (a real Slurm's daemons; the
# sweep's code itself is in test_sweep), install (the installed package's layout and a consumer
# project's build: the Release run checks them) and browser (the viewer's page in Chromium; the
# server's code under it is in test_view, with its load tests).
# Usage: scripts/sanitize.sh [asan] [tsan]   (default: both). Needs scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
kinds=("$@")
((${#kinds[@]})) || kinds=(asan tsan)

configure() {  # build directory, then extra CMake arguments
    local dir=$1
    shift
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -D_GLIBCXX_ASSERTIONS" \
        -DRASTERCHECK_BUILD_BENCH=OFF -DRASTERCHECK_BUILD_EXAMPLES=OFF -DRASTERCHECK_WITH_CUDA=OFF \
        -DRASTERCHECK_UNITY_BUILD=ON "$@" >/dev/null
}

elapsed() { echo "sanitize: $1 took $((SECONDS - $2)) s"; }

asan() {
    local start=$SECONDS
    # Set before building too: the build runs each test program to list its tests.
    export ASAN_OPTIONS="detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1"
    export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
    export RASTERCHECK_CONCURRENCY_STATES=${RASTERCHECK_CONCURRENCY_STATES:-10000}
    export RASTERCHECK_SAMPLE_SCALE=${RASTERCHECK_SAMPLE_SCALE:-0.25}
    export RASTERCHECK_VIEW_LOAD_SCALE=${RASTERCHECK_VIEW_LOAD_SCALE:-0.05}
    export RASTERCHECK_SOAK_SCALE=${RASTERCHECK_SOAK_SCALE:-0.02}
    configure build-asan -DCMAKE_CXX_COMPILER=g++ -DRASTERCHECK_SANITIZE=ON
    cmake --build build-asan -j2
    # Not the tests labelled slurm, install or browser (see the top of this file).
    ctest --test-dir build-asan --output-on-failure -j2 --no-tests=error -LE '^(slurm|install|browser)$'
    elapsed "AddressSanitizer + UndefinedBehaviorSanitizer (all tests)" "$start"
}

tsan() {
    local start=$SECONDS
    configure build-tsan -DCMAKE_CXX_COMPILER=clang++ -DRASTERCHECK_TSAN=ON
    cmake --build build-tsan -j2 --target test_concurrency test_batch_planners
    local openmp archer
    openmp=$(sed -n 's/^OpenMP_omp_LIBRARY:FILEPATH=//p' build-tsan/CMakeCache.txt)
    archer=$(dirname "$(readlink -f "${openmp:-/missing}")")/libarcher.so
    [[ -f $archer ]] || { echo "sanitize: no Archer beside LLVM's OpenMP runtime ($openmp); install libomp-dev" >&2; exit 1; }
    # ignore_noninstrumented_modules: what Archer's documentation requires. The OpenMP runtime's own
    # pthread calls are not instrumented, and TSan would take them for races with our code.
    OMP_TOOL_LIBRARIES=$archer \
        TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:ignore_noninstrumented_modules=1" \
        RASTERCHECK_CONCURRENCY_STATES=${RASTERCHECK_CONCURRENCY_STATES:-10000} \
        RASTERCHECK_SOAK_SCALE=${RASTERCHECK_SOAK_SCALE:-0.02} \
        ctest --test-dir build-tsan -L concurrency --output-on-failure --no-tests=error
    elapsed "ThreadSanitizer (tests labelled concurrency)" "$start"
}

for kind in "${kinds[@]}"; do
    case $kind in
        asan | tsan) "$kind" ;;
        *) echo "usage: scripts/sanitize.sh [asan] [tsan]" >&2 && exit 2 ;;
    esac
done
