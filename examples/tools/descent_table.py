#!/usr/bin/python3
"""Every descent of the adaptive strategy in adaptseg_evaluate runs, its forecast against what it
did to the field's map: why a region's gain and the field's disagree.

Per descent (decisions.csv of each run directory): the GSD and images, the forecast field gain,
the realised field gain and the region's gain (realised_region_delta_miou, sign turned: > 0
helped), and what the descent changed in the field's map over L in pixels: true positives
gained (ΔTP: misses corrected, net), false positives added (ΔFP; < 0: removed). A class's field
IoU moves by about (ΔTP − IoU·ΔFP) / (TP + FP + FN): a false positive removed is worth IoU times
a miss corrected, one added costs as much. Then, over all descents: how often the region's gain
and the field's disagree in sign, and for those, whether the descent added false positives.

Usage: descent_table.py [--strategy adaptive] RUN_DIR [RUN_DIR ...]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path


def number(text: str) -> float:
    return float(text) if text not in ("", None) else math.nan


def correlation(x: list[float], y: list[float]) -> float:
    n = len(x)
    if n < 3:
        return math.nan
    mx, my = sum(x) / n, sum(y) / n
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sx = math.sqrt(sum((a - mx) ** 2 for a in x))
    sy = math.sqrt(sum((b - my) ** 2 for b in y))
    return sxy / (sx * sy) if sx > 0 and sy > 0 else math.nan


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strategy", default="adaptive")
    ap.add_argument("runs", nargs="+")
    args = ap.parse_args()
    rows = []
    for run in args.runs:
        path = Path(run) / "decisions.csv"
        with open(path, newline="") as f:
            for d in csv.DictReader(f):
                if d["strategy"] != args.strategy or d["action"] != "descend":
                    continue
                if "realised_delta_tp" not in d:
                    raise SystemExit(f"{path}: no realised_delta_tp column (written by adaptseg_evaluate since 2026-11-29)")
                rows.append((Path(run).name, d))
    print("| run | decision | GSD [cm/px] | images | forecast field gain | realised field gain | region gain | "
          "ΔTP [px] | ΔFP [px] |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    forecast, realised = [], []
    disagree = disagree_fp = 0
    for run, d in rows:
        fg, rg = number(d["forecast_field_gain"]), number(d["realised_field_gain"])
        region = -number(d["realised_region_delta_miou"])
        tp, fp = int(d["realised_delta_tp"]), int(d["realised_delta_fp"])
        print(f"| {run} | {d['decision']} | {number(d['gsd_cm']):g} | {d['images']} | {fg:+.4f} | {rg:+.4f} | "
              f"{region:+.4f} | {tp:+d} | {fp:+d} |")
        if math.isfinite(fg) and math.isfinite(rg):
            forecast.append(fg)
            realised.append(rg)
        if math.isfinite(region) and math.isfinite(rg) and (region > 0) != (rg > 0):
            disagree += 1
            disagree_fp += fp > 0
    print()
    print(f"{len(rows)} descents; forecast and realised field gain correlate at {correlation(forecast, realised):+.2f}; "
          f"the region's gain and the field's disagree in sign in {disagree}, of which {disagree_fp} added false "
          f"positives; false positives added in {sum(int(d['realised_delta_fp']) > 0 for _, d in rows)} descents, "
          f"misses corrected (ΔTP > 0) in {sum(int(d['realised_delta_tp']) > 0 for _, d in rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
