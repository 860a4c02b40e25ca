#!/usr/bin/env bash
# Installs the independent LAS readers of package-lock.json (npm ci) into
# DEST/node_modules, once (a later call with the same lock file installs
# nothing), and copies read_las.mjs beside them.
# Used by test/outputs/las/las_reader_test.cpp (docs/testing.md "Independent LAS readers").
#
#   bash test/support/las_reader/install.sh DEST
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dest=${1:?usage: install.sh DEST}
mkdir -p "$dest"
cp "$here/read_las.mjs" "$dest/"  # ES modules find their packages beside them
stamp="$dest/node_modules/.rvlio-package-lock.json"
if [[ -f "$stamp" ]] && cmp -s "$stamp" "$here/package-lock.json"; then
  exit 0
fi
command -v npm >/dev/null || { echo "install.sh: npm not found (Node.js 20 and npm)" >&2; exit 1; }
cp "$here/package.json" "$here/package-lock.json" "$dest/"
(cd "$dest" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
cp "$here/package-lock.json" "$stamp"
