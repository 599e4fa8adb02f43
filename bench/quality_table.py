#!/usr/bin/python3
"""Builds the results tables of docs/quality.md from bench/quality.sh's work directory.
usage: quality_table.py WORK_DIR DOC.md|- --datasets a,b --methods x,y"""
import argparse, json, os, re

from doc_section import write_section

NAMES = {"lodforge": "**lodforge** (default)", "paper": "paper (deformed route, bounded mesh)", "paper_coarse": "paper, coarse mesh (1 px runs, 20 px mesh)", "cgal": "CGAL Shape_regularization",
         "douglas_peucker": "Douglas–Peucker (0.5 m)", "none": "raw contour"}
TITLES = {"delft": "Delft: AHN3 class 6 (0.5 m) vs BGT inside the AOI",
          "campus": "TU Delft campus: BAG footprints, segmentation simulated at 0.25 m (degraded, seed 1)",
          "campus_clean": "TU Delft campus: BAG footprints rasterized at 0.25 m (clean)",
          "synth": "Synthetic city: 1 km x 1 km at 0.25 m (lodforge synth --seed 11)"}
# (key, header, format, higher is better: True / False / None = closeness to 1)
METRICS = [("overall_iou", "overall IoU", "{:.4f}", True), ("blob_iou", "blob IoU", "{:.4f}", True),
           ("f1", "F1", "{:.3f}", True), ("mean_iou", "mean IoU", "{:.4f}", True), ("c_iou", "C-IoU", "{:.3f}", True),
           ("n_ratio", "N-ratio", "{:.2f}", None), ("polis_m", "PoLiS (m)", "{:.3f}", False),
           ("hausdorff_p95_m", "Hausdorff p95 (m)", "{:.2f}", False),
           ("max_tangent_angle_deg", "max tangent (°)", "{:.1f}", False), ("corner_share_5deg", "corners ≤ 5°", "{:.2f}", True),
           ("right_angle_share", "right angles", "{:.2f}", True)]
TARGET = ["overall_iou", "polis_m", "max_tangent_angle_deg"]
PEERS = ["cgal", "douglas_peucker", "none"]

ap = argparse.ArgumentParser()
ap.add_argument("work"); ap.add_argument("doc"); ap.add_argument("--datasets"); ap.add_argument("--methods")
a = ap.parse_args()
datasets, methods = a.datasets.split(","), a.methods.split(",")

def better(key, x, y):  # is x better than y
    hib = dict((k, h) for k, _, _, h in METRICS)[key]
    if hib is None: return abs(x - 1) < abs(y - 1)
    return x > y if hib else x < y

out = []
summary = []
for d in datasets:
    rows = {}
    for m in methods:
        base = os.path.join(a.work, f"{d}.{m}")
        with open(base + ".metrics.json") as f: metrics = json.load(f)
        with open(base + ".stats.json") as f: stats = json.load(f)
        rows[m] = (metrics, stats)
    any_row = next(iter(rows.values()))[0]
    out.append(f"### {TITLES.get(d, d)}\n")
    out.append(f"{any_row['predicted']} footprints against {any_row['truth']} true footprints; "
               f"right-angled corners of the truth: {any_row.get('truth_right_angle_share', 0):.2f}.\n")
    out.append("| method | " + " | ".join(h for _, h, _, _ in METRICS) + " | fallbacks | ms / building (median, p99) |")
    out.append("|---" * (len(METRICS) + 3) + "|")
    for m in methods:
        metrics, stats = rows[m]
        cells = []
        for key, _, fmt, _ in METRICS:
            v = metrics[key]
            best = all(not better(key, rows[o][0][key], v) for o in methods)
            text = fmt.format(v)
            cells.append(f"**{text}**" if best and len(methods) > 1 else text)
        cells.append(str(stats["fallback"]))
        cells.append("{:.2f}, {:.1f}".format(1000 * stats["seconds_median"], 1000 * stats["seconds_p99"]))
        out.append(f"| {NAMES.get(m, m)} | " + " | ".join(cells) + " |")
    if "lodforge" in rows and all(p in rows for p in PEERS):
        ours = rows["lodforge"][0]
        verdict = []
        for key in TARGET:
            header = dict((k, h) for k, h, _, _ in METRICS)[key]
            beaten = [p for p in PEERS if better(key, ours[key], rows[p][0][key])]
            lost = [NAMES[p] for p in PEERS if p not in beaten]
            verdict.append(f"{header}: " + ("beats all three peers" if not lost else "not better than " + ", ".join(lost)))
        out.append("\nTarget (the default beats every peer on overall IoU, PoLiS and max tangent): " + "; ".join(verdict) + ".\n")
        summary.append((d, verdict))
    else:
        out.append("")

text = "\n".join(out)
if a.doc == "-":
    print(text)
else:
    write_section(a.doc, "quality-results", f"bench/quality.sh --datasets {a.datasets} --methods {a.methods}",
                  "times are each building's regularization on one core (contours extracted once, before).", text)
