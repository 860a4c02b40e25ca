#!/usr/bin/env bash
# Byte-identity check of the command's outputs across a restructuring.
#
#   bash scripts/identity_check.sh --save DIR  [--rvlio BIN]   # record a baseline
#   bash scripts/identity_check.sh --check DIR [--rvlio BIN]   # compare against it
#
# Runs, on short simulated flights (6 s, 512 columns; presets tunnel and corridor,
# seeds 1 and 2): simulate; run with both backends (ieskf, smoother); and on the
# first flight refine (whole, and --chunk 1/2 + 2/2 then merge), compare and a
# 2-cell ablate; on a tunnel simulated with its reference map, run in that map
# (--map, --initial-pose-tum) and with the online time offset and extrinsic
# estimated (each backend), refine --map, and compare --ref-map (the map
# figures). The outputs are normalized (scans.csv without the time and memory
# columns `ms` and `rss_mb`; JSON files without timing/memory/environment keys) and
# saved to, or diffed against, DIR. Exit 0 when every file is identical.
set -euo pipefail
cd "$(dirname "$0")/.."
mode="" ; ref="" ; bin="build/bin/rvlio"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --save) mode=save; ref="$2"; shift 2 ;;
    --check) mode=check; ref="$2"; shift 2 ;;
    --rvlio) bin="$2"; shift 2 ;;
    *) echo "identity_check.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ -n "$mode" ]] || { echo "identity_check.sh: need --save DIR or --check DIR" >&2; exit 2; }
bin=$(readlink -f "$bin")
work=$(mktemp -d /tmp/rvlio_identity.XXXXXX)
trap 'rm -rf "$work"' EXIT
raw="$work/raw"; norm="$work/norm"
mkdir -p "$raw" "$norm"
R() { "$bin" "$@" --quiet 2>>"$work/log" >>"$work/log" || { echo "FAILED: rvlio $*" >&2; tail -5 "$work/log" >&2; exit 1; }; }
Rq() { "$bin" "$@" 2>>"$work/log" >>"$work/log" || { echo "FAILED: rvlio $*" >&2; tail -5 "$work/log" >&2; exit 1; }; }

first=""
for preset in tunnel corridor; do
  for seed in 1 2; do
    s="$raw/${preset}_${seed}"
    Rq simulate --preset "$preset" --seed "$seed" --duration 6 --set lidar.columns=512 --out "$s/sim" --name seq
    for backend in ieskf smoother; do
      R run --bag "$s/sim/seq.bag" --config "$s/sim/seq.yaml" --set backend=$backend --out "$s/run_$backend" --allow-divergence
    done
    [[ -n "$first" ]] || first="$s"
  done
done
s="$first"
# Localization in a reference map, and the online estimation of the time
# offset and the extrinsic (each backend), on the tunnel with a survey map.
m="$raw/map"
Rq simulate --preset tunnel --seed 1 --duration 6 --set lidar.columns=512 --reference-map \
  --set survey.x_min=-10 --set survey.x_max=30 --out "$m/sim" --name seq
for backend in ieskf smoother; do
  R run --bag "$m/sim/seq.bag" --config "$m/sim/seq.yaml" --set backend=$backend \
    --map "$m/sim/reference_map.pcd" --initial-pose-tum "$m/sim/seq_gt.tum" --out "$m/run_map_$backend" --allow-divergence
  R run --bag "$m/sim/seq.bag" --config "$m/sim/seq.yaml" --set backend=$backend \
    --set lidar.estimate_time_offset=true --out "$m/run_td_$backend" --allow-divergence
done
R run --bag "$m/sim/seq.bag" --config "$m/sim/seq.yaml" --set ieskf.estimate_extrinsics=true \
  --out "$m/run_ext_ieskf" --allow-divergence
R run --bag "$m/sim/seq.bag" --config "$m/sim/seq.yaml" --set backend=smoother \
  --set smoother.estimate_extrinsics=true --out "$m/run_ext_smoother" --allow-divergence
Rq refine --bag "$m/sim/seq.bag" --config "$m/sim/seq.yaml" --init "$m/run_map_ieskf/trajectory.tum" \
  --map "$m/sim/reference_map.pcd" --out "$m/refine_map" --allow-divergence
Rq refine --bag "$s/sim/seq.bag" --config "$s/sim/seq.yaml" --init "$s/run_ieskf/trajectory.tum" --out "$s/refine" --allow-divergence
for k in 1 2; do
  Rq refine --bag "$s/sim/seq.bag" --config "$s/sim/seq.yaml" --init "$s/run_ieskf/trajectory.tum" \
    --set smoother.refine_job_overlap_s=1 --chunk $k --of 2 --out "$s/chunk$k" --allow-divergence
done
Rq merge --chunks "$s/chunk1" --chunks "$s/chunk2" --out "$s/merge"
R compare --bag "$s/sim/seq.bag" --gt "$s/sim/seq_gt.tum" --config "$s/sim/seq.yaml" --out "$s/compare" --no-plots
R compare --bag "$m/sim/seq.bag" --gt "$m/sim/seq_gt.tum" --config "$m/sim/seq.yaml" \
  --ref-map "$m/sim/reference_map.pcd" --out "$m/compare_map" --no-plots
cat > "$work/grid.yaml" <<GRID
sequences:
  - name: sim
    simulate: {preset: tunnel, duration: 6, set: {lidar.columns: 512}}
    seeds: [1]
variants:
  off: {rv: {enabled: false}}
  on: {}
GRID
R ablate --grid "$work/grid.yaml" --out "$s/ablate" --no-plots

# Normalize: keep trajectories, maps, simulated files, CSV/JSON outputs.
timing_keys='(^|_)(ms|rss_mb|rtf|estimator_total_s|stderr_tail|wall|elapsed|real_time_factor|runtime|seconds|time_s|cpu|memory|rss|started|finished|date|host|version|duration_wall_s)($|_)'
python3 - "$work" "$norm" "$timing_keys" <<'PY'
import csv, io, json, os, re, sys
work, norm, pat = sys.argv[1], sys.argv[2], re.compile(sys.argv[3])
def clean(o):
    if isinstance(o, dict):
        return {k: clean(v) for k, v in o.items() if not pat.search(k)}
    if isinstance(o, list):
        return [clean(v) for v in o]
    return o
keep = ('.tum', '.pcd', '.csv', '.json', '.yaml')
raw = os.path.join(work, 'raw')
for root, _, files in os.walk(raw):
    for f in sorted(files):
        if not f.endswith(keep) or f.endswith('.log'):
            continue
        src = os.path.join(root, f)
        dst = os.path.join(norm, os.path.relpath(src, raw))
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        data = open(src, 'rb').read()
        if f.endswith('.json'):
            try:
                data = (json.dumps(clean(json.loads(data)), indent=1, sort_keys=True) + '\n').encode()
            except ValueError:
                pass
        elif f.endswith('.csv'):
            rows = list(csv.reader(io.StringIO(data.decode())))
            if rows:
                drop = [i for i, c in enumerate(rows[0]) if c in ('ms', 'rss_mb') or pat.search(c)]
                out = io.StringIO()
                w = csv.writer(out, lineterminator='\n')
                for r in rows:
                    w.writerow([c for i, c in enumerate(r) if i not in drop])
                data = out.getvalue().encode()
        # Absolute temporary paths differ from run to run.
        data = data.replace(work.encode(), b'WORK')
        open(dst, 'wb').write(data)
PY
# The simulated recording itself (binary bag).
for b in "$raw"/*/sim/seq.bag; do
  d="$norm/${b#"$raw"/}"; mkdir -p "$(dirname "$d")"; sha256sum < "$b" > "$d.sha256"
done
if [[ $mode == save ]]; then
  rm -rf "$ref"; mkdir -p "$ref"; cp -r "$norm"/. "$ref"/
  echo "identity_check.sh: baseline saved to $ref ($(find "$ref" -type f | wc -l) files)"
else
  if diff -r "$ref" "$norm" > "$work/diff.txt"; then
    echo "identity_check.sh: identical ($(find "$ref" -type f | wc -l) files)"
  else
    head -40 "$work/diff.txt"
    echo "identity_check.sh: the files that differ:"
    diff -rq "$ref" "$norm" | sed "s#$norm/##" || true
    echo "identity_check.sh: DIFFERENT outputs" >&2; exit 1
  fi
fi
