#!/usr/bin/python3
"""PoLiS of two predictions over the truth buildings both match. `lodforge eval` averages PoLiS
over each prediction's own matches (a predicted outline and the truth footprint it overlaps at
IoU >= 0.5), so a method that matches more, harder buildings averages over a harder set. This
script takes, per truth footprint, each prediction's outline of highest IoU with it (at least
0.5), and averages PoLiS (the mean distance of each polygon's vertices to the other's boundary,
the two directions averaged) over the footprints both predictions match.
usage: common_polis.py PRED_A PRED_B TRUTH   (any OGR polygon sources, one CRS)"""
import sys

from osgeo import ogr

if len(sys.argv) != 4:
    sys.exit("usage: common_polis.py PRED_A PRED_B TRUTH")


def polygons(path):
    source = ogr.Open(path)
    if source is None:
        sys.exit(f"common_polis.py: cannot open {path}")
    out = []
    for feature in source.GetLayer(0):
        geometry = feature.GetGeometryRef()
        if geometry is None:
            continue
        geometry = geometry.Clone()
        if ogr.GT_Flatten(geometry.GetGeometryType()) == ogr.wkbMultiPolygon:
            out += [geometry.GetGeometryRef(k).Clone() for k in range(geometry.GetGeometryCount())]
        else:
            out.append(geometry)
    return [(g, g.GetEnvelope()) for g in out]


def vertices(polygon):
    points = []
    for k in range(polygon.GetGeometryCount()):
        points += polygon.GetGeometryRef(k).GetPoints()[:-1]
    return points


def mean_distance(points, polygon):
    boundary = polygon.GetBoundary()
    total = 0.0
    for x, y, *_ in points:
        point = ogr.Geometry(ogr.wkbPoint)
        point.AddPoint_2D(x, y)
        total += point.Distance(boundary)
    return total / max(1, len(points))


def polis(a, b):
    return 0.5 * (mean_distance(vertices(a), b) + mean_distance(vertices(b), a))


def best_match(truth, candidates):
    geometry, (x0, x1, y0, y1) = truth
    best, best_iou = None, 0.5
    for other, (a0, a1, b0, b1) in candidates:
        if a1 < x0 or a0 > x1 or b1 < y0 or b0 > y1:
            continue
        union = geometry.Union(other).GetArea()
        iou = geometry.Intersection(other).GetArea() / union if union > 0 else 0.0
        if iou >= best_iou:
            best, best_iou = other, iou
    return best


a, b, truths = (polygons(p) for p in sys.argv[1:4])
sum_a = sum_b = 0.0
count = 0
for truth in truths:
    match_a, match_b = best_match(truth, a), best_match(truth, b)
    if match_a is None or match_b is None:
        continue
    sum_a += polis(truth[0], match_a)
    sum_b += polis(truth[0], match_b)
    count += 1
if count == 0:
    sys.exit("common_polis.py: no truth footprint matched by both")
print(f"truth footprints matched by both: {count}; mean PoLiS (m): A {sum_a / count:.3f}, B {sum_b / count:.3f}")
