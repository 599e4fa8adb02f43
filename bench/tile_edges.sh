#!/usr/bin/env bash
# Buildings a tile's edge cuts (session 47): a sweep row's mask (bench/sweep.sh's
# build/bench-sweep/data/ROW) cut into tiles, as a user brings a city's tiles one by one, each
# regularized alone (`lodforge regularize --mask TILE`), with the default and with
# stages.contour.edge_sweep_m=0 (a cut building traced as it is, not swept across the edge nor
# clipped back), and scored against the truth clipped to the tile (`lodforge eval --aoi TILE`).
# Prints the tiles' mean overall IoU, N-ratio, right angles (ours and the truth's), max tangent
# angle and PoLiS, then the same for the buildings the tile's edge cuts and the others
# (bench/tile_edges.py).
#
#   bench/tile_edges.sh ROW TRUTH TILE_M [--work DIR] [--every K] [--lodforge BIN] [--peers]
#
# --peers: also CGAL's and Douglas-Peucker's regularizers on each tile, on its contour as traced
# (stages.contour.edge_sweep_m=0: as a tool that knows nothing of the tile's edge runs them), the
# tiles' means printed beside ours.
#
# TILE_M: the tiles' width (their height 1.25 times it, as the 0.09 m tiles of issue 14); every
# K-th tile of the grid is taken (default 1). TRUTH: the row's true footprints (the campus's BAG
# footprints, or the row's data/ROW/footprints.gpkg for the synthetic city).
# Example (docs/quality-log.md, session 47):
#   bench/tile_edges.sh campus.p0.1.w0.5 ../shared/data/tudelft-campus-bag/tudcampus_bag_footprints.geojson 200 --every 2
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
row=$1; truth=$(realpath "$2"); tile_m=$3; shift 3
work=$root/build/tile-edges; every=1; lf=$root/build/lodforge; peers=0
while [[ $# -gt 0 ]]; do
  case $1 in
    --work) work=$2; shift 2;;
    --every) every=$2; shift 2;;
    --lodforge) lf=$2; shift 2;;
    --peers) peers=1; shift;;
    *) echo "tile_edges.sh: unknown option '$1'" >&2; exit 2;;
  esac
done
mask=$root/build/bench-sweep/data/$row/seg_class.tif
[[ -f $mask ]] || { echo "tile_edges.sh: '$mask' not found: run bench/sweep.sh first" >&2; exit 1; }
[[ -x $lf ]] || { echo "tile_edges.sh: lodforge binary '$lf' not found (--lodforge)" >&2; exit 1; }
out=$work/$row.$tile_m; mkdir -p "$out"
read -r width height < <(gdalinfo "$mask" | awk '/^Size is/{gsub(",", ""); print $3, $4}')
read -r x0 y0 px < <(gdalinfo "$mask" | awk -F'[(), ]+' '/^Origin/{x=$3; y=$4} /^Pixel Size/{p=$4} END{print x, y, p}')
tw=$(/usr/bin/python3 -c "print(round($tile_m / $px))"); th=$(/usr/bin/python3 -c "print(round(1.25 * $tile_m / $px))")
k=0
for ((r = 0; r + th <= height; r += th)); do
  for ((c = 0; c + tw <= width; c += tw)); do
    k=$((k + 1)); (( k % every == 0 )) || continue
    t=$out/t$c.$r
    gdal_translate -q -srcwin $c $r $tw $th "$mask" $t.tif
    read -r a b d e < <(/usr/bin/python3 -c "x=$x0+$c*$px; y=$y0-$r*$px; print(x, y-$th*$px, x+$tw*$px, y)")
    ogr2ogr -q -f GPKG $t.truth.gpkg "$truth" -clipsrc $a $b $d $e -nlt MULTIPOLYGON
    printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"Polygon","coordinates":[[[%s,%s],[%s,%s],[%s,%s],[%s,%s],[%s,%s]]]}}]}\n' \
      $a $b $d $b $d $e $a $e $a $b > $t.aoi.geojson
    runs=(default:"" cut:"--set stages.contour.edge_sweep_m=0")
    [[ $peers == 1 ]] && runs+=(cgal:"--regularizer cgal --set stages.contour.edge_sweep_m=0"
                                douglas_peucker:"--regularizer douglas_peucker --set stages.contour.edge_sweep_m=0")
    for run in "${runs[@]}"; do
      name=${run%%:*}; options=${run#*:}
      # (A tile without a building is skipped: regularize refuses an empty mask.)
      if "$lf" regularize -q --mask $t.tif $options --threads 1 --out $t.$name.gpkg 2> $t.$name.log; then
        "$lf" eval -q --pred $t.$name.gpkg --gt $t.truth.gpkg --aoi $t.aoi.geojson --json $t.$name.json --scores $t.$name.csv > /dev/null 2>> $t.$name.log
      fi
    done
  done
done
/usr/bin/python3 "$root/bench/tile_edges.py" "$out"
