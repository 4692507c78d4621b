#!/usr/bin/env bash
# Configures and builds rastercheck in ./build (Release, Ninja). Extra arguments go to CMake's
# configure step, e.g. scripts/build.sh -DRASTERCHECK_WITH_CUDA=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRASTERCHECK_UNITY_BUILD=ON "$@" >/dev/null
cmake --build build
