#!/usr/bin/env bash
# The README's second command: installs what is missing, builds, and runs the whole test suite.
# The tests read the open data in tests/data; the output validation reads the official CityGML 2.0
# and CityJSON 2.0 schemas from LODFORGE_SCHEMAS (or ../shared/data beside the clone) and is
# skipped, saying so, without them. The Slurm test starts its own single-node Slurm (slurm-wlm,
# installed here). Ends with one line: passed, failed, skipped and why.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --tests
scripts/build.sh
root="$PWD"
cd "${BUILD_DIR:-build}"
status=0
ctest --output-on-failure -j "${JOBS:-$(nproc)}" --output-junit "$PWD/ctest-junit.xml" || status=$?
/usr/bin/python3 "$root/scripts/dev/test_summary.py" "$PWD/ctest-junit.xml" || true
exit "$status"
