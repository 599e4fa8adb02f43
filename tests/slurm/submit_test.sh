#!/usr/bin/env bash
# The Slurm scripts without a scheduler: scripts/slurm/submit.sh's usage errors, and the
# output directory it gives the merge job is where lodforge really writes, for several ways
# of writing output.dir, with python3's yaml module and with the small fallback parser;
# lodforge-array.sbatch and lodforge-merge.sbatch turn Slurm's variables into the right
# lodforge command line.
#
# usage: tests/slurm/submit_test.sh LODFORGE_BINARY [SOURCE_DIR]
set -euo pipefail

[ $# -ge 1 ] && [ $# -le 2 ] || { echo "usage: $0 LODFORGE_BINARY [SOURCE_DIR]" >&2; exit 2; }
lodforge="$(realpath "$1")"
src="$(realpath "${2:-$(dirname "$0")/../..}")"
slurm="$src/scripts/slurm"
tmp="$(cd "$(mktemp -d -t lodforge-submit-test.XXXXXX)" && pwd -P)"
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "submit_test: FAIL: $*" >&2; failures=$((failures + 1)); }
ok() { echo "submit_test: ok: $*"; }

expect() {  # CODE TEXT COMMAND...: exit code CODE and TEXT in its output
  local code="$1" text="$2" out rc=0
  shift 2
  out="$("$@" 2>&1)" || rc=$?
  if [ "$rc" -ne "$code" ] || [[ "$out" != *"$text"* ]]; then
    fail "'$*': exit $rc (expected $code), output: $out (expected to contain '$text')"
  else
    ok "$* -> $code, '$text'"
  fi
}

# ---- submit.sh: arguments ---------------------------------------------------------------------
"$lodforge" synth --out "$tmp/city" --size-m 60 --pixel-size 1 --seed 4 > /dev/null 2>&1
mkdir -p "$tmp/jobs/sub"
job="$tmp/jobs/plain.yaml"
echo "inputs: {segmentation: {path: ../city/seg_class.tif}}" > "$job"
expect 2 "usage:" "$slurm/submit.sh"
expect 2 "usage:" "$slurm/submit.sh" --help
expect 1 "job file '$tmp/none.yaml' not found" "$slurm/submit.sh" "$tmp/none.yaml" --shards 2
expect 1 "--shards N is required" "$slurm/submit.sh" "$job"
for bad in 0 -3 abc 04 2.5; do
  expect 1 "N must be a positive integer, got '$bad'" "$slurm/submit.sh" "$job" --shards "$bad"
done
expect 1 "'$tmp/no-sbatch' not found" env SBATCH="$tmp/no-sbatch" "$slurm/submit.sh" "$job" --shards 2
expect 1 "'--array=0-3' is set by" "$slurm/submit.sh" "$job" --shards 4 --array=0-3
expect 1 "is not an executable" "$slurm/submit.sh" "$job" --shards 4 --lodforge "$tmp/none" --dry-run
expect 0 "--array=0-2 -p big -c 8 $slurm/lodforge-array.sbatch $job 3" "$slurm/submit.sh" "$job" --shards 3 --dry-run -p big -c 8

# ---- submit.sh: the output directory is where lodforge writes ---------------------------------
# NAME CONTENT(after the inputs line) EXPECTED(output dir, relative to $tmp/jobs unless absolute)
check_out_dir() {
  local name="$1" body="$2" expected="$3" parser dir
  printf 'inputs: {segmentation: {path: %s/city/seg_class.tif}}\n%b' "$tmp" "$body" > "$tmp/jobs/sub/$name.yaml"
  case "$expected" in /*) ;; *) expected="$tmp/jobs/$expected" ;; esac
  rm -rf "$expected"
  (cd "$tmp/jobs/sub" && "$lodforge" run "$name.yaml" --set tiling.tile_size_m=60 > /dev/null 2>&1) || { fail "$name: lodforge run failed"; return; }
  [ -f "$expected/tile_index.geojson" ] || { fail "$name: lodforge did not write to $expected"; return; }
  for parser in python awk; do
    [ "$parser" = awk ] || python3 -c 'import yaml' 2>/dev/null || continue
    # from another working directory, with a relative job path
    dir="$(cd "$tmp" && LODFORGE_YAML_PARSER="$parser" "$slurm/submit.sh" "jobs/sub/./$name.yaml" --shards 2 --dry-run 2>/dev/null |
           sed -n 's/.*, 2 shards, output //p')"
    if [ "$dir" = "$expected" ]; then ok "$name ($parser): $dir"; else fail "$name ($parser): output '$dir', lodforge wrote to '$expected'"; fi
  done
}
check_out_dir flow 'output: {formats: [gpkg, geojson], dir: ../flow-out, quicklook: false}\n' flow-out
check_out_dir flow_first 'output: {dir: "flow first"}  # a comment\n' "sub/flow first"
check_out_dir block 'work_dir: w\noutput:   # outputs\n  formats: [gpkg]\n  dir: '\''../block out'\''  # the dir\n  quicklook: false\nthreads: 1\n' "block out"
check_out_dir default 'tiling: {tile_size_m: 60}\n' sub/out
check_out_dir no_dir 'output:\n  quicklook: false\nwork_dir: w2\n' sub/out
check_out_dir absolute "output: {dir: $tmp/abs/./out}\n" "$tmp/abs/out"
check_out_dir dots 'output:\n  dir: ./a/../b//c\n' sub/b/c

# ---- the sbatch scripts outside Slurm, with a lodforge that prints its arguments -------------
fake="$tmp/fake-lodforge"
printf '#!/bin/sh\necho "lodforge $*"\n' > "$fake"
chmod +x "$fake"
array="$slurm/lodforge-array.sbatch"
expect 1 "not an array task" "$array" "$job" 4 --lodforge "$fake"
expect 0 "lodforge run $job --shard 2/4 --threads 3" env SLURM_ARRAY_TASK_ID=2 SLURM_CPUS_PER_TASK=3 "$array" "$job" 4 --lodforge "$fake"
expect 0 "lodforge run $job --shard 1/4 --threads 2" env SLURM_ARRAY_TASK_ID=1 SLURM_JOB_CPUS_PER_NODE='2(x3)' "$array" "$job" 4 --lodforge="$fake"
expect 0 "lodforge run $job --shard 3/4" env SLURM_ARRAY_TASK_ID=3 SLURM_ARRAY_TASK_COUNT=4 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_MAX=3 "$array" "$job" --lodforge "$fake"
expect 1 "give the shard count N" env SLURM_ARRAY_TASK_ID=2 SLURM_ARRAY_TASK_COUNT=1 SLURM_ARRAY_TASK_MIN=2 SLURM_ARRAY_TASK_MAX=2 "$array" "$job" --lodforge "$fake"
expect 1 "array task 4 is not a shard of 4" env SLURM_ARRAY_TASK_ID=4 "$array" "$job" 4 --lodforge "$fake"
expect 1 "N must be a positive integer, got 'x'" env SLURM_ARRAY_TASK_ID=0 "$array" "$job" x --lodforge "$fake"
expect 1 "job file '$tmp/none.yaml' not found" env SLURM_ARRAY_TASK_ID=0 "$array" "$tmp/none.yaml" 2 --lodforge "$fake"
expect 1 "lodforge binary '$tmp/none' not found" env SLURM_ARRAY_TASK_ID=0 "$array" "$job" 2 --lodforge "$tmp/none"
expect 2 "usage:" "$array"
merge="$slurm/lodforge-merge.sbatch"
expect 0 "lodforge merge $tmp/city" "$merge" "$tmp/city" --lodforge "$fake"
expect 1 "output directory '$tmp/none' not found" "$merge" "$tmp/none" --lodforge "$fake"
expect 2 "usage:" "$merge"

if [ "$failures" -gt 0 ]; then
  echo "submit_test: $failures failure(s)"
  exit 1
fi
echo "submit_test: PASS"
