"""Fixtures of the rvlio Python tests.

Run from the repository with the build tree's package on the path:
    PYTHONPATH=build/python RVLIO_BIN=build/bin/rvlio python3 -m pytest python/tests
(scripts/python_test.sh does this). The simulated sequences are short
(512-column tunnels of a few seconds) to keep the suite well under 2 minutes.
"""
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def rvlio_bin():
    path = pathlib.Path(os.environ.get("RVLIO_BIN", REPO / "build" / "bin" / "rvlio"))
    if not path.exists():
        pytest.fail(f"the rvlio command is not at {path}: build it or set RVLIO_BIN")
    return str(path)


def run_cli(rvlio_bin, *args, check=True):
    r = subprocess.run([rvlio_bin, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"rvlio {' '.join(map(str, args))} exited {r.returncode}: {r.stderr}")
    return r


@pytest.fixture(scope="session")
def tunnel(tmp_path_factory, rvlio_bin):
    """A 6 s, 512-column simulated tunnel written by the command-line tool."""
    d = tmp_path_factory.mktemp("tunnel")
    run_cli(rvlio_bin, "simulate", "--preset", "tunnel", "--seed", 3, "--duration", 6,
            "--set", "lidar.columns=512", "--out", d)
    return {"dir": d, "bag": d / "tunnel.bag", "config": d / "tunnel.yaml",
            "gt": d / "tunnel_gt.tum"}


@pytest.fixture(scope="session")
def cli_run(tmp_path_factory, rvlio_bin, tunnel):
    """`rvlio run` on the tunnel: its output folder."""
    out = tmp_path_factory.mktemp("cli_run")
    run_cli(rvlio_bin, "run", "--bag", tunnel["bag"], "--config", tunnel["config"],
            "--out", out, "--quiet")
    return out


@pytest.fixture(scope="session")
def evo_dir():
    shared = REPO.parent.parent / "shared" / "evo_reference"
    for d in (pathlib.Path(os.environ.get("RVLIO_EVO_REFERENCE", shared)),
              REPO / "test" / "data" / "evo"):
        if (d / "reference.json").exists():
            return d
    pytest.fail("no evo reference.json (set RVLIO_EVO_REFERENCE)")
