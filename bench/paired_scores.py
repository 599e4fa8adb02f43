#!/usr/bin/python3
"""Compares regularizers on the buildings they all matched.

usage: paired_scores.py NAME=SCORES.csv NAME=SCORES.csv [...]

Each SCORES.csv is `lodforge eval --scores` of one method's footprints against the same truth.
eval's PoLiS, max tangent angle and N-ratio are means over each method's own matches (IoU >= 0.5),
so a method that matches more of the harder buildings averages over more of them; here the means
are taken over the truth features every method matched (a truth feature's first match in each
file), beside how many each matched. Prints one line per method."""

import csv
import sys


def matches(path):
    """truth feature -> its first matching prediction's row."""
    out = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["truth"]:
                out.setdefault(row["truth"], row)
    return out


def main(argv):
    if len(argv) < 3 or any("=" not in a for a in argv[1:]):
        sys.exit(__doc__.strip())
    methods = [a.split("=", 1) for a in argv[1:]]
    scored = {name: matches(path) for name, path in methods}
    common = set.intersection(*(set(m) for m in scored.values()))
    if not common:
        sys.exit("no truth feature is matched by every method")
    print(f"{len(common)} truth features matched by every method")
    for name, _ in methods:
        rows = [scored[name][t] for t in sorted(common)]
        mean = lambda key: sum(float(r[key]) for r in rows) / len(rows)
        ratio = sum(float(r["vertices"]) / float(r["truth_vertices"]) for r in rows) / len(rows)
        print(f"{name}: matched {len(scored[name])}; on the common ones IoU {mean('iou'):.4f}, N-ratio {ratio:.2f}, "
              f"PoLiS {mean('polis_m'):.3f} m, max tangent {mean('max_tangent_deg'):.1f} deg")


if __name__ == "__main__":
    main(sys.argv)
