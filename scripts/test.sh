#!/usr/bin/env bash
# The README's test command (CI runs it through .ci/run): installs what is
# missing, then runs the stages in order and stops at the first failure:
#
#   release   Release build in build/ (warnings are errors: RVLIO_WERROR)
#             + ctest (every test)
#   python    scripts/python_test.sh: pytest of the Python module against
#             the Release build tree, examples/compare_backends.py on a 6 s
#             tunnel, and `import rvlio` from a temporary install prefix
#             (about 2 minutes)
#   sanitize  scripts/sanitize.sh: the test suite built with gcc
#             ASan + UBSan (-O1 -g, RVLIO_WERROR) in build-asan/ + ctest there
#   fuzz      scripts/fuzz.sh --ci: the libFuzzer targets of fuzz/ (clang,
#             RVLIO_WERROR) in build-fuzz/, seed 1, a fixed number of
#             inputs (about 60 s) per target, at most $RVLIO_FUZZ_SECONDS
#             (default 60) s each
#   slurm     scripts/slurm_test.sh: a single-node Slurm cluster started
#             here (scripts/slurm_local.sh), config/grids/tiny.yaml through
#             the Snakemake workflow on it, the table compared with the one
#             of `rvlio ablate`, a failing cell and cancelled jobs (about
#             2 minutes); the cluster is stopped afterwards, also on failure
#
# A developer may run a subset: RVLIO_CI_STAGES=release (or "release,fuzz",
# ...) bash scripts/test.sh. RVLIO_FUZZ_SECONDS=10 shortens the fuzz stage.
# Each stage's wall time is printed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
stages=${RVLIO_CI_STAGES:-release,install,python,sanitize,fuzz,slurm}
jobs=$(nproc 2>/dev/null || echo 2)
for s in ${stages//,/ }; do
  case "$s" in
    release|install|python|sanitize|fuzz|slurm) ;;
    *) echo "test.sh: unknown stage '$s' in RVLIO_CI_STAGES (release, install, python, sanitize, fuzz, slurm)" >&2; exit 2 ;;
  esac
done
want() { [[ ",$stages," == *",$1,"* ]]; }

times=()
stage_start=$SECONDS
finish_stage() { times+=("$1 $((SECONDS - stage_start)) s"); stage_start=$SECONDS; }
# Tests run, summed over the stages, from each runner's closing line.
log=$(mktemp)
trap 'rm -f "$log"' EXIT
passed=0
count_tests() {
  local n
  n=$(grep -Eo '(tests failed out of [0-9]+|^(fuzz|slurm|install|python): [0-9]+ passed)' "$log" | grep -Eo '[0-9]+' | tail -1 || true)
  passed=$((passed + ${n:-0}))
}

bash scripts/install_deps.sh --with-test-tools
finish_stage deps
# Every stage's new build folder is configured for Ninja (scripts/build.sh).
command -v ninja >/dev/null && export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}

# run_stage NAME COMMAND...: one stage whose output names its count of tests.
run_stage() {
  local name=$1
  shift
  want "$name" || return 0
  "$@" 2>&1 | tee "$log"
  count_tests
  finish_stage "$name"
}
release() {
  bash scripts/build.sh -DRVLIO_WERROR=ON && (cd build && ctest --output-on-failure -j "$jobs")
}
run_stage release release
run_stage install bash scripts/install_test.sh
run_stage python bash scripts/python_test.sh
run_stage sanitize bash scripts/sanitize.sh
run_stage fuzz bash scripts/fuzz.sh --ci
run_stage slurm bash scripts/slurm_test.sh

echo "test.sh: stages $stages passed; wall time per stage: $(IFS=,; echo "${times[*]}" | sed 's/,/, /g')"
echo "test.sh: $passed passed, 0 failed"
