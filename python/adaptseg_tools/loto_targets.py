"""The leave-one-tile-out yardstick's targets, per configuration of the 24 runs.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.loto_targets [--oracle DIR] LABEL=DIR [LABEL=DIR ...]

Each DIR holds the runs of one configuration of `scripts/results.sh loto` (adaptseg_evaluate
output folders named ...-CLASS-tile-K, one per class of interest and Dubai tile); --oracle
DIR the oracle's runs of the same folds (part oracle-default: dubai-CLASS-tile-K). Runs are
matched by class and tile. Prints, as Markdown, per configuration (margins against the
lawnmower curve's upper envelope, `front_margin` of results.csv):
  - adaptive above +0.001 (target: at least 14 of 24), the median (target >= +0.004) and mean;
  - runs below max(non-adaptive, 0) - 0.002 (target: none);
  - descents and the correlation of forecast and realised field gain per descent (decisions.csv;
    target >= 0.5);
  - the oracle above 0 in the runs where any strategy (this configuration's or the oracle's)
    beats the curve (target: all);
then one row per run: class, tile, each configuration's adaptive margin (descents).
"""
import argparse
import os
import re
import statistics
import sys

from .sweep_table import correlation, load

RUN = re.compile(r"(building|road|vegetation|water)-tile-([1-9])$")


def by_run(directory):
    """{(class, tile): {strategy: (margin, descents, ...)}} and the descents' (forecast, realised)."""
    dirs = sorted(os.path.join(directory, d) for d in os.listdir(directory)
                  if os.path.isdir(os.path.join(directory, d)) and RUN.search(d))
    if not dirs:
        sys.exit(f"no runs named ...-CLASS-tile-K in {directory}")
    runs, decisions = load(dirs)
    out = {}
    for (name, _field), strategies in runs.items():
        m = RUN.search(name)
        out[(m.group(1), int(m.group(2)))] = strategies
    pairs = [(float(d["forecast_field_gain"]), float(d["realised_field_gain"])) for d in decisions
             if d["strategy"] == "adaptive" and d["action"] == "descend" and d["forecast_field_gain"] != ""
             and d["realised_field_gain"] != ""]
    return out, pairs


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--oracle", help="the oracle's runs of the same folds")
    parser.add_argument("configs", nargs="+", help="LABEL=DIR")
    args = parser.parse_args(argv)
    configs = []
    for c in args.configs:
        label, _, d = c.partition("=")
        if not d:
            sys.exit(f"expected LABEL=DIR, got {c!r}")
        configs.append((label, *by_run(d)))
    oracle = by_run(args.oracle)[0] if args.oracle else {}

    print("| configuration | runs | adaptive > +0.001 | median | mean | below max(non-adaptive, 0) − 0.002 | "
          "descents | forecast/realised correlation | oracle > 0 where any strategy beats the curve |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for label, runs, pairs in configs:
        keys = sorted(runs)
        a = [runs[k]["adaptive"][0] for k in keys]
        below = sum(runs[k]["adaptive"][0] < max(runs[k]["nonadaptive"][0], 0.0) - 0.002 for k in keys)
        beatable = [k for k in keys if any(v[0] > 0 for v in runs[k].values())
                    or any(v[0] > 0 for v in oracle.get(k, {}).values())]
        held = [k for k in beatable if k in oracle and oracle[k]["adaptive"][0] > 0]
        with_oracle = sum(k in oracle for k in beatable)
        oracle_cell = f"{len(held)} of {with_oracle}" if oracle else "—"
        r = correlation([f for f, _ in pairs], [g for _, g in pairs])
        print(f"| {label} | {len(a)} | {sum(v > 0.001 for v in a)} | {statistics.median(a):+.4f} | "
              f"{statistics.mean(a):+.4f} | {below} | {len(pairs)} | {r:+.2f} | {oracle_cell} |")

    print()
    print("| class | tile |" + "".join(f" {c[0]} |" for c in configs) + (" oracle |" if oracle else ""))
    print("| --- | ---: |" + " ---: |" * (len(configs) + bool(oracle)))
    keys = sorted({k for _, runs, _ in configs for k in runs})
    for k in keys:
        cells = []
        for source in [c[1] for c in configs] + ([oracle] if oracle else []):
            v = source.get(k, {}).get("adaptive")
            cells.append("—" if v is None else f"{v[0]:+.4f} ({v[1]})")
        print(f"| {k[0]} | {k[1]} |" + "".join(f" {c} |" for c in cells))


if __name__ == "__main__":
    main(sys.argv[1:])
