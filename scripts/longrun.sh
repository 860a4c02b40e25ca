#!/usr/bin/env bash
# Long-run check: simulates a 10-minute sequence (the loopback corridor flown
# back and forth, OS0-32 at 512 columns, ~8 MB of bag per second), runs
# `rvlio run` on it and reports the resident memory (RSS) over sequence time
# from scans.csv's rss_mb column, plus the peak (summary.json peak_memory_mb).
# Fails (exit 1) when the run fails or when memory keeps growing: RSS at the
# end more than GROWTH_LIMIT_MB above RSS at minute 2.
#
# usage: scripts/longrun.sh [--duration S] [--backend ieskf|smoother] [--keep] [--work DIR]
#   --duration S   sequence length in seconds (default 600)
#   --work DIR     scratch folder (default: a new folder under /tmp); needs
#                  ~8 MB per simulated second; the bag is deleted at the end
#                  unless --keep is given
# Environment: RVLIO (path of the rvlio binary, default build/bin/rvlio),
# GROWTH_LIMIT_MB (default 50).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
rvlio="${RVLIO:-$root/build/bin/rvlio}"
duration=600
backend=ieskf
keep=0
work=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --duration) duration="$2"; shift 2 ;;
    --backend) backend="$2"; shift 2 ;;
    --keep) keep=1; shift ;;
    --work) work="$2"; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "longrun.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
[[ -x "$rvlio" ]] || { echo "longrun.sh: $rvlio is not built (bash scripts/build.sh)" >&2; exit 2; }
[[ -n "$work" ]] || work="$(mktemp -d /tmp/rvlio_longrun_XXXXXX)"
mkdir -p "$work"
cleanup() { [[ $keep == 1 ]] || rm -f "$work/data/loopback.bag"; }
trap cleanup EXIT

need_mb=$(( duration * 9 ))
free_mb=$(df -Pm "$work" | awk 'NR==2 {print $4}')
if (( free_mb < need_mb )); then
  echo "longrun.sh: $work has $free_mb MB free, the bag needs ~$need_mb MB" >&2
  exit 2
fi

# Laps of the loopback corridor: 45 m out at 1.8 m, up, 45 m back at 2.3 m, down.
lap="45,0,1.8; 45,0,2.3; 0,0,2.3; 0,0,1.8"
waypoints="0,0,0; 0,0,1.8"
laps=$(( duration / 50 + 1 ))
for ((i = 0; i < laps; ++i)); do waypoints+="; $lap"; done

echo "== simulating ${duration} s (loopback corridor, $laps laps, 512 columns) into $work/data"
/usr/bin/time -f "simulate: %e s wall, %U s user, peak %M KB" \
  "$rvlio" simulate --preset loopback --seed 1 --duration "$duration" --out "$work/data" \
  --set lidar.columns=512 --set "trajectory.waypoints=$waypoints"
ls -l "$work/data/loopback.bag"

echo "== rvlio run (backend $backend)"
/usr/bin/time -f "run: %e s wall, %U s user, peak %M KB" \
  "$rvlio" run --bag "$work/data/loopback.bag" --config "$work/data/loopback.yaml" \
  --set "backend=$backend" --out "$work/run" --quiet

echo "== resident memory over sequence time (scans.csv rss_mb)"
status=0
/usr/bin/python3 - "$work" "${GROWTH_LIMIT_MB:-50}" <<'EOF' || status=$?
import csv, json, sys
work, limit = sys.argv[1], float(sys.argv[2])
rows = list(csv.DictReader(open(work + "/run/scans.csv")))
t0 = float(rows[0]["t"])
summary = json.load(open(work + "/run/summary.json"))
minutes = int((float(rows[-1]["t"]) - t0) // 60)
rss_at = {}
for r in rows:
  m = int((float(r["t"]) - t0) // 60)
  rss_at[m] = max(rss_at.get(m, 0.0), float(r["rss_mb"]))
print("  minute  max RSS [MB]")
for m in sorted(rss_at):
  print("  %6d  %12.1f" % (m + 1, rss_at[m]))
print("scans %d, peak_memory_mb %.1f, per-scan median %.2f ms, real-time factor %.1f" %
      (summary["scan_count"], summary["peak_memory_mb"], summary["per_scan_ms"]["median"],
       summary["real_time_factor"]))
base = rss_at.get(1, rss_at[min(rss_at)])
end = rss_at[max(rss_at)]
growth = end - base
print("growth from minute 2 to the end: %+.1f MB (limit %.0f MB)" % (growth, limit))
sys.exit(0 if growth <= limit else 1)
EOF
echo "== accuracy"
"$rvlio" eval --gt "$work/data/loopback_gt.tum" --est "$work/run/trajectory.tum" || true
exit $status
