"""add_scan makes one copy of the points on the way in: the peak memory of
the call grows by one std::vector<LidarPoint> of the scan and by no array
copy (a float64 or contiguous conversion would add 23 MiB or more here)."""
import os
import subprocess
import sys

CHILD = r"""
import resource, numpy as np, rvlio
n = 2_000_000
points = np.full((n, 3), 5.0, dtype=np.float32)  # no temporary arrays: the peak is the current size
times = np.arange(n, dtype=np.int64)
odo = rvlio.Odometry()
odo.add_imu(0, [0, 0, 0], [0, 0, 9.81])
peak_mib = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
before = peak_mib()
odo.add_scan(10**9, points, times)
print(peak_mib() - before, rvlio.LIDAR_POINT_BYTES * n / 2**20)
"""


def test_add_scan_copies_the_points_once():
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                         env=dict(os.environ), check=True).stdout.split()
    grown_mib, one_copy_mib = float(out[0]), float(out[1])
    points_mib = 2_000_000 * 3 * 4 / 2**20  # 22.9 MiB: any extra copy of the input
    assert one_copy_mib * 0.9 <= grown_mib < one_copy_mib + points_mib, (grown_mib, one_copy_mib)
