"""Whether the way a closer look relabels a cell, into the class of interest or out of it, tells
its field gain on a field the rates were not fitted on (issue 53, item 3: the field's gain, not
the region's). Reads calibration's cell samples (`adaptseg_calibrate --cell-samples-csv`, whose
`added` and `removed` columns are the shares of a cell's field pixels the finer look moved into L
and out of it: observable in flight).

A field's IoU of L moves by about (ΔTP − IoU·ΔFP) / U (U = TP + FP + FN of its top-level map), and
with A pixels added and R removed, ΔTP = p_a·A − (1 − p_r)·R and ΔFP = (A − R) − ΔTP, where p_a is
the share of the additions that are truly L and p_r of the removals that are truly not. For each
field left out and each finer GSD, p_a and p_r are fitted on the other fields' cells (least
squares of ΔTP on A and −R through the origin, pixels) and the left-out field's cells are forecast
so (`signed`), beside the same with the unsigned relabelled share X (`unsigned`: gain·U = k·X, k
fitted on the other fields alike). Both use the left-out field's own U and IoU, which a flight
does not know: an upper bound on what the split can tell. Prints per field and GSD p_a, p_r, each
forecast's correlation with the cells' real gains and the summed gains, then over all left-out
cells per GSD.

Usage: relabel_rates.py CELLS_CSV [--top GSD]   (--top: only the cells seen from that top level)
"""

from __future__ import annotations

import csv
import math
import sys

from .descent_table import correlation


def cells_of(rows: list[dict], top: float | None) -> list[dict]:
    out = []
    for r in rows:
        if top is not None and abs(float(r["top_gsd_cm"]) - top) > 1e-6:
            continue
        n = float(r["field_px"])
        tp, fp, fn = (float(r[k]) for k in ("field_tp", "field_fp", "field_fn"))
        union = tp + fp + fn
        if not (n > 0 and union > 0):
            continue
        out.append({"field": r["field"], "sub": float(r["sub_gsd_cm"]), "A": float(r["added"]) * n,
                    "R": float(r["removed"]) * n, "X": float(r["relabelled"]) * n, "gain": float(r["field_gain"]),
                    "dtp": float(r["delta_tp"]), "U": union, "iou": tp / union})
    return out


def fit_rates(cells: list[dict]) -> tuple[float, float]:
    """(p_a, p_r): ΔTP = p_a·A − (1 − p_r)·R by least squares through the origin."""
    saa = sum(c["A"] ** 2 for c in cells)
    srr = sum(c["R"] ** 2 for c in cells)
    sar = sum(c["A"] * c["R"] for c in cells)
    sat = sum(c["A"] * c["dtp"] for c in cells)
    srt = sum(-c["R"] * c["dtp"] for c in cells)
    # normal equations for [p_a, q] on columns [A, −R]
    det = saa * srr - sar * sar
    if det <= 0:
        return math.nan, math.nan
    p_a = (sat * srr + sar * srt) / det
    q = (saa * srt + sar * sat) / det
    return p_a, 1.0 - q


def signed(c: dict, p_a: float, p_r: float) -> float:
    dtp = p_a * c["A"] - (1.0 - p_r) * c["R"]
    dfp = (c["A"] - c["R"]) - dtp
    return (dtp - c["iou"] * dfp) / c["U"]


def main(argv: list[str]) -> int:
    top = None
    if "--top" in argv:
        i = argv.index("--top")
        if i + 1 >= len(argv):
            print(__doc__.strip().splitlines()[-1], file=sys.stderr)
            return 2
        top = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 1:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    with open(argv[0], newline="") as f:
        rows = list(csv.DictReader(f))
    if rows and not {"added", "removed"} <= set(rows[0]):
        print(f"{argv[0]} has no added and removed columns: written before 2026-12-07, calibrate again",
              file=sys.stderr)
        return 2
    cells = cells_of(rows, top)
    fields = sorted({c["field"] for c in cells})
    print("| finer GSD [cm/px] | field left out | cells | p_a | p_r | correlation signed | unsigned "
          "| summed gain real | signed | unsigned |")
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    pooled = {}
    for g in sorted({c["sub"] for c in cells}):
        real_all, signed_all, unsigned_all = [], [], []
        for f in fields:
            train = [c for c in cells if c["field"] != f and c["sub"] == g]
            test = [c for c in cells if c["field"] == f and c["sub"] == g]
            if not train or not test:
                continue
            p_a, p_r = fit_rates(train)
            xx = sum(c["X"] ** 2 for c in train)
            k = sum(c["X"] * c["gain"] * c["U"] for c in train) / xx if xx > 0 else 0.0
            real = [c["gain"] for c in test]
            s = [signed(c, p_a, p_r) for c in test]
            u = [k * c["X"] / c["U"] for c in test]
            real_all += real
            signed_all += s
            unsigned_all += u
            print(f"| {g:g} | {f} | {len(test)} | {p_a:.2f} | {p_r:.2f} | {correlation(s, real):+.2f} "
                  f"| {correlation(u, real):+.2f} | {sum(real):+.4f} | {sum(s):+.4f} | {sum(u):+.4f} |")
        pooled[g] = (len(real_all), correlation(signed_all, real_all), correlation(unsigned_all, real_all))
    print("\n| finer GSD [cm/px] | left-out cells | correlation signed | unsigned |")
    print("| ---: | ---: | ---: | ---: |")
    for g, (n, cs, cu) in pooled.items():
        print(f"| {g:g} | {n} | {cs:+.2f} | {cu:+.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
