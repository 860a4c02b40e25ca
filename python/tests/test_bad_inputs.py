"""The Python API with the bad inputs of the command-line matrix (test/cli/badinput):
the same refusals and the same marks, raised as exceptions."""
import os

import pytest

import rvlio


def test_empty_out_is_refused_not_read_as_no_files(tunnel, cli_run, tmp_path):
    with pytest.raises(ValueError, match="out is an empty path"):
        rvlio.run(tunnel["bag"], tunnel["config"], out="")
    with pytest.raises(ValueError, match="out is an empty path"):
        rvlio.refine(tunnel["bag"], cli_run / "trajectory.tum", tunnel["config"], out="")
    with pytest.raises(ValueError, match="out is an empty path"):
        rvlio.merge([tmp_path], out="")
    assert not os.listdir(tmp_path)


def test_truncated_mcap_is_read_to_the_cut_and_marked(tmp_path):
    sim = rvlio.simulate("tunnel", seed=3, duration=4, out=tmp_path, format="mcap",
                         set={"lidar.columns": 512})
    data = open(sim["bag"], "rb").read()
    part = tmp_path / "part.mcap"
    part.write_bytes(data[: len(data) * 7 // 10])
    result = rvlio.run(part, sim["config"])
    assert result.summary["truncated"] is True
    assert any("cut short" in w for w in result.warnings)
    tiny = tmp_path / "tiny.mcap"
    tiny.write_bytes(data[: len(data) // 10])
    with pytest.raises(ValueError, match="is truncated"):
        rvlio.run(tiny, sim["config"])


def test_eval_refuses_collapsed_stamps(tunnel, tmp_path):
    est = tmp_path / "collapsed.tum"
    est.write_text("1.7e+09 0 0 0 0 0 0 1\n1.7e+09 1 0 0 0 0 0 1\n1.7e+09 2 0 0 0 0 0 1\n")
    with pytest.raises(ValueError, match="third in a row"):
        rvlio.evaluate(tunnel["gt"], est)


def test_eval_refuses_collapsed_stamps_in_arrays(tunnel):
    import numpy as np
    est = np.zeros((3, 8))
    est[:, 0] = 1.7e9
    est[:, 7] = 1.0
    with pytest.raises(ValueError, match="row 2: time stamp is the third in a row"):
        rvlio.evaluate(tunnel["gt"], est)
