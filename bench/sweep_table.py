#!/usr/bin/python3
"""Builds the sweep tables of docs/quality.md from bench/sweep.sh's work directory.
usage: sweep_table.py WORK --sets a,b --pixels p,q --wobbles w,v [--wavelength 8] [--seed N] [--radius R] [--blur S] --methods m,n [--doc DOC.md]
Rows of a wavelength other than 8 m are read from ROW.lL files and written to the sweep-results-lL section;
rows of another seed from ROW[.lL].sN files, to the sweep-results[-lL]-sN section; rows whose corners are
rounded by R m from ROW[.lL][.sN].rR files, to the ...-rR section."""
import argparse, json, os

from doc_section import write_section

PEERS = ["cgal", "douglas_peucker"]
SHORT = {"lodforge": "ours", "cgal": "CGAL", "douglas_peucker": "DP", "none": "raw", "paper": "paper", "nocriterion": "no criterion"}
TITLES = {"synth": "Synthetic city, 500 m x 500 m (seed 11)", "campus": "TU Delft campus, 1,529 BAG footprints (seed 1)",
          "delft": "Delft old town, 160 BGT footprints (seed 1)"}

ap = argparse.ArgumentParser()
ap.add_argument("work")
for key in ("sets", "pixels", "wobbles", "methods"): ap.add_argument("--" + key, required=True)
ap.add_argument("--wavelength", default="8")
ap.add_argument("--seed")
ap.add_argument("--radius")
ap.add_argument("--blur")
ap.add_argument("--doc")
a = ap.parse_args()
sets, pixels, wobbles, methods = (getattr(a, k).split(",") for k in ("sets", "pixels", "wobbles", "methods"))
if float(a.wavelength) == 8: a.wavelength = "8"  # the main sweep's, however written


def load(row, m):
    base = os.path.join(a.work, f"{row}.{m}")
    with open(base + ".metrics.json") as f: metrics = json.load(f)
    with open(base + ".stats.json") as f: stats = json.load(f)
    return metrics, stats


def targets(r, method="lodforge"):
    """The issue's targets for one of our methods on one row: the names of those missed."""
    ours, ostats = r[method]
    missed = []
    raw = r.get("none", (None,))[0]
    peers = [r[p][0] for p in PEERS if p in r]
    if raw and ours["overall_iou"] < raw["overall_iou"]: missed.append("IoU<raw")
    if peers and ours["overall_iou"] < max(p["overall_iou"] for p in peers) - 0.002: missed.append("IoU<peer")
    if ostats["fallback"] > 0.01 * ostats["buildings"]: missed.append("fallbacks")
    if not 0.8 <= ours["n_ratio"] <= 1.5: missed.append("N-ratio")
    if ours["right_angle_share"] < ours["truth_right_angle_share"] - 0.10: missed.append("right angles")
    if peers and ours["max_tangent_angle_deg"] > min(p["max_tangent_angle_deg"] for p in peers): missed.append("tangent")
    if peers and ours["polis_m"] > min(p["polis_m"] for p in peers): missed.append("PoLiS")
    return missed


out, met, rows_total = [], 0, 0
for s in sets:
    title = TITLES.get(s, s) + ("" if a.wavelength == "8" else f", wobble wavelength {a.wavelength} m")
    if a.seed: title = title.replace("(seed 11)", f"(seed {a.seed})").replace("(seed 1)", f"(seed {a.seed})")
    if a.radius: title += f", corners rounded by {a.radius} m"
    if a.blur: title += f", blurred by {a.blur} m"
    out.append(f"#### {title}\n")
    head = ["pixel (m)", "wobble (m)"]
    head += [f"IoU {SHORT[m]}" for m in methods]
    head += [f"N-ratio {SHORT[m]}" for m in methods]
    head += ["right angles ours / truth"] + [f"right angles {SHORT[m]}" for m in methods if m != "lodforge"]
    head += [f"tangent ° {SHORT[m]}" for m in methods] + [f"PoLiS {SHORT[m]}" for m in methods]
    head += ["fallbacks ours", "ms ours (median)", "targets missed"]
    if "nocriterion" in methods: head.append("targets missed (no criterion)")
    out.append("| " + " | ".join(head) + " |")
    out.append("|---" * len(head) + "|")
    for p in pixels:
        for w in wobbles:
            row = f"{s}.p{p}.w{w}" + ("" if a.wavelength == "8" else f".l{a.wavelength}") + (f".s{a.seed}" if a.seed else "") + (f".r{a.radius}" if a.radius else "") + (f".b{a.blur}" if a.blur else "")
            try:
                r = {m: load(row, m) for m in methods}
            except FileNotFoundError:
                continue
            cells = [p, w]
            cells += ["{:.4f}".format(r[m][0]["overall_iou"]) for m in methods]
            cells += ["{:.2f}".format(r[m][0]["n_ratio"]) for m in methods]
            ours = r["lodforge"][0]
            cells.append("{:.2f} / {:.2f}".format(ours["right_angle_share"], ours["truth_right_angle_share"]))
            cells += ["{:.2f}".format(r[m][0]["right_angle_share"]) for m in methods if m != "lodforge"]
            cells += ["{:.1f}".format(r[m][0]["max_tangent_angle_deg"]) for m in methods]
            cells += ["{:.3f}".format(r[m][0]["polis_m"]) for m in methods]
            st = r["lodforge"][1]
            cells.append(f"{st['fallback']} / {st['buildings']}")
            cells.append("{:.2f}".format(1000 * st["seconds_median"]))
            missed = targets(r) if "lodforge" in r else []
            rows_total += 1
            met += not missed
            cells.append(", ".join(missed) if missed else "none")
            if "nocriterion" in methods: cells.append(", ".join(targets(r, "nocriterion")) or "none")
            out.append("| " + " | ".join(cells) + " |")
    out.append("")
out.append(f"Rows meeting every target: {met} of {rows_total}.\n")
text = "\n".join(out)
if not a.doc:
    print(text)
else:
    section, wavelength = ("sweep-results", "") if a.wavelength == "8" else (f"sweep-results-l{a.wavelength}", f" --wavelength {a.wavelength}")
    if a.seed: section, wavelength = f"{section}-s{a.seed}", f"{wavelength} --seed {a.seed}"
    if a.radius: section, wavelength = f"{section}-r{a.radius}", f"{wavelength} --radius {a.radius}"
    if a.blur: section, wavelength = f"{section}-b{a.blur}", f"{wavelength} --blur {a.blur}"
    write_section(a.doc, section,
                  f"bench/sweep.sh --sets {a.sets} --pixels {a.pixels} --wobbles {a.wobbles}{wavelength} --methods {a.methods}",
                  "ms: each building's regularization, one thread, the median a building (of the run whose median is the middle one of `--time-runs`, three by default).", text)
