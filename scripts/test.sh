#!/usr/bin/env bash
# The README's second command: installs what is missing, builds, and runs the whole test suite.
# Real-data tests read ../shared/data (or LODFORGE_SHARED_DATA); the Slurm test starts its own
# single-node Slurm (slurm-wlm, installed here).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --tests
scripts/build.sh
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j "${JOBS:-$(nproc)}"
