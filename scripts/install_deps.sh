#!/usr/bin/env bash
# Installs the Debian 12 packages rvlio needs, only those that are missing.
# Safe to run again: when everything is present it does nothing but check.
# Uses sudo only when not root.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git ccache
  libeigen3-dev libceres-dev libsuitesparse-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev
  libpcl-dev libzstd-dev liblz4-dev libdeflate-dev zlib1g-dev
  libsqlite3-dev libproj-dev
  librosbag-storage-dev libsensor-msgs-dev libroscpp-core-dev
  pluginlib-dev libclass-loader-dev librcpputils-dev libament-index-cpp-dev
  python3-rosbag python3-matplotlib python3-yaml
  libtbb-dev pybind11-dev python3-dev python3-numpy
  libjs-three
  libroscpp-dev libtopic-tools-dev libnav-msgs-dev libtf2-msgs-dev libdiagnostic-msgs-dev
  cyclonedds-dev
)
# Extra packages the test command needs (Snakemake workflow test; clang with
# the libFuzzer/ASan runtimes and llvm-symbolizer for scripts/fuzz.sh — gcc's
# ASan/UBSan runtimes for scripts/sanitize.sh come with build-essential; a
# Slurm controller, node daemon, client and munge for scripts/slurm_local.sh;
# GNU time for the peak memory of scripts/refine_scaling.sh; scipy for the
# independent check of the map metrics in python/tests/test_evaluate_map.py;
# chromium for the headless browser test of report.html; lld, the faster
# linker the build uses when it is installed; rosmaster for test/live).
if [[ "${1:-}" == "--with-test-tools" ]]; then
  packages+=(python3-pytest python3-scipy snakemake clang-14 libclang-rt-14-dev llvm-14 munge slurmctld slurmd slurm-client)
  packages+=(time chromium lld)
  # rosmaster for the live tests (test/live: `rvlio live --ros1` against a real master).
  packages+=(python3-rosmaster)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install_deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "install_deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps: done"
