#!/usr/bin/env bash
# End-to-end throughput of every backend on one fixed, seeded simulated bag.
#
#   scripts/throughput.sh [--preset P] [--seed N] [--duration S] [--columns C]
#                         [--bin RVLIO] [--cache DIR] [--rv-off] [--no-refine]
#                         [--set KEY=VALUE ...]
#
# Simulates the bag once (cached under --cache, default
# ${RVLIO_BENCH_CACHE:-/tmp/rvlio-throughput}/P-sN-dS-cC), then runs
#   rvlio run    --set backend=ieskf     (RV on, the defaults)
#   rvlio run    --set backend=smoother  (RV on)
#   rvlio run    --set backend=ieskf --set rv.enabled=false   (with --rv-off)
#   rvlio refine --init <the ieskf trajectory>                 (unless --no-refine)
# and prints one row per run: scans, per-scan CPU ms median/p95/max (thread
# CPU time of the estimator, summary.json per_scan_ms), real-time factor on
# CPU time and on wall time, peak memory (MB) and the ATE against the ground
# truth (rvlio eval, se3 alignment). `--set` options go to every run.
# Exit status: 0 on success, 2 on bad arguments, 1 when a run fails.
set -euo pipefail

usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; }

root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${RVLIO_BIN:-$root/build/bin/rvlio}"
preset=tunnel seed=1 duration="" columns="" rv_off=0 refine=1
cache_root="${RVLIO_BENCH_CACHE:-/tmp/rvlio-throughput}"
sets=()
py=/usr/bin/python3
[ -x "$py" ] || py=python3

while [ $# -gt 0 ]; do
  case "$1" in
    --preset) preset="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --duration) duration="$2"; shift 2 ;;
    --columns) columns="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --cache) cache_root="$2"; shift 2 ;;
    --rv-off) rv_off=1; shift ;;
    --no-refine) refine=0; shift ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "throughput.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [ ! -x "$bin" ]; then
  echo "throughput.sh: rvlio binary not found: $bin (build it or pass --bin)" >&2
  exit 2
fi

data="$cache_root/$preset-s$seed-d${duration:-full}-c${columns:-default}"
bag="$data/$preset.bag"
if [ ! -f "$bag" ]; then
  sim=(simulate --preset "$preset" --seed "$seed" --out "$data")
  [ -n "$duration" ] && sim+=(--duration "$duration")
  [ -n "$columns" ] && sim+=(--set "lidar.columns=$columns")
  echo "simulating: rvlio ${sim[*]}" >&2
  "$bin" "${sim[@]}" >&2 || { echo "throughput.sh: simulation failed" >&2; exit 1; }
fi

out="$(mktemp -d "${TMPDIR:-/tmp}/rvlio-throughput-runs.XXXXXX")"
trap 'rm -rf "$out"' EXIT

# run NAME ARGS...: one `rvlio run` into $out/NAME.
run() {
  local name="$1"; shift
  echo "running: $name" >&2
  "$bin" run --bag "$bag" --config "$data/$preset.yaml" "$@" "${sets[@]}" \
    --out "$out/$name" --quiet >&2 || { echo "throughput.sh: run '$name' failed" >&2; exit 1; }
  "$bin" eval --gt "$data/${preset}_gt.tum" --est "$out/$name/trajectory.tum" --json \
    > "$out/$name/eval.json" || { echo "throughput.sh: eval of '$name' failed" >&2; exit 1; }
}

names=(ieskf smoother)
run ieskf --set backend=ieskf
run smoother --set backend=smoother
if [ "$rv_off" = 1 ]; then
  run ieskf_rv_off --set backend=ieskf --set rv.enabled=false
  run smoother_rv_off --set backend=smoother --set rv.enabled=false
  names+=(ieskf_rv_off smoother_rv_off)
fi
if [ "$refine" = 1 ]; then
  echo "running: refine" >&2
  "$bin" refine --bag "$bag" --init "$out/ieskf/trajectory.tum" --config "$data/$preset.yaml" \
    "${sets[@]}" --out "$out/refine" >&2 || { echo "throughput.sh: refine failed" >&2; exit 1; }
  "$bin" eval --gt "$data/${preset}_gt.tum" --est "$out/refine/trajectory.tum" --json \
    > "$out/refine/eval.json" || { echo "throughput.sh: eval of refine failed" >&2; exit 1; }
  names+=(refine)
fi

echo "preset $preset, seed $seed, duration ${duration:-full}, columns ${columns:-default}, bag $bag"
"$py" - "$out" "${names[@]}" <<'EOF'
import json, sys
out, names = sys.argv[1], sys.argv[2:]
hdr = ("run", "scans", "med ms", "p95 ms", "max ms", "RTF cpu", "RTF wall", "peak MB", "ATE m")
rows = []
for n in names:
    s = json.load(open(f"{out}/{n}/summary.json"))
    ate = json.load(open(f"{out}/{n}/eval.json"))["ape"]["rmse"]
    if s.get("command") == "refine":
        t = s["time_s"]
        dur = s["sequence_duration_s"]
        rows.append((n, s["scan_count"], "-", "-", "-", f"{dur / t['refine']:.2f}",
                     f"{dur / t['wall']:.2f}", f"{s['peak_memory_mb']:.0f}", f"{ate:.4f}"))
        rows.append((f"  (refine {t['refine']:.1f} s, wall {t['wall']:.1f} s incl. bag read "
                     f"{t['read_bag']:.1f} s)",) + ("",) * 8)
        continue
    p = s["per_scan_ms"]
    rows.append((n, s["scan_count"], f"{p['median']:.2f}", f"{p['p95']:.2f}", f"{p['max']:.2f}",
                 f"{s['real_time_factor']:.1f}", f"{s['real_time_factor_wall']:.1f}",
                 f"{s['peak_memory_mb']:.0f}", f"{ate:.4f}"))
w = [max(len(str(r[i])) for r in rows + [hdr]) for i in range(len(hdr))]
for r in [hdr] + rows:
    if len(r[0]) > w[0]:
        print(r[0]); continue
    print("  ".join(str(c).rjust(w[i]) if i else str(c).ljust(w[i]) for i, c in enumerate(r)))
EOF
