"""rvlio.refine(..., control=...): outputs in the survey frame and the quality report as a table."""
import math

import numpy as np
import pytest

import rvlio
from conftest import run_cli


@pytest.fixture(scope="module")
def stopgo(tmp_path_factory, rvlio_bin):
    """A 14 s stop-and-go flight: the start and one landing 4 m on, in a UTM-sized survey frame."""
    d = tmp_path_factory.mktemp("stopgo")
    run_cli(rvlio_bin, "simulate", "--preset", "stopgo", "--seed", 2, "--duration", 14,
            "--name", "sg", "--set", "lidar.columns=512",
            "--set", "trajectory.waypoints=0,0,0; 0,0,1; 4,0,1; 4,0,0",
            "--set", "trajectory.landing_time=2.5", "--set", "marks.check_every=0", "--out", d)
    run = d / "run"
    run_cli(rvlio_bin, "run", "--bag", d / "sg.bag", "--config", d / "sg.yaml", "--out", run,
            "--quiet")
    return {"dir": d, "bag": d / "sg.bag", "config": d / "sg.yaml", "run": run,
            "control": d / "sg_control.csv"}


def test_refine_with_control_gives_the_report_and_the_command_files(rvlio_bin, stopgo, tmp_path):
    config = rvlio.Config.load(stopgo["config"], set={"refine.rounds": 1})
    py = rvlio.refine(stopgo["bag"], stopgo["run"] / "trajectory.tum", config,
                      out=tmp_path / "py", control=stopgo["control"])
    table = py.control
    assert table["name"] == ["M1", "M2"]
    assert table["role"] == ["control", "control"]
    assert all(d < 0.05 for d in table["d3d"]), table
    assert math.isclose(table["x"][0], 500000.0, abs_tol=0.05)  # the start, survey frame
    assert py.trajectory[:, 2].min() > 5399999.0  # northing: the survey frame
    assert py.summary["control"]["control"]["count"] == 2
    cli = tmp_path / "cli"
    run_cli(rvlio_bin, "refine", "--bag", stopgo["bag"], "--config", stopgo["config"], "--init",
            stopgo["run"] / "trajectory.tum", "--control", stopgo["control"], "--out", cli,
            "--set", "refine.rounds=1")
    assert (tmp_path / "py" / "control.csv").read_bytes() == (cli / "control.csv").read_bytes()
    assert (tmp_path / "py" / "trajectory.tum").read_bytes() == (cli / "trajectory.tum").read_bytes()


def test_bad_control_files(stopgo, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("name,x,y\nM1,1,2\n")
    with pytest.raises(ValueError, match="lacks the column 'z'"):
        rvlio.refine(stopgo["bag"], stopgo["run"] / "trajectory.tum", stopgo["config"], control=bad)
    with pytest.raises((ValueError, OSError, FileNotFoundError)):
        rvlio.refine(stopgo["bag"], stopgo["run"] / "trajectory.tum", stopgo["config"],
                     control=tmp_path / "missing.csv")
