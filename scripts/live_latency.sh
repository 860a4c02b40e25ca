#!/usr/bin/env bash
# The latency and IMU-rate figures of `rvlio live --ros1` (docs/live.md
# "Latency"): starts a rosmaster on a free port, `rvlio live`, plays a ROS1
# recording with `rosbag play` at RATE, stops live with SIGINT and prints the
# "live" section of its summary.json with the estimator's per-scan time.
# Every process it starts is stopped by its pid (process group).
#
#   bash scripts/live_latency.sh BAG CONFIG [RATE] [--set key=value ...]
#
# BUILD (default build) selects the tool: $BUILD/bin/rvlio.
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 2 ]] || { echo "usage: $0 BAG CONFIG [RATE] [--set key=value ...]" >&2; exit 2; }
bag=$1 config=$2
shift 2
rate=1
if [[ $# -gt 0 && $1 != --* ]]; then rate=$1; shift; fi
tool=${BUILD:-build}/bin/rvlio
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM -- "-$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
# Everything on the loopback interface (roscpp's URIs).
export ROS_HOME=$work/ros ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1
setsid rosmaster --core -p "$port" >"$work/master.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do python3 -c "import socket; socket.create_connection(('127.0.0.1', $port))" 2>/dev/null && break; sleep 0.1; done
setsid "$tool" live --ros1 --config "$config" --out "$work/out" "$@" >"$work/live.out" 2>"$work/live.err" &
live=$!
pids+=($live)
for _ in $(seq 100); do [[ -e $work/out/trajectory.partial.tum ]] && break; sleep 0.1; done  # subscribed
setsid rosbag play -q -d 1 -r "$rate" "$bag" >"$work/play.log" 2>&1 &
play=$!
pids+=($play)
wait "$play"
sleep 1
kill -INT "$live"
wait "$live" || { cat "$work/live.err" >&2; exit 1; }
python3 - "$work/out/summary.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
l = s["live"]
print(json.dumps({"backend": s["backend"], "scans": s["scan_count"],
                  "per_scan_ms": s["per_scan_ms"], "latency_ms": l["latency_ms"],
                  "scans_dropped": l["scans_dropped"], "imu_input_hz": round(l["imu_input_hz"], 1),
                  "imu_odometry_hz": round(l["imu_odometry_hz"], 1)}))
EOF
