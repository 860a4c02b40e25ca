#!/usr/bin/env python3
"""Paired comparison of `rvlio ablate` variants against a baseline, seed by seed.

Seed-to-seed spread in simulated sequences is often as large as the effect of
a module, so a mean +- std table (OUT/table.md) cannot say whether a variant
is better. This compares each variant with the baseline on the same
sequence and seed (same bag) and counts the seeds where it is lower.

Usage:
  ablate_paired.py OUT [--baseline off] [--metric ate_rmse --metric axis_rmse ...]

Reads OUT/summary.csv (written by `rvlio ablate`); prints a Markdown table:
per sequence and variant the mean of each metric over the seeds both cells
finished, "k / n" seeds below the baseline for each metric, the worst ratio
of the first metric to the baseline, and the mean ms/scan. Cells that did not
finish are left out of their pair and counted in the last column. Exit 2 with
one line on bad input (missing file or column, unknown baseline).
Standard library only.
"""
import argparse
import csv
import os
import sys

DEFAULT_METRICS = ("ate_rmse", "axis_rmse", "axis_max")


def Fail(message):
  sys.stderr.write("ablate_paired.py: %s\n" % message)
  sys.exit(2)


def ReadSummary(out_dir, metrics):
  path = os.path.join(out_dir, "summary.csv")
  if not os.path.isfile(path):
    Fail("%s: no such file (run `rvlio ablate` first)" % path)
  with open(path, newline="") as f:
    reader = csv.DictReader(f)
    needed = ("sequence", "variant", "seed", "status", "ms_per_scan") + tuple(metrics)
    missing = [c for c in needed if c not in (reader.fieldnames or [])]
    if missing:
      Fail("%s: missing column(s) %s" % (path, ", ".join(missing)))
    return list(reader)


def Number(text):
  try:
    return float(text)
  except ValueError:
    return None


def Index(rows, metrics):
  """{(sequence, variant): {seed: {metric: value}}} of finished cells, the
  sequences and variants in order of appearance, and unfinished counts."""
  cells, sequences, variants, unfinished = {}, [], [], {}
  for r in rows:
    key = (r["sequence"], r["variant"])
    if r["sequence"] not in sequences:
      sequences.append(r["sequence"])
    if r["variant"] not in variants:
      variants.append(r["variant"])
    values = {m: Number(r[m]) for m in tuple(metrics) + ("ms_per_scan",)}
    if r["status"] != "done" or any(v is None for v in values.values()):
      unfinished[key] = unfinished.get(key, 0) + 1
      continue
    cells.setdefault(key, {})[r["seed"]] = values
  return cells, sequences, variants, unfinished


def Mean(values):
  return sum(values) / len(values) if values else float("nan")


def Fmt(value):
  return "%.4f" % value


def Row(sequence, variant, pairs, metrics, baseline, unfinished):
  """pairs: [(variant values, baseline values)] over the common seeds."""
  means = [Fmt(Mean([v[m] for v, _ in pairs])) for m in metrics]
  if variant == baseline:
    wins, worst = "-", "-"
  else:
    wins = " / ".join("%d" % sum(v[m] < b[m] for v, b in pairs) for m in metrics)
    wins += " of %d" % len(pairs)
    ratios = [v[metrics[0]] / b[metrics[0]] for v, b in pairs if b[metrics[0]] > 0]
    worst = "%+.0f %%" % (100.0 * (max(ratios) - 1.0)) if ratios else "-"
  ms = "%.2f" % Mean([v["ms_per_scan"] for v, _ in pairs])
  return "| %s | %s | %d | %s | %s | %s | %s | %d |" % (
      sequence, variant, len(pairs), " | ".join(means), wins, worst, ms, unfinished)


def main(argv):
  parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
  parser.add_argument("out", help="output folder of `rvlio ablate`")
  parser.add_argument("--baseline", default="off", help="variant to compare with (default off)")
  parser.add_argument("--metric", action="append", help="metric column (repeatable)")
  args = parser.parse_args(argv)
  metrics = tuple(args.metric or DEFAULT_METRICS)
  cells, sequences, variants, unfinished = Index(ReadSummary(args.out, metrics), metrics)
  if args.baseline not in variants:
    Fail("baseline variant '%s' is not in the grid (variants: %s)"
         % (args.baseline, ", ".join(variants)))
  print("| sequence | variant | seeds | %s | seeds below %s: %s | worst %s vs %s | ms/scan "
        "| unfinished |" % (" | ".join("%s mean" % m for m in metrics), args.baseline,
                            " / ".join(metrics), metrics[0], args.baseline))
  print("|" + "---|" * (len(metrics) + 7))
  for sequence in sequences:
    base = cells.get((sequence, args.baseline), {})
    for variant in variants:
      mine = cells.get((sequence, variant), {})
      seeds = sorted(set(mine) & set(base), key=lambda s: (len(s), s))
      pairs = [(mine[s], base[s]) for s in seeds]
      print(Row(sequence, variant, pairs, metrics, args.baseline,
                unfinished.get((sequence, variant), 0)))
  return 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))
