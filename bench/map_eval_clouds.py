#!/usr/bin/env python3
"""Synthetic clouds for timing `rvlio eval --map` (docs/map_eval.md): a round
tunnel wall (radius 3 m, 100 m long), a 10 M point survey with 2 mm noise
(ref10m.pcd) and a 2 M point map with 2 cm noise (map2m.pcd), binary x y z
float32 PCD, written into the folder given (default: .)."""
import os
import sys

import numpy as np


def wall(n, noise, seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 100, n)
    a = rng.uniform(0, 2 * np.pi, n)
    r = 3 + rng.normal(0, noise, n)
    return np.c_[x, r * np.cos(a), r * np.sin(a)].astype("<f4")


def write(path, p):
    header = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {len(p)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(p)}\nDATA binary\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(p.tobytes())


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    write(os.path.join(out, "ref10m.pcd"), wall(10_000_000, 0.002, 1))
    write(os.path.join(out, "map2m.pcd"), wall(2_000_000, 0.02, 2))
