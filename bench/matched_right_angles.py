#!/usr/bin/python3
"""Right-angled corners on the buildings a method matched, against their own truth.

usage: matched_right_angles.py SCORES.csv TRUTH_SCORES.csv

SCORES.csv is `lodforge eval --pred FOOTPRINTS --gt TRUTH --scores SCORES.csv` of a method's
footprints; TRUTH_SCORES.csv is `lodforge eval --pred TRUTH --gt TRUTH --scores TRUTH_SCORES.csv`,
which lists every truth feature's corners under the name SCORES.csv matches it by. eval's
right-angle share counts every prediction's corners and every truth footprint's; where the
predictions merge houses into blocks or a degradation removes small buildings, the two populations
differ. This prints the share over the matched predictions beside the share over the truth
features they matched (each feature once), and the share over the predictions that matched none."""

import csv
import sys


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__.strip())
    with open(argv[2], newline="") as f:
        truth = {row["prediction"]: (int(row["corners"]), int(row["right_corners"])) for row in csv.DictReader(f)}
    matched, unmatched, their_truth = [0, 0], [0, 0], [0, 0]
    seen = set()
    with open(argv[1], newline="") as f:
        for row in csv.DictReader(f):
            counts = unmatched if not row["truth"] else matched
            counts[0] += int(row["corners"])
            counts[1] += int(row["right_corners"])
            if not row["truth"] or row["truth"] in seen:
                continue
            seen.add(row["truth"])
            if row["truth"] not in truth:
                sys.exit(f"matched_right_angles.py: truth feature {row['truth']} is not in {argv[2]}")
            their_truth[0] += truth[row["truth"]][0]
            their_truth[1] += truth[row["truth"]][1]
    share = lambda c: f"{c[1] / c[0]:.3f}" if c[0] else "-"
    print(f"matched {len(seen)} truth features: right angles {share(matched)} ({matched[1]} of {matched[0]}), "
          f"their truth {share(their_truth)} ({their_truth[1]} of {their_truth[0]}); "
          f"unmatched predictions {share(unmatched)} ({unmatched[1]} of {unmatched[0]})")


if __name__ == "__main__":
    main(sys.argv)
