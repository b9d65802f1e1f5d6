"""The leave-one-tile-out yardstick's targets, per configuration of the 24 runs.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.loto_targets [--oracle DIR] LABEL=DIR[+DIR...] ...

Each DIR holds the runs of one configuration of `scripts/results.sh loto` (adaptseg_evaluate
output folders named ...-CLASS-tile-K, one per class of interest and Dubai tile); --oracle
DIR the oracle's runs of the same folds (part oracle-default: dubai-CLASS-tile-K). Runs are
matched by class and tile. LABEL=DIR+DIR pools the runs of several folders as one
configuration (the same flags flown by each seed's networks: 48 runs), each run counted once
(every DIR must hold the same runs). Prints, as Markdown, per configuration (margins against the
lawnmower curve's upper envelope, `front_margin` of results.csv):
  - adaptive above +0.001 (target: at least 14 of 24), the median (target >= +0.004) and mean;
  - runs below max(non-adaptive, 0) - 0.002 (target: none);
  - descents and the correlation of forecast and realised field gain per descent (decisions.csv;
    target >= 0.5);
  - the oracle above 0 in the runs where any strategy (this configuration's or the oracle's)
    beats the curve (target: all);
with several configurations, in how many runs any of them is above +0.001 (each run's best
adaptive margin over them: what the configurations reach together) and the runs where none is;
then one row per run: class, tile, each configuration's adaptive margin (descents), a pooled
configuration's margins side by side ("a / b", in the order of its folders).
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


def pooled(dirs):
    """by_run over several folders holding the same runs: {(class, tile, i): strategies} for the
    i-th folder, and every folder's descents."""
    out, pairs, names = {}, [], None
    for i, d in enumerate(dirs):
        runs, p = by_run(d)
        if names is not None and set(runs) != names:
            sys.exit(f"{d} holds other runs than {dirs[0]}: a pooled configuration needs the same runs in each")
        names = set(runs)
        out.update({(*k, i): v for k, v in runs.items()})
        pairs += p
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
        dirs = d.split("+")
        configs.append((label, *(by_run(d) if len(dirs) == 1 else pooled(dirs))))
    oracle = by_run(args.oracle)[0] if args.oracle else {}

    print("| configuration | runs | adaptive > +0.001 | median | mean | below max(non-adaptive, 0) − 0.002 | "
          "descents | forecast/realised correlation | oracle > 0 where any strategy beats the curve |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for label, runs, pairs in configs:
        keys = sorted(runs)
        a = [runs[k]["adaptive"][0] for k in keys]
        below = sum(runs[k]["adaptive"][0] < max(runs[k]["nonadaptive"][0], 0.0) - 0.002 for k in keys)
        beatable = [k for k in keys if any(v[0] > 0 for v in runs[k].values())
                    or any(v[0] > 0 for v in oracle.get(k[:2], {}).values())]
        held = [k for k in beatable if k[:2] in oracle and oracle[k[:2]]["adaptive"][0] > 0]
        with_oracle = sum(k[:2] in oracle for k in beatable)
        oracle_cell = f"{len(held)} of {with_oracle}" if oracle else "—"
        r = correlation([f for f, _ in pairs], [g for _, g in pairs])
        print(f"| {label} | {len(a)} | {sum(v > 0.001 for v in a)} | {statistics.median(a):+.4f} | "
              f"{statistics.mean(a):+.4f} | {below} | {len(pairs)} | {r:+.2f} | {oracle_cell} |")

    if len(configs) > 1:
        # What the configurations reach together: each run's best adaptive margin over all of
        # them (a pooled configuration's flights counted as runs of their class and tile).
        best = {}
        for _, runs, _ in configs:
            for k, v in runs.items():
                if "adaptive" in v:
                    best[k[:2]] = max(best.get(k[:2], float("-inf")), v["adaptive"][0])
        won = [k for k in sorted(best) if best[k] > 0.001]
        never = ", ".join(f"{c} {t}" for c, t in sorted(best) if best[(c, t)] <= 0.001) or "none"
        print(f"\nany configuration above +0.001: {len(won)} of {len(best)} runs (each run's best "
              f"adaptive margin over the configurations); in none: {never}")

    print()
    print("| class | tile |" + "".join(f" {c[0]} |" for c in configs) + (" oracle |" if oracle else ""))
    print("| --- | ---: |" + " ---: |" * (len(configs) + bool(oracle)))
    keys = sorted({k[:2] for _, runs, _ in configs for k in runs})

    def cell(v):
        return "—" if v is None else f"{v[0]:+.4f} ({v[1]})"

    for k in keys:
        cells = []
        for source in [c[1] for c in configs] + ([oracle] if oracle else []):
            parts = sorted(p for p in source if p[:2] == k and len(p) == 3)
            if parts:
                cells.append(" / ".join(cell(source[p].get("adaptive")) for p in parts))
            else:
                cells.append(cell(source.get(k, {}).get("adaptive")))
        print(f"| {k[0]} | {k[1]} |" + "".join(f" {c} |" for c in cells))


if __name__ == "__main__":
    main(sys.argv[1:])
