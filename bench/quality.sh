#!/usr/bin/env bash
# The footprint-quality benchmark (issue 5): every regularizer on every dataset, scored by
# `lodforge eval`, with the regularization time per building. Regenerates the results section of
# docs/quality.md (between its results markers) and leaves every footprint file, stats and metrics
# JSON in the work directory.
#
#   bench/quality.sh [--work DIR] [--datasets delft,campus,campus_clean,synth] [--methods M,...] [--no-docs]
#
# Datasets (real data from ../shared/data or LODFORGE_SHARED_DATA):
#   delft        AHN3 class 6 at 0.5 m vs the BGT footprints inside the coverage AOI
#   campus       TU Delft campus BAG footprints, segmentation simulated at 0.25 m (seed 1):
#                rounded corners, boundary noise, speckles (lodforge synth --from)
#   campus_clean the same footprints rasterized at 0.25 m, not degraded
#   synth        a 1 km x 1 km procedural city at 0.25 m (lodforge synth --seed 11)
# Methods: lodforge (the default regularizer), paper (deformation, the paper's deformed corner
# route, its mesh bounded by budget.max_mesh_vertices), paper_coarse (the same on a coarser mesh), cgal,
# douglas_peucker, none (the raw contour).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
lodforge="${LODFORGE:-$root/build/lodforge}"
shared="${LODFORGE_SHARED_DATA:-$root/../shared/data}"
work="$root/build/bench-quality"
datasets="delft,campus,campus_clean,synth"
methods="lodforge,paper,paper_coarse,cgal,douglas_peucker,none"
docs=1
while [ $# -gt 0 ]; do
  case "$1" in
    --work) work="$2"; shift 2 ;;
    --datasets) datasets="$2"; shift 2 ;;
    --methods) methods="$2"; shift 2 ;;
    --no-docs) docs=0; shift ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "bench/quality.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -x "$lodforge" ] || { echo "bench/quality.sh: no lodforge binary at $lodforge; run scripts/build.sh first" >&2; exit 1; }
[ -d "$shared/delft-ahn3-bgt" ] || { echo "bench/quality.sh: no real data in $shared (set LODFORGE_SHARED_DATA)" >&2; exit 1; }
mkdir -p "$work/data"
campus_gt="$shared/tudelft-campus-bag/tudcampus_bag_footprints.geojson"

# Inputs of each dataset: mask, truth, optional AOI (made once, seeded).
prepare() {
  case "$1" in
    delft) mask="$shared/delft-ahn3-bgt/derived/top_class_50cm.tif"; gt="$shared/delft-ahn3-bgt/derived/bgt_pand_buildings.geojson"
           aoi="$shared/delft-ahn3-bgt/derived/gt_coverage_aoi.geojson" ;;
    campus) [ -f "$work/data/campus/seg_class.tif" ] || "$lodforge" synth --from "$campus_gt" --pixel-size 0.25 --seed 1 --out "$work/data/campus" >/dev/null
            mask="$work/data/campus/seg_class.tif"; gt="$campus_gt"; aoi="" ;;
    campus_clean) [ -f "$work/data/campus_clean/seg_class.tif" ] || "$lodforge" synth --from "$campus_gt" --pixel-size 0.25 --seed 1 \
                    --set boundary_noise_px=0 --set corner_radius_px=0 --set speckle_per_km2=0 --out "$work/data/campus_clean" >/dev/null
            mask="$work/data/campus_clean/seg_class.tif"; gt="$campus_gt"; aoi="" ;;
    synth) [ -f "$work/data/synth/seg_class.tif" ] || "$lodforge" synth --size-m 1000x1000 --pixel-size 0.25 --seed 11 --out "$work/data/synth" >/dev/null
           mask="$work/data/synth/seg_class.tif"; gt="$work/data/synth/footprints.gpkg"; aoi="" ;;
    *) echo "bench/quality.sh: unknown dataset '$1'" >&2; exit 2 ;;
  esac
}

method_args() {
  case "$1" in
    lodforge) echo "" ;;
    # The paper's route with its default budgets: the mesh coarsened to about
    # budget.max_mesh_vertices vertices, the Newton iterations bounded by budget.max_deformation_work.
    paper) echo "--regularizer deformation --route deformed" ;;
    # The paper's route on a coarse mesh (runs simplified to 1 px, mesh edges up to 20 px).
    paper_coarse) echo "--regularizer deformation --route deformed --set deformation.simplify_px=1 --set triangulation.size_bound_px=20" ;;
    cgal|douglas_peucker|none) echo "--regularizer $1" ;;
    *) echo "bench/quality.sh: unknown method '$1'" >&2; exit 2 ;;
  esac
}

IFS=, read -ra dataset_list <<< "$datasets"
IFS=, read -ra method_list <<< "$methods"
for m in "${method_list[@]}"; do method_args "$m" > /dev/null || exit 2; done  # a typo stops here
for d in "${dataset_list[@]}"; do
  case "$d" in delft|campus|campus_clean|synth) ;; *) echo "bench/quality.sh: unknown dataset '$d'" >&2; exit 2 ;; esac
done
for d in "${dataset_list[@]}"; do
  prepare "$d"
  for m in "${method_list[@]}"; do
    out="$work/$d.$m"
    echo "bench/quality.sh: $d / $m" >&2
    # The time per building is measured around each building's regularization, on one core.
    "$lodforge" regularize --mask "$mask" $(method_args "$m") --threads "$(nproc)" --out "$out.gpkg" --stats "$out.stats.json" >"$out.log" 2>&1
    "$lodforge" eval --pred "$out.gpkg" --gt "$gt" ${aoi:+--aoi "$aoi"} --json "$out.metrics.json" >>"$out.log" 2>&1
  done
done
if [ "$docs" = 1 ]; then
  /usr/bin/python3 "$root/bench/quality_table.py" "$work" "$root/docs/quality.md" --datasets "$datasets" --methods "$methods"
  echo "bench/quality.sh: results written to docs/quality.md" >&2
else
  /usr/bin/python3 "$root/bench/quality_table.py" "$work" - --datasets "$datasets" --methods "$methods"
fi
