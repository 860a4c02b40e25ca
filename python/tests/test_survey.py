"""rvlio.run / rvlio.refine in a reference map (map=, initial_pose=) against the command."""
import pathlib

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


def read_map_pcd(path):
    """x y z (N, 3) of a map.pcd (float32 or float64 x y z, with its attributes)."""
    return rvlio.read_map(path)["xyz"]


def write_map_pcd_f8(path, points):
    header = ("VERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {len(points)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
              f"POINTS {len(points)}\nDATA binary\n")
    pathlib.Path(path).write_bytes(header.encode() + points.astype("<f8").tobytes())


def test_run_in_a_reference_map_at_utm_coordinates(tunnel, cli_run, tmp_path):
    """The map and the initial pose moved to a UTM easting and northing: the
    same trajectory (shifted) and deviation as near zero, the map.pcd in
    float64 and the summary's local_origin."""
    shift = np.array([500000.0, 5400000.0, 0.0])
    write_map_pcd_f8(tmp_path / "utm.pcd", read_map_pcd(cli_run / "map.pcd") + shift)
    pose = first_pose_text(cli_run / "trajectory.tum")
    config = rvlio.Config.load(tunnel["config"])
    near = rvlio.run(tunnel["bag"], config, map=cli_run / "map.pcd", initial_pose=pose)
    far = rvlio.run(tunnel["bag"], config, out=tmp_path / "far", map=tmp_path / "utm.pcd",
                    initial_pose=[*(np.array(pose[:3]) + shift), *pose[3:]])
    assert far.trajectory[:, 1:4] - shift == pytest.approx(near.trajectory[:, 1:4], abs=1e-3)
    assert far.scans["y"] - shift[1] == pytest.approx(near.scans["y"], abs=1e-3)
    assert far.summary["local_origin"] == list(shift)
    for key in ("median_abs_m", "p95_abs_m"):
        assert far.summary["localization"]["deviation"][key] == pytest.approx(
            near.summary["localization"]["deviation"][key], abs=1e-3)
    assert read_map_pcd(tmp_path / "far" / "map.pcd")[:, 1].min() > 5.39e6  # float64: not rounded
    assert b"SIZE 8 8 8 4" in (tmp_path / "far" / "map.pcd").read_bytes()[:300]


def test_run_in_a_reference_map_bad_arguments(tunnel, cli_run, tmp_path):
    with pytest.raises(ValueError, match="--initial-pose"):
        rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), map=cli_run / "map.pcd",
                  initial_pose="1,2,3")
    with pytest.raises(ValueError, match="nothere.pcd"):
        rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), map=tmp_path / "nothere.pcd",
                  initial_pose=[0, 0, 0, 0, 0, 0])
