"""Ctrl-C (SIGINT from another process) stops a long call with KeyboardInterrupt
and leaves the interpreter usable."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np

# Each child restores Python's own SIGINT handler: a process started in the
# background by a non-interactive shell (nohup, CI runners) inherits SIGINT
# ignored, and Python then keeps it ignored.
RUN_CHILD = r"""
import signal, sys, rvlio
signal.signal(signal.SIGINT, signal.default_int_handler)
bag, config, out = sys.argv[1:4]
told = False
def progress(scans, fraction):
    global told
    if scans >= 2 and not told:
        told = True
        print("running", flush=True)
try:
    rvlio.run(bag, rvlio.Config.load(config), out=out, progress=progress)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
print("usable", rvlio.Config().backend, flush=True)
"""

SIMULATE_CHILD = r"""
import signal, sys, rvlio
signal.signal(signal.SIGINT, signal.default_int_handler)
print("ready", flush=True)
try:
    rvlio.simulate("tunnel", duration=600, out=sys.argv[1])
    print("finished", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
print("usable", sum(range(10)), flush=True)
"""


def start(code, *args):
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ))


def interrupt_after(p, line, delay_s=0.0):
    assert p.stdout.readline().strip() == line
    time.sleep(delay_s)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    return out.split()


def test_ctrl_c_stops_run_and_writes_the_scans_done(tunnel, cli_run, tmp_path):
    p = start(RUN_CHILD, tunnel["bag"], tunnel["config"], tmp_path)
    out = interrupt_after(p, "running")
    assert out[:3] == ["KeyboardInterrupt", "usable", "ieskf"], out
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["interrupted"] is True
    done = np.loadtxt(tmp_path / "trajectory.tum", ndmin=2)
    full = np.loadtxt(cli_run / "trajectory.tum")
    assert 2 <= len(done) < len(full)
    np.testing.assert_array_equal(done, full[:len(done)])  # the scans done, unchanged


def test_ctrl_c_stops_simulate_and_leaves_no_recording(tmp_path):
    p = start(SIMULATE_CHILD, tmp_path)
    out = interrupt_after(p, "ready", delay_s=1.0)
    assert out == ["KeyboardInterrupt", "usable", "45"], out
    assert not any(f.name.startswith("tunnel.bag") for f in tmp_path.iterdir())
