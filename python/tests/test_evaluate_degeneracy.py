"""rvlio.evaluate_degeneracy: hand-built tables with known precision, recall
and angles, the command line's JSON on a simulated run, and bad input."""
import json
import math

import pytest

import rvlio

from conftest import run_cli

T0 = 1700000000.0


def write_case(tmp_path):
    """Truth: 6 scans along x, the first 4 degenerate. Detection: flags scans
    0, 1 (directions 10 and 30 degrees off x) and 4; misses 2 and 3."""
    truth = tmp_path / "sim"
    run = tmp_path / "run"
    truth.mkdir()
    run.mkdir()
    rows = ["t,points,lambda_min,lambda_mid,lambda_max,weak_dir_x,weak_dir_y,weak_dir_z,ratio,"
            "pose_lambda_min,pose_weak_rx,pose_weak_ry,pose_weak_rz,pose_weak_tx,pose_weak_ty,"
            "pose_weak_tz,degenerate"]
    scans = ["t,status,rv_active,n_alpha_x,n_alpha_y,n_alpha_z"]
    gt, est = [], []
    flagged = {0: 10.0, 1: 30.0, 4: 0.0}
    for k in range(6):
        t = T0 + 0.1 * k
        ratio = 0.0 if k < 4 else 0.5
        rows.append(f"{t:.9f},1000,{ratio / 3},0.3,0.6,1,0,0,{ratio},0,0,0,0,1,0,0,"
                    f"{int(k < 4)}")
        a = math.radians(flagged.get(k, 90.0))
        scans.append(f"{t:.9f},ok,{int(k in flagged)},{math.cos(a)},{math.sin(a)},0")
        gt.append(f"{t:.9f} {0.5 * k} 0 0 0 0 0 1")
        est.append(f"{t:.9f} {0.55 * k} 0 0 0 0 0 1")
    (truth / "localizability.csv").write_text("\n".join(rows) + "\n")
    (truth / "case_gt.tum").write_text("\n".join(gt) + "\n")
    (run / "scans.csv").write_text("\n".join(scans) + "\n")
    (run / "trajectory.tum").write_text("\n".join(est) + "\n")
    return run, truth


def test_known_scores_and_cli_agreement(tmp_path, rvlio_bin):
    run, truth = write_case(tmp_path)
    r = rvlio.evaluate_degeneracy(run, truth, align="none")
    assert r["detection_columns"] == "rv_active,n_alpha"
    assert r["matched"] == 6
    assert (r["true_positive"], r["false_positive"], r["false_negative"]) == (2, 1, 2)
    assert r["precision"] == pytest.approx(2 / 3)
    assert r["recall"] == pytest.approx(0.5)
    assert r["angle_deg"]["mean"] == pytest.approx(20.0)
    assert r["along_weak"]["final"] == pytest.approx(0.25)
    assert r["along_weak"]["growth_per_100m"] == pytest.approx(10.0)
    cli = json.loads(run_cli(rvlio_bin, "eval", "--degeneracy", run, "--truth", truth,
                             "--align", "none", "--json").stdout)
    assert cli == r
    # Re-thresholded truth: ratio < 0.6 makes every scan degenerate.
    r2 = rvlio.evaluate_degeneracy(run, truth, align="none", truth_ratio=0.6)
    assert (r2["true_positive"], r2["false_positive"], r2["false_negative"]) == (3, 0, 3)


def test_simulated_run(tunnel, cli_run, rvlio_bin):
    r = rvlio.evaluate_degeneracy(cli_run, tunnel["dir"])
    cli = json.loads(run_cli(rvlio_bin, "eval", "--degeneracy", cli_run, "--truth",
                             tunnel["dir"], "--json").stdout)
    assert r == cli
    assert r["matched"] > 40


def test_bad_input(tmp_path):
    run, truth = write_case(tmp_path)
    with pytest.raises(ValueError, match="localizability.csv"):
        rvlio.evaluate_degeneracy(run, tmp_path / "nowhere")
    (run / "scans.csv").write_text("t,status\n1700000000.0,ok\n")
    with pytest.raises(ValueError, match="no column 'rv_active'"):
        rvlio.evaluate_degeneracy(run, truth)


def test_simulate_returns_the_truth_file(tmp_path):
    cheap = {"lidar.columns": 64}
    sim = rvlio.simulate("featureless", seed=2, duration=1, out=tmp_path / "a", set=cheap)
    assert sim["localizability"].endswith("localizability.csv")
    assert sim["degenerate_scans"] == sim["scans"]  # planar tunnel: every scan
    off = rvlio.simulate("featureless", seed=2, duration=1, out=tmp_path / "b",
                         set={**cheap, "localizability.enabled": False})
    assert off["localizability"] is None
    assert not (tmp_path / "b" / "localizability.csv").exists()
