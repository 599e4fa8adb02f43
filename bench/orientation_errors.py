#!/usr/bin/python3
"""How far each predicted outline is turned off its truth. For every prediction that matches a
truth footprint (the footprint of highest IoU with it, at least 0.5), the angle between the two
polygons' longest edges of their outer rings, modulo quarter turns (0-45 degrees); printed as the
count of matches more than 10 and 20 degrees off and the mean, overall and per `model` (the
outline the paper's chain chose, docs/models.md; '-' where the prediction has no such field).
With a threshold, also every match turned more than it, smallest area first. A crude measure
(a building's longest edge need not be its main direction), for a regularizer's orientation on
small buildings, where the pixel grid or a wobble decides it.
usage: orientation_errors.py PRED TRUTH [DEGREES]   (any OGR polygon sources, one CRS)"""
import math
import sys
from collections import defaultdict

from osgeo import ogr

if len(sys.argv) not in (3, 4):
    sys.exit("usage: orientation_errors.py PRED TRUTH [DEGREES]")
pred, truth = ogr.Open(sys.argv[1]), ogr.Open(sys.argv[2])
if pred is None or truth is None:
    sys.exit("orientation_errors.py: cannot open " + (sys.argv[1] if pred is None else sys.argv[2]))
listed = float(sys.argv[3]) if len(sys.argv) == 4 else None
truth_layer = truth.GetLayer(0)


def orientation(g):
    """The direction of the longest edge of the outer ring (of the first part), modulo 90 degrees."""
    if g.GetGeometryType() in (ogr.wkbMultiPolygon, ogr.wkbMultiPolygon25D):
        g = g.GetGeometryRef(0)
    points = g.GetGeometryRef(0).GetPoints()
    longest, angle = 0.0, 0.0
    for a, b in zip(points, points[1:]):
        d = math.dist(a[:2], b[:2])
        if d > longest:
            longest, angle = d, math.degrees(math.atan2(b[1] - a[1], b[0] - a[0])) % 90
    return angle


errors = defaultdict(list)
rows = []
for f in pred.GetLayer(0):
    g = f.GetGeometryRef()
    if g is None or g.IsEmpty():
        continue
    x0, x1, y0, y1 = g.GetEnvelope()
    truth_layer.SetSpatialFilterRect(x0, y0, x1, y1)
    best, best_iou = None, 0.5
    for t in truth_layer:
        tg = t.GetGeometryRef()
        if tg is None or not tg.Intersects(g):
            continue
        union = g.Union(tg).GetArea()
        iou = g.Intersection(tg).GetArea() / union if union > 0 else 0.0
        if iou >= best_iou:
            best, best_iou = tg.Clone(), iou
    if best is None:
        continue
    d = abs(orientation(g) - orientation(best))
    d = min(d, 90 - d)
    model = f.GetField("model") if f.GetFieldIndex("model") >= 0 else "-"
    errors[model].append(d)
    fid = f.GetField("id") if f.GetFieldIndex("id") >= 0 else f.GetFID()
    rows.append((g.GetArea(), fid, model, d))


def line(name, values):
    return "%-16s matched %4d  over 10 deg: %4d  over 20 deg: %4d  mean %.1f deg" % (
        name, len(values), sum(v > 10 for v in values), sum(v > 20 for v in values), sum(values) / max(1, len(values)))


print(line("all", [v for vs in errors.values() for v in vs]))
for model in sorted(errors):
    print(line("  " + model, errors[model]))
if listed is not None:
    for area, fid, model, d in sorted(r for r in rows if r[3] > listed):
        print("id %s  %-16s %9.1f m2  %5.1f deg off" % (fid, model, area, d))
