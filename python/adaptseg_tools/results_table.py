"""Prints a markdown table of one or more adaptseg_evaluate results.csv files.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.results_table OUTDIR [OUTDIR ...]
One row per field x strategy: GSD, field mIoU over the labels of interest and over all
classes, execution time and its parts, images, descents and front margin.
"""
import csv
import os
import sys


def main(dirs):
    print("| run | field | strategy | GSD [cm/px] | mIoU L | mIoU all | time [s] | flight [s] | images | descents | front margin |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for d in dirs:
        with open(os.path.join(d, "results.csv"), newline="") as f:
            for r in csv.DictReader(f):
                print(f"| {os.path.basename(os.path.normpath(d))} | {r['field']} | {r['strategy']} | "
                      f"{float(r['gsd_cm']):.2f} | {float(r['miou_interest']):.4f} | {float(r['miou_all']):.4f} | "
                      f"{float(r['time_total']):.1f} | {float(r['time_flight']):.1f} | {r['images']} | "
                      f"{r['descents']} | {float(r['front_margin']):+.4f} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
