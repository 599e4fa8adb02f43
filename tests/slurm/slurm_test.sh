#!/usr/bin/env bash
# Integration test on a real scheduler: starts a single-node Slurm (Debian's slurm-wlm) on
# loopback with its state in a temporary directory, runs a job through scripts/slurm/submit.sh
# as an array of 4 shards plus the merge job, and checks that the outputs are byte-identical
# to a single-process run of the same job. Second case: one array task is killed (SIGKILL)
# mid-run, the merge job is then cancelled; the task is resubmitted alone with the command
# submit.sh prints, resumes from its checkpoints, and the outputs are again byte-identical.
#
# usage: tests/slurm/slurm_test.sh LODFORGE_BINARY [SOURCE_DIR]
# Exit 77 (skipped) only when slurmctld or slurmd is not installed. Runs as root (daemons as
# root) or as any other user (daemons and jobs as that user). LODFORGE_KEEP_TMP=1 keeps the
# temporary directory.
set -euo pipefail

[ $# -ge 1 ] && [ $# -le 2 ] || { echo "usage: $0 LODFORGE_BINARY [SOURCE_DIR]" >&2; exit 2; }
# The daemons live in an sbin directory that is often not on a user's PATH: look beside the
# client tools' directory too (bin/../sbin), or where SLURM_SBIN says.
if client="$(command -v sbatch 2>/dev/null)"; then
  export PATH="$PATH:${SLURM_SBIN:-$(dirname "$client")/../sbin}"
fi
for daemon in slurmctld slurmd; do
  if ! command -v "$daemon" >/dev/null 2>&1; then
    echo "slurm_test: SKIP: $daemon not installed (apt-get install slurm-wlm; or set SLURM_SBIN)"
    exit 77
  fi
done
lodforge="$(realpath "$1")"
src="$(realpath "${2:-$(dirname "$0")/../..}")"
submit="$src/scripts/slurm/submit.sh"
[ -x "$lodforge" ] || { echo "slurm_test: '$lodforge' is not executable" >&2; exit 1; }
[ -x "$submit" ] || { echo "slurm_test: '$submit' is not executable" >&2; exit 1; }
for tool in sbatch squeue scontrol scancel sinfo ss; do
  command -v "$tool" >/dev/null 2>&1 || { echo "slurm_test: $tool not found (slurm-client, iproute2)" >&2; exit 1; }
done

start=$SECONDS
limit=$((SECONDS + ${LODFORGE_SLURM_TEST_LIMIT:-600}))  # every wait ends by then (ctest's TIMEOUT is longer)
log() { echo "slurm_test [$((SECONDS - start)) s]: $*"; }
tmp="$(mktemp -d -t lodforge-slurm-test.XXXXXX)"  # in $TMPDIR, else the system default
chmod 755 "$tmp"
export SLURM_CONF="$tmp/slurm/slurm.conf"
mkdir -p "$tmp/slurm/state" "$tmp/slurm/spool" "$tmp/logs"

dump() {
  echo "---- slurmctld.log (tail) ----"; tail -n 40 "$tmp/slurm/slurmctld.log" 2>/dev/null || true
  echo "---- slurmd.log (tail) ----"; tail -n 40 "$tmp/slurm/slurmd.log" 2>/dev/null || true
  squeue -h -t all -r -o '%i %j %T %r' 2>/dev/null || true
  for f in "$tmp"/logs/*; do
    [ -f "$f" ] || continue
    echo "---- $(basename "$f") (tail) ----"; tail -n 15 "$f"
  done
}
stop_daemons() {
  if [ -f "$tmp/slurm/slurmctld.pid" ]; then
    scancel --user="$(id -un)" >/dev/null 2>&1 || true
    for _ in $(seq 50); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
  fi
  local pids=() p
  for p in slurmd slurmctld; do
    [ -f "$tmp/slurm/$p.pid" ] && pids+=("$(cat "$tmp/slurm/$p.pid")")
  done
  [ ${#pids[@]} -gt 0 ] || return 0
  kill "${pids[@]}" 2>/dev/null || true
  for _ in $(seq 50); do
    kill -0 "${pids[@]}" 2>/dev/null || return 0
    sleep 0.2
  done
  kill -KILL "${pids[@]}" 2>/dev/null || true
}
finish() {
  local rc=$?
  trap - EXIT
  if [ "$rc" -ne 0 ]; then
    echo "slurm_test: FAILED (exit $rc); logs:"
    dump
  fi
  stop_daemons
  if [ "${LODFORGE_KEEP_TMP:-0}" = 1 ]; then echo "slurm_test: kept $tmp"; else rm -rf "$tmp"; fi
  exit "$rc"
}
trap finish EXIT
trap 'exit 130' INT TERM
fail() {
  echo "slurm_test: FAIL: $*" >&2
  exit 1
}

# ---- a single-node Slurm on loopback --------------------------------------------------------
# Two free ports next to each other, chosen from the process id so parallel runs differ.
# (Listening TCP sockets from iproute2's ss: no port in use is listed.)
port_free() { [ -z "$(ss -Htln "( sport = :$1 )")" ]; }
port=""
for attempt in $(seq 0 49); do
  p=$((20000 + ($$ * 7 + attempt * 211) % 12000))  # below the ephemeral range (32768-)
  if port_free "$p" && port_free "$((p + 1))"; then port=$p; break; fi
done
[ -n "$port" ] || fail "no two free ports next to each other"
user="$(id -un)"
node="lodforge-test-node"
: > "$tmp/slurm/plugstack.conf"
cat > "$SLURM_CONF" <<EOF
ClusterName=lodforgetest
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/none
CredType=cred/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
MinJobAge=3600
MailProg=$(type -P true)
PlugStackConfig=$tmp/slurm/plugstack.conf
StateSaveLocation=$tmp/slurm/state
SlurmdSpoolDir=$tmp/slurm/spool
SlurmctldPidFile=$tmp/slurm/slurmctld.pid
SlurmdPidFile=$tmp/slurm/slurmd.pid
SlurmctldLogFile=$tmp/slurm/slurmctld.log
SlurmdLogFile=$tmp/slurm/slurmd.log
SlurmdParameters=config_overrides
NodeName=$node NodeHostname=$(hostname) NodeAddr=127.0.0.1 CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
log "starting slurmctld and slurmd as $user on 127.0.0.1:$port-$((port + 1)), state in $tmp/slurm"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" -N "$node" || fail "slurmd did not start"
for _ in $(seq 150); do
  state="$(sinfo -h -n "$node" -o %t 2>/dev/null || true)"
  [ "$state" = idle ] && break
  sleep 0.2
done
[ "$state" = idle ] || fail "node $node is '$state', not idle, after 30 s"
log "node $node idle ($(sinfo --version))"

# ---- the job: a city with 96 tiles, slow enough (the paper's deformed route) to kill a task --
width=600 height=400 tile=50 shards=4 killed=2
"$lodforge" synth --out "$tmp/city" --size-m "${width}x$height" --pixel-size 0.5 --seed 3 > "$tmp/logs/synth.log" 2>&1 ||
  fail "lodforge synth failed"
write_job() {  # NAME: a job writing to NAME/out with its checkpoints in NAME/work
  cat > "$tmp/$1.yaml" <<EOF
inputs:
  segmentation: {path: city/seg_class.tif, building_values: [6]}
  dsm: {path: city/dsm.tif}
  dtm: {path: city/dtm.tif}
tiling: {tile_size_m: $tile}
output:
  dir: $1/out  # relative to this file
work_dir: $1/work
stages: {corners: {route: deformed}}
EOF
}

log "reference: one process, lodforge run + lodforge merge"
write_job single
"$lodforge" run "$tmp/single.yaml" --threads 2 > "$tmp/logs/single-run.log" 2>&1 || fail "reference run failed"
"$lodforge" merge "$tmp/single/out" > "$tmp/logs/single-merge.log" 2>&1 || fail "reference merge failed"
[ -n "$(ls "$tmp/single/out/merged")" ] || fail "the reference merge wrote nothing"
log "reference done: $(ls "$tmp/single/out/tiles" | wc -l) tile files, merged: $(ls "$tmp/single/out/merged" | tr '\n' ' ')"

# ---- helpers -----------------------------------------------------------------------------------
terminal_state() {
  case "$1" in
    COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | BOOT_FAIL | DEADLINE | PREEMPTED) return 0 ;;
    *) return 1 ;;
  esac
}
states() {  # JOBID...: "id state" per job and array task
  local ids
  ids="$(IFS=,; echo "$*")"
  squeue -h -t all -r -j "$ids" -o '%i %T' | sort
}
state_of() {  # ID (e.g. 12 or 12_2)
  squeue -h -t all -r -j "$1" -o '%i %T' | awk -v id="$1" '$1 == id { print $2 }'
}
wait_jobs() {  # JOBID...: until every task has ended
  local finished
  while :; do
    finished=1
    while read -r _ s; do terminal_state "$s" || finished=0; done < <(states "$@")
    [ "$finished" -eq 1 ] && [ -n "$(states "$@")" ] && return 0
    [ "$SECONDS" -lt "$limit" ] || fail "jobs $* still not finished after $((SECONDS - start)) s: $(states "$@" | tr '\n' ' ')"
    sleep 0.5
  done
}
expect_state() {  # ID STATE
  local s
  s="$(state_of "$1")"
  [ "$s" = "$2" ] || fail "job $1 is $s, expected $2"
}
same_outputs() {  # NAME: NAME/out has the reference's tile index, per-tile files and merged files
  local out="$tmp/$1/out" ref="$tmp/single/out" f
  cmp "$ref/tile_index.geojson" "$out/tile_index.geojson" || fail "$1: tile_index.geojson differs from the single run"
  for d in tiles merged; do
    diff <(cd "$ref/$d" && ls -A) <(cd "$out/$d" && ls -A) || fail "$1: the files in $d/ differ from the single run"
    for f in "$ref/$d"/*; do
      # (report.html tells the run's times and shards, as report.json does: checked for its numbers below)
      [ "$(basename "$f")" = report.html ] && continue
      cmp "$f" "$out/$d/$(basename "$f")" || fail "$1: $d/$(basename "$f") differs from the single run"
    done
  done
  [ -f "$out/report.json" ] || fail "$1: the merge job wrote no report.json"
  grep -q "<tr><th>buildings</th><td class=\"n\">$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['buildings'])" "$ref/report.json")</td></tr>" "$out/merged/report.html" ||
    fail "$1: merged/report.html does not give the single run's building count"
  log "$1: tile_index.geojson, $(ls "$out/tiles" | wc -l) files in tiles/ and $(ls "$out/merged" | wc -l) in merged/ are byte-identical to the single run (report.html: its numbers)"
}
submit_job() {  # NAME: submits NAME.yaml; sets array_id, merge_id and keeps submit.sh's output
  "$submit" "$tmp/$1.yaml" --shards "$shards" --lodforge "$lodforge" -o "$tmp/logs/%x-%A_%a.out" > "$tmp/logs/$1-submit.txt" 2>&1 ||
    { cat "$tmp/logs/$1-submit.txt"; fail "submit.sh failed"; }
  array_id="$(sed -n 's/^array job: \([0-9][0-9]*\).*/\1/p' "$tmp/logs/$1-submit.txt")"
  merge_id="$(sed -n 's/^merge job: \([0-9][0-9]*\).*/\1/p' "$tmp/logs/$1-submit.txt")"
  [ -n "$array_id" ] && [ -n "$merge_id" ] || { cat "$tmp/logs/$1-submit.txt"; fail "no job ids in submit.sh's output"; }
  grep -q "output $tmp/$1/out\$" "$tmp/logs/$1-submit.txt" || { cat "$tmp/logs/$1-submit.txt"; fail "submit.sh did not resolve output.dir to $tmp/$1/out"; }
}

# ---- case 1: an array of 4 shards and the merge job ------------------------------------------
write_job array
submit_job array
log "case 1: array job $array_id ($shards tasks), merge job $merge_id"
wait_jobs "$array_id" "$merge_id"
for k in $(seq 0 $((shards - 1))); do expect_state "${array_id}_$k" COMPLETED; done
expect_state "$merge_id" COMPLETED
log "case 1: every task and the merge COMPLETED"
same_outputs array

# ---- case 2: a task killed mid-run, resubmitted alone -----------------------------------------
write_job killed
submit_job killed
log "case 2: array job $array_id, merge job $merge_id; waiting for task $killed to run and write two tiles"
cols=$(((width + tile - 1) / tile)) rows=$(((height + tile - 1) / tile))
shard_tiles=()  # the done marker of every tile of the shard that will be killed
for ((n = killed; n < cols * rows; n += shards)); do
  shard_tiles+=("$(printf '%s/killed/work/r%04d_c%04d.done' "$tmp" $((n / cols)) $((n % cols)))")
done
written() { local f c=0; for f in "${shard_tiles[@]}"; do [ -f "$f" ] && c=$((c + 1)); done; echo "$c"; }
while :; do
  s="$(state_of "${array_id}_$killed")"
  # two tiles complete (their done markers, written last): the rerun surely resumes them
  if [ "$s" = RUNNING ] && [ "$(written)" -ge 2 ]; then break; fi
  terminal_state "${s:-PENDING}" && fail "task $killed ended ($s) before it could be killed: the job is too fast for this test"
  [ "$SECONDS" -lt "$limit" ] || fail "task $killed did not start in time"
  sleep 0.1
done
scancel --batch --signal=KILL "${array_id}_$killed"
log "case 2: sent SIGKILL to task ${array_id}_$killed after $(written) of its tiles were written"
wait_jobs "$array_id" "$merge_id"
s="$(state_of "${array_id}_$killed")"
[ "$s" = FAILED ] || [ "$s" = CANCELLED ] || fail "the killed task is $s, expected FAILED"
for k in $(seq 0 $((shards - 1))); do [ "$k" -eq "$killed" ] || expect_state "${array_id}_$k" COMPLETED; done
expect_state "$merge_id" CANCELLED
[ ! -e "$tmp/killed/out/report.shard-$killed-of-$shards.json" ] || fail "the killed shard finished (its report exists)"
[ ! -e "$tmp/killed/out/merged" ] || fail "merged/ exists although a task failed"
partial="$(written)"
[ "$partial" -lt "$(ls "$tmp"/single/out/tiles/*.gml | awk -v k="$killed" -v s="$shards" -v c="$cols" '
  { n = split($0, p, "/"); f = p[n]; r = substr(f, 2, 4) + 0; col = substr(f, 8, 4) + 0; if ((r * c + col) % s == k) t++ }
  END { print t + 0 }')" ] || fail "every tile of the killed shard was written: it was not killed mid-run"
log "case 2: task $killed $s with $partial tiles written, the others COMPLETED, merge job $merge_id CANCELLED (dependency never satisfied)"

# Resubmit with the commands submit.sh printed, task K := the killed one.
resubmit_array="$(grep '^  new=' "$tmp/logs/killed-submit.txt" | sed "s/--array=K/--array=$killed/")"
resubmit_merge="$(grep -A1 '^  new=' "$tmp/logs/killed-submit.txt" | tail -n 1)"
[ -n "$resubmit_array" ] && [ -n "$resubmit_merge" ] || fail "submit.sh printed no resubmission commands"
new=""
eval "$resubmit_array"
[ -n "$new" ] || fail "resubmitting task $killed gave no job id"
merge2="$(eval "$resubmit_merge" | sed -n 's/^Submitted batch job \([0-9][0-9]*\).*/\1/p')"
[ -n "$merge2" ] || fail "resubmitting the merge gave no job id"
log "case 2: resubmitted task $killed as job $new, merge as job $merge2"
wait_jobs "$new" "$merge2"
expect_state "${new}_$killed" COMPLETED
expect_state "$merge2" COMPLETED
resumed="$(sed -n 's/.*tiles (\([0-9]*\) computed, \([0-9]*\) resumed.*/\2/p' "$tmp/logs/lodforge-${new}_$killed.out")"
[ "${resumed:-0}" -ge 1 ] || fail "the resubmitted task resumed no tile: $(grep 'tiles (' "$tmp/logs/lodforge-${new}_$killed.out")"
log "case 2: the resubmitted task resumed $resumed tiles from its checkpoints"
same_outputs killed

log "PASS"
