#!/usr/bin/env python3
"""Plots of rvlio run directories: trajectories, RV profile, ablations.

Usage:
  rvlio_plot.py trajectories --gt GT.tum --run LABEL=DIR [--run ...] --out PREFIX
                             [--align origin|se3|none] [--max-dt S] [--no-z]
  rvlio_plot.py rv-profile   --run DIR [--gt GT.tum] --out PREFIX
  rvlio_plot.py ablation     --table CSV --out PREFIX [--metric NAME ...]
                             [--yscale auto|linear|log]
  rvlio_plot.py compare-bars --table CSV --out PREFIX [--metric NAME ...]
  rvlio_plot.py deviation    --run DIR --out PREFIX [--title TEXT]
  rvlio_plot.py map          --run DIR --out PREFIX [--field intensity|z|NAME]
                             [--box XMIN,XMAX,YMIN,YMAX] [--title TEXT]
  rvlio_plot.py control      --gt GT_SURVEY.tum [--run LABEL=DIR ...] [--run-origin LABEL=DIR ...]
                             [--control CSV] --out PREFIX
  rvlio_plot.py check        (exit 0 when matplotlib is usable)

Inputs follow the run-directory contract of `rvlio run` (docs/design.md, "The command-line contract"):
DIR/trajectory.tum (t x y z qx qy qz qw, seconds), DIR/scans.csv (one row per
scan) and DIR/summary.json. Every plot is written as PREFIX_<kind>.png (150 dpi)
and PREFIX_<kind>.pdf, atomically (temp file, then rename); a PREFIX ending in
'/' is a folder and gives FOLDER/<kind>.png and .pdf. The written paths and a
few figures (matched poses, along-axis error) go to stdout. compare-bars reads
the compare.csv of `rvlio compare` (one row per variant, status ok|failed).

Exit status: 0 success; 2 bad input (one line `rvlio_plot: error: ...` on
stderr, nothing written); 3 matplotlib/numpy not available; 1 internal error.

Matplotlib comes from Debian (python3-matplotlib, Agg backend, no display).
When the running interpreter lacks it (e.g. a pyenv python3 first on PATH),
the script re-executes itself once with /usr/bin/python3.
"""

import argparse
import csv
import json
import math
import os
import sys
import tempfile

PROG = "rvlio_plot"
SYSTEM_PYTHON = "/usr/bin/python3"
REEXEC_ENV = "RVLIO_PLOT_REEXEC"
DPI = 150
EXIT_BAD_INPUT = 2
EXIT_NO_MATPLOTLIB = 3

np = None  # numpy, bound by LoadNumpy()
_pyplot = []  # matplotlib.pyplot once imported by Pyplot()


class PlotError(Exception):
  """Bad input: reported as one line on stderr with exit status 2."""


def Fail(message, code):
  sys.stderr.write("%s: error: %s\n" % (PROG, message))
  sys.exit(code)


# --------------------------------------------------------------------------
# Environment: matplotlib from Debian, re-exec with the system python if needed
# --------------------------------------------------------------------------

def ReexecWithSystemPython():
  """Re-runs this script with /usr/bin/python3 when that is another interpreter."""
  if os.environ.get(REEXEC_ENV) or not os.path.exists(SYSTEM_PYTHON):
    return
  if os.path.realpath(sys.executable) == os.path.realpath(SYSTEM_PYTHON):
    return
  env = dict(os.environ, **{REEXEC_ENV: "1"})
  sys.stdout.flush()
  os.execve(SYSTEM_PYTHON, [SYSTEM_PYTHON, os.path.abspath(__file__)] + sys.argv[1:], env)


def LoadNumpy():
  """Binds numpy; when numpy or matplotlib is missing, re-executes with the
  system python or exits 3. Matplotlib itself is imported only to draw, so
  bad input is reported quickly."""
  global np
  import importlib.util
  missing = [m for m in ("numpy", "matplotlib") if importlib.util.find_spec(m) is None]
  if missing:
    ReexecWithSystemPython()
    Fail("%s not available to %s; install python3-matplotlib"
         % (" and ".join(missing), sys.executable), EXIT_NO_MATPLOTLIB)
  import numpy
  np = numpy


def Pyplot():
  """matplotlib.pyplot with the Agg backend (no display) and legible defaults."""
  if not _pyplot:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot
    matplotlib.pyplot.rcParams.update({"font.size": 9, "axes.grid": True, "grid.alpha": 0.3,
                                       "legend.fontsize": 8, "figure.dpi": DPI})
    _pyplot.append(matplotlib.pyplot)
  return _pyplot[0]


# --------------------------------------------------------------------------
# Input files
# --------------------------------------------------------------------------

def ReadTum(path):
  """Reads a TUM file -> (t [N], p [N,3], q_xyzw [N,4]); '#' lines are comments."""
  if not os.path.isfile(path):
    raise PlotError("cannot read %s: no such file" % path)
  rows = []
  with open(path) as f:
    for number, line in enumerate(f, 1):
      text = line.strip()
      if not text or text.startswith("#"):
        continue
      fields = text.split()
      try:
        values = [float(v) for v in fields]
      except ValueError:
        values = []
      if len(values) != 8 or not all(math.isfinite(v) for v in values):
        raise PlotError("%s:%d: expected 8 numbers 't x y z qx qy qz qw'" % (path, number))
      rows.append(values)
  if not rows:
    raise PlotError("%s: no poses" % path)
  data = np.array(rows)
  order = np.argsort(data[:, 0], kind="stable")
  data = data[order]
  return data[:, 0], data[:, 1:4], data[:, 4:8]


def ToFloat(text):
  try:
    return float(text)
  except (TypeError, ValueError):
    return float("nan")


def ReadScansCsv(path, required):
  """Reads scans.csv -> dict column -> numpy array (NaN where not numeric)."""
  if not os.path.isfile(path):
    raise PlotError("cannot read %s: no such file" % path)
  with open(path, newline="") as f:
    reader = csv.DictReader(f)
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in required if c not in header]
    if missing:
      raise PlotError("%s: missing column(s) %s" % (path, ", ".join(missing)))
    rows = list(reader)
  if not rows:
    raise PlotError("%s: no scans" % path)
  columns = {}
  for name in header:
    if name == "status":
      columns[name] = [r.get(name, "") for r in rows]
    else:
      columns[name] = np.array([ToFloat(r.get(name)) for r in rows])
  if not np.all(np.isfinite(columns["t"])):
    raise PlotError("%s: column t is not numeric in every row" % path)
  return columns


def ReadSummary(run_dir):
  """summary.json of a run, or {} when absent (it is informational only)."""
  path = os.path.join(run_dir, "summary.json")
  if not os.path.isfile(path):
    return {}
  try:
    with open(path) as f:
      summary = json.load(f)
  except ValueError as e:
    raise PlotError("%s: not valid JSON (%s)" % (path, e))
  return summary if isinstance(summary, dict) else {}


def RunTrajectoryPath(run):
  """A run is a directory holding trajectory.tum or a TUM file itself."""
  if os.path.isdir(run):
    return os.path.join(run, "trajectory.tum")
  if not os.path.isfile(run):
    raise PlotError("run %s: no such directory or TUM file" % run)
  return run


def ParseRunSpec(spec):
  """'LABEL=DIR' -> (LABEL, DIR); a bare DIR is labelled by its base name."""
  if "=" in spec:
    label, path = spec.split("=", 1)
    if label and path:
      return label, path
    raise PlotError("--run %s: expected LABEL=DIR" % spec)
  return os.path.basename(os.path.normpath(spec)) or spec, spec


# --------------------------------------------------------------------------
# Trajectory math (numpy)
# --------------------------------------------------------------------------

def QuatToRot(q_xyzw):
  """Rotation matrices [N,3,3] of unit quaternions (x, y, z, w)."""
  q = q_xyzw / np.linalg.norm(q_xyzw, axis=1, keepdims=True)
  x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
  return np.stack([
      np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
      np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
      np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
  ], -2)


def Associate(t_est, t_gt, max_dt):
  """Index pairs (i_est, i_gt) of each estimate and its nearest GT stamp within max_dt."""
  right = np.clip(np.searchsorted(t_gt, t_est), 1, len(t_gt) - 1) if len(t_gt) > 1 else \
      np.zeros(len(t_est), dtype=int)
  left = np.maximum(right - 1, 0)
  pick_left = np.abs(t_est - t_gt[left]) <= np.abs(t_gt[right] - t_est)
  nearest = np.where(pick_left, left, right)
  ok = np.abs(t_gt[nearest] - t_est) <= max_dt
  return np.nonzero(ok)[0], nearest[ok]


def UmeyamaSe3(p_est, p_gt):
  """R, t minimising sum |p_gt - (R p_est + t)|^2 (Umeyama 1991, no scale)."""
  mu_est, mu_gt = p_est.mean(0), p_gt.mean(0)
  sigma = (p_gt - mu_gt).T @ (p_est - mu_est) / len(p_est)
  u, _, vt = np.linalg.svd(sigma)
  d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u) * np.linalg.det(vt)) or 1.0])
  r = u @ d @ vt
  return r, mu_gt - r @ mu_est


def Alignment(mode, est, gt, i_est, i_gt):
  """R, t mapping estimate positions into the GT frame."""
  if mode == "none":
    return np.eye(3), np.zeros(3)
  if mode == "origin":  # T = T_gt0 * T_est0^-1 at the first matched pose
    r_gt = QuatToRot(gt[2][i_gt[:1]])[0]
    r_est = QuatToRot(est[2][i_est[:1]])[0]
    r = r_gt @ r_est.T
    return r, gt[1][i_gt[0]] - r @ est[1][i_est[0]]
  if len(i_est) < 3:
    raise PlotError("se3 alignment needs at least 3 matched poses")
  return UmeyamaSe3(est[1][i_est], gt[1][i_gt])


def GtMoves(p_gt):
  return bool(np.ptp(p_gt, axis=0).max() > 1e-6)


def TunnelAxis(p_gt):
  """Unit principal axis of the GT positions, pointing from start to end."""
  centered = p_gt - p_gt.mean(0)
  eigenvalues, eigenvectors = np.linalg.eigh(centered.T @ centered)
  axis = eigenvectors[:, -1] if eigenvalues[-1] > 1e-12 else np.array([1.0, 0.0, 0.0])
  travel = float(axis @ (p_gt[-1] - p_gt[0]))
  if travel < 0 or (travel == 0 and axis[np.argmax(np.abs(axis))] < 0):
    axis = -axis
  return axis


class RunErrors(object):
  """One run aligned to GT: aligned positions and along-axis error per match."""

  def __init__(self, label, est, gt, align, max_dt, axis):
    i_est, i_gt = Associate(est[0], gt[0], max_dt)
    if len(i_est) == 0:
      raise PlotError("run '%s': no estimate stamp within %g s of a GT stamp" % (label, max_dt))
    r, t = Alignment(align, est, gt, i_est, i_gt)
    self.label = label
    self.num_poses = len(est[0])
    self.t = est[0]
    self.p = est[1] @ r.T + t
    self.t_match = est[0][i_est]
    self.axis_error = (self.p[i_est] - gt[1][i_gt]) @ axis

  def Describe(self):
    e = np.abs(self.axis_error)
    return "run '%s': %d/%d poses matched, along-axis error max %.6f m, final %.6f m" % (
        self.label, len(e), self.num_poses, e.max(), self.axis_error[-1])


# --------------------------------------------------------------------------
# Output
# --------------------------------------------------------------------------

def OutputStem(prefix, kind):
  """PREFIX_kind, or FOLDER/kind when the prefix ends with a path separator."""
  if prefix.endswith("/") or prefix.endswith(os.sep):
    return os.path.join(prefix, kind)
  return "%s_%s" % (prefix, kind)


def SaveFigure(fig, prefix, kind):
  """Writes PREFIX_kind.png and .pdf atomically; returns the paths."""
  stem = OutputStem(prefix, kind)
  directory = os.path.dirname(os.path.abspath(stem))
  finals, temps = [], []
  umask = os.umask(0)
  os.umask(umask)
  try:
    os.makedirs(directory, exist_ok=True)
    for ext in ("png", "pdf"):
      final = "%s.%s" % (stem, ext)
      fd, temp = tempfile.mkstemp(prefix=".%s." % os.path.basename(final), dir=directory)
      temps.append(temp)
      with os.fdopen(fd, "wb") as f:
        fig.savefig(f, format=ext, dpi=DPI)
      os.chmod(temp, 0o666 & ~umask)  # mkstemp creates 0600
      finals.append(final)
    for temp, final in zip(temps, finals):
      os.replace(temp, final)
  except OSError as e:
    raise PlotError("cannot write %s: %s" % (stem, e))
  finally:
    Pyplot().close(fig)
    for temp in temps:
      if os.path.exists(temp):
        os.remove(temp)
  for final in finals:
    print("wrote %s" % final)
  return finals


def ColorCycle():
  return Pyplot().rcParams["axes.prop_cycle"].by_key()["color"]


# --------------------------------------------------------------------------
# trajectories
# --------------------------------------------------------------------------

def RunWidth(index):
  """Later runs are drawn thinner, so runs that coincide stay distinguishable."""
  return max(0.9, 2.4 - 0.5 * index)


def PlotTopView(ax, gt, runs, colors):
  ax.plot(gt[1][:, 0], gt[1][:, 1], color="black", lw=2.2, ls="--", label="ground truth",
          zorder=3)
  ax.plot(gt[1][0, 0], gt[1][0, 1], "ko", ms=5, zorder=4)
  for i, (run, color) in enumerate(zip(runs, colors)):
    ax.plot(run.p[:, 0], run.p[:, 1], color=color, lw=RunWidth(i), label=run.label)
    ax.plot(run.p[-1, 0], run.p[-1, 1], "x", color=color, ms=7, mew=2)
  ax.set_xlabel("x [m]")
  ax.set_ylabel("y [m]")
  ax.set_title("(a) Top view (o start, x end of each run; axes not to scale)")
  ax.legend(loc="best")


def PlotAxisError(ax, runs, colors, t0, axis, moving):
  for i, (run, color) in enumerate(zip(runs, colors)):
    ax.plot(run.t_match - t0, run.axis_error, color=color, lw=RunWidth(i),
            label="%s (max |e| %.3g m)" % (run.label, np.abs(run.axis_error).max()))
  ax.axhline(0.0, color="black", lw=0.8)
  ax.set_xlabel("time [s]")
  ax.set_ylabel("along-axis error [m]")
  direction = "(%.2f, %.2f, %.2f)" % tuple(np.round(axis, 2) + 0.0)
  ax.set_title("(b) Error along the tunnel axis %s%s"
               % (direction, "" if moving else ": GT does not move, x axis used"))
  ax.legend(loc="best")


def PlotHeight(ax, gt, runs, colors, t0):
  ax.plot(gt[0] - t0, gt[1][:, 2], color="black", lw=2.2, ls="--", label="ground truth")
  for i, (run, color) in enumerate(zip(runs, colors)):
    ax.plot(run.t - t0, run.p[:, 2], color=color, lw=RunWidth(i), label=run.label)
  ax.set_xlabel("time [s]")
  ax.set_ylabel("z [m]")
  ax.set_title("(c) Height over time")
  ax.legend(loc="best")


def CmdTrajectories(args):
  if not args.run:
    raise PlotError("trajectories: give at least one --run LABEL=DIR")
  gt = ReadTum(args.gt)
  axis = TunnelAxis(gt[1])
  runs = []
  for spec in args.run:
    label, path = ParseRunSpec(spec)
    est = ReadTum(RunTrajectoryPath(path))
    runs.append(RunErrors(label, est, gt, args.align, args.max_dt, axis))
  for run in runs:
    print(run.Describe())
  t0 = gt[0][0]
  colors = [ColorCycle()[i % len(ColorCycle())] for i in range(len(runs))]
  panels = 2 if args.no_z else 3
  fig, axes = Pyplot().subplots(panels, 1, figsize=(9, 3.1 * panels + 0.6),
                           gridspec_kw={"height_ratios": [1.3] + [1] * (panels - 1)})
  PlotTopView(axes[0], gt, runs, colors)
  PlotAxisError(axes[1], runs, colors, t0, axis, GtMoves(gt[1]))
  if not args.no_z:
    PlotHeight(axes[2], gt, runs, colors, t0)
    axes[2].sharex(axes[1])
  fig.suptitle("Trajectories vs ground truth %s (alignment: %s)"
               % (os.path.basename(args.gt), args.align), fontsize=11)
  fig.tight_layout()
  SaveFigure(fig, args.out, "trajectories")


# --------------------------------------------------------------------------
# rv-profile
# --------------------------------------------------------------------------

RV_REQUIRED = ("t", "rv_active", "scv", "constraints")
ACTIVE_COLOR = "tab:orange"


def ActiveSpans(t, active):
  """[(start, end)] time spans of consecutive scans with rv_active == 1; each scan
  covers half the gap to its neighbours."""
  if len(t) == 1:
    edges = np.array([t[0] - 0.05, t[0] + 0.05])
  else:
    mid = 0.5 * (t[1:] + t[:-1])
    edges = np.concatenate([[2 * t[0] - mid[0]], mid, [2 * t[-1] - mid[-1]]])
  on = np.concatenate([[False], active > 0.5, [False]])
  starts = np.nonzero(on[1:] & ~on[:-1])[0]
  ends = np.nonzero(~on[1:] & on[:-1])[0]
  return [(edges[a], edges[b]) for a, b in zip(starts, ends)]


def ShadeSpans(ax, spans):
  """Full-height shaded spans; they do not change the y limits of the panel."""
  from matplotlib.collections import PolyCollection
  boxes = [[(a, 0), (b, 0), (b, 1), (a, 1)] for a, b in spans]
  ax.add_collection(PolyCollection(boxes, transform=ax.get_xaxis_transform(),
                                   facecolor=ACTIVE_COLOR, alpha=0.2, lw=0, zorder=0),
                    autolim=False)


def RunTitle(run_dir, summary):
  parts = []
  if "backend" in summary:
    parts.append("backend %s" % summary["backend"])
  config = summary.get("config")
  rv = config.get("rv", {}) if isinstance(config, dict) else {}
  if isinstance(rv, dict) and "enabled" in rv:
    parts.append("RV %s" % ("on" if rv["enabled"] else "off"))
  if isinstance(summary.get("real_time_factor"), (int, float)):
    parts.append("real-time factor %.2f" % summary["real_time_factor"])
  name = os.path.basename(os.path.normpath(run_dir))
  return "RV profile of %s" % name + (" (%s)" % ", ".join(parts) if parts else "")


def AxisAcceleration(t, p, axis, window_s=0.1):
  """World-frame acceleration along `axis` [m/s^2]: the second derivative of
  the positions projected on the axis, averaged over `window_s` (centred; the
  ends, where the average would be one-sided, are dropped). (times, values) or
  None when the trajectory is too short."""
  if len(t) < 5:
    return None
  s = p @ axis
  a = np.gradient(np.gradient(s, t), t)
  n = max(1, int(round(window_s / float(np.median(np.diff(t))))))
  if n > 1:
    if len(a) <= n:
      return None
    a = np.convolve(a, np.ones(n) / n, mode="valid")
    t = t[(n - 1) // 2:(n - 1) // 2 + len(a)]
  return t, a


def ProfilePanels(scans, t, run_errors, axis_acc=None):
  """[(title, ylabel, x, y, color, log)] for each panel drawn; optional columns
  (older scans.csv files lack some), the GT error and the GT axis acceleration
  only when available."""
  panels = [
      ("Number of SCVs (special constraint vectors, d_i > eps0)", "count", t, scans["scv"],
       "tab:blue", False),
      ("Number of point-to-plane constraints", "count", t, scans["constraints"], "tab:gray",
       False)]
  if "coplanar_fraction" in scans:
    panels.append(("Coplanar fraction (constraint vectors with d_i <= eps0)", "fraction", t,
                   scans["coplanar_fraction"], "tab:green", False))
  if "localizability" in scans:
    panels.append(("Localizability (smallest eigenvalue of sum w u u^T, log scale)",
                   "eigenvalue", t, scans["localizability"], "tab:purple", True))
  if "acc_x" in scans:
    panels.append(("IMU acceleration along x (mean specific force per scan, IMU frame)",
                   "acc_x [m/s$^2$]", t, scans["acc_x"], "tab:red", False))
  if axis_acc is not None:
    # A multirotor accelerates by tilting, so the body-frame specific force
    # above hardly shows the speed changes ("shocks", paper Fig. 6); this is
    # the world-frame acceleration along the axis, from the ground truth.
    panels.append(("Acceleration along the tunnel axis (ground truth, world frame)",
                   "a_axis [m/s$^2$]", axis_acc[0], axis_acc[1], "tab:orange", False))
  if run_errors is not None:
    panels.append(("Error along the tunnel axis vs ground truth (origin-aligned)",
                   "error [m]", run_errors[0], run_errors[1], "black", False))
  return panels


def DrawPanel(ax, panel, spans):
  title, ylabel, x, y, color, log = panel
  if log:
    y = np.where(y > 0, y, np.nan)  # log scale: hide non-positive values
  ax.plot(x, y, color=color, lw=1.1)
  if log and np.any(np.isfinite(y)):
    ax.set_yscale("log")
  if ylabel == "count":
    ax.set_ylim(bottom=0)
  ShadeSpans(ax, spans)
  ax.set_ylabel(ylabel)
  ax.set_title(title, fontsize=9, loc="left")


def RepairScanTimes(scans, run_dir):
  """Scan stamps written with too few digits (e.g. 1.7e+09) collapse to a few
  values; trajectory.tum has one row per scan in the same order, so its stamps
  replace them when the counts agree."""
  t = scans["t"]
  if len(t) < 2 or len(np.unique(t)) == len(t):
    return
  path = os.path.join(run_dir, "trajectory.tum")
  if not os.path.isfile(path):
    return
  stamps = ReadTum(path)[0]
  if len(stamps) == len(t):
    print("note: %s: column t has only %d distinct values for %d scans; using the stamps "
          "of trajectory.tum" % (os.path.join(run_dir, "scans.csv"), len(np.unique(t)), len(t)))
    scans["t"] = stamps


def CmdRvProfile(args):
  scans = ReadScansCsv(os.path.join(args.run, "scans.csv"), RV_REQUIRED)
  RepairScanTimes(scans, args.run)
  summary = ReadSummary(args.run)
  t0 = scans["t"][0]
  run_errors = axis_acc = None
  if args.gt:
    gt = ReadTum(args.gt)
    est = ReadTum(RunTrajectoryPath(args.run))
    axis = TunnelAxis(gt[1])
    run = RunErrors(os.path.basename(os.path.normpath(args.run)), est, gt, "origin",
                    args.max_dt, axis)
    print(run.Describe())
    t0 = gt[0][0]
    run_errors = (run.t_match - t0, run.axis_error)
    axis_acc = AxisAcceleration(gt[0], gt[1], axis)
    if axis_acc is not None:
      print("ground truth: acceleration along the axis median %.6f m/s^2, largest |a| %.6f m/s^2"
            % (float(np.median(axis_acc[1])), float(np.max(np.abs(axis_acc[1])))))
      axis_acc = (axis_acc[0] - t0, axis_acc[1])
  t = scans["t"] - t0
  active = np.nan_to_num(scans["rv_active"])
  spans = ActiveSpans(t, active)
  panels = ProfilePanels(scans, t, run_errors, axis_acc)
  for column in ("coplanar_fraction", "localizability", "acc_x"):
    if column not in scans:
      print("note: scans.csv has no column %s; its panel is left out" % column)
  fig, axes = Pyplot().subplots(len(panels), 1, sharex=True, figsize=(9, 1.7 * len(panels) + 1.0))
  for ax, panel in zip(axes, panels):
    DrawPanel(ax, panel, spans)
  from matplotlib.patches import Patch
  axes[0].legend(handles=[Patch(facecolor=ACTIVE_COLOR, alpha=0.2, label="RV active")],
                 loc="upper right")
  axes[-1].set_xlabel("time [s]")
  fig.suptitle("%s\nshaded: RV active in %d of %d scans"
               % (RunTitle(args.run, summary), int(np.sum(active > 0.5)), len(t)), fontsize=10)
  fig.tight_layout()
  SaveFigure(fig, args.out, "rv_profile")


# --------------------------------------------------------------------------
# ablation
# --------------------------------------------------------------------------

METRIC_UNITS = (("_ms", "ms"), ("ms_", "ms"), ("_deg", "deg"), ("rtf", "x"),
                ("real_time", "x"), ("rmse", "m"), ("error", "m"), ("ate", "m"), ("rpe", "m"))


def MetricLabel(metric):
  for key, unit in METRIC_UNITS:
    if key in metric.lower():
      return "%s [%s]" % (metric, unit)
  return metric


def ReadCsvTable(path):
  """A CSV file with a header -> (stripped column names, rows as dicts)."""
  if not os.path.isfile(path):
    raise PlotError("cannot read %s: no such file" % path)
  with open(path, newline="") as f:
    reader = csv.DictReader(f)
    header = [h.strip() for h in (reader.fieldnames or [])]
    return header, list(reader)


def ReadAblationTable(path, metrics):
  """Rows of the table -> {metric: {(sequence, variant): [values]}}, orders kept."""
  header, rows = ReadCsvTable(path)
  missing = [c for c in ("sequence", "variant") if c not in header]
  if missing:
    raise PlotError("%s: missing column(s) %s" % (path, ", ".join(missing)))
  columns = {}
  for metric in metrics:
    if metric in header:
      columns[metric] = (metric, None)
    elif metric + "_mean" in header:
      std = metric + "_std" if metric + "_std" in header else None
      columns[metric] = (metric + "_mean", std)
    else:
      raise PlotError("%s: no column '%s' (have: %s)" % (path, metric, ", ".join(header)))
  if not rows:
    raise PlotError("%s: no rows" % path)
  sequences, variants = [], []
  for r in rows:
    if r["sequence"] not in sequences:
      sequences.append(r["sequence"])
    if r["variant"] not in variants:
      variants.append(r["variant"])
  cells = {m: Aggregate(rows, c[0], c[1]) for m, c in columns.items()}
  if any(std for _, std in columns.values()):
    note = "mean \u00b1 std as given in the table"
  elif "seed" in header:
    note = "mean \u00b1 std over seeds"
  else:
    note = "one value per cell" if len(rows) == len(set(
        (r["sequence"], r["variant"]) for r in rows)) else "mean \u00b1 std over repeated rows"
  return sequences, variants, cells, note


def Aggregate(rows, column, std_column):
  """(sequence, variant) -> (mean, spread, n) over finite values; NaN when none."""
  values, spreads = {}, {}
  for r in rows:
    key = (r["sequence"], r["variant"])
    values.setdefault(key, [])
    v = ToFloat(r.get(column))
    if math.isfinite(v):
      values[key].append(v)
      if std_column:
        spreads.setdefault(key, []).append(ToFloat(r.get(std_column)))
  cells = {}
  for key, vs in values.items():
    if not vs:
      cells[key] = (float("nan"), 0.0, 0)
    elif std_column and len(vs) == 1:
      cells[key] = (vs[0], np.nan_to_num(spreads[key][0]), 1)
    else:
      cells[key] = (float(np.mean(vs)), float(np.std(vs, ddof=1)) if len(vs) > 1 else 0.0,
                    len(vs))
  return cells


def UseLog(yscale, means):
  positive = [m for m in means if math.isfinite(m) and m > 0]
  if yscale != "auto":
    return yscale == "log"
  return len(positive) >= 2 and max(positive) / min(positive) > 50


def LabelBar(ax, x, mean, spread):
  """Value above the bar (and its error bar); 'n/a' at the bottom when no value."""
  if math.isfinite(mean):
    ax.annotate("%.3g" % mean, (x, mean + spread), xytext=(0, 2), textcoords="offset points",
                ha="center", va="bottom", fontsize=7)
  else:
    ax.annotate("n/a", (x, 0.01), xycoords=ax.get_xaxis_transform(), ha="center",
                va="bottom", fontsize=7, color="tab:red")


def PlotBars(ax, sequences, variants, cells, metric, yscale):
  width = min(0.8 / len(variants), 0.25)
  x = np.arange(len(sequences))
  colors = ColorCycle()
  means = [cells.get((s, v), (float("nan"), 0, 0))[0] for s in sequences for v in variants]
  log = UseLog(yscale, means)
  for j, variant in enumerate(variants):
    stats = [cells.get((s, variant), (float("nan"), 0.0, 0)) for s in sequences]
    mean = np.array([m for m, _, _ in stats])
    spread = np.array([d for _, d, _ in stats])
    xs = x + width * (j + 0.5 - 0.5 * len(variants))
    bars = ax.bar(xs, np.nan_to_num(mean), width * 0.92, yerr=spread if spread.any() else None,
                  capsize=3, color=colors[j % len(colors)], label=variant)
    for bar, m, d in zip(bars, mean, spread):
      LabelBar(ax, bar.get_x() + bar.get_width() / 2, m, d)
  if log:
    ax.set_yscale("log")
  ax.set_xticks(x)
  ax.set_xlim(-0.5, len(sequences) - 0.5)
  ax.set_xticklabels(sequences)
  ax.set_xlabel("sequence")
  ax.set_ylabel(MetricLabel(metric) + (" (log)" if log else ""))
  ax.margins(y=0.15)


def CmdAblation(args):
  metrics = args.metric or ["ate_rmse"]
  sequences, variants, cells, note = ReadAblationTable(args.table, metrics)
  width = max(7.0, 1.2 + 0.45 * len(sequences) * len(variants))
  fig, axes = Pyplot().subplots(len(metrics), 1, figsize=(width, 3.6 * len(metrics) + 0.8),
                           squeeze=False)
  for ax, metric in zip(axes[:, 0], metrics):
    PlotBars(ax, sequences, variants, cells[metric], metric, args.yscale)
    ax.set_title(metric, fontsize=9, loc="left")
  axes[0, 0].legend(title="variant", loc="upper left", bbox_to_anchor=(1.01, 1.0))
  fig.suptitle("Ablation: %s (%s; n/a = no result)" % (os.path.basename(args.table), note),
               fontsize=10)
  fig.tight_layout()
  SaveFigure(fig, args.out, "ablation")


# --------------------------------------------------------------------------
# compare-bars
# --------------------------------------------------------------------------

COMPARE_METRICS = ("ate_rmse_m", "rpe_rmse_m", "axis_max_m")
COMPARE_TITLES = {"ate_rmse_m": ("ATE (RMSE)", "ATE [m]"),
                  "rpe_rmse_m": ("RPE (1-frame RMSE)", "RPE [m]"),
                  "axis_max_m": ("largest error along the tunnel axis", "along-axis max [m]"),
                  "end_point_m": ("end-point error", "end-point [m]"),
                  "ms_per_scan": ("time per scan", "ms/scan"),
                  "real_time_factor": ("real-time factor", "real-time factor [x]"),
                  "map_rms_m": ("map accuracy (point-to-plane RMS)", "map RMS [m]"),
                  "map_completeness": ("map completeness", "completeness")}


def ReadCompareTable(path, metrics):
  """compare.csv -> (variant names, {metric: [value or NaN per variant]}, failed flags)."""
  header, rows = ReadCsvTable(path)
  missing = [c for c in ("variant",) + tuple(metrics) if c not in header]
  if missing:
    raise PlotError("%s: missing column(s) %s" % (path, ", ".join(missing)))
  if not rows:
    raise PlotError("%s: no rows" % path)
  names = [r["variant"] for r in rows]
  failed = [r.get("status", "ok") not in ("ok", "") for r in rows]
  values = {m: [float("nan") if bad else ToFloat(r.get(m)) for r, bad in zip(rows, failed)]
            for m in metrics}
  return names, values, failed


def CmdCompareBars(args):
  metrics = args.metric or list(COMPARE_METRICS)
  names, values, failed = ReadCompareTable(args.table, metrics)
  colors = ColorCycle()
  width = max(7.0, 2.0 + 1.1 * len(names) * len(metrics) / 2.0)
  fig, axes = Pyplot().subplots(1, len(metrics), figsize=(width, 3.8), squeeze=False)
  x = np.arange(len(names))
  for ax, metric in zip(axes[0], metrics):
    v = np.array(values[metric])
    bars = ax.bar(x, np.nan_to_num(v), 0.7, color=[colors[i % len(colors)] for i in x])
    for bar, value, bad in zip(bars, v, failed):
      if math.isfinite(value):
        ax.annotate("%.3g" % value, (bar.get_x() + bar.get_width() / 2, value), xytext=(0, 2),
                    textcoords="offset points", ha="center", va="bottom", fontsize=7)
      else:
        ax.annotate("failed" if bad else "n/a", (bar.get_x() + bar.get_width() / 2, 0.01),
                    xycoords=ax.get_xaxis_transform(), ha="center", va="bottom", fontsize=7,
                    color="tab:red")
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=30, ha="right", fontsize=8)
    title, ylabel = COMPARE_TITLES.get(metric, (metric, MetricLabel(metric)))
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9, loc="left")
    finite = v[np.isfinite(v)]
    top = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
    ax.set_ylim(0.0, 1.18 * top)  # room for the value labels
  fig.suptitle("rvlio compare: %s" % os.path.basename(os.path.dirname(os.path.abspath(
      args.table))), fontsize=10)
  fig.tight_layout()
  for name, metric_values in zip(names, zip(*[values[m] for m in metrics])):
    print("variant %s: %s" % (name, ", ".join("%s %.6g" % (m, v)
                                              for m, v in zip(metrics, metric_values))))
  SaveFigure(fig, args.out, "compare_bars")


# --------------------------------------------------------------------------
# deviation
# --------------------------------------------------------------------------

def CmdDeviation(args):
  """DIR/deviation.csv of `rvlio run --map`: deviation per metre of chainage."""
  path = os.path.join(args.run, "deviation.csv")
  header, rows = ReadCsvTable(path)
  needed = ("chainage_m", "count", "median_m", "median_abs_m", "p95_abs_m")
  missing = [c for c in needed if c not in header]
  if missing:
    raise PlotError("%s: missing column(s) %s" % (path, ", ".join(missing)))
  if not rows:
    raise PlotError("%s: no rows" % path)
  col = {c: np.array([ToFloat(r.get(c)) for r in rows]) for c in needed}
  # Per surface (left, right, floor, ceiling): a second panel with each
  # surface's signed median, when the file has those columns.
  sides = [s for s in ("left", "right", "floor", "ceiling") if s + "_median_m" in header]
  for side in sides:
    col[side] = np.array([ToFloat(r.get(side + "_median_m")) for r in rows])
  plt = Pyplot()
  if sides:
    fig, (ax, ax_sides) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
  else:
    fig, ax = plt.subplots(figsize=(8, 3.5))
  cm = 100.0
  ax.plot(col["chainage_m"], cm * col["p95_abs_m"], label="p95 |deviation|", color="tab:red")
  ax.plot(col["chainage_m"], cm * col["median_abs_m"], label="median |deviation|",
          color="tab:blue")
  ax.plot(col["chainage_m"], cm * col["median_m"], label="median (signed)", color="tab:green",
          linestyle="--")
  ax.axhline(0.0, color="0.6", linewidth=0.8)
  ax.set_xlabel("chainage [m]")
  ax.set_ylabel("deviation from the reference [cm]")
  ax.set_title(args.title or "deviation of %s from its reference map" %
               os.path.basename(os.path.normpath(args.run)))
  ax.grid(True, alpha=0.3)
  ax.legend(loc="upper right", fontsize=8)
  if sides:
    ax.set_xlabel("")
    for side in sides:
      ax_sides.plot(col["chainage_m"], cm * col[side], label=side)
    ax_sides.axhline(0.0, color="0.6", linewidth=0.8)
    ax_sides.set_xlabel("chainage [m]")
    ax_sides.set_ylabel("signed median per surface [cm]")
    ax_sides.grid(True, alpha=0.3)
    ax_sides.legend(loc="upper right", fontsize=8, ncol=len(sides))
  fig.tight_layout()
  peak = int(np.nanargmax(col["p95_abs_m"]))
  print("peak p95 |deviation| %.4f m at chainage %.1f m; median |deviation| median %.4f m" %
        (col["p95_abs_m"][peak], col["chainage_m"][peak], float(np.nanmedian(col["median_abs_m"]))))
  largest = []
  for side in sides:
    if np.all(np.isnan(col[side])):
      continue
    k = int(np.nanargmax(np.abs(col[side])))
    largest.append("%s %.4f m at %.1f m" % (side, col[side][k], col["chainage_m"][k]))
  if largest:
    print("largest signed median per surface: " + ", ".join(largest))
  SaveFigure(fig, args.out, "deviation")


def ReadControlCsv(path):
  """control.csv of `refine --control` (or a control file): rows with name, role, x, y, z."""
  header, rows = ReadCsvTable(path)
  missing = [c for c in ("name", "x", "y", "z") if c not in header]
  if missing:
    raise PlotError("%s: missing column(s) %s" % (path, ", ".join(missing)))
  return rows


def CmdControl(args):
  """Along-axis and height error against the survey-frame ground truth, over the
  chainage, for runs in the survey frame (--run, no alignment) and runs in their
  own frame (--run-origin, placed at the ground truth's first pose), with the marks."""
  if not args.run and not args.run_origin:
    raise PlotError("control: give at least one --run or --run-origin LABEL=DIR")
  gt = ReadTum(args.gt)
  axis = TunnelAxis(gt[1])
  runs = []
  for specs, align in ((args.run, "none"), (args.run_origin, "origin")):
    for spec in specs:
      label, path = ParseRunSpec(spec)
      run = RunErrors(label, ReadTum(RunTrajectoryPath(path)), gt, align, args.max_dt, axis)
      i_est, i_gt = Associate(run.t, gt[0], args.max_dt)
      run.chainage = (gt[1][i_gt] - gt[1][0]) @ axis
      run.height_error = run.p[i_est][:, 2] - gt[1][i_gt][:, 2]
      runs.append(run)
  for run in runs:
    print(run.Describe() + ", at the far end %.4f m (height %.4f m)" %
          (run.axis_error[-1], run.height_error[-1]))
  marks = ReadControlCsv(args.control) if args.control else []
  colors = [ColorCycle()[i % len(ColorCycle())] for i in range(len(runs))]
  plt = Pyplot()
  fig, (ax, ax_z) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
  cm = 100.0
  for i, (run, color) in enumerate(zip(runs, colors)):
    ax.plot(run.chainage, cm * run.axis_error, color=color, lw=RunWidth(i),
            label="%s (far end %.1f cm)" % (run.label, cm * run.axis_error[-1]))
    ax_z.plot(run.chainage, cm * run.height_error, color=color, lw=RunWidth(i), label=run.label)
  origin = gt[1][0]
  for k, m in enumerate(marks):
    c = (np.array([ToFloat(m["x"]), ToFloat(m["y"]), ToFloat(m["z"])]) - origin) @ axis
    check = m.get("role") == "check"
    for a in (ax, ax_z):
      a.axvline(c, color="0.5", lw=0.8, ls="--" if check else "-",
                label=None if a is ax_z or k > 1 else None)
    ax.annotate(m["name"] + (" (check)" if check else ""), (c, 1.0), xycoords=("data", "axes fraction"),
                fontsize=7, ha="center", va="bottom")
  for a, what in ((ax, "along-axis error [cm]"), (ax_z, "height error [cm]")):
    a.axhline(0.0, color="black", lw=0.8)
    a.set_ylabel(what)
    a.grid(True, alpha=0.3)
  ax.legend(loc="best", fontsize=8)
  ax_z.set_xlabel("chainage along the tunnel axis [m] (marks: solid control, dashed check)")
  fig.suptitle(args.title or "error in the survey frame against %s" % os.path.basename(args.gt),
               fontsize=10)
  fig.tight_layout()
  SaveFigure(fig, args.out, "control")


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------

class Parser(argparse.ArgumentParser):
  """argparse with one-line errors and exit status 2."""

  def error(self, message):
    Fail(message, EXIT_BAD_INPUT)


PCD_TYPES = {("F", 4): "<f4", ("F", 8): "<f8", ("U", 1): "u1", ("U", 2): "<u2", ("U", 4): "<u4",
             ("U", 8): "<u8", ("I", 1): "i1", ("I", 2): "<i2", ("I", 4): "<i4", ("I", 8): "<i8"}


def ReadMapPcd(path):
  """The fields of a binary PCD as rvlio writes map.pcd (COUNT 1 each):
  {name: array}."""
  try:
    with open(path, "rb") as f:
      raw = f.read()
  except OSError as e:
    raise PlotError("%s: %s" % (path, e.strerror))
  header, sep, body = raw.partition(b"DATA binary\n")
  if not sep:
    raise PlotError("%s: not a binary PCD (DATA binary)" % path)
  words = {}
  for line in header.decode("ascii", "replace").splitlines():
    parts = line.split()
    if parts and not parts[0].startswith("#"):
      words[parts[0]] = parts[1:]
  try:
    dtype = np.dtype([(n, PCD_TYPES[(t, int(z))]) for n, t, z in
                      zip(words["FIELDS"], words["TYPE"], words["SIZE"])])
    count = int(words["POINTS"][0])
  except (KeyError, ValueError, IndexError):
    raise PlotError("%s: malformed PCD header" % path)
  if len(body) < count * dtype.itemsize:
    raise PlotError("%s: truncated: %d points declared" % (path, count))
  cloud = np.frombuffer(body[:count * dtype.itemsize], dtype=dtype)
  return {n: cloud[n].astype(np.float64) for n in dtype.names}


def CmdMap(args):
  """DIR/map.pcd coloured by a field (grey for intensity): a top view of the
  points below their median height (the ceiling would hide the rest) and an
  elevation of the +y side (the points within 0.5 m of the 99th percentile
  of y), both of the points inside --box when given."""
  path = os.path.join(args.run, "map.pcd")
  m = ReadMapPcd(path)
  if args.field not in m:
    raise PlotError("%s has no field %s (fields: %s)" % (path, args.field, " ".join(m)))
  keep = np.ones(len(m["x"]), dtype=bool)
  if args.box:
    x0, x1, y0, y1 = args.box
    keep = (m["x"] >= x0) & (m["x"] <= x1) & (m["y"] >= y0) & (m["y"] <= y1)
  x, y, z, v = m["x"][keep], m["y"][keep], m["z"][keep], m[args.field][keep]
  if len(x) == 0:
    raise PlotError("%s has no points%s" % (path, " in the box" if args.box else ""))
  grey = args.field == "intensity"
  lo, hi = np.nanpercentile(v, 2), np.nanpercentile(v, 98)
  plt = Pyplot()
  fig, (top, side) = plt.subplots(2, 1, figsize=(12, 5.5), sharex=True)
  below = z < np.median(z)
  wall = y >= np.percentile(y, 99) - 0.5
  im = None
  for ax, shown, vertical in ((top, below, y), (side, wall, z)):
    order = np.argsort(v[shown])  # bright points drawn last
    im = ax.scatter(x[shown][order], vertical[shown][order], c=v[shown][order], s=1.5,
                    cmap="gray" if grey else "viridis", vmin=lo, vmax=hi, linewidths=0,
                    rasterized=True)
    ax.set_facecolor("0.82" if grey else "white")
  top.set_ylabel("y [m] (top view)")
  top.set_title(args.title or "map.pcd of %s, coloured by %s" %
                (os.path.basename(os.path.normpath(args.run)), args.field))
  side.set_ylabel("z [m] (the +y side)")
  side.set_xlabel("x [m]")
  fig.colorbar(im, ax=[top, side], label=args.field, shrink=0.9)
  print("%d points, %s %.4g to %.4g (2nd to 98th percentile)" % (len(x), args.field, lo, hi))
  SaveFigure(fig, args.out, "map_" + args.field)


def Box(text):
  try:
    box = [float(t) for t in text.split(",")]
  except ValueError:
    box = []
  if len(box) != 4 or not all(math.isfinite(b) for b in box) or box[0] >= box[1] or box[2] >= box[3]:
    raise argparse.ArgumentTypeError("expected XMIN,XMAX,YMIN,YMAX with XMIN < XMAX, YMIN < YMAX, "
                                     "got '%s'" % text)
  return box


def PositiveFloat(text):
  v = ToFloat(text)
  if not (math.isfinite(v) and v > 0):
    raise argparse.ArgumentTypeError("expected a positive number, got '%s'" % text)
  return v


def BuildParser():
  parser = Parser(prog=PROG, description=__doc__.split("\n")[0])
  sub = parser.add_subparsers(dest="command", parser_class=Parser)
  sub.required = True
  p = sub.add_parser("trajectories", help="runs vs GT: top view, along-axis error, height")
  p.add_argument("--gt", required=True, help="ground-truth TUM file")
  p.add_argument("--run", action="append", default=[], help="LABEL=DIR (repeatable)")
  p.add_argument("--out", required=True, help="output prefix")
  p.add_argument("--align", choices=("origin", "se3", "none"), default="origin")
  p.add_argument("--max-dt", type=PositiveFloat, default=0.01, help="association [s]")
  p.add_argument("--no-z", action="store_true", help="omit the height panel")
  p.set_defaults(func=CmdTrajectories)
  p = sub.add_parser("rv-profile", help="SCVs, constraints, RV activation, IMU acceleration")
  p.add_argument("--run", required=True, help="run directory")
  p.add_argument("--gt", help="ground-truth TUM file: adds the along-axis error")
  p.add_argument("--out", required=True, help="output prefix")
  p.add_argument("--max-dt", type=PositiveFloat, default=0.01, help="association [s]")
  p.set_defaults(func=CmdRvProfile)
  p = sub.add_parser("ablation", help="grouped bar chart of an ablation table")
  p.add_argument("--table", required=True, help="CSV: sequence,variant[,seed],metrics...")
  p.add_argument("--out", required=True, help="output prefix")
  p.add_argument("--metric", action="append", help="metric column (repeatable)")
  p.add_argument("--yscale", choices=("auto", "linear", "log"), default="auto")
  p.set_defaults(func=CmdAblation)
  p = sub.add_parser("compare-bars", help="bar chart of the compare.csv of rvlio compare")
  p.add_argument("--table", required=True, help="compare.csv: variant,status,metrics...")
  p.add_argument("--out", required=True, help="output prefix (or folder ending in /)")
  p.add_argument("--metric", action="append",
                 help="metric column (repeatable; default ATE, RPE, along-axis max)")
  p.set_defaults(func=CmdCompareBars)
  p = sub.add_parser("deviation", help="deviation.csv of run --map along the chainage")
  p.add_argument("--run", required=True, help="run directory of rvlio run --map")
  p.add_argument("--out", required=True, help="output prefix (or folder ending in /)")
  p.add_argument("--title", help="figure title (default: from summary.json)")
  p.set_defaults(func=CmdDeviation)
  p = sub.add_parser("map", help="map.pcd coloured by a field: top view and the +y wall")
  p.add_argument("--run", required=True, help="run, refine or merge output folder")
  p.add_argument("--out", required=True, help="output prefix (or folder ending in /)")
  p.add_argument("--field", default="intensity", help="field to colour by (default intensity)")
  p.add_argument("--box", type=Box, help="XMIN,XMAX,YMIN,YMAX: only the points inside [m]")
  p.add_argument("--title", help="figure title")
  p.set_defaults(func=CmdMap)
  p = sub.add_parser("control", help="error in the survey frame over the chainage, with marks")
  p.add_argument("--gt", required=True, help="ground truth in the survey frame (NAME_gt_survey.tum)")
  p.add_argument("--run", action="append", default=[],
                 help="LABEL=DIR in the survey frame (no alignment; repeatable)")
  p.add_argument("--run-origin", action="append", default=[],
                 help="LABEL=DIR in its own frame, placed at the ground truth's first pose")
  p.add_argument("--control", help="control.csv (or the control file): the marks")
  p.add_argument("--out", required=True, help="output prefix (or folder ending in /)")
  p.add_argument("--max-dt", type=PositiveFloat, default=0.01, help="association [s]")
  p.add_argument("--title", help="figure title")
  p.set_defaults(func=CmdControl)
  p = sub.add_parser("check", help="exit 0 when matplotlib is usable")
  p.set_defaults(func=None)
  return parser


def main(argv):
  args = BuildParser().parse_args(argv)
  LoadNumpy()
  if args.func is None:  # check: can we draw?
    Pyplot()
    import matplotlib
    print("matplotlib %s (%s)" % (matplotlib.__version__, sys.executable))
    return 0
  try:
    args.func(args)
  except PlotError as e:
    Fail(str(e), EXIT_BAD_INPUT)
  return 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))
