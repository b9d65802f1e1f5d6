"""Whether the training folds can tell a run's losing descents from its winning ones: gates replayed on flown runs.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fold_gate DIR [DIR ...]

Each DIR holds runs of `scripts/results.sh loto` (adaptseg_evaluate output folders
...-CLASS-tile-K and their logs ...-CLASS-tile-K.log). Each log lists the setting its calibration
kept first, with each training fold's front margin. A gate is a rule on those fold margins that
lets the run descend as calibrated or keeps it at its top level: where it keeps it there, the run
flies no descent, and its margin is that of the lawnmower at the top-level GSD it flew (results.csv),
adaptive and non-adaptive alike. Gates replayed:

  - `as flown`: every run as calibrated;
  - `mean > SE`: the kept setting's mean fold margin beats flying no descent (every fold 0) by
    more than one standard error (select_pooling's rule);
  - `no fold lost`: no fold below −0.002 (the targets' floor);
  - `most folds gain`: more folds above +0.001 than at or below it.

Prints, as Markdown, one row per run (class, tile, the kept setting, its fold margins' mean,
standard error, folds above +0.001 and below −0.002, the run's margin and descents) and one row
per gate with the targets' measures over the runs (above +0.001, median, mean, below
max(non-adaptive, 0) − 0.002, descents).
"""
from __future__ import annotations

import csv
import os
import re
import statistics
import sys

from .fold_choice import kept_trial

RUN = re.compile(r"(building|road|vegetation|water)-tile-([1-9])$")


def run_results(directory: str) -> dict:
    """{strategy: row} of a run's results.csv, and the lawnmowers by GSD under 'lawnmower'."""
    out: dict = {"lawnmower": {}}
    with open(os.path.join(directory, "results.csv")) as f:
        for row in csv.DictReader(f):
            if row["strategy"] == "lawnmower":
                out["lawnmower"][round(float(row["gsd_cm"]), 3)] = row
            else:
                out[row["strategy"]] = row
    return out


def mean_se(values: list[float]) -> tuple[float, float]:
    """The mean of `values` and its standard error (0 for one value)."""
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, 0.0
    return mean, (sum((v - mean) ** 2 for v in values) / (n - 1) / n) ** 0.5


GATES = {
    "as flown": lambda folds: True,
    "mean > SE": lambda folds: mean_se(folds)[0] > mean_se(folds)[1] * (1.0 + 1e-9),
    "no fold lost": lambda folds: all(v >= -0.002 for v in folds),
    "most folds gain": lambda folds: sum(v > 0.001 for v in folds) > sum(v <= 0.001 for v in folds),
}


def runs_of(directories: list[str]) -> list[dict]:
    """Every run of the folders: class, tile, kept setting and fold margins, the flown margins."""
    runs = []
    for d in directories:
        names = sorted(n for n in os.listdir(d) if RUN.search(n) and os.path.isdir(os.path.join(d, n)))
        if not names:
            sys.exit(f"no runs named ...-CLASS-tile-K in {d}")
        for name in names:
            path = os.path.join(d, name)
            setting, _mean, _descents, folds = kept_trial(path + ".log")
            res = run_results(path)
            adaptive, nonadaptive = res["adaptive"], res["nonadaptive"]
            top = res["lawnmower"].get(round(float(adaptive["gsd_cm"]), 3))
            if top is None:
                sys.exit(f"{path}: no lawnmower at the top-level GSD {adaptive['gsd_cm']} cm/px")
            m = RUN.search(name)
            runs.append({"class": m.group(1), "tile": int(m.group(2)), "setting": setting, "folds": folds,
                         "adaptive": float(adaptive["front_margin"]), "descents": int(adaptive["descents"]),
                         "nonadaptive": float(nonadaptive["front_margin"]),
                         "nonadaptive_descents": int(nonadaptive["descents"]),
                         "top": float(top["front_margin"])})
    return runs


def replay(runs: list[dict], gate) -> dict:
    """The targets' measures over `runs` with `gate` applied."""
    margins, below, descents = [], 0, 0
    for r in runs:
        if gate(r["folds"]):
            a, na, n = r["adaptive"], r["nonadaptive"], r["descents"]
        else:
            a = na = r["top"]
            n = 0
        margins.append(a)
        descents += n
        below += a < max(na, 0.0) - 0.002
    return {"above": sum(m > 0.001 for m in margins), "median": statistics.median(margins),
            "mean": sum(margins) / len(margins), "below": below, "descents": descents}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if not argv or any(a.startswith("-") for a in argv):
        sys.exit(__doc__.split("\n\n")[1])
    runs = runs_of(argv)
    print("| class | tile | kept setting | fold mean | SE | folds > +0.001 | folds < −0.002 | margin (descents) |")
    print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: |")
    for r in sorted(runs, key=lambda r: (r["class"], r["tile"])):
        mean, se = mean_se(r["folds"])
        print(f"| {r['class']} | {r['tile']} | {r['setting']} | {mean:+.4f} | {se:.4f} | "
              f"{sum(v > 0.001 for v in r['folds'])} | {sum(v < -0.002 for v in r['folds'])} | "
              f"{r['adaptive']:+.4f} ({r['descents']}) |")
    print()
    print(f"| gate ({len(runs)} runs) | > +0.001 | median | mean | below the floor | descents |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, gate in GATES.items():
        s = replay(runs, gate)
        print(f"| {name} | {s['above']} | {s['median']:+.4f} | {s['mean']:+.4f} | {s['below']} | {s['descents']} |")


if __name__ == "__main__":
    main()
