#!/usr/bin/env python3
"""Checks that two ablation output folders hold the same results.

    scripts/ablate_compare.py OUT_A OUT_B [--rel-tol 1e-9]

Compares OUT/summary.csv (one row per cell, keyed by cell id) and
OUT/table.csv (one row per sequence x variant x parameters) of the two
folders, as written by `rvlio ablate` or by workflow/Snakefile: the same rows,
the same text in every column and the same numbers (relative tolerance
--rel-tol), except the timing columns (ms_per_scan, rtf and their
_mean/_std, wall_s), which differ from run to run. Prints what was compared, or
every difference; exit 0 when equal, 1 when not, 2 on unreadable input.
Standard library only.
"""
import argparse
import csv
import math
import os
import sys

TIMING = ("ms_per_scan", "rtf", "wall_s")


def is_timing(column):
    return any(column == t or column.startswith(t + "_") for t in TIMING)


def read_rows(path, key_columns):
    """{key tuple: row} of a CSV file; key columns must be unique together."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        header = reader.fieldnames or []
        missing = [k for k in key_columns if k not in header]
        if missing:
            raise ValueError("%s: no column %s" % (path, ", ".join(missing)))
        rows = {}
        for row in reader:
            key = tuple(row[k] for k in key_columns)
            if key in rows:
                raise ValueError("%s: two rows for %s" % (path, "/".join(key)))
            rows[key] = row
    return header, rows


def same_value(a, b, rel_tol):
    if a == b:
        return True
    try:
        x, y = float(a), float(b)
    except ValueError:
        return False
    if math.isnan(x) or math.isnan(y):
        return False
    return math.isclose(x, y, rel_tol=rel_tol, abs_tol=rel_tol)


def compare_file(name, dir_a, dir_b, key_columns, rel_tol):
    """Differences between NAME in the two folders, and the number of values compared."""
    header_a, rows_a = read_rows(os.path.join(dir_a, name), key_columns(dir_a))
    header_b, rows_b = read_rows(os.path.join(dir_b, name), key_columns(dir_b))
    problems = []
    if header_a != header_b:
        problems.append("%s: different columns:\n  %s\n  %s" % (name, header_a, header_b))
        return problems, 0
    for key in sorted(set(rows_a) ^ set(rows_b)):
        where = dir_a if key in rows_a else dir_b
        problems.append("%s: row %s only in %s" % (name, "/".join(key), where))
    compared = 0
    for key in sorted(set(rows_a) & set(rows_b)):
        for column in header_a:
            if is_timing(column):
                continue
            a, b = rows_a[key][column], rows_b[key][column]
            compared += 1
            if not same_value(a, b, rel_tol):
                problems.append("%s: %s: %s: '%s' != '%s'" % (name, "/".join(key), column, a, b))
    return problems, compared


def table_keys(out_dir):
    """sequence, variant and the parameter columns (those before `cells`)."""
    with open(os.path.join(out_dir, "table.csv"), newline="") as f:
        header = next(csv.reader(f), [])
    if "cells" not in header:
        raise ValueError("%s/table.csv: no column cells" % out_dir)
    return header[: header.index("cells")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out_a")
    parser.add_argument("out_b")
    parser.add_argument("--rel-tol", type=float, default=1e-9)
    args = parser.parse_args()
    problems, counts = [], []
    try:
        for name, keys in (("summary.csv", lambda d: ["id"]), ("table.csv", table_keys)):
            p, n = compare_file(name, args.out_a, args.out_b, keys, args.rel_tol)
            problems += p
            counts.append("%s %d values" % (name, n))
    except (OSError, ValueError, StopIteration) as e:
        print("ablate_compare: error: %s" % e, file=sys.stderr)
        return 2
    for p in problems:
        print("ablate_compare: %s" % p)
    verdict = "differ" if problems else "equal"
    print("ablate_compare: %s and %s %s (%s compared; timing columns skipped)"
          % (args.out_a, args.out_b, verdict, ", ".join(counts)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
