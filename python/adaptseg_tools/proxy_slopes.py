"""The scene check's proxy slope on each training field, and their spread.

After a descent the scene check (FrontAwarePolicy::observe, docs/method.md) reads the drop of
the cell gain model's input from the top-level to the finer image, d = x - x', as a gain:
gamma * d. CellGainModel::fit fits gamma over the cells of all the training fields (least
squares through the origin, cells weighted by their field pixels) and tau, the spread of the
slopes fitted on each field alone about it. This tool reads the cell samples that
`adaptseg_calibrate --cell-samples-csv` writes and prints, per pair of GSDs, the gain slope
beta and the proxy slope gamma pooled, tau, and both slopes per field, so that a reader sees
where the fields disagree, and each field's share of the pooled fit's weight (its cells'
summed w * d^2: a field where the finer look barely changes the input says little about gamma).

  proxy_slopes.py CELLS.csv INPUT

INPUT: the model's `gain_model.cells.input` (sigma, expected_error, second_choice, ...).
"""
import csv
import math
import sys
from collections import defaultdict


def normalized_gain(c):
    """A cell sample's field gain per unit of its field share and of the field's sigma
    (CellSample::normalized_gain)."""
    share = float(c["field_share"])
    return float(c["field_gain"]) * float(c["field_sigma"]) / share if share > 0 else 0.0


def slopes(cells, inp, mean_px):
    """(gamma, beta, weight) of `cells`: least squares through the origin of the normalised gain
    on the input's drop and on the input, each cell weighted by its field pixels over `mean_px`;
    weight: the summed w * d^2 of the gamma fit."""
    wdd = wdg = wxx = wxg = 0.0
    for c in cells:
        x = float(c["top_" + inp])
        d = x - float(c["fine_" + inp])
        w = float(c["field_px"]) / mean_px
        nu = normalized_gain(c)
        wdd += w * d * d
        wdg += w * d * nu
        wxx += w * x * x
        wxg += w * x * nu
    return (wdg / wdd if wdd > 0 else math.nan, wxg / wxx if wxx > 0 else math.nan, wdd)


def cell_pairs(path, inp):
    """The cell samples of `path` per pair of GSDs {(top, descent): rows}, and the fields' names
    sorted; exits naming the file where it has no column top_<inp>."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if rows and "top_" + inp not in rows[0]:
        sys.exit(f"{path}: no input '{inp}' (columns top_<input>, fine_<input>)")
    pairs = defaultdict(list)
    for r in rows:
        pairs[(float(r["top_gsd_cm"]), float(r["sub_gsd_cm"]))].append(r)
    return pairs, sorted({r["field"] for r in rows})


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    path, inp = sys.argv[1], sys.argv[2]
    pairs, fields = cell_pairs(path, inp)
    print(f"{path}: input {inp}; per field: gamma_f / beta_f (share of the gamma fit's weight)")
    print("| top -> descent [cm/px] | beta | gamma | tau | " + " | ".join(fields) + " |")
    print("| --- | ---: | ---: | ---: | " + " | ".join("---:" for _ in fields) + " |")
    for key in sorted(pairs):
        cells = pairs[key]
        mean_px = sum(float(c["field_px"]) for c in cells) / len(cells)
        gamma, beta, weight = slopes(cells, inp, mean_px)
        per = {}
        for name in fields:
            own = [c for c in cells if c["field"] == name]
            per[name] = slopes(own, inp, mean_px) if own else (math.nan, math.nan, 0.0)
        known = [g for g, _, _ in per.values() if math.isfinite(g)]
        tau = (math.sqrt(sum((g - gamma) ** 2 for g in known) / (len(known) - 1)) if len(known) >= 2
               else abs(gamma))
        cols = " | ".join(f"{g:+.2f} / {b:+.3f} ({w / weight if weight > 0 else 0:.2f})"
                          for g, b, w in (per[n] for n in fields))
        print(f"| {key[0]:g} -> {key[1]:g} | {beta:+.3f} | {gamma:+.3f} | {tau:.3f} | {cols} |")


if __name__ == "__main__":
    main()
