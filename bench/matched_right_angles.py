#!/usr/bin/python3
"""Right-angled corners on the buildings a method matched, against their own truth.

usage: matched_right_angles.py SCORES.csv TRUTH

SCORES.csv is `lodforge eval --scores` of a method's footprints against TRUTH (any polygon file
OGR reads, as given to eval). eval's right-angle share counts every prediction's corners and
every truth footprint's; where the predictions merge houses into blocks or a degradation removes
small buildings, the two populations differ. This prints the share over the matched predictions
beside the share over the truth features they matched (each feature once), and the share over
the predictions that matched none. A corner turns by more than 5 degrees; a right one within 5
degrees of 90 or 180, as eval counts them. Needs GDAL's Python bindings (Debian's python3-gdal)."""

import csv
import math
import sys

from osgeo import ogr


def corners(geometry):
    """(corners, right-angled corners) of a polygon's rings."""
    count = right = 0
    for i in range(geometry.GetGeometryCount()):
        points = geometry.GetGeometryRef(i).GetPoints()[:-1]
        n = len(points)
        for k in range(n):
            a, b, c = points[k - 1], points[k], points[(k + 1) % n]
            u = (b[0] - a[0], b[1] - a[1])
            v = (c[0] - b[0], c[1] - b[1])
            turn = abs(math.degrees(math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])))
            if turn > 5:
                count += 1
                right += abs(turn - 90) <= 5 or abs(turn - 180) <= 5
    return count, right


def truth_corners(path):
    """feature key as eval names it (its id field, else its FID; '.K' for a multipolygon's K-th part) -> corners."""
    out = {}
    source = ogr.Open(path)
    if source is None:
        sys.exit(f"matched_right_angles.py: cannot open {path}")
    for layer in source:
        has_id = layer.GetLayerDefn().GetFieldIndex("id") >= 0
        for feature in layer:
            geometry = feature.GetGeometryRef()
            if geometry is None:
                continue
            key = str(feature.GetField("id") if has_id and feature.IsFieldSetAndNotNull("id") else feature.GetFID())
            flat = ogr.GT_Flatten(geometry.GetGeometryType())
            if flat == ogr.wkbMultiPolygon:
                for k in range(geometry.GetGeometryCount()):
                    out[f"{key}.{k + 1}"] = corners(geometry.GetGeometryRef(k))
            elif flat == ogr.wkbPolygon:
                out[key] = corners(geometry)
    return out


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__.strip())
    truth = truth_corners(argv[2])
    matched = [0, 0]
    unmatched = [0, 0]
    their_truth = [0, 0]
    seen = set()
    missing = 0
    with open(argv[1], newline="") as f:
        for row in csv.DictReader(f):
            pair = (int(row["corners"]), int(row["right_corners"]))
            if not row["truth"]:
                unmatched[0] += pair[0]
                unmatched[1] += pair[1]
                continue
            matched[0] += pair[0]
            matched[1] += pair[1]
            if row["truth"] in seen:
                continue
            seen.add(row["truth"])
            if row["truth"] not in truth:
                missing += 1
                continue
            their_truth[0] += truth[row["truth"]][0]
            their_truth[1] += truth[row["truth"]][1]
    if missing:
        sys.exit(f"matched_right_angles.py: {missing} matched truth feature(s) not found in {argv[2]}")
    share = lambda c: f"{c[1] / c[0]:.3f}" if c[0] else "-"
    print(f"matched {len(seen)} truth features: right angles {share(matched)} ({matched[1]} of {matched[0]}), "
          f"their truth {share(their_truth)} ({their_truth[1]} of {their_truth[0]}); "
          f"unmatched predictions {share(unmatched)} ({unmatched[1]} of {unmatched[0]})")


if __name__ == "__main__":
    main(sys.argv)
