#!/usr/bin/env bash
# Installs every build and test dependency of rastercheck from Debian 12 packages, and the browser
# test's npm packages (package-lock.json: puppeteer-core) into ./node_modules.
# Idempotent and non-interactive; runs as root or through sudo. CUDA is optional and not installed here.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
    build-essential cmake ninja-build pkg-config git ca-certificates
    libeigen3-dev liburdfdom-dev liburdfdom-headers-dev libtinyxml2-dev libconsole-bridge-dev
    libassimp-dev libyaml-cpp-dev libcli11-dev libcairo2-dev
    libompl-dev ompl-demos
    libboost-serialization-dev libboost-filesystem-dev libboost-system-dev libboost-program-options-dev
    libfcl-dev libccd-dev
    libgtest-dev libgmock-dev libbenchmark-dev
    # the Python module (python/) for Debian's python3, and its tests
    pybind11-dev python3-dev python3-numpy python3-pytest
    # scripts/sanitize.sh: ThreadSanitizer with clang, its runtime, LLVM's OpenMP (with the Archer
    # tool) and llvm-symbolizer for the reports (GCC's own sanitizers come with build-essential)
    clang libclang-rt-dev libomp-dev llvm
    # rastercheck view: its HTTP server and JSON, three.js for the page (served by the viewer: no
    # CDN), and the browser its test drives headless
    libcpp-httplib-dev nlohmann-json3-dev libjs-three chromium
    # scripts/gpu-check.sh bundle: ../shared/tools/gpu-bundle copies with cpio (a fresh Debian 12
    # machine lacks it; the first GPU run, 2026-11-26, stopped there)
    cpio
    # rastercheck sweep: ompl_benchmark_statistics (ompl-demos, above) merges the logs; the sweep's
    # test starts a one-node Slurm (slurmctld, slurmd, sbatch) with MUNGE authentication
    # (tests/slurm/local-cluster.sh), and sweep merge reads the database through SQLite
    slurm-wlm munge libsqlite3-dev
)
# Node.js and npm for the browser test: Debian's, unless a node with npm is already installed (a
# NodeSource nodejs, which carries its own npm, conflicts with Debian's npm package).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    packages+=(nodejs npm)
fi

# puppeteer-core at the version package-lock.json pins; the copy of the lock file beside it says
# the installed tree is current.
install_npm_packages() {
    local stamp=node_modules/.rastercheck-package-lock.json
    if cmp -s package-lock.json "$stamp"; then
        echo "install-deps: npm packages current"
        return
    fi
    echo "install-deps: npm ci (puppeteer-core for the browser test)"
    npm ci --no-audit --no-fund --loglevel=error
    cp package-lock.json "$stamp"
}

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
    echo "install-deps: all ${#packages[@]} packages present"
    install_npm_packages
    exit 0
fi

sudo=""
if ((EUID != 0)); then
    command -v sudo >/dev/null || { echo "install-deps: run as root or install sudo" >&2; exit 1; }
    sudo=sudo
fi
echo "install-deps: installing ${missing[*]}"
$sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
$sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
install_npm_packages
