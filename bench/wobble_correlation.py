#!/usr/bin/python3
"""How far along a wall a mask's boundary wobble stays correlated (docs/quality-log.md, session 42).

usage: wobble_correlation.py OUTLINES RAW [--bin M] [--min-wall M]

OUTLINES: regularized footprints (any OGR polygon source); RAW: the same mask's raw contours
(`lodforge regularize --regularizer none`). Along each wall of OUTLINES at least --min-wall long
(12 m), the RAW boundary's offset from the wall (its points within 2 m of the wall's line, not
within 1.5 m of its ends) is averaged in bins of --bin metres (0.25) along it; each wall's series,
its mean taken out, gives the autocorrelation at every lag, pooled over the walls. Prints the
number of walls, the median standard deviation of the offsets, the lags where the pooled
autocorrelation first falls below 1/e and below 0, and its values at 0.5, 1, 2 and 4 m.
Walls with bins left empty over a tenth of their length (a step or a gap) are left out."""
import argparse
import math

import numpy as np
from osgeo import ogr


def rings(path):
    source = ogr.Open(path)
    if source is None:
        raise SystemExit(f"wobble_correlation.py: cannot open '{path}'")
    out = []
    for layer in range(source.GetLayerCount()):
        for feature in source.GetLayer(layer):
            geometry = feature.GetGeometryRef()
            if geometry is None:
                continue
            polygons = [geometry.GetGeometryRef(i) for i in range(geometry.GetGeometryCount())] \
                if geometry.GetGeometryType() in (ogr.wkbMultiPolygon, ogr.wkbMultiPolygon25D) else [geometry]
            for polygon in polygons:
                for r in range(polygon.GetGeometryCount()):
                    out.append(np.array(polygon.GetGeometryRef(r).GetPoints())[:, :2])
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("outlines")
    parser.add_argument("raw")
    parser.add_argument("--bin", type=float, default=0.25)
    parser.add_argument("--min-wall", type=float, default=12.0)
    args = parser.parse_args()
    # The raw boundary as points every 5 cm.
    points = []
    for ring in rings(args.raw):
        for a, b in zip(ring[:-1], ring[1:]):
            n = max(1, int(np.hypot(*(b - a)) / 0.05))
            points.append(a + np.outer(np.arange(n) / n, b - a))
    if not points:
        raise SystemExit(f"wobble_correlation.py: no polygon in '{args.raw}'")
    points = np.vstack(points)
    points = points[np.argsort(points[:, 0], kind="stable")]  # (by x: each wall looks at its strip only)
    lags = int(round(8.0 / args.bin))
    products, counts, variances = np.zeros(lags), np.zeros(lags), []
    for ring in rings(args.outlines):
        for a, b in zip(ring[:-1], ring[1:]):
            length = np.hypot(*(b - a))
            if length < args.min_wall:
                continue
            along = (b - a) / length
            across = np.array([-along[1], along[0]])
            lo, hi = np.searchsorted(points[:, 0], [min(a[0], b[0]) - 2, max(a[0], b[0]) + 2])
            strip = points[lo:hi]
            t, y = (strip - a) @ along, (strip - a) @ across
            near = (t > 1.5) & (t < length - 1.5) & (np.abs(y) < 2)
            if near.sum() < 50:
                continue
            k = ((t[near] - 1.5) / args.bin).astype(int)
            bins = k.max() + 1
            sums, hits = np.bincount(k, y[near], bins), np.bincount(k, None, bins)
            if (hits > 0).mean() < 0.9:
                continue
            z = np.where(hits > 0, sums / np.maximum(hits, 1), np.nan)
            z -= np.nanmean(z)
            variances.append(np.nanvar(z))
            for h in range(min(lags, bins)):
                p = z[:bins - h] * z[h:]
                p = p[~np.isnan(p)]
                products[h] += p.sum()
                counts[h] += p.size
    if not variances:
        raise SystemExit("wobble_correlation.py: no wall long enough")
    acf = products / np.maximum(counts, 1)
    acf /= acf[0]
    below_e = next((h * args.bin for h in range(lags) if acf[h] < 1 / math.e), None)
    below_0 = next((h * args.bin for h in range(lags) if acf[h] < 0), None)
    at = " ".join(f"{x:g} m {acf[int(round(x / args.bin))]:.2f}" for x in (0.5, 1, 2, 4) if int(round(x / args.bin)) < lags)
    print(f"walls {len(variances)}, offsets' sd {math.sqrt(np.median(variances)):.3f} m, "
          f"autocorrelation below 1/e at {below_e} m, below 0 at {below_0} m; at {at}")


if __name__ == "__main__":
    main()
