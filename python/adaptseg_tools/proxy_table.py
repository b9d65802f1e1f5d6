"""How well the scene check's measurement tracks what a descent gains, cell by cell.

After a descent the planner sees, without ground truth, each decision input over the re-mapped
cells twice: as the top-level image gave it and as the finer image gives it. The scene check
(FrontAwarePolicy::observe, docs/method.md) reads the drop, top minus fine, as evidence of the
gain. This tool reads the cells written by `adaptseg_cell_study --csv` (every cell re-mapped
alone, with its realised field-IoU gain) and prints, per class and GSD and over all classes,
the rank correlation (Spearman) of the realised gain with each input's drop, each drop weighted
as the gain is (the cell's share of the field over the field's share of the class), and with
the top-level input itself (what ranks the cells before the descent), beside the cells' summed
gain and the summed drop of the expected error (the drop read as a gain, unfitted); then, per
input about the class, what the cells gain per unit of their top-level input where the finer
look was less sure, about as sure, or surer (drop_bins).

  proxy_table.py LABEL=CELLS.csv [LABEL=CELLS.csv ...]

e.g. the fields a network was trained on against fields it never saw (docs/journal/2026-11-cells.md,
"After a descent").
"""
import csv
import math
import sys
from collections import defaultdict


def ranks(v):
    order = sorted(range(len(v)), key=lambda k: v[k])
    r = [0.0] * len(v)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = 0.5 * (i + j) + 1.0
        i = j + 1
    return r


def spearman(a, b):
    if len(a) < 3:
        return math.nan
    ra, rb = ranks(a), ranks(b)
    n = float(len(a))
    ma, mb = sum(ra) / n, sum(rb) / n
    sab = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    saa = sum((x - ma) ** 2 for x in ra)
    sbb = sum((y - mb) ** 2 for y in rb)
    return sab / math.sqrt(saa * sbb) if saa > 0 and sbb > 0 else math.nan


def value(row, name):
    """An input's value in a CSV row, 0 where the backend could not give it (nan)."""
    x = float(row[name])
    return 0.0 if math.isnan(x) else x


def fmt(x):
    return "nan" if math.isnan(x) else f"{x:+.2f}"


def main(args):
    if not args or any("=" not in a for a in args):
        sys.exit("usage: proxy_table.py LABEL=CELLS.csv [LABEL=CELLS.csv ...]")
    for arg in args:
        label, path = arg.split("=", 1)
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            sys.exit(f"proxy_table.py: {path} holds no cells")
        inputs = [c[len("top_"):] for c in rows[0] if c.startswith("top_")]
        # Only the inputs the backend gave (a labels-only or single backend writes nan).
        inputs = [i for i in inputs if any(not math.isnan(float(r["top_" + i])) for r in rows)]
        groups = defaultdict(list)
        for r in rows:
            groups[(r["class"], float(r["gsd_cm"]))].append(r)
            groups[("all classes", float(r["gsd_cm"]))].append(r)
        print(f"\n{label} ({path}): rank correlation of the realised gain with each input's drop "
              "(top - fine) over the cell, then with the top-level expected error")
        print("| class | GSD [cm/px] | cells | " + " | ".join(f"{i} drop" for i in inputs) +
              " | expected_error at the top | gain (sum) | expected-error drop (sum) |")
        print("| --- | ---: | ---: | " + " | ".join("---:" for _ in inputs) + " | ---: | ---: | ---: |")
        for (cls, gsd), rs in sorted(groups.items(), key=lambda kv: (kv[0][0] == "all classes", kv[0])):
            gain = [float(r["gain"]) for r in rs]
            weight = [float(r["field_share"]) / float(r["field_sigma"]) if float(r["field_sigma"]) > 0 else 0.0
                      for r in rs]

            drops = {i: [(value(r, "top_" + i) - value(r, "fine_" + i)) * w for r, w in zip(rs, weight)]
                     for i in inputs}
            top_ee = [value(r, "top_expected_error") * w for r, w in zip(rs, weight)] \
                if "expected_error" in inputs else []
            ee_drop = sum(drops["expected_error"]) if "expected_error" in inputs else math.nan
            print(f"| {cls} | {gsd:g} | {len(rs)} | " + " | ".join(fmt(spearman(drops[i], gain)) for i in inputs) +
                  f" | {fmt(spearman(top_ee, gain)) if top_ee else 'nan'} | {sum(gain):+.4f} | {ee_drop:+.4f} |")
        drop_bins(label, rows, [i for i in ABOUT_L if i in inputs])


ABOUT_L = ("ambiguity", "expected_error", "second_choice")  # the inputs about the class
# Relative drop of an input from the top-level to the finer look, (top - fine) / top: the finer
# look less sure (rose by more than 10 %), about as sure, surer, much surer.
BINS = ((-math.inf, -0.1, "rose > 10 %"), (-0.1, 0.1, "within 10 %"), (0.1, 0.3, "fell 10-30 %"),
        (0.3, math.inf, "fell > 30 %"))


def drop_bins(label, rs_all, inputs):
    """What a cell gains per unit of its top-level input, by how far the finer look moved that
    input: Σ ν / Σ x over the cells (all classes) with x > 0.01 in each bin of the relative drop,
    ν the cell's normalised gain (field gain × the field's σ / the cell's field share, the share
    of its pixels corrected; CellSample::normalized_gain). The scene check reads a drop as gain
    and a rise as loss; where a rise comes with the largest gains, it reads the field backwards."""
    print(f"\n{label}: gain per unit of the top-level input by the relative drop (top - fine) / top of that "
          "input (cells with input > 0.01; all classes): Σ ν / Σ x (cells)")
    print("| input | GSD [cm/px] | " + " | ".join(b[2] for b in BINS) + " |")
    print("| --- | ---: | " + " | ".join("---:" for _ in BINS) + " |")
    for inp in inputs:
        for gsd in sorted({float(r["gsd_cm"]) for r in rs_all}):
            cols = []
            for lo, hi, _ in BINS:
                num = den = 0.0
                n = 0
                for r in rs_all:
                    x, xf = value(r, "top_" + inp), value(r, "fine_" + inp)
                    share, sigma = float(r["field_share"]), float(r["field_sigma"])
                    if float(r["gsd_cm"]) != gsd or x <= 0.01 or share <= 0 or not lo <= (x - xf) / x < hi:
                        continue
                    num += float(r["gain"]) * sigma / share
                    den += x
                    n += 1
                cols.append(f"{num / den:+.3f} ({n})" if n else "—")
            print(f"| {inp} | {gsd:g} | " + " | ".join(cols) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
