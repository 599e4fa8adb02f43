#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, generates the demo city and
# runs the main job (config/demo.yaml) on it. Outputs land in ./demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
build/lodforge synth --out demo --size-m 400 --seed 1
build/lodforge run config/demo.yaml
echo "demo: LOD0/LOD1 models per tile in demo/out/tiles/ (CityGML, CityJSON, CityJSONSeq, OBJ, GeoPackage, glTF),"
echo "      tile index demo/out/tile_index.geojson,"
echo "      run report demo/out/report.json; the true footprints are demo/footprints.gpkg"
