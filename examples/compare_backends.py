#!/usr/bin/env python3
"""IESKF vs sliding-window smoother, RV on and off, on a simulated tunnel.

Simulates the paper's tunnel (rvlio.simulate), runs the four variants
(rvlio.run), evaluates each against the ground truth (rvlio.evaluate, evo's
definitions) and plots the error along the tunnel axis over time -- the
direction a tunnel leaves unconstrained and RV-LIO reinforces.

    PYTHONPATH=build/python python3 examples/compare_backends.py --out /tmp/compare
    # CI: a short, narrow sequence
    PYTHONPATH=build/python python3 examples/compare_backends.py --duration 6 --columns 512 --out /tmp/c

Writes OUT/along_axis_error.png and prints one table row per variant.
"""
import argparse
import pathlib
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import rvlio  # noqa: E402

VARIANTS = [  # label, config overrides
    ("IESKF, RV on", {"backend": "ieskf", "rv.enabled": True}),
    ("IESKF, RV off", {"backend": "ieskf", "rv.enabled": False}),
    ("smoother, RV on", {"backend": "smoother", "rv.enabled": True}),
    ("smoother, RV off", {"backend": "smoother", "rv.enabled": False}),
]


def along_axis_error(gt, est):
    """Signed error along the principal axis of the reference positions (the
    tunnel axis), at the estimate's stamps; positions of the ground truth
    interpolated linearly. Both are in the world frame of the IMU at start."""
    centered = gt[:, 1:4] - gt[:, 1:4].mean(axis=0)
    axis = np.linalg.svd(centered, full_matrices=False)[2][0]
    inside = (est[:, 0] >= gt[0, 0]) & (est[:, 0] <= gt[-1, 0])
    t = est[inside, 0]
    p_ref = np.column_stack([np.interp(t, gt[:, 0], gt[:, k]) for k in (1, 2, 3)])
    return t - gt[0, 0], (est[inside, 1:4] - p_ref) @ axis


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=None,
                    help="seconds of simulated flight (default: the preset's 52 s)")
    ap.add_argument("--columns", type=int, default=None,
                    help="LiDAR columns (default: the preset's; 512 makes it faster)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=pathlib.Path, default=None,
                    help="output folder (default: a new temporary folder)")
    args = ap.parse_args()
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="rvlio_compare_"))
    out.mkdir(parents=True, exist_ok=True)

    sim_set = {"lidar.columns": args.columns} if args.columns else None
    files = rvlio.simulate("tunnel", seed=args.seed, duration=args.duration, out=out / "data",
                           set=sim_set)
    gt = np.loadtxt(files["ground_truth"])
    print(f"simulated {files['scans']} scans, {files['duration_s']:.1f} s -> {files['bag']}")

    fig, ax = plt.subplots(figsize=(8, 4.5))
    print(f"{'variant':<18} {'scans':>5} {'APE rmse [m]':>12} {'along rmse [m]':>14} "
          f"{'along max [m]':>13} {'RV active':>9}")
    for label, overrides in VARIANTS:
        config = rvlio.Config.load(files["config"], set=overrides)
        result = rvlio.run(files["bag"], config)
        ev = rvlio.evaluate(files["ground_truth"], result.trajectory, align="none")
        t, err = along_axis_error(gt, result.trajectory)
        print(f"{label:<18} {len(result):>5} {ev['ape']['rmse']:>12.3f} "
              f"{ev['along_axis']['rmse']:>14.3f} {ev['along_axis']['max']:>13.3f} "
              f"{int(result.scans['rv_active'].sum()):>9}")
        ax.plot(t, err, label=label)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("error along the tunnel axis [m]")
    ax.set_title("Simulated tunnel: IESKF vs smoother, RV on/off")
    ax.legend()
    fig.tight_layout()
    plot = out / "along_axis_error.png"
    fig.savefig(plot, dpi=120)
    print(f"plot: {plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
