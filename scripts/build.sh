#!/usr/bin/env bash
# Configures and builds lodforge in ./build (Release, ccache when present).
# BUILD_DIR and JOBS may be set in the environment.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${BUILD_DIR:-build}"
jobs="${JOBS:-$(nproc)}"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build "$build_dir" -j "$jobs"
