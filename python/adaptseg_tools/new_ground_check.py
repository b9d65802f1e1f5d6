"""What a network's behaviour on new ground lets the decision forecast, field by field.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.new_ground_check CELLS_DIR RUNS_DIR

CELLS_DIR holds `cells-CLASS.csv` (adaptseg_calibrate --cell-samples-csv, docs/data_format.md)
for each class, every field segmented by a network that never saw it; RUNS_DIR the runs
`CLASS-tile-K/` of `scripts/results.sh loto-proxy` over the same fields (results.csv,
model.yaml). Both come from `bash scripts/results.sh new-ground-check`. Three tables:

1. Descents forecast leaving each field out. On each field, region and (top, descent) GSD pair,
   the 30 % of the region's cells with the most input mass (x times field pixels, as a ranked
   descent chooses them) re-mapped; their summed field gain against two forecasts fitted on the
   other fields' cells by weighted least squares through the origin (weights: field pixels):
   - normalised (the cell gain model's): nu = gain * sigma_f / share = beta * x, forecast
     beta * sum(px * x) / S_f, S_f the field's pixels labelled L;
   - exchange rate: dTP / px = b_tp * x and dFP / px = b_fp * x, forecast
     (b_tp - IoU_f * b_fp) * sum(px * x) / U_f, with the field's own top-level IoU and union
     (TP + FP + FN) from its labels: what a false positive costs on this field, an upper bound
     for any estimate of them in flight.
2. Whole-field curve: the sum over a field's cells of their field gains against the field's real
   lawnmower rise from 15 cm/px to each finer lawnmower (are the cells the curve?), and the rise
   each run's decision model predicted for its test field (FrontAwarePolicy::field_curve with
   the training fields' ratios, field factor 1) against the real one.
   The training fields' own rises, per test field: how far one field's curve tells another's.
3. The scene check's signal: per class, the same descents' realised field gain against what the
   finer images show without labels, the drop of the input over the re-mapped cells,
   sum(px * (x - x')) (the cell samples' fine_NAME columns; CellGainModel's proxy).
"""
import collections
import csv
import math
import os
import sys

import numpy as np
import yaml

CLASSES = ("building", "road", "vegetation", "water")


def load_cells(path, inp):
    out = []
    with open(path) as f:
        for r in csv.DictReader(f):
            x = float(r["top_" + inp])
            px, share = float(r["field_px"]), float(r["field_share"])
            if not math.isfinite(x) or px <= 0 or share <= 0:
                continue
            out.append({
                "field": r["field"], "region": int(r["region"]), "pair": (float(r["top_gsd_cm"]), float(r["sub_gsd_cm"])),
                "x": x, "px": px, "share": share, "sigma": float(r["field_sigma"]), "gain": float(r["field_gain"]),
                "dtp": int(r["delta_tp"]), "dfp": int(r["delta_fp"]),
                "tp": int(r["field_tp"]), "fp": int(r["field_fp"]), "fn": int(r["field_fn"]), "n": px / share,
            })
    return out


def slope(cells, y):
    """Weighted least squares through the origin of y on x, weights px."""
    sxx = sum(c["px"] * c["x"] ** 2 for c in cells)
    return sum(c["px"] * c["x"] * y(c) for c in cells) / sxx if sxx > 0 else 0.0


def corr(a, b):
    return float(np.corrcoef(a, b)[0, 1]) if len(a) > 2 and np.std(a) > 0 and np.std(b) > 0 else float("nan")


def descents(cells_dir, inp_of):
    print("| class | regions | normalised: correlation | exchange rate: correlation | normalised: sign right | exchange rate: sign right |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    every = []
    for cls in CLASSES:
        cells = load_cells(f"{cells_dir}/cells-{cls}.csv", inp_of[cls])
        rows = []
        for f in sorted({c["field"] for c in cells}):
            for pair in sorted({c["pair"] for c in cells}):
                train = [c for c in cells if c["field"] != f and c["pair"] == pair]
                test = [c for c in cells if c["field"] == f and c["pair"] == pair]
                if not train or not test:
                    continue
                b_nu = slope(train, lambda c: c["gain"] * c["sigma"] / c["share"])
                b_tp = slope(train, lambda c: c["dtp"] / c["px"])
                b_fp = slope(train, lambda c: c["dfp"] / c["px"])
                t0 = test[0]
                union = t0["tp"] + t0["fp"] + t0["fn"]
                iou = t0["tp"] / union
                labelled = t0["sigma"] * t0["n"]
                for region in sorted({c["region"] for c in test}):
                    rc = sorted((c for c in test if c["region"] == region), key=lambda c: -c["x"] * c["px"])
                    chosen = rc[: max(1, round(0.3 * len(rc)))]
                    mass = sum(c["x"] * c["px"] for c in chosen)
                    rows.append((sum(c["gain"] for c in chosen), b_nu * mass / labelled, (b_tp - iou * b_fp) * mass / union))
        a = np.array(rows)
        every += rows
        print(f"| {cls} | {len(a)} | {corr(a[:, 0], a[:, 1]):+.2f} | {corr(a[:, 0], a[:, 2]):+.2f} | "
              f"{np.mean(np.sign(a[:, 0]) == np.sign(a[:, 1])):.2f} | {np.mean(np.sign(a[:, 0]) == np.sign(a[:, 2])):.2f} |")
    a = np.array(every)
    print(f"| all | {len(a)} | {corr(a[:, 0], a[:, 1]):+.2f} | {corr(a[:, 0], a[:, 2]):+.2f} | "
          f"{np.mean(np.sign(a[:, 0]) == np.sign(a[:, 1])):.2f} | {np.mean(np.sign(a[:, 0]) == np.sign(a[:, 2])):.2f} |")


def lawnmowers(run):
    with open(f"{run}/results.csv") as f:
        return {float(r["gsd_cm"]): float(r["miou_interest"]) for r in csv.DictReader(f) if r["strategy"] == "lawnmower"}


def curves(cells_dir, runs_dir, tiles):
    print()
    print("| class | tile | 15 -> GSD [cm/px] | cells summed | real rise | predicted rise | training fields' real rises |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | --- |")
    pred_real, cells_real, train_real = [], [], []
    for cls in CLASSES:
        with open(f"{cells_dir}/cells-{cls}.csv") as f:
            raw = list(csv.DictReader(f))
        for t in tiles:
            run = f"{runs_dir}/{cls}-tile-{t}"
            with open(f"{run}/model.yaml") as f:
                model = yaml.safe_load(f)
            cm = model["gain_model"]["cells"]
            inp = cm["input"]
            beta = {(a, b): s for a, b, s in zip(cm["top_gsd_cm"], cm["sub_gsd_cm"], cm["gain_slope"])}
            lm = lawnmowers(run)
            field = f"dubai-tile-{t}"
            summed = collections.defaultdict(float)
            for r in raw:
                if r["field"] == field:
                    summed[(float(r["top_gsd_cm"]), float(r["sub_gsd_cm"]))] += float(r["field_gain"])
            top = 15.0
            first_sub = min(p[1] for p in summed if p[0] == top)
            own = [r for r in raw if r["field"] == field and float(r["top_gsd_cm"]) == top and float(r["sub_gsd_cm"]) == first_sub]
            px = sum(float(r["field_px"]) for r in own)
            x_field = sum(float(r["field_px"]) * float(r["top_" + inp]) for r in own if math.isfinite(float(r["top_" + inp]))) / px
            sigma = float(own[0]["field_sigma"])
            for g in sorted(g for g in lm if g < top):
                if (top, g) not in beta:
                    continue
                b = beta[(top, g)]
                preds, others = [], []
                for ref in model["rule"]["reference"]:
                    x_ref = dict(zip(ref.get("top_input_gsd_cm", []), ref.get("top_input", []))).get(top, ref["field_input"])
                    rc = dict(zip(ref["gsd_cm"], ref["miou"]))
                    real_ref = rc[g] - rc[top]
                    others.append(real_ref)
                    predicted_ref = b * x_ref / ref["field_sigma"] if ref["field_sigma"] > 0 else 0.0
                    ratio = min(4.0, max(0.25, real_ref / predicted_ref)) if predicted_ref > 0 else 1.0
                    preds.append(b * x_field / sigma * ratio)
                real = lm[g] - lm[top]
                pred_real.append((float(np.mean(preds)), real))
                cells_real.append((summed[(top, g)], real))
                train_real.append((float(np.mean(others)), real))
                print(f"| {cls} | {t} | {g:g} | {summed[(top, g)]:+.3f} | {real:+.3f} | {np.mean(preds):+.3f} | "
                      + " ".join(f"{o:+.3f}" for o in others) + " |")
    print()
    print("| forecast of the real rise | pairs | correlation | mean absolute error |")
    print("| --- | ---: | ---: | ---: |")
    for name, pr in (("the field's cells summed (labels: not a forecast)", cells_real),
                     ("the decision model's field curve", pred_real), ("the training fields' mean real rise", train_real)):
        a = np.array(pr)
        print(f"| {name} | {len(a)} | {corr(a[:, 0], a[:, 1]):+.2f} | {np.mean(np.abs(a[:, 0] - a[:, 1])):.4f} |")


def scene_check(cells_dir, inp_of):
    print()
    print("| class | regions | realised gain against the finer look's drop of the input: correlation |")
    print("| --- | ---: | ---: |")
    for cls in CLASSES:
        groups = collections.defaultdict(list)
        with open(f"{cells_dir}/cells-{cls}.csv") as f:
            for r in csv.DictReader(f):
                x, xf, px = float(r["top_" + inp_of[cls]]), float(r["fine_" + inp_of[cls]]), float(r["field_px"])
                if math.isfinite(x) and math.isfinite(xf) and px > 0:
                    groups[(r["field"], r["top_gsd_cm"], r["sub_gsd_cm"], r["region"])].append(
                        (x * px, (x - xf) * px, float(r["field_gain"])))
        rows = []
        for cells in groups.values():
            cells.sort(key=lambda c: -c[0])
            chosen = cells[: max(1, round(0.3 * len(cells)))]
            rows.append((sum(c[2] for c in chosen), sum(c[1] for c in chosen)))
        a = np.array(rows)
        print(f"| {cls} | {len(a)} | {corr(a[:, 0], a[:, 1]):+.2f} |")


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    cells_dir, runs_dir = sys.argv[1], sys.argv[2]
    tiles = sorted({int(d.split("-tile-")[1]) for d in
                    (p for p in os.listdir(runs_dir) if "-tile-" in p and not p.endswith(".log"))})
    inp_of = {}
    for cls in CLASSES:
        with open(f"{runs_dir}/{cls}-tile-{tiles[0]}/model.yaml") as f:
            inp_of[cls] = yaml.safe_load(f)["gain_model"]["cells"]["input"]
    descents(cells_dir, inp_of)
    curves(cells_dir, runs_dir, tiles)
    scene_check(cells_dir, inp_of)


if __name__ == "__main__":
    main()
