#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, generates the demo city and
# runs the main job (config/demo.yaml) on it. Outputs land in ./demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
build/lodforge synth --out demo --size-m 400 --seed 1
build/lodforge run config/demo.yaml
build/lodforge merge demo/out
echo "demo: LOD0/LOD1 models per tile in demo/out/tiles/ (CityGML, CityJSON, CityJSONSeq, OBJ, GeoPackage, glTF),"
echo "      merged into one file per format in demo/out/merged/, tile index demo/out/tile_index.geojson,"
echo "      run report demo/out/report.json; open demo/out/merged/report.html (the numbers and an overview"
echo "      of the whole area, also demo/out/merged/overview.tif); the true footprints are demo/footprints.gpkg"
