# Sourced by the test stages that count their own checks (install, python,
# slurm; see scripts/test.sh): `check NAME COMMAND...` runs one check and
# counts it in $passed or $failed; `fatal MESSAGE` stops the stage with its
# closing line. The stage sets $stage (the name in "STAGE: N passed, M
# failed", which test.sh adds up) and starts $passed and $failed.
check() {  # check NAME COMMAND...: one test
  local name=$1
  shift
  if "$@"; then
    echo "ok - $name"
    passed=$((passed + 1))
  else
    echo "FAIL - $name" >&2
    failed=$((failed + 1))
  fi
}
fatal() {
  echo "$stage: error: $*" >&2
  echo "$stage: $passed passed, $((failed + 1)) failed"
  exit 1
}
