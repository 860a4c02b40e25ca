#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, runs `rvlio demo`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
./build/bin/rvlio demo --out out/demo "$@"
