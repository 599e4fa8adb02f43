#!/usr/bin/env bash
# Submits a lodforge job to Slurm as an array of N shards (lodforge-array.sbatch, one
# `lodforge run JOB.yaml --shard K/N` per task) and a merge job (lodforge-merge.sbatch,
# `lodforge merge OUT_DIR`) that runs once every task has succeeded (afterok) and is
# cancelled when one fails. Prints both job ids, how to follow them and how to resubmit a
# failed task alone (it resumes from its checkpoints). See docs/cluster.md.
#
# usage: scripts/slurm/submit.sh JOB.yaml --shards N [--lodforge PATH] [--dry-run] [sbatch options...]
#
# Every other argument is passed to both sbatch calls (e.g. -p PARTITION -c 8 --mem=2G -t 2:00:00).
# OUT_DIR is the job's output.dir, resolved as lodforge resolves it: relative to the directory
# of the job file (taken as given, not through symbolic links), default 'out'. It is read with
# python3's yaml module when present, otherwise by a small parser that understands
# `output: {dir: X, ...}` and a block `output:` with an indented `dir: X`.
# Environment: SBATCH (default sbatch) is the submit command; LODFORGE_YAML_PARSER=awk forces
# the small parser (for tests).
set -euo pipefail

prog="scripts/slurm/submit.sh"
usage() {
  cat >&2 <<EOF
usage: $prog JOB.yaml --shards N [--lodforge PATH] [--dry-run] [sbatch options...]

  JOB.yaml          the lodforge job (on a file system every node sees at the same path)
  --shards N        number of shards = array tasks (a positive integer)
  --lodforge PATH   the lodforge binary on the nodes (default: lodforge in PATH)
  --dry-run         print the sbatch commands instead of running them
  sbatch options    passed to both jobs, e.g. -p PARTITION -c 8 --mem=2G -t 2:00:00
EOF
  exit 2
}
fail() {
  echo "$prog: error: $*" >&2
  exit 1
}

[ $# -ge 1 ] || usage
case "$1" in -h | --help) usage ;; -*) echo "$prog: error: the first argument is the job file" >&2; usage ;; esac
job="$1"
shift
shards="" lodforge="" dry_run=0
sbatch_opts=()
while [ $# -gt 0 ]; do
  case "$1" in
    --shards) [ $# -ge 2 ] || usage; shards="$2"; shift 2 ;;
    --shards=*) shards="${1#--shards=}"; shift ;;
    --lodforge) [ $# -ge 2 ] || usage; lodforge="$2"; shift 2 ;;
    --lodforge=*) lodforge="${1#--lodforge=}"; shift ;;
    --dry-run) dry_run=1; shift ;;
    -h | --help) usage ;;
    -a | --array | --array=* | -d | --dependency | --dependency=* | --parsable | --kill-on-invalid-dep*)
      fail "'$1' is set by $prog, do not pass it" ;;
    *) sbatch_opts+=("$1"); shift ;;
  esac
done

[ -f "$job" ] || fail "job file '$job' not found"
[ -n "$shards" ] || fail "--shards N is required"
case "$shards" in
  *[!0-9]* | 0*) fail "--shards: N must be a positive integer, got '$shards'" ;;
esac
sbatch="${SBATCH:-sbatch}"
if [ "$dry_run" -eq 0 ]; then
  command -v "$sbatch" >/dev/null 2>&1 || fail "'$sbatch' not found: run this on a Slurm submit host (or set SBATCH)"
fi
if [ -n "$lodforge" ]; then
  case "$lodforge" in */*) lodforge="$(realpath -s -- "$lodforge")" ;; esac
  command -v "$lodforge" >/dev/null 2>&1 || fail "--lodforge: '$lodforge' is not an executable"
  lodforge_opt=(--lodforge "$lodforge")
else
  command -v lodforge >/dev/null 2>&1 || echo "$prog: warning: lodforge is not in PATH here; the nodes must have it (or give --lodforge PATH)" >&2
  lodforge_opt=()
fi

# The job file as lodforge sees it from any working directory: lodforge takes its parent
# directory without resolving symbolic links (std::filesystem::absolute, then
# lexically_normal), so do the same (physical working directory, realpath --no-symlinks).
case "$job" in /*) job_abs="$job" ;; *) job_abs="$(pwd -P)/$job" ;; esac

# output.dir as written in the job file.
output_dir_python() {
  python3 - "$job_abs" <<'EOF'
import sys, yaml
# BaseLoader: every scalar stays the text it is, as yaml-cpp reads it.
root = yaml.load(open(sys.argv[1], encoding="utf-8"), Loader=yaml.BaseLoader)
out = root.get("output") if isinstance(root, dict) else None
d = out.get("dir", "out") if isinstance(out, dict) else "out"
if not isinstance(d, str):
    sys.exit("output.dir is not a string")
print(d)
EOF
}
output_dir_awk() {
  awk '
    function clean(v) {
      sub(/[ \t]+#.*$/, "", v); gsub(/^[ \t]+|[ \t]+$/, "", v)
      if (v ~ /^".*"$/ || v ~ /^'\''.*'\''$/) v = substr(v, 2, length(v) - 2)
      return v
    }
    /^output[ \t]*:[ \t]*\{/ {
      s = $0; sub(/^output[ \t]*:[ \t]*\{/, "", s); sub(/\}[^}]*$/, "", s)
      n = split(s, part, ",")
      for (i = 1; i <= n; i++)
        if (part[i] ~ /^[ \t]*dir[ \t]*:/) { v = part[i]; sub(/^[ \t]*dir[ \t]*:/, "", v); found = clean(v); exit }
      exit
    }
    /^output[ \t]*:[ \t]*(#.*)?$/ { block = 1; next }
    block && /^[^ \t#]/ { exit }
    block && /^[ \t]+dir[ \t]*:/ { v = $0; sub(/^[ \t]+dir[ \t]*:/, "", v); found = clean(v); exit }
    END { print (found == "" ? "out" : found) }
  ' "$job_abs"
}
if [ "${LODFORGE_YAML_PARSER:-}" != awk ] && python3 -c 'import yaml' >/dev/null 2>&1; then
  out_dir="$(output_dir_python)" || fail "'$job': cannot read output.dir (is it valid YAML? lodforge run says more)"
else
  out_dir="$(output_dir_awk)"
fi
[ -n "$out_dir" ] || out_dir=out
case "$out_dir" in /*) ;; *) out_dir="$(dirname -- "$job_abs")/$out_dir" ;; esac
out_dir="$(realpath -m -s -- "$out_dir")"

here="$(cd "$(dirname -- "${BASH_SOURCE[0]}")" && pwd -P)"
array_script="$here/lodforge-array.sbatch"
merge_script="$here/lodforge-merge.sbatch"
[ -f "$array_script" ] && [ -f "$merge_script" ] || fail "lodforge-array.sbatch and lodforge-merge.sbatch must be beside $prog"

q() {  # a command line, quoted for the shell, with a trailing space
  local a
  for a in "$@"; do printf '%q ' "$a"; done
}
array_cmd=("$sbatch" --parsable --array="0-$((shards - 1))" "${sbatch_opts[@]}" "$array_script" "$job_abs" "$shards" "${lodforge_opt[@]}")
merge_cmd=("$sbatch" --parsable --kill-on-invalid-dep=yes "${sbatch_opts[@]}" "$merge_script" "$out_dir" "${lodforge_opt[@]}")

echo "$prog: job $job_abs, $shards shards, output $out_dir"
if [ "$dry_run" -eq 1 ]; then
  q "${array_cmd[@]}"
  echo
  echo "$(q "${merge_cmd[@]:0:3}")--dependency=afterok:ARRAY_JOB_ID $(q "${merge_cmd[@]:3}")"
  exit 0
fi

array_id="$("${array_cmd[@]}")" || fail "sbatch refused the array job"
array_id="${array_id%%;*}"
merge_id="$("${merge_cmd[@]:0:3}" --dependency="afterok:$array_id" "${merge_cmd[@]:3}")" || fail "sbatch refused the merge job (array job $array_id is submitted)"
merge_id="${merge_id%%;*}"

cat <<EOF
array job: $array_id (tasks 0-$((shards - 1)): lodforge run --shard K/$shards)
merge job: $merge_id (lodforge merge $out_dir, after every task succeeded)
follow:    squeue -j $array_id,$merge_id    (sacct -j $array_id,$merge_id with accounting)
If task K fails, the merge job is cancelled. Resubmit the task alone (it resumes from its
checkpoints in work_dir), then the merge (after the new task and the rest of the array):
  new=\$($(q "$sbatch" --parsable --array=K "${sbatch_opts[@]}" "$array_script" "$job_abs" "$shards" "${lodforge_opt[@]}"))
  $(q "$sbatch" --kill-on-invalid-dep=yes)--dependency=afterok:\$new,afterany:$array_id $(q "${sbatch_opts[@]}" "$merge_script" "$out_dir" "${lodforge_opt[@]}")
EOF
