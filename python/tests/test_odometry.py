"""rvlio.Odometry and rvlio.read_bag: the estimator fed from Python."""
import numpy as np
import pytest

import rvlio


def feed(bag, config):
    """The loop of `rvlio run`: every message of the recording, poll after each."""
    odo = rvlio.Odometry(config)
    results = []
    for m in rvlio.read_bag(bag, config):
        if m.kind == "imu":
            odo.add_imu(m.t_ns, m.gyro, m.acc)
        else:
            odo.add_scan(m.t_ns, m.points, m.times, m.intensity)
        results += odo.poll()
    return odo, results + odo.finish()


def tum_stamps_ns(path):
    """The exact stamps of a TUM file (seconds with 9 decimals) in ns."""
    stamps = np.loadtxt(path, usecols=0, dtype=str)
    return np.array([int(s.replace(".", "")) for s in stamps], dtype=np.int64)


def test_scan_by_scan_gives_the_cli_trajectory(tunnel, cli_run):
    config = rvlio.Config.load(tunnel["config"])
    odo, results = feed(tunnel["bag"], config)
    cli = np.loadtxt(cli_run / "trajectory.tum")
    ours = rvlio.tum_array(results)
    assert ours.shape == cli.shape and len(ours) > 20
    np.testing.assert_array_equal([r.t_ns for r in results], tum_stamps_ns(cli_run / "trajectory.tum"))
    # trajectory.tum prints 9 decimals for positions, 12 for quaternions.
    np.testing.assert_allclose(ours[:, 1:4], cli[:, 1:4], rtol=0, atol=6e-10)
    np.testing.assert_allclose(ours[:, 4:], cli[:, 4:], rtol=0, atol=6e-13)
    r = results[-1]
    assert r.status in ("updated", "predict_only", "map_init", "diverged")
    assert r.position.shape == (3,) and r.velocity.shape == (3,) and r.quaternion.shape == (4,)
    np.testing.assert_array_equal(r.T_world_imu[:3, 3], r.position)
    assert isinstance(r.rv.active, bool) and r.rv.n_alpha.shape == (3,)
    assert odo.stats["scans_processed"] == len(results)
    assert odo.map_points().shape[1] == 3


def test_read_bag_messages(tunnel):
    config = rvlio.Config.load(tunnel["config"])
    reader = rvlio.read_bag(tunnel["bag"], config)
    imu = scans = 0
    last_t = -1
    for m in reader:
        if isinstance(m, rvlio.LidarScan):
            scans += 1
            assert m.points.dtype == np.float32 and m.points.shape == (len(m), 3)
            assert m.times.dtype == np.int64 and m.times.min() == 0
            assert m.t_end_ns == m.t_ns + m.times.max()
        else:
            imu += 1
            assert m.t_ns > last_t and m.gyro.shape == (3,) and m.acc.shape == (3,)
            last_t = m.t_ns
    assert reader.stats["scans"] == scans > 0 and reader.stats["imu_samples"] == imu > 0
    assert reader.lidar_layout == "ouster"


def test_imu_arrays_equal_single_samples(tunnel):
    config = rvlio.Config.load(tunnel["config"])
    msgs = list(rvlio.read_bag(tunnel["bag"], config, duration=2.0))
    one, batch = rvlio.Odometry(config), rvlio.Odometry(config)
    out_one, out_batch, pending = [], [], []

    def flush():
        if pending:
            batch.add_imu(np.array([m.t_ns for m in pending], dtype=np.int64),
                          np.array([m.gyro for m in pending]), np.array([m.acc for m in pending]))
            pending.clear()

    for m in msgs:
        if m.kind == "imu":
            one.add_imu(m.t_ns, m.gyro, m.acc)
            pending.append(m)
        else:
            one.add_scan(m.t_ns, m.points, m.times)
            flush()
            batch.add_scan(m.t_ns, m.points.astype(np.float64), m.times.astype(np.uint32))
        out_one += one.poll()
        out_batch += batch.poll()
    flush()
    out_one += one.finish()
    out_batch += batch.finish()
    assert len(out_one) > 5
    np.testing.assert_array_equal(rvlio.tum_array(out_one), rvlio.tum_array(out_batch))


@pytest.fixture
def odo():
    o = rvlio.Odometry()
    o.add_imu(1_000_000_000, [0, 0, 0], [0, 0, 9.81])
    return o


POINTS = np.random.default_rng(1).uniform(-10, 10, (100, 3)).astype(np.float32)
TIMES = np.arange(100, dtype=np.int64) * 1000


@pytest.mark.parametrize("points, times, message", [
    (POINTS[:, :2], TIMES, r"points must be an \(N, 3\) array, got shape \(100, 2\)"),
    (POINTS.ravel(), TIMES, r"points must be an \(N, 3\) array, got shape \(300,\)"),
    (POINTS.astype(np.int32), TIMES, "points must be float32 or float64, got dtype int32"),
    (POINTS, TIMES[:50], r"times must be an \(N,\) array with one offset per point \(N = 100\)"),
    (POINTS, TIMES.astype(np.float64), "times must be integer nanoseconds"),
    (POINTS[:0], TIMES[:0], "the scan has no point"),
])
def test_bad_scan_arrays(odo, points, times, message):
    with pytest.raises(ValueError, match=message):
        odo.add_scan(2_000_000_000, points, times)


def test_scan_must_be_arrays(odo):
    with pytest.raises(TypeError, match="points must be a numpy array"):
        odo.add_scan(2_000_000_000, POINTS.tolist(), TIMES)


def test_nan_point(odo):
    p = POINTS.copy()
    p[17, 1] = np.nan
    with pytest.raises(ValueError, match=r"points\[17\] is not finite"):
        odo.add_scan(2_000_000_000, p, TIMES)


def test_non_monotonic_times(odo):
    with pytest.raises(ValueError, match="IMU times must increase: t_ns = 999"):
        odo.add_imu(999, [0, 0, 0], [0, 0, 9.81])
    with pytest.raises(ValueError, match="IMU times must increase"):
        odo.add_imu(np.array([2_000_000_000, 1_500_000_000]), np.zeros((2, 3)), np.zeros((2, 3)))
    odo.add_scan(3_000_000_000, POINTS, TIMES)
    with pytest.raises(ValueError, match="scan times must increase"):
        odo.add_scan(2_000_000_000, POINTS, TIMES)


def test_bad_imu_values(odo):
    with pytest.raises(TypeError, match="t_ns must be an integer number of nanoseconds"):
        odo.add_imu(2.5e9, [0, 0, 0], [0, 0, 9.81])
    with pytest.raises(ValueError, match="gyro must be 3 numbers"):
        odo.add_imu(2_000_000_000, [0, 0], [0, 0, 9.81])
    with pytest.raises(ValueError, match="is not finite"):
        odo.add_imu(2_000_000_000, [0, np.nan, 0], [0, 0, 9.81])
    with pytest.raises(ValueError, match=r"acc must be an \(M, 3\) float array with M = 2"):
        odo.add_imu(np.array([2, 3], dtype=np.int64) * 10**9, np.zeros((2, 3)), np.zeros((3, 3)))


def test_missing_recording(tmp_path):
    with pytest.raises(FileNotFoundError, match="recording '.*nothere.bag' does not exist"):
        rvlio.read_bag(tmp_path / "nothere.bag")


def test_unreadable_recording(tmp_path):
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"not a bag at all")
    with pytest.raises(ValueError, match="junk.bag"):
        rvlio.read_bag(junk)
