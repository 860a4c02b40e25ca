"""rvlio.Config: files, overrides, the command-line tool's messages."""
import pytest

import rvlio
from conftest import run_cli


def test_defaults_and_round_trip(tmp_path):
    c = rvlio.Config()
    d = c.to_dict()
    assert d["backend"] == c.backend
    assert "rv" in d and "lidar" in d and "imu" in d
    # dump() is YAML that loads back to the same configuration.
    path = tmp_path / "dumped.yaml"
    path.write_text(c.dump())
    assert rvlio.Config.load(path).to_dict() == d


def test_files_then_overrides(tunnel):
    c = rvlio.Config.load(tunnel["config"], set={"rv.enabled": False, "backend": "smoother",
                                                  "lidar.max_range": 40,
                                                  "extrinsics.imu_T_lidar.translation": [0.1, 0, 0.05]})
    d = c.to_dict()
    assert d["rv"]["enabled"] is False
    assert d["backend"] == "smoother" and c.backend == "smoother"
    assert d["lidar"]["max_range"] == 40.0
    assert d["lidar"]["topic"] == rvlio.Config.load(tunnel["config"]).to_dict()["lidar"]["topic"]
    assert d["extrinsics"]["imu_T_lidar"]["translation"] == [0.1, 0.0, 0.05]
    assert c.files == [str(tunnel["config"])]
    assert "rv.enabled=false" in c.overrides


def cli_message(rvlio_bin, tunnel, tmp_path, *config_args):
    r = run_cli(rvlio_bin, "run", "--bag", tunnel["bag"], *config_args, "--out", tmp_path / "o",
                check=False)
    assert r.returncode == 2
    prefix = "rvlio run: error: "
    assert r.stderr.startswith(prefix), r.stderr
    return r.stderr[len(prefix):].strip()


def test_unknown_key_has_the_cli_message(rvlio_bin, tunnel, tmp_path):
    with pytest.raises(ValueError) as e:
        rvlio.Config.load(set={"rv.epsilon0": 0.1})
    assert "rv.epsilon0" in str(e.value)
    assert str(e.value) == cli_message(rvlio_bin, tunnel, tmp_path, "--set", "rv.epsilon0=0.1")


def test_bad_value_in_a_file_has_the_cli_message(rvlio_bin, tunnel, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("rv:\n  eps0: 7\n")
    with pytest.raises(ValueError) as e:
        rvlio.Config.load(bad)
    assert "bad.yaml:2" in str(e.value)
    assert str(e.value) == cli_message(rvlio_bin, tunnel, tmp_path, "--config", bad)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="configuration file '.*nothere.yaml' does not exist"):
        rvlio.Config.load(tmp_path / "nothere.yaml")


def test_set_must_be_a_dict():
    with pytest.raises(TypeError):
        rvlio.Config.load(set=["rv.enabled=false"])
