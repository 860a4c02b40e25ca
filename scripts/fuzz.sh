#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan) in
# ./build-fuzz and runs each for a bounded time from its committed seeds.
#
#   bash scripts/fuzz.sh [--seconds N] [--ci] [TARGET ...]
#
#   --seconds N   fuzzing time per target (default: $RVLIO_FUZZ_SECONDS or 60)
#   --ci          what scripts/test.sh uses: libFuzzer seed 1 and a fixed number
#                 of inputs per target (about a minute here), starting from the
#                 committed seeds only. The inputs tried are nearly, not exactly,
#                 the same on every machine: CI once found an input that a local
#                 --ci run of the same commit did not. Without --ci the seed is
#                 random and new inputs accumulate: use that to hunt for bugs.
#   TARGET        pointcloud2, config, trajectory, mcap, cdr, ouster (default: all six)
#
# Seeds: fuzz/corpus/<target>/ (read only; refresh with fuzz/make_seeds.py).
# New interesting inputs go to build-fuzz/corpus/<target>/, which later runs
# reuse. A crash, a timeout (> 10 s on one input) or an out-of-memory (> 2 GB)
# stops the target; the script then prints the reproducer
# (build-fuzz/artifacts/<target>-crash-...) and the command that replays it,
# and exits 1 once every target has run. Logs: build-fuzz/logs/<target>.log.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
seconds=${RVLIO_FUZZ_SECONDS:-60}
targets=()
ci=false
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --seconds=*) seconds=${1#*=}; shift ;;
    --ci) ci=true; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option '$1'" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[[ ${#targets[@]} -eq 0 ]] && targets=(pointcloud2 config trajectory mcap cdr ouster)
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [[ "$seconds" -lt 1 ]]; then
  echo "fuzz.sh: --seconds must be a positive integer (got '$seconds')" >&2
  exit 2
fi

# Longest input per target: a few times the largest seed.
declare -A max_len=([pointcloud2]=8192 [config]=8192 [trajectory]=4096 [mcap]=8192)
# --ci: inputs per target, about 60 s each on the 2-core machine of bench/RESULTS.md.
declare -A ci_runs=([pointcloud2]=600000 [config]=10000 [trajectory]=500000 [mcap]=200000)
max_len[cdr]=8192
ci_runs[cdr]=500000
# ouster: seeds are real captures cut to a few packets (fuzz/corpus/ouster);
# about 24 inputs per second: 1400 is about 60 s.
max_len[ouster]=65536
ci_runs[ouster]=1400
for t in "${targets[@]}"; do
  [[ -n "${max_len[$t]:-}" ]] || { echo "fuzz.sh: unknown target '$t'" >&2; exit 2; }
done

build=$root/build-fuzz
cxx=$(command -v clang++ || command -v clang++-14 || true)
[[ -n "$cxx" ]] || { echo "fuzz.sh: clang++ not found (bash scripts/install_deps.sh --with-test-tools)" >&2; exit 1; }
cmake -S fuzz -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DRVLIO_WERROR=ON >/dev/null
cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" --target "${targets[@]/#/fuzz_}"

symbolizer=$(command -v llvm-symbolizer || command -v llvm-symbolizer-14 || true)
[[ -n "$symbolizer" ]] && export ASAN_SYMBOLIZER_PATH=$symbolizer
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"

mkdir -p "$build/artifacts" "$build/logs"

# Fuzzes one target for $seconds; prints its verdict; returns nonzero on a finding.
fuzz_one() {
  local t=$1 corpus=$build/corpus/$1 log=$build/logs/$1.log rc=0
  local mode=()
  if $ci; then
    corpus=$build/corpus-ci/$t
    rm -rf "$corpus"
    mode=(-seed=1 -runs="${ci_runs[$t]}")
  fi
  mkdir -p "$corpus"
  local before
  before=$(ls "$build/artifacts" | grep -c "^$t-" || true)
  "$build/fuzz_$t" -max_total_time="$seconds" -max_len="${max_len[$t]}" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
    "${mode[@]}" "$corpus" "fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  local runs cov after
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
  after=$(ls "$build/artifacts" | grep -c "^$t-" || true)
  if [[ $rc -ne 0 || $after -gt $before ]]; then
    {
      echo "fuzz: $t FAILED (exit $rc) after $runs runs; last lines of $log:"
      tail -n 40 "$log" | sed 's/^/  | /'
      local artifact
      artifact=$(ls -t "$build/artifacts" | grep "^$t-" | head -1 || true)
      if [[ -n "$artifact" ]]; then
        echo "fuzz: reproducer: $build/artifacts/$artifact"
        echo "fuzz: replay with: $build/fuzz_$t $build/artifacts/$artifact"
      fi
    } >"$log.verdict"
    return 1
  fi
  echo "fuzz: $t ok: $runs runs, coverage $cov, corpus $(ls "$corpus" | wc -l) inputs" >"$log.verdict"
}

# The targets run side by side (each for $seconds of wall time), so the stage
# takes about $seconds however many targets there are.
declare -A pids=()
for t in "${targets[@]}"; do
  echo "fuzz: $t for ${seconds} s$($ci && echo ", seed 1, at most ${ci_runs[$t]} inputs") (max_len ${max_len[$t]}, seeds fuzz/corpus/$t)"
  fuzz_one "$t" &
  pids[$t]=$!
done
failed=()
for t in "${targets[@]}"; do
  wait "${pids[$t]}" || failed+=("$t")
  cat "$build/logs/$t.log.verdict"
done

if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz: failing targets: ${failed[*]}"
  echo "fuzz: $(( ${#targets[@]} - ${#failed[@]} )) passed, ${#failed[@]} failed"
  exit 1
fi
echo "fuzz: ${#targets[@]} passed, 0 failed"
