#!/usr/bin/env bash
# The README's main command: installs what is missing, builds the `rvlio`
# tool only (not the tests and benchmarks), runs `rvlio demo`.
# The build folder is configured exactly as scripts/test.sh configures it
# (build/, Release, RVLIO_WERROR=ON), so the test command later reuses these
# objects and builds only the tests and benchmarks on top.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh --target rvlio -DRVLIO_WERROR=ON
./build/bin/rvlio demo --out out/demo "$@"
