"""What the jump guard reads, on calibration's cell samples (adaptseg_calibrate --cell-samples-csv):
per cell, the jump of its finer image's σ over its top-level σ (the cell's: what the guard reads
in flight; and over its region's, the cells' field-pixel-weighted mean, for comparison), and what
re-mapping it gained the field (field_gain). Prints, per field, the largest jumps of both kinds;
the cells by cell-level jump in bins, with their summed field gain and how many added false
positives; and the bound each fold would learn with the field left out (the library's
jump_bound(): from the largest jump down, the cells whose gains sum to the lowest negative total
are refused, the bound halfway between the smallest of their jumps and the next).

With --drops, the same for the other direction: each cell's drop, its top-level σ minus its finer
image's (a closer look that takes the class away), the bins counting the cells that lost true
positives, and the bound a guard on drops would learn by the same rule. Where the training fields'
large drops gained, it learns none.

Usage: jump_table.py [--drops] CELLS_CSV
"""

from __future__ import annotations

import csv
import math
import sys
from collections import defaultdict


def number(text: str) -> float:
    return float(text) if text not in ("", None) else math.nan


def bound(cells: list[tuple[float, float]]) -> tuple[float, int, float]:
    """(bound, cells refused, their summed gain) as jump_bound() computes it; inf: no guard."""
    ranked = sorted(cells, reverse=True)
    total, lowest, refused = 0.0, 0.0, 0
    for k in range(len(ranked) - 1):
        total += ranked[k][1]
        if total < lowest:
            lowest, refused = total, k + 1
    if refused == 0:
        return math.inf, 0, 0.0
    return 0.5 * (ranked[refused - 1][0] + ranked[refused][0]), refused, lowest


def main(argv: list[str]) -> int:
    drops = "--drops" in argv
    argv = [a for a in argv if a != "--drops"]
    if len(argv) != 1:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    sign = -1.0 if drops else 1.0  # a drop is a jump down
    word = "drop" if drops else "jump"
    with open(argv[0], newline="") as f:
        rows = list(csv.DictReader(f))
    region = defaultdict(lambda: [0.0, 0.0])
    for r in rows:
        s, px = number(r["top_sigma"]), number(r["field_px"])
        if math.isfinite(s) and px > 0:
            key = (r["field"], r["region"], r["sub_gsd_cm"])
            region[key][0] += s * px
            region[key][1] += px
    cells = []  # (field, cell jump, region jump, field gain, delta fp; with --drops the drops and delta tp)
    for r in rows:
        top, fine = number(r["top_sigma"]), number(r["fine_sigma"])
        if not (math.isfinite(top) and math.isfinite(fine)):
            continue
        acc = region[(r["field"], r["region"], r["sub_gsd_cm"])]
        cells.append((r["field"], sign * (fine - top), sign * (fine - acc[0] / acc[1]) if acc[1] > 0 else math.nan,
                       number(r["field_gain"]), int(r["delta_tp" if drops else "delta_fp"])))
    fields = sorted({c[0] for c in cells})
    print(f"| field | cells | largest {word} over the cell's top-level σ | over the region's |")
    print("| --- | ---: | ---: | ---: |")
    for f in fields:
        mine = [c for c in cells if c[0] == f]
        print(f"| {f} | {len(mine)} | {max(c[1] for c in mine):+.3f} | {max(c[2] for c in mine):+.3f} |")
    print()
    print(f"| cell-level {word} | cells | summed field gain | losing | "
          + ("losing true positives |" if drops else "adding false positives |"))
    print("| --- | ---: | ---: | ---: | ---: |")
    for lo, hi in ((0.3, math.inf), (0.2, 0.3), (0.1, 0.2), (0.05, 0.1), (-math.inf, 0.05)):
        b = [c for c in cells if lo < c[1] <= hi]
        print(f"| ({lo:g}, {hi:g}] | {len(b)} | {sum(c[3] for c in b):+.4f} | {sum(c[3] < 0 for c in b)} | "
              f"{sum((c[4] < 0) if drops else (c[4] > 0) for c in b)} |")
    print()
    print("| field left out | bound | cells refused | their summed field gain |")
    print("| --- | ---: | ---: | ---: |")
    for f in fields:
        b, n, g = bound([(c[1], c[3]) for c in cells if c[0] != f])
        print(f"| {f} | {b:.3f} | {n} | {g:+.4f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
