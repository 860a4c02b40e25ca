#!/usr/bin/python3
"""Writes a binary PCD shaped like a surveyed tunnel map with the attributes a
map can carry, for the `rvlio export` benchmark of docs/speed.md:

    x y z (F8, UTM-sized: easting 500 000, northing 5 400 000), intensity (F4,
    0..255), time (F8, UNIX seconds), ring (U2), deviation_m (F4, NaN for one
    point in ten), scan_index (U4)

    /usr/bin/python3 scripts/make_map_pcd.py big.pcd --points 10000000

(Debian's python3 with python3-numpy, scripts/install_deps.sh.)

The points lie on the wall of a 5 m radius tube along +x, 20 000 points per
scan, rings 0..127; deterministic (seeded).
"""
import argparse

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    n = a.points
    rng = np.random.default_rng(a.seed)
    rec = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("intensity", "<f4"), ("time", "<f8"),
                    ("ring", "<u2"), ("deviation_m", "<f4"), ("scan_index", "<u4")])
    header = ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
              "FIELDS x y z intensity time ring deviation_m scan_index\n"
              "SIZE 8 8 8 4 8 2 4 4\nTYPE F F F F F U F U\nCOUNT 1 1 1 1 1 1 1 1\n"
              f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n")
    block = 1_000_000
    with open(a.out, "wb") as f:
        f.write(header.encode("ascii"))
        for start in range(0, n, block):
            k = min(block, n - start)
            i = np.arange(start, start + k)
            angle = rng.uniform(0, 2 * np.pi, k)
            r = np.empty(k, rec)
            r["x"] = 500000.0 + 0.0004 * i
            r["y"] = 5400000.0 + 5.0 * np.cos(angle)
            r["z"] = 300.0 + 5.0 * np.sin(angle)
            r["intensity"] = rng.integers(0, 256, k)
            r["time"] = 1.7e9 + 1e-5 * i
            r["ring"] = i % 128
            dev = rng.normal(0.0, 0.01, k).astype(np.float32)
            dev[i % 10 == 0] = np.nan
            r["deviation_m"] = dev
            r["scan_index"] = i // 20000
            f.write(r.tobytes())


if __name__ == "__main__":
    main()
