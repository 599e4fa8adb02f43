#!/usr/bin/python3
"""Right-angled corners of a truth dissolved into its blocks, beside each prediction's.

usage: block_corners.py TRUTH PRED [PRED ...]

eval's right-angle share counts every truth footprint's corners (turn over 5 deg, within 5 deg of
90 or 180). Where touching footprints (row houses) are one blob in the mask, the predictions
are blocks. This dissolves the truth into its blocks (the union of its footprints, collinear
vertices within a centimetre dropped) and prints, for the truth's footprints, its blocks and each
prediction, the share of right-angled corners and their count, over every corner and over the
corners between two edges of 1 m or more; and for each prediction, how many of its corners of
the second kind that are not right-angled lie within 1.5 m of a right-angled corner of a block
(a corner the truth has square, drawn otherwise) and how many within 1.5 m of an oblique one."""

import math
import sys

from osgeo import ogr

ogr.UseExceptions()


def polygons(path):
    out = []
    for layer in ogr.Open(path):
        for feature in layer:
            g = feature.GetGeometryRef()
            if g is None:
                continue
            parts = [g.GetGeometryRef(i) for i in range(g.GetGeometryCount())] if g.GetGeometryType() in (ogr.wkbMultiPolygon, ogr.wkbMultiPolygon25D) else [g]
            out += [p.Clone() for p in parts]
    return out


def corners(polys, min_edge):
    """(x, y, turn in degrees, right-angled) of every corner turning by more than 5 degrees."""
    out = []
    for p in polys:
        for r in range(p.GetGeometryCount()):
            ring = p.GetGeometryRef(r)
            pts = [ring.GetPoint_2D(i) for i in range(ring.GetPointCount())]
            if len(pts) > 1 and pts[0] == pts[-1]:
                pts = pts[:-1]
            n = len(pts)
            for i in range(n):
                a, b, c = pts[i - 1], pts[i], pts[(i + 1) % n]
                u = (b[0] - a[0], b[1] - a[1])
                v = (c[0] - b[0], c[1] - b[1])
                lu, lv = math.hypot(*u), math.hypot(*v)
                if lu == 0 or lv == 0 or min(lu, lv) < min_edge:
                    continue
                turn = abs(math.degrees(math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])))
                if turn > 5:
                    out.append((b[0], b[1], turn, abs(turn - 90) <= 5 or abs(turn - 180) <= 5))
    return out


def share(cs):
    return "%.2f of %d" % (sum(1 for c in cs if c[3]) / max(1, len(cs)), len(cs))


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__.strip())
    truth = polygons(argv[1])
    union = ogr.Geometry(ogr.wkbMultiPolygon)
    for p in truth:
        union.AddGeometry(p)
    dissolved = union.UnionCascaded().SimplifyPreserveTopology(0.01)
    blocks = polygons_of(dissolved)
    block_corners = corners(blocks, 0)
    print("%-40s %-16s %-16s" % ("", "every corner", "edges >= 1 m"))
    print("%-40s %-16s %-16s" % ("truth footprints (%d)" % len(truth), share(corners(truth, 0)), share(corners(truth, 1))))
    print("%-40s %-16s %-16s" % ("truth blocks (%d)" % len(blocks), share(block_corners), share(corners(blocks, 1))))
    for path in argv[2:]:
        pred = polygons(path)
        long_corners = corners(pred, 1)
        square = oblique = 0
        for (x, y, _, right) in long_corners:
            if right:
                continue
            near = [c for c in block_corners if math.hypot(c[0] - x, c[1] - y) < 1.5]
            if near and all(c[3] for c in near):
                square += 1
            elif near:
                oblique += 1
        off = sum(1 for c in long_corners if not c[3])
        print("%-40s %-16s %-16s not right-angled: %d, near a square block corner %d, near an oblique one %d" %
              (path.split("/")[-1][:40], share(corners(pred, 0)), share(long_corners), off, square, oblique))


def polygons_of(g):
    if g.GetGeometryType() in (ogr.wkbMultiPolygon, ogr.wkbMultiPolygon25D):
        return [g.GetGeometryRef(i).Clone() for i in range(g.GetGeometryCount())]
    return [g.Clone()]


if __name__ == "__main__":
    main(sys.argv)
