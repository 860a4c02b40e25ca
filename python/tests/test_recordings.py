"""rvlio.read_bag reads every recording kind the command reads: the same
sensor data from a ROS1 bag, a ROS 2 .mcap and a ROS 2 .db3, and Livox
CustomMsg scans."""
import numpy as np
import pytest

import rvlio


def messages(files):
    config = rvlio.Config.load(files["config"])
    reader = rvlio.read_bag(files["bag"], config)
    return list(reader), reader.lidar_layout


@pytest.fixture(scope="module")
def ros1(tmp_path_factory):
    files = rvlio.simulate("tunnel", seed=5, duration=2, out=tmp_path_factory.mktemp("ros1"),
                           set={"lidar.columns": 512})
    return messages(files)


@pytest.mark.parametrize("fmt", ["mcap", "db3"])
def test_ros2_recordings_hold_the_same_data(ros1, fmt, tmp_path):
    files = rvlio.simulate("tunnel", seed=5, duration=2, out=tmp_path, format=fmt,
                           set={"lidar.columns": 512})
    assert files["bag"].endswith("." + fmt)
    expected, _ = ros1
    got, layout = messages(files)
    assert layout == "ouster"
    assert [m.kind for m in got] == [m.kind for m in expected]
    for a, b in zip(got, expected):
        assert a.t_ns == b.t_ns
        if a.kind == "imu":
            np.testing.assert_array_equal(a.acc, b.acc)
            np.testing.assert_array_equal(a.gyro, b.gyro)
        else:
            np.testing.assert_array_equal(a.points, b.points)
            np.testing.assert_array_equal(a.times, b.times)


def test_livox_custom_messages(tmp_path):
    files = rvlio.simulate("tunnel", seed=5, duration=2, out=tmp_path, lidar_msg="livox",
                           set={"lidar.columns": 512})
    got, layout = messages(files)
    assert layout == "livox_custom"
    scans = [m for m in got if m.kind == "scan"]
    assert len(scans) >= 10 and all(len(s) > 100 for s in scans)


def test_second_flight_through_the_same_world_and_its_reference_map(tmp_path):
    """flight_seed changes the flight, not the world: the same path and the
    same reference map, another yaw motion."""
    cheap = {"lidar.columns": 64, "survey.angular_step": 1.0, "survey.voxel_size": 0.1,
             "survey.x_max": 10.0}
    a = rvlio.simulate("tunnel", seed=5, duration=5, out=tmp_path / "a", reference_map=True,
                       set=cheap)
    b = rvlio.simulate("tunnel", seed=5, flight_seed=6, duration=5, out=tmp_path / "b",
                       reference_map=True, set=cheap)
    assert a["reference_map"].endswith("reference_map.pcd")
    with open(a["reference_map"], "rb") as fa, open(b["reference_map"], "rb") as fb:
        assert fa.read() == fb.read()
    ga, gb = np.loadtxt(a["ground_truth"]), np.loadtxt(b["ground_truth"])
    np.testing.assert_array_equal(ga[:, :4], gb[:, :4])  # time and position
    assert not np.array_equal(ga[:, 4:], gb[:, 4:])  # orientation: another yaw motion
    assert rvlio.simulate("tunnel", seed=5, duration=1, out=tmp_path / "c",
                          set=cheap)["reference_map"] is None
