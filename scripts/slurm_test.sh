#!/usr/bin/env bash
# The `slurm` stage of scripts/test.sh: runs an ablation grid through a real
# single-node Slurm cluster (scripts/slurm_local.sh) with the Snakemake
# workflow and its Slurm profile, and checks the result against `rvlio ablate`
# run locally on the same grid. The cluster is stopped at the end, also on
# failure or interruption.
#
#   1. config/grids/tiny.yaml with `rvlio ablate` (the reference table)
#   2. the same grid through Slurm; one cell's job is cancelled with scancel
#      while it runs (--restart-times 0): that invocation fails, the cell has
#      no result, the others do
#   3. the workflow again: only the cancelled cell runs; every simulation and
#      cell was one Slurm job, seen running in squeue with the grid's CPUs,
#      memory and time limit, and listed by `sacct --completion`; the tables
#      equal the local ones (scripts/ablate_compare.py)
#   4. a grid with a cell whose configuration makes `rvlio run` fail: that
#      cell alone fails and its log is named; a job cancelled while it runs is
#      submitted again (the profile's restart-times) and the grid finishes
#
#   5. refine chunk jobs (workflow/refine_chunks.smk): a short simulated
#      tunnel refined in 3 chunks + merge through Slurm (each chunk and the
#      merge one Slurm job, COMPLETED) gives the same merged trajectory.tum
#      and map.pcd, byte for byte, as the same workflow run locally
#   6. no process of any job is left
#
# Prints "ok - ..." / "FAIL - ..." per check and ends with
# "slurm: N passed, M failed"; exit 1 when a check failed or the cluster did
# not start. RVLIO_BIN: the rvlio binary (default build/bin/rvlio, built when
# missing).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
rvlio=${RVLIO_BIN:-$repo/build/bin/rvlio}
grid=$repo/config/grids/tiny.yaml
work=$(mktemp -d "${TMPDIR:-/tmp}/rvlio-slurm-test.XXXXXX")
passed=0
failed=0
poller=""
snake_pid=""

cleanup() {
  local rc=$? i
  if [[ -n $poller ]]; then kill "$poller" 2>/dev/null || true; fi
  if [[ -n $snake_pid ]]; then  # interrupted: Snakemake cancels its jobs on SIGTERM
    kill "$snake_pid" 2>/dev/null || true
    for ((i = 0; i < 40; i++)); do kill -0 "$snake_pid" 2>/dev/null || break; sleep 0.5; done
  fi
  bash scripts/slurm_local.sh down || rc=1
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

stage=slurm
source scripts/stage_checks.sh

if [[ ! -x $rvlio ]]; then
  echo "slurm: building $rvlio"
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j "$(nproc)" --target rvlio >/dev/null
fi
command -v snakemake >/dev/null || fatal "snakemake is not installed (bash scripts/install_deps.sh --with-test-tools)"

# slurm_local.sh knows its daemons by their command line (our_pid); right
# after the fork, $! is still a copy of the script ("munged exited at
# start" for a munged that was starting). 40 starts of a stand-in daemon:
# when start_daemon returns, the recorded pid's command line names the
# folder. Read with builtins only, at once (our_pid's own forks would give
# the exec time).
start_daemon_knows_its_daemon() (
  RVLIO_SLURM_DIR=$work/start-probe
  source scripts/slurm_local.sh
  mkdir -p "$dir/log"
  local i pid missed=0 args
  for ((i = 0; i < 40; i++)); do
    start_daemon probe bash -c 'sleep 30 & wait' "$dir/probe"
    pid=$(<"$dir/probe.pid")
    args=()
    mapfile -d '' args <"/proc/$pid/cmdline" || true
    [[ " ${args[*]} " == *" $dir/probe "* ]] || missed=$((missed + 1))
    kill -- "-$pid" 2>/dev/null || kill "$pid" 2>/dev/null || true
  done
  [[ $missed -eq 0 ]] || { echo "start_daemon: $missed of 40 starts not known as ours at once" >&2; return 1; }
)
check "a daemon just started is known as ours (no exec race)" start_daemon_knows_its_daemon

if ! up_out=$(bash scripts/slurm_local.sh up 2>&1); then
  echo "$up_out" >&2
  fatal "the Slurm daemons did not start (scripts/slurm_local.sh up; see its message and logs above)"
fi
echo "$up_out"
eval "$(bash scripts/slurm_local.sh env)"
export SLURM_CONF
export USER=${USER:-$(id -un)}  # Snakemake's Slurm executor reads it (to guess an account)

# Snakemake with the shipped profile, on the local cluster's partition; status
# checked every second instead of every 30 s.
# Replaces the calling (sub)shell: run it as `(snake ...)` or `snake ... &`
# (then $! is the pid of `timeout`, which passes SIGTERM on to Snakemake).
# An invocation normally takes 20-40 s; 180 s bounds a hung cluster.
snake() {  # snake GRID OUT LOG [extra snakemake options]
  local g=$1 out=$2 log=$3; shift 3
  cd "$sm"
  exec timeout 180 snakemake -s "$repo/workflow/Snakefile" --profile "$repo/workflow/profiles/slurm" \
    --default-resources slurm_partition=rvlio --max-status-checks-per-second 1 --latency-wait 5 \
    --config grid="$g" out="$out" rvlio="$rvlio" plots=false "$@" >"$log" 2>&1
}

# Every quarter second: the jobs in the queue (id|name|state|cpus|memory|time limit).
poll_queue() {
  while true; do
    squeue -h -o '%i|%j|%T|%C|%m|%l' >>"$work/squeue.txt" 2>/dev/null || true
    sleep 0.25
  done
}

# Slurm job ids of one rule: "SLURMID WILDCARD_VALUE" from the jobs' Slurm
# logs in Snakemake's working folder $sm.
jobs_of_rule() {  # jobs_of_rule cell|data
  local f
  for f in "$sm/.snakemake/slurm_logs/rule_$1"/*.log; do
    [[ -f $f ]] || continue
    echo "$(basename "$f" .log) $(grep -Eo "${1}_id=[^ ,]+" "$f" | head -1 | cut -d= -f2)"
  done
}

job_state() { sacct -c -j "$1" -n -o state 2>/dev/null | tr -d ' '; }

# Waits until a job of a cell matching PATTERN runs `rvlio run` (its run.log
# exists, its cell.json does not), cancels it and prints "SLURMID CELL_ID"
# once Slurm has recorded it as CANCELLED (a job that finished just before
# the scancel does not count; the next one is tried). Gives up after 120 s.
cancel_running_cell() {  # cancel_running_cell OUT PATTERN
  local i id cell tried=" " j
  for ((i = 0; i < 1200; i++)); do  # every 0.1 s: a tiny cell runs for well under a second
    while read -r id cell; do
      # shellcheck disable=SC2053  # $2 is a glob pattern
      [[ -n $cell && $cell == $2 && $tried != *" $id "* ]] || continue
      if [[ $(squeue -h -j "$id" -o %T 2>/dev/null) == RUNNING && -f $1/cells/$cell/run.log &&
            ! -f $1/cells/$cell/cell.json ]]; then
        tried+="$id "
        scancel "$id"
        for ((j = 0; j < 60; j++)); do
          [[ -n $(job_state "$id") ]] && break
          sleep 0.5
        done
        [[ $(job_state "$id") == CANCELLED ]] && { echo "$id $cell"; return 0; }
      fi
    done < <(jobs_of_rule cell)
    sleep 0.1
  done
  return 1
}

sm=$work/sm
mkdir -p "$sm"
poll_queue &
poller=$!
plan=$("$rvlio" ablate --grid "$grid" --out "$work/slurm" --plan)
field() { python3 -c "import json,sys; p=json.load(sys.stdin); print(eval(sys.argv[1]))" "$1" <<<"$plan"; }
cells=$(field '" ".join(c["id"] for c in p["cells"])')
data=$(field '" ".join(d["id"] for d in p["data"])')
resources=$(field '"%d %d %d" % (p["resources"]["cpus"], p["resources"]["mem_mb"], p["resources"]["runtime"])')
echo "slurm: grid $grid: $(wc -w <<<"$cells") cells, $(wc -w <<<"$data") simulations; per job (cpus mem_mb minutes): $resources"

# 1. The reference: rvlio ablate locally.
"$rvlio" ablate --grid "$grid" --out "$work/local" --jobs 2 --no-plots --quiet >"$work/local.log" 2>&1 ||
  fatal "rvlio ablate on $grid failed: $(tail -3 "$work/local.log")"

# 2. Through Slurm, with one cell cancelled while it runs.
snake "$grid" "$work/slurm" "$work/run1.log" --restart-times 0 &
snake_pid=$!
cancelled=$(cancel_running_cell "$work/slurm" '*') || cancelled=""
rc1=0
wait "$snake_pid" || rc1=$?
snake_pid=""
read -r cancelled_job cancelled_cell <<<"${cancelled:-- -}"
check "scancel stopped a running cell job ($cancelled_job, cell $cancelled_cell)" test -n "$cancelled"
check "the invocation with the cancelled job fails (exit $rc1)" test "$rc1" -ne 0
check "Slurm records the cancelled job as CANCELLED" test "$(job_state "$cancelled_job")" = CANCELLED
# cell.json is written as cell.json.tmp.<pid>, then renamed.
no_result() { ! compgen -G "$work/slurm/cells/$cancelled_cell/cell.json*" >/dev/null; }
check "the cancelled cell left no result (no cell.json, no temporary file)" no_result
others_done() {
  local c
  for c in $cells; do
    [[ $c == "$cancelled_cell" ]] && continue
    grep -q '"status": *"done"' "$work/slurm/cells/$c/cell.json" 2>/dev/null || return 1
  done
}
check "the other cells finished in that invocation" others_done

# 3. Again: the cancelled cell runs, nothing else does.
jobs_before=$(jobs_of_rule cell | wc -l)
rc2=0
(snake "$grid" "$work/slurm" "$work/run2.log") || rc2=$?
check "the next invocation completes (exit $rc2)" test "$rc2" -eq 0
only_cancelled_again() {
  [[ $(($(jobs_of_rule cell | wc -l) - jobs_before)) -eq 1 ]] &&
    grep -q '"status": *"done"' "$work/slurm/cells/$cancelled_cell/cell.json"
}
check "it ran the cancelled cell again, and only that cell" only_cancelled_again

# Every simulation and cell: a Slurm job seen running with the grid's
# resources, completed according to sacct, with its own log.
read -r cpus mem_mb minutes <<<"$resources"
limit=$(printf '%d:%02d:00' $((minutes / 60)) $((minutes % 60)))
[[ $minutes -lt 60 ]] && limit=$minutes:00  # squeue's %l: M:SS or H:MM:SS
kill "$poller" 2>/dev/null || true
wait "$poller" 2>/dev/null || true
poller=""
seen_as_job() {  # seen_as_job RULE ID
  local id
  for id in $(jobs_of_rule "$1" | awk -v w="$2" '$2 == w {print $1}'); do
    grep -q "^$id|snakejob_$1_[0-9]*|RUNNING|$cpus|${mem_mb}M|$limit$" "$work/squeue.txt" &&
      [[ $(job_state "$id") == COMPLETED ]] && return 0
  done
  return 1
}
all_seen() {
  local d c
  for d in $data; do seen_as_job data "$d" || { echo "  simulation $d: no such job" >&2; return 1; }; done
  for c in $cells; do
    seen_as_job cell "$c" || { echo "  cell $c: no such job" >&2; return 1; }
    [[ -s $work/slurm/logs/cell_$c.log ]] || { echo "  cell $c: no log" >&2; return 1; }
  done
}
check "every simulation and cell ran as a Slurm job (squeue: RUNNING, $cpus CPU, $mem_mb MB, $minutes min; sacct: COMPLETED) with its own log" all_seen
check "Slurm's table equals rvlio ablate's (scripts/ablate_compare.py)" \
  python3 scripts/ablate_compare.py "$work/local" "$work/slurm"

# 4. A bad cell, and a retried job.
cat >"$work/bad.yaml" <<EOF
# tiny.yaml's tunnel with one seed, 12 s long: its one good cell is the only
# one to cancel while it runs, and at 6 s it ran for well under a second,
# too short a window to catch it running every time. The variant "bad"
# reads a topic the bag does not have, so its \`rvlio run\` fails.
sequences:
  - name: tunnel
    simulate: {preset: tunnel, duration: 12, set: {lidar.columns: 512}}
    seeds: [3]
variants:
  good: {}
  bad: {lidar.topic: /no/such/topic}
resources: {cpus: $cpus, mem_mb: $mem_mb, runtime: $minutes}
EOF
bad_plan=$("$rvlio" ablate --grid "$work/bad.yaml" --out "$work/bad" --plan)
bad_cell=$(python3 -c "import json,sys; print([c['id'] for c in json.load(sys.stdin)['cells'] if c['variant'] == 'bad'][0])" <<<"$bad_plan")
sm=$work/sm_bad
mkdir -p "$sm"
snake "$work/bad.yaml" "$work/bad" "$work/run3.log" &
snake_pid=$!
retried=$(cancel_running_cell "$work/bad" 'tunnel_good_*') || retried=""
rc3=0
wait "$snake_pid" || rc3=$?
snake_pid=""
read -r retried_job retried_cell <<<"${retried:-- -}"
check "a grid with a failing cell completes (exit $rc3)" test "$rc3" -eq 0
bad_alone() {
  grep -q '^tunnel,good,1,1,0,' "$work/bad/table.csv" && grep -q '^tunnel,bad,1,0,1,' "$work/bad/table.csv"
}
check "the failing cell alone failed (table: good 1 done, bad 1 failed)" bad_alone
bad_log_named() {
  grep -qF "cell $bad_cell failed" "$work/run3.log" &&
    grep -qF "logs $work/bad/logs/cell_$bad_cell.log" "$work/run3.log" &&
    grep -qi 'topic' "$work/bad/cells/$bad_cell/run.log"
}
check "the workflow names the failing cell's log, which says why" bad_log_named
tables_differ() {
  python3 scripts/ablate_compare.py "$work/local" "$work/bad" >"$work/compare_bad.txt"
  [[ $? -eq 1 ]] && grep -q "row tunnel/bad only in" "$work/compare_bad.txt"
}
check "scripts/ablate_compare.py tells different tables apart" tables_differ
retried_ok() {
  [[ -n $retried ]] && [[ $(jobs_of_rule cell | awk -v c="$retried_cell" '$2 == c' | wc -l) -ge 2 ]] &&
    grep -q '"status": *"done"' "$work/bad/cells/$retried_cell/cell.json"
}
check "a job cancelled while running ($retried_job, cell $retried_cell) was submitted again and finished" retried_ok

# 5. Refine chunk jobs: the same 3 chunks + merge locally and through Slurm.
chunks_cfg() {  # the --config of workflow/refine_chunks.smk for output folder $1
  echo bag="$work/chunks_data/tunnel.bag" init="$work/chunks_init/trajectory.tum" chunks=3 \
    out="$1" config="[$work/chunks_data/tunnel.yaml]" rvlio="$rvlio" \
    "set=[refine.rounds=2,refine.job_overlap_s=3]" cpus="$cpus" mem_mb="$mem_mb" \
    runtime="$minutes"
}
chunks_ready() {
  "$rvlio" simulate --preset tunnel --seed 3 --duration 12 --set lidar.columns=512 \
    --out "$work/chunks_data" >"$work/chunks_sim.log" 2>&1 &&
    "$rvlio" run --bag "$work/chunks_data/tunnel.bag" --config "$work/chunks_data/tunnel.yaml" \
      --set backend=ieskf --out "$work/chunks_init" >"$work/chunks_run.log" 2>&1
}
check "a 12 s tunnel simulated and run (IESKF) for the chunk jobs" chunks_ready
# shellcheck disable=SC2046  # chunks_cfg prints one word per key=value
chunks_local() {
  (cd "$work" && timeout 300 snakemake -s "$repo/workflow/refine_chunks.smk" -j 2 \
    --config $(chunks_cfg "$work/chunks_local") >"$work/run_chunks_local.log" 2>&1)
}
check "workflow/refine_chunks.smk runs 3 chunks + merge locally" chunks_local
sm=$work/sm_chunks
mkdir -p "$sm"
# shellcheck disable=SC2046
chunks_slurm() {
  (cd "$sm" && timeout 300 snakemake -s "$repo/workflow/refine_chunks.smk" \
    --profile "$repo/workflow/profiles/slurm" --default-resources slurm_partition=rvlio \
    --max-status-checks-per-second 1 --latency-wait 5 \
    --config $(chunks_cfg "$work/chunks_slurm") >"$work/run_chunks_slurm.log" 2>&1)
}
check "workflow/refine_chunks.smk runs 3 chunks + merge through Slurm" chunks_slurm
chunk_jobs_completed() {  # every chunk and the merge: one Slurm job, COMPLETED
  local rule f n
  for rule in chunk:3 merge:1; do
    n=0
    for f in "$sm/.snakemake/slurm_logs/rule_${rule%%:*}"/*.log; do
      [[ -f $f ]] || continue
      [[ $(job_state "$(basename "$f" .log)") == COMPLETED ]] || { echo "  $f: not COMPLETED" >&2; return 1; }
      n=$((n + 1))
    done
    [[ $n -eq ${rule##*:} ]] || { echo "  rule ${rule%%:*}: $n Slurm jobs, expected ${rule##*:}" >&2; return 1; }
  done
}
check "each chunk and the merge ran as one Slurm job (sacct: COMPLETED)" chunk_jobs_completed
same_merge() {
  cmp "$work/chunks_local/merged/trajectory.tum" "$work/chunks_slurm/merged/trajectory.tum" &&
    cmp "$work/chunks_local/merged/map.pcd" "$work/chunks_slurm/merged/map.pcd"
}
check "Slurm's merged trajectory.tum and map.pcd equal the local ones (cmp)" same_merge

# Nothing of any job is still running (a cancelled job's processes included;
# Slurm kills them KillWait = 5 s after the SIGTERM).
leftovers() {
  local i f pids
  for ((i = 0; i < 30; i++)); do
    pids=""
    for f in /proc/[0-9]*/cmdline; do
      tr '\0' ' ' 2>/dev/null <"$f" | grep -qF -- "$work/" && pids+=" $(basename "$(dirname "$f")")"
    done
    [[ -z $pids ]] && return 0
    sleep 0.5
  done
  echo "  still running:$pids" >&2
  ps -o pid,ppid,pgid,etime,args -p "${pids// /,}" >&2 || true
  return 1
}
check "no process of any job (cancelled ones included) is left running" leftovers

if [[ $failed -gt 0 ]]; then
  for f in "$work"/run*.log "$work"/chunks_*.log; do
    [[ -f $f ]] && { echo "---- $f (last 30 lines)"; tail -n 30 "$f"; }
  done
fi
echo "slurm: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
