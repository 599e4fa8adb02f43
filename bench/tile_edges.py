#!/usr/bin/python3
"""tile_edges.py DIR: the summary bench/tile_edges.sh prints. Over the tiles in DIR (tX.Y.tif, their
aoi, truth and each run's eval JSON and --scores CSV): the tiles' mean overall IoU, N-ratio, right
angles (the prediction's and the truth's), max tangent angle and PoLiS per run (and per peer, CGAL
and Douglas-Peucker, where --peers scored them on every tile); then, over the truth
features both runs match, their mean IoU, max tangent and PoLiS, for those the tile's edge cuts
(the truth clipped there reaches the edge) and the others."""
import csv
import glob
import json
import os
import sys

from osgeo import ogr

RUNS = ('default', 'cut')
PEERS = ('cgal', 'douglas_peucker')  # (bench/tile_edges.sh --peers)
KEYS = (('overall_iou', 'IoU', 4), ('n_ratio', 'N-ratio', 2), ('right_angle_share', 'right angles', 3),
        ('truth_right_angle_share', 'truth', 3), ('max_tangent_angle_deg', 'max tangent', 1), ('polis_m', 'PoLiS', 3))


def main(d):
    tiles = sorted(p[:-len('.aoi.geojson')] for p in glob.glob(os.path.join(d, 't*.aoi.geojson')))
    tiles = [t for t in tiles if all(os.path.exists(f'{t}.{r}.json') for r in RUNS)]
    if not tiles:
        sys.exit(f'tile_edges.py: no tile of {d} was scored by both runs')
    # The peers where every tile has their scores too.
    runs = RUNS + tuple(p for p in PEERS if all(os.path.exists(f'{t}.{p}.json') for t in tiles))
    print(f'{len(tiles)} tiles of {d}')
    print('| run | ' + ' | '.join(label for _, label, _ in KEYS) + ' |')
    print('|---' * (len(KEYS) + 1) + '|')
    for r in runs:
        js = [json.load(open(f'{t}.{r}.json')) for t in tiles]
        print(f'| {r} | ' + ' | '.join(f'{sum(j[k] for j in js) / len(js):.{p}f}' for k, _, p in KEYS) + ' |')
    pairs = {True: [], False: []}
    for t in tiles:
        c = json.load(open(f'{t}.aoi.geojson'))['features'][0]['geometry']['coordinates'][0]
        x0, y0, x1, y1 = c[0][0], c[0][1], c[2][0], c[2][1]
        truth = ogr.Open(f'{t}.truth.gpkg')
        layer = truth.GetLayer(0)
        id_field = layer.GetLayerDefn().GetFieldIndex('id')  # (eval names a feature by its id field where there is one, else its FID)
        cut = {}
        for f in layer:
            e = f.GetGeometryRef().GetEnvelope()
            name = str(f.GetField(id_field)) if id_field >= 0 and f.IsFieldSetAndNotNull(id_field) else str(f.GetFID())
            cut[name] = e[0] < x0 + 0.05 or e[1] > x1 - 0.05 or e[2] < y0 + 0.05 or e[3] > y1 - 0.05
        rows = [{row['truth']: row for row in csv.DictReader(open(f'{t}.{r}.csv')) if row['truth']} for r in RUNS]
        for k in set(rows[0]) & set(rows[1]):
            pairs[cut.get(k.split('.')[0], False)].append([rows[i][k] for i in range(len(RUNS))])
    print('\n| buildings | matched by both | IoU default / cut | max tangent default / cut | PoLiS default / cut |')
    print('|---|---|---|---|---|')
    for edge in (True, False):
        v = pairs[edge]
        if not v:
            continue
        mean = lambda key, i: sum(float(p[i][key]) for p in v) / len(v)
        print(f"| {'cut by the edge' if edge else 'inside'} | {len(v)} | {mean('iou', 0):.4f} / {mean('iou', 1):.4f} | "
              f"{mean('max_tangent_deg', 0):.1f} / {mean('max_tangent_deg', 1):.1f} | {mean('polis_m', 0):.3f} / {mean('polis_m', 1):.3f} |")


if __name__ == '__main__':
    main(sys.argv[1])
