#!/usr/bin/env bash
# The performance benchmark (issue 7): per-stage micro-benchmarks, and end-to-end runs of
# `lodforge run` on procedural cities of 1x, 4x and 16x area (0.5, 2 and 8 km^2 at 0.25 m) with
# wall time, buildings per second, peak RSS, the I/O floor (a process that only reads the same
# rasters with GDAL: build/bench/io_floor), 1 vs 2 threads, and the Douglas-Peucker regularizer
# with LoD1.2 alone (the engine with the cheapest modeling).
# Regenerates the results section of docs/performance.md (between its markers). Warm page cache:
# every raster is read once first.
#
#   bench/performance.sh [--work DIR] [--scales 1,4,16] [--repeat N] [--no-micro] [--no-docs]
#
# N rounds (default 5) run every configuration once each, from scratch; the table keeps each
# configuration's run of median wall time and its highest peak RSS, and the two-thread speedup
# is the median over the rounds of one thread's wall over two threads' in the same round. The
# I/O floor is the median of N reads. Wall times and peak RSS by bench/timed.py.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
lodforge="${LODFORGE:-$root/build/lodforge}"
stages_bench="${STAGES_BENCH:-$root/build/bench/stages_bench}"
io_floor="${IO_FLOOR:-$root/build/bench/io_floor}"
work="$root/build/bench-performance"
scales="1,4,16"
repeat=5
micro=1
docs=1
while [ $# -gt 0 ]; do
  case "$1" in
    --work) work="$2"; shift 2 ;;
    --scales) scales="$2"; shift 2 ;;
    --repeat) repeat="$2"; shift 2 ;;
    --no-micro) micro=0; shift ;;
    --no-docs) docs=0; shift ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "bench/performance.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -x "$lodforge" ] || { echo "bench/performance.sh: no lodforge binary at $lodforge; run scripts/build.sh first" >&2; exit 1; }
[ -x "$io_floor" ] || { echo "bench/performance.sh: no io_floor binary at $io_floor; run scripts/build.sh first" >&2; exit 1; }
mkdir -p "$work"
results="$work/results.jsonl"
: > "$results"

if [ "$micro" = 1 ]; then
  echo "bench/performance.sh: stage micro-benchmarks" >&2
  "$stages_bench" --benchmark_min_time=0.2 --benchmark_format=json --benchmark_out="$work/stages.json" >/dev/null
fi

IFS=, read -ra scale_list <<< "$scales"
for s in "${scale_list[@]}"; do
  side=$(/usr/bin/python3 -c "import math; print(round(math.sqrt(500000 * $s)))")
  data="$work/data/x$s"
  if [ ! -f "$data/seg_class.tif" ]; then
    echo "bench/performance.sh: generating a ${side} m city ($s x 0.5 km^2)" >&2
    "$lodforge" synth --size-m "$side" --pixel-size 0.25 --seed 5 --out "$data" >/dev/null 2>&1
  fi
  rasters=("$data/seg_class.tif" "$data/dsm.tif" "$data/dtm.tif")
  "$io_floor" "${rasters[@]}" >/dev/null  # warm the page cache
  # The floor: the whole process's wall time (start-up and loading GDAL, as in a run), median of
  # N, with the seconds of its reads alone.
  floors=$(for k in $(seq "$repeat"); do
    reads=$("$root/bench/timed.py" "$work/floor.time" "$io_floor" "${rasters[@]}") || exit 1
    echo "$(cut -d' ' -f1 "$work/floor.time") $reads"
  done | sort -g | sed -n "$(( (repeat + 1) / 2 ))p")
  read -r floor floor_reads <<< "$floors"
  configs=("deformation 1" "deformation 2" "douglas_peucker 2")
  for config in "${configs[@]}"; do
    set -- $config
    run="$work/run-x$s-$1-t$2"
    rm -rf "$run"
    mkdir -p "$run"
    cat > "$run/job.yaml" <<YAML
inputs:
  segmentation: {path: $data/seg_class.tif}
  dsm: {path: $data/dsm.tif}
  dtm: {path: $data/dtm.tif}
output: {dir: out, formats: [citygml, cityjson, obj, gpkg]}
work_dir: work
threads: $2
regularizer: $1
stages: {parts: {enabled: $([ "$1" = douglas_peucker ] && echo false || echo true)}}
YAML
    : > "$run/times"
  done
  # Rounds of one run per configuration, so that the machine's drift over minutes falls on all
  # of them alike (the two-thread speedup is also taken round by round).
  echo "bench/performance.sh: x$s, $repeat round(s) of ${#configs[@]} runs" >&2
  for k in $(seq "$repeat"); do
    for config in "${configs[@]}"; do
      set -- $config
      run="$work/run-x$s-$1-t$2"
      # Each run into new directories: deleting a run's ~1,000 files right before the next creates
      # as many made the next run's file creation slow on a journal-less ext4 (it skips inodes
      # freed in the last minutes, scanning past them: up to a fifth of a run in the kernel).
      "$root/bench/timed.py" "$run/time" "$lodforge" run "$run/job.yaml" --set "output.dir=$run/round$k/out" \
        --set "work_dir=$run/round$k/work" > "$run/log" 2>&1
      read -r wall rss_kib < "$run/time"
      cp "$run/round$k/out/report.json" "$run/report-$k.json"
      echo "$wall $rss_kib $k" >> "$run/times"
    done
  done
  for config in "${configs[@]}"; do
    set -- $config
    regularizer=$1 threads=$2
    run="$work/run-x$s-$regularizer-t$threads"
    read -r wall rss_kib k < <(sort -g "$run/times" | sed -n "$(( (repeat + 1) / 2 ))p")
    rss_kib=$(sort -g -k2 "$run/times" | tail -1 | cut -d' ' -f2)  # the highest of the runs
    /usr/bin/python3 - "$run" "$s" "$side" "$regularizer" "$threads" "$wall" "$rss_kib" "$floor" "$floor_reads" "$k" >> "$results" <<'PY'
import json, sys
run, s, side, reg, threads, wall, rss, floor, floor_reads, k = sys.argv[1:]
rep = json.load(open(f"{run}/report-{k}.json"))
walls = [float(l.split()[0]) for l in open(run + "/times")]  # in round order
print(json.dumps({"scale": int(s), "side_m": int(side), "regularizer": reg, "threads": int(threads), "wall_s": float(wall),
                  "wall_runs_s": walls, "peak_rss_mb": int(rss) / 1024, "io_floor_s": float(floor), "io_reads_s": float(floor_reads), "buildings": rep["buildings"],
                  "core_seconds": rep["core_seconds"], "stage_seconds": rep["stage_seconds"], "tiles": rep["tiles"]}))
PY
  done
done
rm -rf "$work"/run-*/round*  # the runs' outputs, once every run is timed
args=("$work" --cores "$(nproc)" --command "bench/performance.sh --scales $scales --repeat $repeat")
[ "$micro" = 1 ] && args+=(--stages "$work/stages.json")
if [ "$docs" = 1 ]; then
  /usr/bin/python3 "$root/bench/performance_table.py" "${args[@]}" --doc "$root/docs/performance.md"
  echo "bench/performance.sh: results written to docs/performance.md" >&2
else
  /usr/bin/python3 "$root/bench/performance_table.py" "${args[@]}"
fi
