"""Prints a markdown table of per-image mIoU against image GSD from adaptseg_evaluate runs.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.per_image_table [--strategy lawnmower] OUTDIR [OUTDIR ...]

Reads OUTDIR/per_image.csv. One row per run x field x image GSD, over the images of the given
strategy (default: the lawnmowers, i.e. every GSD of the sweep): mean and standard deviation of
the per-image mIoU over L (images where it is defined), the same over the images whose
footprint's ground truth is at least 5 % L (column truth_sigma; the subset the per-image figure
also draws), and the per-image mIoU over all classes. The last column says whether each mean
rises as the GSD falls (every finer GSD strictly above the next coarser one).
"""
import argparse
import csv
import os
import statistics
from collections import defaultdict

MIN_TRUTH_SIGMA = 0.05  # also used by plot_evaluation.py


def by_gsd(rows, field, strategy, column="image_miou_interest", min_truth=None):
    """{image GSD: [values of `column`]} over the per_image.csv rows of `field` flown by
    `strategy` where the value is defined; with `min_truth`, only the images whose footprint's
    truth is at least that share L (column truth_sigma). Also used by plot_evaluation.py."""
    groups = defaultdict(list)
    for r in rows:
        if r["field"] != field or r["strategy"] != strategy or r[column] == "":
            continue
        if min_truth is not None and (r.get("truth_sigma", "") == "" or float(r["truth_sigma"]) < min_truth):
            continue
        groups[round(float(r["image_gsd_cm"]), 3)].append(float(r[column]))
    return groups


def stats(values):
    if not values:
        return "–"
    sd = statistics.pstdev(values) if len(values) > 1 else 0.0
    return f"{statistics.fmean(values):.3f} ± {sd:.3f} ({len(values)})"


def rises(means):
    """True if the means (ordered by GSD, finest first) fall strictly with GSD."""
    m = [v for v in means if v is not None]
    return len(m) >= 2 and all(a > b for a, b in zip(m, m[1:]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--strategy", default="lawnmower")
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    print("| run | field | GSD [cm/px] | mIoU L, all images (n) | mIoU L, images with L ≥ 5 % (n) | "
          "mIoU all classes (n) |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    summary = []
    for d in args.dirs:
        with open(os.path.join(d, "per_image.csv"), newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["strategy"] == args.strategy]
        run = os.path.basename(os.path.normpath(d))
        for field in sorted({r["field"] for r in rows}):
            gsds = sorted({round(float(r["image_gsd_cm"]), 3) for r in rows if r["field"] == field})
            series = (by_gsd(rows, field, args.strategy),
                      by_gsd(rows, field, args.strategy, min_truth=MIN_TRUTH_SIGMA),
                      by_gsd(rows, field, args.strategy, column="image_miou_all"))
            for g in gsds:
                print(f"| {run} | {field} | {g:.2f} | " + " | ".join(stats(s.get(g, [])) for s in series) + " |")
            cols = [[statistics.fmean(s[g]) if s.get(g) else None for g in gsds] for s in series]
            summary.append(f"{run} / {field}: rises as GSD falls? L all images: {'yes' if rises(cols[0]) else 'no'}; "
                           f"L, images with L >= 5 %: {'yes' if rises(cols[1]) else 'no'}; "
                           f"all classes: {'yes' if rises(cols[2]) else 'no'}")
    print()
    for s in summary:
        print(s)


if __name__ == "__main__":
    main()
