#!/usr/bin/env bash
# Configures and builds rvlio in ./build (Release).
#
#   bash scripts/build.sh [--target NAME ...] [cmake configure arguments ...]
#
# --target NAME (repeatable) builds only those targets (default: all); every
# other argument goes to the cmake configure step (e.g. -DRVLIO_WERROR=ON).
# The configuration does not depend on --target, so a later call that builds
# more reuses what an earlier one built (scripts/demo.sh builds `rvlio` only,
# scripts/test.sh then builds the rest in the same folder).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
# Ninja when installed (scripts/install_deps.sh installs it): it compiles a
# target's sources while the libraries it links are still being built, where
# Makefiles wait for each library, so no core idles between them. A build
# folder keeps the generator it was first configured with.
command -v ninja >/dev/null && export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}
targets=()
configure_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --target) targets+=(--target "$2"); shift 2 ;;
    --target=*) targets+=(--target "${1#*=}"); shift ;;
    *) configure_args+=("$1"); shift ;;
  esac
done
# Every target as a unity build (RVLIO_UNITY_BUILD=all, docs/testing.md):
# about 0.6x the compiler's CPU time; an argument -DRVLIO_UNITY_BUILD=... wins.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRVLIO_UNITY_BUILD=all "${configure_args[@]}" >/dev/null
cmake --build build -j "$jobs" "${targets[@]}"
