"""rvlio.compare: `rvlio compare` through the library, on the session's tunnel.

One comparison without refine (the four variants); its rows against the
tables it wrote, and the trajectories against the runs' trajectory.tum.
"""
import csv

import numpy as np
import pytest

import rvlio


@pytest.fixture(scope="session")
def compared(tmp_path_factory, tunnel):
    out = tmp_path_factory.mktemp("compare")
    rows = rvlio.compare(tunnel["bag"], tunnel["gt"], out, config=tunnel["config"], refine=False)
    return out, rows


def test_rows_are_the_table_compare_wrote(compared):
    out, rows = compared
    assert [r["variant"] for r in rows] == ["ieskf_rv_off", "ieskf_rv_on", "smoother_rv_off",
                                           "smoother_rv_on"]
    with open(out / "compare.csv") as f:
        table = list(csv.DictReader(f))
    assert len(table) == len(rows)
    for row, line in zip(rows, table):
        assert row["status"] == line["status"] == "ok"
        assert row["scans"] == int(line["scans"])
        assert row["ate_rmse_m"] == pytest.approx(float(line["ate_rmse_m"]), rel=1e-9)
        assert row["ate_rmse_m"] < 0.5
        assert row["map_rms_m"] is None  # no reference cloud
    assert (out / "compare.json").exists() and (out / "compare.md").exists()


def test_trajectories_are_the_files_the_runs_wrote(compared):
    out, rows = compared
    for row in rows:
        written = np.loadtxt(out / row["variant"] / "trajectory.tum")
        assert row["trajectory"].shape == written.shape
        np.testing.assert_allclose(row["trajectory"][:, 0], written[:, 0], rtol=1e-12, atol=0)
        np.testing.assert_allclose(row["trajectory"][:, 1:], written[:, 1:], rtol=0, atol=1e-12)


def test_bad_input_raises_before_any_run(tmp_path, tunnel):
    with pytest.raises(ValueError, match="--gt"):
        rvlio.compare(tunnel["bag"], tmp_path / "missing.tum", tmp_path / "out",
                      config=tunnel["config"])
    assert not (tmp_path / "out").exists()
