#!/usr/bin/env python3
"""Writes a denser copy of a binary x y z float32 PCD: every point COPIES
times, each copy moved by a uniform jitter of +-JITTER metres. Makes a large
reference map for the load benchmark of docs/survey.md, e.g. 10 M points from
the simulator's survey:

    python3 scripts/densify_pcd.py d/reference_map.pcd big.pcd --copies 9
"""
import argparse
import random
import struct
import sys
from array import array


def read_xyz(path):
    with open(path, "rb") as f:
        header = {}
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"{path}: no DATA line")
            words = line.decode("ascii", "replace").split()
            if not words or words[0].startswith("#"):
                continue
            header[words[0]] = words[1:]
            if words[0] == "DATA":
                break
        if header.get("FIELDS") != ["x", "y", "z"] or header.get("DATA") != ["binary"] \
                or header.get("TYPE") != ["F", "F", "F"]:
            sys.exit(f"{path}: not a binary x y z float32 PCD")
        n = int(header["POINTS"][0])
        xyz = array("f")
        xyz.frombytes(f.read(12 * n))
        if len(xyz) != 3 * n:
            sys.exit(f"{path}: truncated ({len(xyz) // 3} of {n} points)")
        return xyz


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--copies", type=int, default=9)
    ap.add_argument("--jitter", type=float, default=0.002, help="metres")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    xyz = read_xyz(a.src)
    rng = random.Random(a.seed)
    out = array("f")
    for _ in range(a.copies):
        out.extend(v + rng.uniform(-a.jitter, a.jitter) for v in xyz)
    n = len(out) // 3
    with open(a.dst, "wb") as f:
        f.write((f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n"
                 f"SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
                 f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n").encode("ascii"))
        out.tofile(f)
    print(f"{a.dst}: {n} points")


if __name__ == "__main__":
    main()
