#!/usr/bin/env bash
# Refine scaling benchmark (docs/refine.md, "Memory and time"): simulates
# OS0-32-like tunnel recordings (32 x 512 points, 10 Hz) of about SCANS scans
# each, runs the IESKF odometry on each for the initial trajectory, then
# `rvlio refine` under /usr/bin/time, and prints one table row per length:
# scans refined, seconds per round (mean of the rounds' wall times), peak
# resident memory (MB, /usr/bin/time %M) and MB per scan.
#
#   scripts/refine_scaling.sh [--bin build/bin/rvlio] [--work DIR]
#       [--scans "1000 3000"] [--rounds N] [--threads N] [--keep]
#
# Recordings and initial trajectories are cached in --work (default
# /tmp/rvlio_refine_scaling) and reused by later calls with the same lengths,
# so a before/after comparison only reruns refine. --keep leaves the refine
# outputs there (tunnel_<scans>/refine_<binary name>/, e.g. to cmp them).
set -euo pipefail

bin=build/bin/rvlio
work=/tmp/rvlio_refine_scaling
scans_list="1000 3000"
rounds=2
threads=2
keep=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bin) bin=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --scans) scans_list=$2; shift 2 ;;
    --rounds) rounds=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "refine_scaling.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
[[ -x $bin ]] || { echo "refine_scaling.sh: --bin $bin is not an executable" >&2; exit 2; }
[[ -x /usr/bin/time ]] || { echo "refine_scaling.sh: /usr/bin/time is missing (apt-get install time)" >&2; exit 2; }
for n in $scans_list; do
  [[ $n =~ ^[0-9]+$ && $n -ge 20 ]] || { echo "refine_scaling.sh: --scans: $n is not a count >= 20" >&2; exit 2; }
done
mkdir -p "$work"

# The recording of ~n scans and the IESKF trajectory on it (cached).
prepare() {
  local n=$1 dir=$work/tunnel_$1
  if [[ ! -f $dir/init/trajectory.tum ]]; then
    # 10 Hz LiDAR: n / 10 s, plus 3 s (n = 1000: 103 s, 1030 scans).
    local duration
    duration=$(awk -v n="$n" 'BEGIN { printf "%.1f", n / 10.0 + 3.0 }')
    "$bin" simulate --preset tunnel --seed 1 --duration "$duration" \
      --set lidar.columns=512 --out "$dir" --name tunnel > "$dir.simulate.log"
    "$bin" run --bag "$dir/tunnel.bag" --config "$dir/tunnel.yaml" --set backend=ieskf \
      --out "$dir/init" --quiet > "$dir.run.log"
  fi
}

printf '%-8s %-10s %-10s %-8s %s\n' scans s/round peak_MB MB/scan rounds
for n in $scans_list; do
  prepare "$n"
  dir=$work/tunnel_$n
  out=$dir/refine_$(basename "$bin")
  rm -rf "$out"
  /usr/bin/time -f %M -o "$dir.maxrss_kb" "$bin" refine --bag "$dir/tunnel.bag" \
    --init "$dir/init/trajectory.tum" --config "$dir/tunnel.yaml" \
    --set refine.rounds="$rounds" --set refine.threads="$threads" \
    --out "$out" > "$dir.refine.log"
  python3 - "$out/summary.json" "$(tail -n 1 "$dir.maxrss_kb")" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
peak_mb = int(sys.argv[2]) / 1024.0
n = s["scan_count"]
r = [x["time_s"]["total"] for x in s["rounds"]]
print("%-8d %-10.2f %-10.0f %-8.3f %d" % (n, sum(r) / len(r), peak_mb, peak_mb / n, len(r)))
EOF
  [[ $keep == 1 ]] || rm -rf "$out"
done
