#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, generates the demo city and
# runs lodforge on it. Outputs land in ./demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
build/lodforge synth --out demo --size-m 400 --seed 1
build/lodforge regularize --mask demo/seg_class.tif --building-value 6 --out demo/lod0.gpkg
echo "demo: footprints in demo/lod0.gpkg (true footprints in demo/footprints.gpkg); open both in QGIS"
