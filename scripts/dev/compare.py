#!/usr/bin/python3
"""Development aid: match predicted footprints to truth and print IoU / vertex counts;
optionally draw both over the mask as a PNG. Usage:
  compare.py PRED.gpkg TRUTH.(gpkg|geojson) [--mask MASK.tif] [--png OUT.png] [--aoi AOI.geojson]"""
import sys, argparse
from osgeo import ogr, gdal
ogr.UseExceptions()

KEEP = []
def load(path):
    ds = ogr.Open(path)
    KEEP.append(ds)
    layer = ds.GetLayer(0)
    out = []
    for f in layer:
        g = f.GetGeometryRef().Clone()
        out.append((f, g))
    return out

ap = argparse.ArgumentParser()
ap.add_argument('pred'); ap.add_argument('truth')
ap.add_argument('--mask'); ap.add_argument('--png'); ap.add_argument('--aoi')
a = ap.parse_args()
pred = load(a.pred); truth = load(a.truth)
aoi = None
if a.aoi:
    aoi = load(a.aoi)[0][1]
    truth = [(f, g) for f, g in truth if g.Intersects(aoi)]
    pred = [(f, g.Intersection(aoi)) for f, g in pred if g.Intersects(aoi)]
# Overall IoU
pu = ogr.Geometry(ogr.wkbMultiPolygon)
for _, g in pred:
    pu = pu.Union(g)
tu = ogr.Geometry(ogr.wkbMultiPolygon)
for _, g in truth:
    tu = tu.Union(g)
inter = pu.Intersection(tu).GetArea(); union = pu.Union(tu).GetArea()
print(f"overall IoU {inter/union:.4f}  pred {len(pred)}  truth {len(truth)}")
# blob-level: each pred vs union of truth it overlaps
ious = []
for f, g in pred:
    cover = ogr.Geometry(ogr.wkbMultiPolygon)
    nv = 0
    for _, t in truth:
        if t.Intersects(g) and t.Intersection(g).GetArea() > 0.3 * t.GetArea():
            cover = cover.Union(t)
    if cover.IsEmpty():
        continue
    iou = g.Intersection(cover).GetArea() / g.Union(cover).GetArea()
    ring = g.GetGeometryRef(0)
    status = f.GetField('status') if f.GetFieldIndex('status') >= 0 else ''
    ious.append(iou)
    print(f"  id {(f.GetField('id') or 0):4d} IoU {iou:.4f} vertices {f.GetField('vertex_count') if f.GetFieldIndex('vertex_count')>=0 else -1:4d} {status} valid={g.IsValid()}")
if ious:
    ious.sort()
    print(f"blob IoU mean {sum(ious)/len(ious):.4f} min {ious[0]:.4f} median {ious[len(ious)//2]:.4f}")
if a.png:
    import numpy as np
    from PIL import Image, ImageDraw
    ds = gdal.Open(a.mask)
    gt = ds.GetGeoTransform()
    m = ds.GetRasterBand(1).ReadAsArray()
    s = 2
    img = Image.fromarray(((m == 6) * 90 + 30).astype('uint8')).convert('RGB').resize((m.shape[1]*s, m.shape[0]*s), Image.NEAREST)
    d = ImageDraw.Draw(img)
    def draw(g, col):
        for i in range(g.GetGeometryCount()):
            r = g.GetGeometryRef(i)
            if r.GetGeometryCount():
                draw(r, col); continue
            pts = [((r.GetX(k)-gt[0])/gt[1]*s, (r.GetY(k)-gt[3])/gt[5]*s) for k in range(r.GetPointCount())]
            d.line(pts, fill=col, width=1)
            for p in pts: d.rectangle([p[0]-1,p[1]-1,p[0]+1,p[1]+1], outline=col)
    for _, t in truth: draw(t, (0,255,0))
    for _, g in pred: draw(g, (255,0,0))
    img.save(a.png)
