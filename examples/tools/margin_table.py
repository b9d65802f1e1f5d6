#!/usr/bin/env python3
"""Compares the adaptive strategy's front margin across configurations, field by field.

Usage: /usr/bin/python3 examples/tools/margin_table.py LABEL=OUTDIR[,OUTDIR...] [LABEL=...]
Each LABEL names one configuration (a column); its OUTDIRs are adaptseg_evaluate output
directories (e.g. one per target class), named alike across configurations (e.g.
out/a/dubai-road and out/b/dubai-road). One row per (run = OUTDIR's name, field); each cell
is adaptive's front margin and, in brackets, its descents. A last row counts the fields with a positive margin.
"""
import csv
import os
import sys


def read(dirs):
    """{(run, field): (margin, descents)} of the adaptive rows of `dirs`."""
    out = {}
    for d in dirs:
        name = os.path.basename(os.path.normpath(d))
        with open(os.path.join(d, "results.csv"), newline="") as f:
            for r in csv.DictReader(f):
                if r["strategy"] == "adaptive":
                    out[(name, r["field"])] = (float(r["front_margin"]), int(r["descents"]))
    return out


def main(args):
    columns = []
    for a in args:
        label, _, dirs = a.partition("=")
        if not dirs:
            sys.exit(f"expected LABEL=OUTDIR[,OUTDIR...], got {a!r}")
        columns.append((label, read(dirs.split(","))))
    rows = sorted({k for _, c in columns for k in c})
    print("| run | field | " + " | ".join(label for label, _ in columns) + " |")
    print("| --- | --- |" + " ---: |" * len(columns))
    for run, field in rows:
        cells = []
        for _, c in columns:
            v = c.get((run, field))
            cells.append("—" if v is None else f"{v[0]:+.4f} ({v[1]})")
        print(f"| {run} | {field} | " + " | ".join(cells) + " |")
    counts = [f"{sum(1 for m, _ in c.values() if m > 0)} of {len(c)}" for _, c in columns]
    print("| **margin > 0** | | " + " | ".join(counts) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
