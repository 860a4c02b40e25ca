#!/usr/bin/env bash
# The `python` stage of scripts/test.sh: the Python module rvlio (python/)
# from the Release build tree build/ (the release stage builds it; built here
# if missing):
#   1. pytest python/tests: rvlio.run against the command-line tool on the
#      same recording, Odometry fed scan by scan, evo's reference numbers,
#      bad arguments, Ctrl-C in a child interpreter (well under 2 minutes)
#   2. examples/compare_backends.py on a short simulated tunnel (6 s, 512
#      columns): the four variants run and the plot is written
#   3. cmake --install into a temporary prefix, `import rvlio` from there
#      (PYTHONPATH=PREFIX/RVLIO_PYTHON_INSTALL_DIR, lib/python3.11/dist-packages
#      on Debian 12), prefix removed
# Ends with "python: N passed, M failed" (pytest's tests + the two checks).
# RVLIO_PYTHON picks the interpreter (default /usr/bin/python3, Debian's, with
# python3-numpy), RVLIO_BUILD_DIR the build tree.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${RVLIO_BUILD_DIR:-build}
python=${RVLIO_PYTHON:-/usr/bin/python3}
[[ -x $python ]] || python=$(command -v python3)
jobs=$(nproc 2>/dev/null || echo 2)
[[ -f $build/CMakeCache.txt ]] || bash scripts/build.sh
cmake --build "$build" -j "$jobs" --target rvlio rvlio_python

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export PYTHONPATH="$PWD/$build/python${PYTHONPATH:+:$PYTHONPATH}"
export RVLIO_BIN="$PWD/$build/bin/rvlio" PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg
passed=0
failed=0

# 1. pytest; its summary line gives the counts ("12 passed, 1 failed in 40.1s").
set +e
"$python" -m pytest -q -p no:cacheprovider python/tests 2>&1 | tee "$work/pytest.log"
set -e
summary=$(tail -n 1 "$work/pytest.log")
count() { grep -Eo "[0-9]+ $1" <<<"$summary" | grep -Eo '[0-9]+' || echo 0; }
passed=$((passed + $(count passed)))
failed=$((failed + $(count failed) + $(count error)))
[[ $(count passed) -gt 0 ]] || failed=$((failed + 1))  # no test ran at all

stage=python
source scripts/stage_checks.sh

# 2. The example on a short sequence.
example() {
  "$python" examples/compare_backends.py --duration 6 --columns 512 --out "$work/compare" &&
    [[ -s $work/compare/along_axis_error.png ]]
}
check "examples/compare_backends.py --duration 6 --columns 512 writes its plot" example

# 3. The installed module imports from the prefix (not from the build tree).
installed_import() {
  local dir
  dir=$(sed -n 's/^RVLIO_PYTHON_INSTALL_DIR:STRING=//p' "$build/CMakeCache.txt")
  cmake --install "$build" --prefix "$work/prefix" >"$work/install.log" || return 1
  (cd "$work" && PYTHONPATH="$work/prefix/$dir" "$python" -c '
import sys, rvlio
assert rvlio.__file__.startswith(sys.argv[1]), rvlio.__file__
assert rvlio.Config.load(set={"backend": "smoother"}).to_dict()["backend"] == "smoother"
print("installed rvlio", rvlio.__version__, "from", rvlio.__file__)
' "$work/prefix")
}
check "cmake --install into a prefix, import rvlio with PYTHONPATH" installed_import

echo "python: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
