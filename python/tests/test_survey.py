"""rvlio.run / rvlio.refine in a reference map (map=, initial_pose=) against the command."""
import numpy as np
import pytest

import rvlio
from conftest import run_cli


def first_pose_text(tum_path):
    """x,y,z,roll,pitch,yaw (deg) of the first pose of a TUM file."""
    t, x, y, z, qx, qy, qz, qw = np.loadtxt(tum_path)[0]
    # R = Rz(yaw) Ry(pitch) Rx(roll) from the quaternion.
    roll = np.degrees(np.arctan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy)))
    pitch = np.degrees(np.arcsin(np.clip(2 * (qw * qy - qz * qx), -1, 1)))
    yaw = np.degrees(np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
    return [x, y, z, roll, pitch, yaw]


def test_run_in_a_reference_map_gives_the_cli_files(rvlio_bin, tunnel, cli_run, tmp_path):
    ref = cli_run / "map.pcd"
    pose = first_pose_text(cli_run / "trajectory.tum")
    cli = tmp_path / "cli"
    run_cli(rvlio_bin, "run", "--bag", tunnel["bag"], "--config", tunnel["config"], "--out", cli,
            "--quiet", "--map", ref, "--initial-pose", ",".join(f"{v:.17g}" for v in pose))
    py = rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), out=tmp_path / "py",
                   map=ref, initial_pose=pose)
    assert (tmp_path / "py" / "trajectory.tum").read_bytes() == (cli / "trajectory.tum").read_bytes()
    assert (tmp_path / "py" / "deviation.csv").read_bytes() == (cli / "deviation.csv").read_bytes()
    table = py.scans
    assert "map_overlap" in table and "localized" in table
    assert table["localized"].all()
    assert np.all(table["map_overlap"] > 0.3)
    refined = rvlio.refine(tunnel["bag"], py, tunnel["config"], map=ref)
    assert refined.trajectory.shape[0] > 0


def test_run_in_a_reference_map_bad_arguments(tunnel, cli_run, tmp_path):
    with pytest.raises(ValueError, match="--initial-pose"):
        rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), map=cli_run / "map.pcd",
                  initial_pose="1,2,3")
    with pytest.raises(ValueError, match="nothere.pcd"):
        rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), map=tmp_path / "nothere.pcd",
                  initial_pose=[0, 0, 0, 0, 0, 0])
