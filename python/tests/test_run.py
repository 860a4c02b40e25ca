"""rvlio.run / refine / simulate against the command-line tool on the same input."""
import filecmp
import json

import numpy as np
import pytest

import rvlio
from conftest import run_cli
from test_odometry import feed, tum_stamps_ns


@pytest.fixture(scope="module")
def py_run(tmp_path_factory, tunnel):
    out = tmp_path_factory.mktemp("py_run")
    return out, rvlio.run(tunnel["bag"], rvlio.Config.load(tunnel["config"]), out=out)


def test_run_writes_the_cli_trajectory_byte_for_byte(tunnel, cli_run, py_run):
    out, result = py_run
    assert result.written
    assert filecmp.cmp(out / "trajectory.tum", cli_run / "trajectory.tum", shallow=False)
    assert filecmp.cmp(out / "map.pcd", cli_run / "map.pcd", shallow=False)
    # The array holds the numbers the file prints (9 decimals; stamps exact in ns).
    np.testing.assert_array_equal([r.t_ns for r in result.results],
                                  tum_stamps_ns(cli_run / "trajectory.tum"))
    np.testing.assert_allclose(result.trajectory[:, 1:], np.loadtxt(cli_run / "trajectory.tum")[:, 1:],
                               rtol=0, atol=6e-10)
    cli_summary = json.loads((cli_run / "summary.json").read_text())
    assert result.summary["scan_count"] == cli_summary["scan_count"] == len(result)
    assert result.summary["config"] == cli_summary["config"]
    assert result.summary["stats"] == cli_summary["stats"]


def test_run_result_table(py_run, cli_run):
    _, result = py_run
    table = result.scans
    csv = np.genfromtxt(cli_run / "scans.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    assert len(table["t"]) == len(csv) == len(result.trajectory)
    for column in ("raw_points", "points", "constraints", "scv", "repaired"):
        np.testing.assert_array_equal(table[column], csv[column])
    np.testing.assert_array_equal(table["status"], csv["status"])
    np.testing.assert_allclose(table["x"], result.trajectory[:, 1], rtol=0, atol=0)
    # The degeneracy columns (the default method rv: its n_alpha when active).
    np.testing.assert_array_equal(table["degeneracy_method"], csv["degeneracy_method"])
    assert set(table["degeneracy_method"]) == {"rv"}
    for column in ("degenerate", "weak_dirs"):
        np.testing.assert_array_equal(table[column], csv[column])
    for column in ("weak_dir_x", "weak_dir_y", "weak_dir_z", "condition_number"):
        np.testing.assert_allclose(table[column], csv[column], rtol=1e-7, atol=1e-9, equal_nan=True)
    active = table["rv_active"].astype(bool)
    np.testing.assert_array_equal(table["degenerate"], active)
    np.testing.assert_allclose(table["weak_dir_x"][active], table["n_alpha_x"][active], rtol=0, atol=0)
    assert np.all(np.isnan(table["weak_dir_x"][~active]))


def test_run_table_has_the_columns_of_scans_csv_in_its_order(py_run, cli_run):
    # Both come from one table (outputs/scan_columns.h): same names, same order.
    out, result = py_run
    for folder in (cli_run, out):
        header = (folder / "scans.csv").read_text().splitlines()[0].split(",")
        assert list(result.scans) == header, folder
    csv = np.genfromtxt(cli_run / "scans.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    for column in ("vx", "vy", "vz"):  # the velocity, in the CSV too
        np.testing.assert_allclose(result.scans[column], csv[column], rtol=1e-8, atol=1e-12)
    assert np.all(result.scans["rss_mb"] > 0)  # the memory, in the table too


def test_odometry_scan_by_scan_equals_run(tunnel, py_run):
    _, result = py_run
    _, results = feed(tunnel["bag"], rvlio.Config.load(tunnel["config"]))
    np.testing.assert_array_equal(rvlio.tum_array(results), result.trajectory)


def test_run_without_out_writes_nothing(tunnel, py_run, tmp_path):
    _, written = py_run
    result = rvlio.run(tunnel["bag"], tunnel["config"], duration=2.0)
    assert not result.written and 0 < len(result) < len(written)
    np.testing.assert_array_equal(result.trajectory, written.trajectory[:len(result)])


def test_refine_gives_the_cli_trajectory(rvlio_bin, tunnel, cli_run, py_run, tmp_path):
    config = rvlio.Config.load(tunnel["config"], set={"refine.rounds": 2})
    cli_out = tmp_path / "cli_refine"
    run_cli(rvlio_bin, "refine", "--bag", tunnel["bag"], "--init", cli_run / "trajectory.tum",
            "--config", tunnel["config"], "--set", "refine.rounds=2", "--out", cli_out)
    _, run_result = py_run
    out = tmp_path / "py_refine"
    refined = rvlio.refine(tunnel["bag"], cli_run / "trajectory.tum", config, out=out)
    assert refined.written and len(refined.rounds) >= 1
    assert filecmp.cmp(out / "trajectory.tum", cli_out / "trajectory.tum", shallow=False)
    cli_rounds = json.loads((cli_out / "summary.json").read_text())["rounds"]
    assert [r["degenerate_scans"] for r in refined.rounds] == \
        [r["degenerate_scans"] for r in cli_rounds]
    from_run = rvlio.refine(tunnel["bag"], run_result, config)
    assert not from_run.written
    # From the exact run trajectory, not its 9-decimal file: the same to well below a micrometre.
    np.testing.assert_allclose(from_run.trajectory, refined.trajectory, rtol=0, atol=1e-6)


def test_simulate_writes_the_cli_files(tunnel, tmp_path):
    files = rvlio.simulate("tunnel", seed=3, duration=6, out=tmp_path,
                           set={"lidar.columns": 512})
    assert files["bag"] == str(tmp_path / "tunnel.bag")
    for key, cli_file in (("bag", "bag"), ("ground_truth", "gt"), ("config", "config")):
        assert filecmp.cmp(files[key], tunnel[cli_file], shallow=False), key


def test_run_bad_arguments(tunnel, tmp_path):
    with pytest.raises(FileNotFoundError, match="recording '.*nothere.bag' does not exist"):
        rvlio.run(tmp_path / "nothere.bag")
    with pytest.raises(ValueError, match="lidar.topic"):
        rvlio.run(tunnel["bag"], rvlio.Config.load(set={"lidar.topic": "/nothere"}))
    with pytest.raises(FileNotFoundError, match="initial trajectory"):
        rvlio.refine(tunnel["bag"], tmp_path / "init.tum", tunnel["config"])
    with pytest.raises(ValueError, match="preset"):
        rvlio.simulate("atlantis", out=tmp_path)


def test_an_exception_in_progress_stops_the_run(tunnel):
    calls = []

    def progress(scans, fraction):
        calls.append((scans, fraction))
        if scans >= 1:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        rvlio.run(tunnel["bag"], tunnel["config"], progress=progress)
    assert calls and all(0.0 <= f <= 1.1 for _, f in calls)


def test_imu_trajectory_is_trajectory_imu_tum(tunnel, py_run, tmp_path):
    _, plain = py_run
    assert plain.imu_trajectory is None  # output.imu_trajectory is off by default
    config = rvlio.Config.load(tunnel["config"], set={"output.imu_trajectory": True,
                                                      "refine.rounds": 1})
    run = rvlio.run(tunnel["bag"], config, out=tmp_path / "run")
    refined = rvlio.refine(tunnel["bag"], run, config, out=tmp_path / "refine")
    for result, out in ((run, tmp_path / "run"), (refined, tmp_path / "refine")):
        written = np.loadtxt(out / "trajectory_imu.tum")
        assert result.imu_trajectory.shape == written.shape
        assert len(written) > 5 * len(result.trajectory)  # 200 Hz against 10 Hz scans
        np.testing.assert_allclose(result.imu_trajectory[:, 0], written[:, 0], rtol=0, atol=1e-6)
        np.testing.assert_allclose(result.imu_trajectory[:, 1:], written[:, 1:], rtol=0,
                                   atol=6e-10)


def test_refine_chunks_and_merge_give_the_cli_files(rvlio_bin, tunnel, cli_run, tmp_path):
    sets = ["refine.rounds=1", "refine.job_overlap_s=1"]
    config = rvlio.Config.load(tunnel["config"], set={"refine.rounds": 1,
                                                      "refine.job_overlap_s": 1})
    init = cli_run / "trajectory.tum"
    cli_dirs, py_dirs = [], []
    for k in (1, 2):
        cli_dirs.append(tmp_path / f"cli_chunk{k}")
        args = ["refine", "--bag", tunnel["bag"], "--init", init, "--config", tunnel["config"],
                "--chunk", k, "--of", 2, "--out", cli_dirs[-1]]
        for s in sets:
            args += ["--set", s]
        run_cli(rvlio_bin, *args)
        py_dirs.append(tmp_path / f"py_chunk{k}")
        job = rvlio.refine(tunnel["bag"], init, config, out=py_dirs[-1], chunk=k, of=2)
        assert job.written and job.summary["chunk"]["chunk"] == k
        for f in ("trajectory.tum", "map.pcd", "chunk.json"):
            assert filecmp.cmp(py_dirs[-1] / f, cli_dirs[-1] / f, shallow=False), (k, f)
    run_cli(rvlio_bin, "merge", "--chunks", cli_dirs[1], "--chunks", cli_dirs[0],
            "--out", tmp_path / "cli_merged")
    merged = rvlio.merge(reversed(py_dirs), out=tmp_path / "py_merged")
    assert merged.written and merged.trajectory.shape[1] == 8 and merged.map_points.shape[1] == 3
    for f in ("trajectory.tum", "map.pcd"):
        assert filecmp.cmp(tmp_path / "py_merged" / f, tmp_path / "cli_merged" / f, shallow=False)
    written = np.loadtxt(tmp_path / "py_merged" / "trajectory.tum")
    # The merged map's scan indices are rows of the merged trajectory.
    assert_times_in_their_scans(rvlio.read_map(tmp_path / "py_merged" / "map.pcd"), written[:, 0])
    np.testing.assert_allclose(merged.trajectory[:, 0], written[:, 0], rtol=0, atol=1e-6)  # s
    np.testing.assert_allclose(merged.trajectory[:, 1:], written[:, 1:], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="missing chunk 2 of 2"):
        rvlio.merge([py_dirs[0]])
    with pytest.raises(ValueError, match="chunk and of go together"):
        rvlio.refine(tunnel["bag"], init, config, chunk=1)
    with pytest.raises(ValueError, match="needs 1 <= chunk <= of"):
        rvlio.refine(tunnel["bag"], init, config, chunk=3, of=2)


def assert_times_in_their_scans(m, stamps_s):
    """Every map point's time lies in the scan its scan_index names: after the
    previous row's stamp, at or before its own (stamps_s: trajectory.tum's t)."""
    k = m["scan_index"].astype(np.int64)
    assert k.max() < len(stamps_s)
    assert np.all(m["time"] <= stamps_s[k] + 1e-6)
    previous = np.where(k > 0, stamps_s[np.maximum(k - 1, 0)], -np.inf)
    assert np.all(m["time"] > previous - 1e-6)


def test_read_map_gives_every_field_of_map_pcd(cli_run, tmp_path):
    m = rvlio.read_map(cli_run / "map.pcd")
    assert list(m) == ["xyz", "intensity", "time", "ring", "scan_index"]
    assert [m[k].dtype for k in m] == [np.float64, np.float32, np.float64, np.uint16, np.uint32]
    # The same numbers as numpy's own reading of the binary PCD.
    header, _, body = (cli_run / "map.pcd").read_bytes().partition(b"DATA binary\n")
    assert b"FIELDS x y z intensity time ring scan_index\n" in header
    raw = np.frombuffer(body, dtype=np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                              ("intensity", "<f4"), ("time", "<f8"),
                                              ("ring", "<u2"), ("scan_index", "<u4")]))
    assert m["xyz"].shape == (len(raw), 3)
    for i, axis in enumerate("xyz"):
        np.testing.assert_array_equal(m["xyz"][:, i], raw[axis].astype(np.float64))
    for name in ("intensity", "time", "ring", "scan_index"):
        np.testing.assert_array_equal(m[name], raw[name])
    assert_times_in_their_scans(m, np.loadtxt(cli_run / "trajectory.tum")[:, 0])
    assert np.all(m["ring"] < 32) and np.mean(m["intensity"] > 0) > 0.9
    with pytest.raises(FileNotFoundError):
        rvlio.read_map(tmp_path / "none.pcd")
    compressed = tmp_path / "compressed.pcd"
    compressed.write_text("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n")
    with pytest.raises(ValueError, match="binary_compressed"):
        rvlio.read_map(compressed)


EXTRINSIC_COLUMNS = ("ext_roll_deg", "ext_pitch_deg", "ext_yaw_deg", "ext_x_m", "ext_y_m", "ext_z_m")


def test_run_table_follows_the_extrinsic_estimate_like_scans_csv(tmp_path, rvlio_bin, tunnel,
                                                                  py_run):
    # Without online estimation neither the table nor scans.csv has the columns.
    assert not set(EXTRINSIC_COLUMNS) & set(py_run[1].scans)
    cli_out = tmp_path / "cli"
    run_cli(rvlio_bin, "run", "--bag", tunnel["bag"], "--config", tunnel["config"], "--out",
            cli_out, "--quiet", "--set", "ieskf.estimate_extrinsics=true")
    config = rvlio.Config.load(tunnel["config"], set={"ieskf.estimate_extrinsics": True})
    result = rvlio.run(tunnel["bag"], config)
    csv = np.genfromtxt(cli_out / "scans.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    for column in EXTRINSIC_COLUMNS:
        assert np.all(np.isfinite(result.scans[column])), column
        np.testing.assert_allclose(result.scans[column], csv[column], rtol=1e-8, atol=1e-12)
    final = result.summary["extrinsic"]["T_imu_lidar"]
    np.testing.assert_allclose([result.scans[c][-1] for c in EXTRINSIC_COLUMNS],
                               final["rpy_deg"] + final["translation_m"], rtol=0, atol=1e-12)


TIME_OFFSET_COLUMNS = ("time_offset_s", "time_offset_std_s")


def test_run_table_follows_the_time_offset_estimate_like_scans_csv(tmp_path, rvlio_bin, tunnel,
                                                                    py_run):
    # Without online estimation neither the table nor scans.csv has the columns.
    assert not set(TIME_OFFSET_COLUMNS) & set(py_run[1].scans)
    cli_out = tmp_path / "cli"
    run_cli(rvlio_bin, "run", "--bag", tunnel["bag"], "--config", tunnel["config"], "--out",
            cli_out, "--quiet", "--set", "lidar.estimate_time_offset=true")
    config = rvlio.Config.load(tunnel["config"], set={"lidar.estimate_time_offset": True})
    result = rvlio.run(tunnel["bag"], config)
    csv = np.genfromtxt(cli_out / "scans.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    header = (cli_out / "scans.csv").read_text().splitlines()[0].split(",")
    assert header[-2:] == list(TIME_OFFSET_COLUMNS)
    # The columns both have come in the same order.
    assert [c for c in result.scans if c in header] == [c for c in header if c in result.scans]
    for column in TIME_OFFSET_COLUMNS:
        assert np.all(np.isfinite(result.scans[column])), column
        np.testing.assert_allclose(result.scans[column], csv[column], rtol=1e-8, atol=1e-12)
    assert result.scans["time_offset_s"][-1] == result.summary["time_offset"]["estimate_s"]
