"""add_scan makes one copy of the points on the way in: the peak memory of
the call grows by one std::vector<LidarPoint> of the scan and by no array
copy (a float64 or contiguous conversion would add 23 MiB or more here).

The peak is the call's own: the kernel's resident high-water mark (VmHWM) is
reset just before the call (/proc/self/clear_refs, "5"), so memory that an
earlier step touched and gave back cannot hide part of the growth, which is
what ru_maxrss deltas did when the import or the allocator had a transient
peak above the resident size."""
import os
import subprocess
import sys

import pytest

CHILD = r"""
import numpy as np, rvlio
def status_mib(key):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024
    raise SystemExit("no " + key)
n = 2_000_000
points = np.full((n, 3), 5.0, dtype=np.float32)  # no temporary arrays
times = np.arange(n, dtype=np.int64)
odo = rvlio.Odometry()
odo.add_imu(0, [0, 0, 0], [0, 0, 9.81])
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")  # reset the peak resident size to the current one
before = status_mib("VmRSS")
odo.add_scan(10**9, points, times)
print(status_mib("VmHWM") - before, rvlio.LIDAR_POINT_BYTES * n / 2**20)
"""


@pytest.mark.skipif(not os.access("/proc/self/clear_refs", os.W_OK),
                    reason="needs Linux /proc/self/clear_refs to reset the peak resident size")
def test_add_scan_copies_the_points_once():
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                         env=dict(os.environ), check=True).stdout.split()
    grown_mib, one_copy_mib = float(out[0]), float(out[1])
    points_mib = 2_000_000 * 3 * 4 / 2**20  # 22.9 MiB: any extra copy of the input
    assert one_copy_mib * 0.9 <= grown_mib < one_copy_mib + points_mib, (grown_mib, one_copy_mib)
