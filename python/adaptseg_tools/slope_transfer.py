"""How well the cell gain model's slope, fitted on some fields, forecasts another field's best cells.

The cell gain model (include/adaptseg/core/cell_gain_model.hpp) forecasts a cell's normalised
gain as beta * x, x a decision input of the top-level image. This tool compares three ways of
fitting beta on the training fields, leave one field out: on the cells of every field but one,

  pooled          least squares through the origin over all their cells (weights: field
                  pixels), what CellGainModel::fit does;
  field mean      the same fit on each field alone, then the mean of the fields' slopes;
  random effects  the fields' slopes pooled as random effects (DerSimonian-Laird: weights
                  1 / (v_f + tau^2), v_f the variance of a field's slope from its cells' scatter,
                  tau^2 the spread between fields); flown on 2026-11-27 and not adopted
                  (docs/journal/2026-11-defaults.md, "Slopes pooled over the training fields
                  as random effects");

then forecasts the field gain of the held-out field's best 20 % of cells (ranked by the input's
mass, as the planner ranks them) and compares it with what re-mapping those cells alone gained.
It prints, per input, the root mean squared error of that forecast and how often its sign is
right, over every (held-out field, pair of GSDs), with --pairs the sums per pair of GSDs, and
with --field-slopes each field's own slope (the fit on its cells alone) per (network, class,
input, pair of GSDs): how far apart the fields are that any pooling has to bridge; and beside
it each field's mean input at the top (weighted by the cells' field pixels): whether a field
whose top-level images are less sure also gains more per unit of input (a statistic of the field
a decision could read before any descent).

  slope_transfer.py [--pairs] [--field-slopes] [--inputs a,b,...] CELLS.csv [CELLS.csv ...]

CELLS.csv: the cell samples `adaptseg_calibrate --cell-samples-csv` writes (one file per
network and class), or the cells `adaptseg_cell_study --csv` writes (columns class, gsd_cm and
gain instead: each class on its own; the top level, the study's, is printed as 0). The study's
files of one network (NAME-trained-on.csv, NAME-never-seen.csv) join one group per class; a
group needs at least two fields. An input a backend does not give (nan) counts as 0, as in
CellGainModel.
"""
import argparse
import csv
import math
from collections import defaultdict

INPUTS = ["sigma", "boundary", "ambiguity", "expected_error", "second_choice"]


def x_of(c, inp):
    """The cell's top-level input; 0 where unknown (CellGainModel::value_of)."""
    x = float(c["top_" + inp])
    return x if math.isfinite(x) else 0.0


def normalised_gain(c):
    share = float(c["field_share"])
    return float(c["field_gain"]) * float(c["field_sigma"]) / share if share > 0 else 0.0


def slope_sums(cells, inp, mean_px):
    """(sum w x nu, sum w x^2) of `cells`, w = field pixels / mean_px."""
    a = b = 0.0
    for c in cells:
        x = x_of(c, inp)
        w = float(c["field_px"]) / mean_px
        a += w * x * normalised_gain(c)
        b += w * x * x
    return a, b


def pooled(cells, inp, mean_px):
    a, b = slope_sums(cells, inp, mean_px)
    return a / b if b > 0 else 0.0


def mean_input(cells, inp):
    """The field-pixel weighted mean of the cells' top-level input."""
    w = sum(float(c["field_px"]) for c in cells)
    return sum(float(c["field_px"]) * x_of(c, inp) for c in cells) / w if w > 0 else 0.0


def by_field(cells):
    """The cells of each field, by field."""
    out = defaultdict(list)
    for c in cells:
        out[c["field"]].append(c)
    return out


def field_mean(cells, inp, mean_px):
    slopes = [a / b for a, b in (slope_sums(own, inp, mean_px) for own in by_field(cells).values()) if b > 0]
    return sum(slopes) / len(slopes) if slopes else 0.0


def random_effects(cells, inp, mean_px):
    """Each field's slope b_f and its variance v_f = s_f^2 / sum w x^2 (fields of two cells or
    more whose cells hold input), tau^2 by the method of moments (Cochran's Q about the
    precision-weighted mean), then the mean of the b_f weighted by 1 / (v_f + tau^2)."""
    est = []
    for own in by_field(cells).values():
        a, b = slope_sums(own, inp, mean_px)
        if b <= 0 or len(own) < 2:
            continue
        beta = a / b
        rss = sum(float(c["field_px"]) / mean_px * (normalised_gain(c) - beta * x_of(c, inp)) ** 2
                  for c in own)
        est.append((beta, max(rss / (len(own) - 1), 1e-12) / b))
    if not est:
        return pooled(cells, inp, mean_px)
    w = [1 / v for _, v in est]
    fe = sum(wi * b for wi, (b, _) in zip(w, est)) / sum(w)
    q = sum(wi * (b - fe) ** 2 for wi, (b, _) in zip(w, est))
    c = sum(w) - sum(wi * wi for wi in w) / sum(w)
    tau2 = max(0.0, (q - (len(est) - 1)) / c) if c > 0 else 0.0
    wr = [1 / (v + tau2) for _, v in est]
    return sum(wi * b for wi, (b, _) in zip(wr, est)) / sum(wr)


FITS = {"pooled": pooled, "field mean": field_mean, "random effects": random_effects}


def path_key(path):
    """The group a file's cells join: its name without the cell study's -trained-on / -never-seen
    (one network's cells of every tile) and without the folder."""
    name = path.rsplit("/", 1)[-1].removesuffix(".csv")
    for tail in ("-trained-on", "-never-seen"):
        name = name.removesuffix(tail)
    return name


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cells", nargs="+", help="cell sample CSVs")
    ap.add_argument("--inputs", default=",".join(INPUTS), help="decision inputs to compare (comma-separated)")
    ap.add_argument("--pairs", action="store_true", help="also print the sums per file, input and pair of GSDs")
    ap.add_argument("--field-slopes", action="store_true",
                    help="also print each field's own slope per file, input and pair of GSDs")
    ap.add_argument("--share", type=float, default=0.2, help="share of the held-out field's cells taken (0.2)")
    args = ap.parse_args()
    inputs = args.inputs.split(",")
    # Per input and over all of them: per fit, squared error, forecasts of the right sign, count.
    total = {inp: {k: [0.0, 0, 0] for k in FITS} for inp in inputs + ["all"]}
    pair_rows = []
    slope_rows = []  # (group, input, pair of GSDs, {field: own slope})
    mean_inputs = {}  # (group, input) -> {field: mean input}, from the first pair of GSDs
    groups_of = defaultdict(list)  # (network, class) -> cells of every file given for it
    for path in args.cells:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if rows and any("top_" + inp not in rows[0] for inp in inputs):
            raise SystemExit(f"{path}: not every input of {inputs} is a column (top_<input>)")
        for r in rows:  # adaptseg_cell_study's columns
            if "sub_gsd_cm" not in r:
                r["top_gsd_cm"], r["sub_gsd_cm"], r["field_gain"] = "0", r["gsd_cm"], r["gain"]
        for r in rows:
            groups_of[(path_key(path), r.get("class", ""))].append(r)
    for (name, cls), rows in sorted(groups_of.items()):
        path = name + (f" ({cls})" if cls else "")
        groups = defaultdict(list)
        for r in rows:
            groups[(float(r["top_gsd_cm"]), float(r["sub_gsd_cm"]))].append(r)
        for inp in inputs:
            for key in sorted(groups):
                cells = groups[key]
                mean_px = sum(float(c["field_px"]) for c in cells) / len(cells)
                fields = sorted({c["field"] for c in cells})
                if len(fields) < 2:
                    continue
                own = by_field(cells)
                slope_rows.append((path, inp, key, {f: pooled(own[f], inp, mean_px) for f in fields}))
                if (path, inp) not in mean_inputs:
                    mean_inputs[(path, inp)] = {f: mean_input(own[f], inp) for f in fields}
                realised_sum = 0.0
                forecast_sum = {k: 0.0 for k in FITS}
                for held in fields:
                    train = [c for c in cells if c["field"] != held]
                    test = sorted((c for c in cells if c["field"] == held),
                                  key=lambda c: -x_of(c, inp) * float(c["field_share"]))
                    best = test[:round(args.share * len(test))]
                    realised = sum(float(c["field_gain"]) for c in best)
                    # Field gain per unit of beta: x * share / field sigma (CellSample::normalized_gain).
                    per_beta = sum(x_of(c, inp) * float(c["field_share"]) / float(c["field_sigma"])
                                   for c in best if float(c["field_sigma"]) > 0)
                    realised_sum += realised
                    for fit_name, fit in FITS.items():
                        forecast = fit(train, inp, mean_px) * per_beta
                        forecast_sum[fit_name] += forecast
                        for t in (total[inp][fit_name], total["all"][fit_name]):
                            t[0] += (forecast - realised) ** 2
                            t[1] += (forecast > 0) == (realised > 0)
                            t[2] += 1
                pair_rows.append((path, inp, key, realised_sum, forecast_sum))
    print(f"Leave one field out: forecast field gain of the held-out field's best {args.share:.0%} of cells "
          f"against what re-mapping them gained, over {len(groups_of)} (network, class) group(s) and every "
          "(field, pair of GSDs): root mean squared error / share of the forecasts of the right sign")
    print("| input | cases | " + " | ".join(FITS) + " |")
    print("| --- | ---: | " + " | ".join("---:" for _ in FITS) + " |")
    for inp in inputs + ["all"]:
        t = total[inp]
        n = t["pooled"][2]
        if n:
            cols = " | ".join(f"{math.sqrt(t[k][0] / n):.4f} / {t[k][1] / n:.2f}" for k in FITS)
            print(f"| {inp} | {n} | {cols} |")
    if args.pairs:
        print()
        print("| cells | input | top -> descent [cm/px] | realised (sum over held-out fields) | "
              + " | ".join(FITS) + " |")
        print("| --- | --- | --- | ---: | " + " | ".join("---:" for _ in FITS) + " |")
        for path, inp, key, realised, forecast in pair_rows:
            cols = " | ".join(f"{forecast[k]:+.4f}" for k in FITS)
            print(f"| {path} | {inp} | {key[0]:g} -> {key[1]:g} | {realised:+.4f} | {cols} |")
    if args.field_slopes:
        names = sorted({f for *_, slopes in slope_rows for f in slopes})
        print()
        print("Each field's own slope (normalised gain per unit of the input, its cells alone):")
        print("| cells | input | top -> descent [cm/px] | " + " | ".join(names) + " |")
        print("| --- | --- | --- | " + " | ".join("---:" for _ in names) + " |")
        for path, inp, key, slopes in slope_rows:
            cols = " | ".join(f"{slopes[f]:+.3f}" if f in slopes else "" for f in names)
            print(f"| {path} | {inp} | {key[0]:g} -> {key[1]:g} | {cols} |")
        print()
        print("Each field's mean input at the top (its cells, weighted by their field pixels; the cells of "
              "the first pair of GSDs: the same top-level images at every pair):")
        print("| cells | input | " + " | ".join(names) + " |")
        print("| --- | --- | " + " | ".join("---:" for _ in names) + " |")
        for (path, inp), means in mean_inputs.items():
            cols = " | ".join(f"{means[f]:.3f}" if f in means else "" for f in names)
            print(f"| {path} | {inp} | {cols} |")


if __name__ == "__main__":
    main()
