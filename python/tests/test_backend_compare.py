#!/usr/bin/env python3
"""Self-test of backend_compare.py on synthetic runs (run by CTest; exit code != 0 on failure).

Two backends flew building on tile 4, a third named on the command line flew nothing (as
`NETS=... bash scripts/results.sh network` leaves it): the two are compared against each
other's curves, the third left out; with one backend flown there is nothing to compare, and that
is said, not an error.
"""
import os
import sys
import tempfile

from tool_output import printed

from adaptseg_tools import backend_compare

HEADER = "field,strategy,gsd_cm,miou_interest,time_total,front_margin\n"


def write_run(root, name, lawnmowers, adaptive):
    os.makedirs(os.path.join(root, name))
    with open(os.path.join(root, name, "results.csv"), "w") as f:
        f.write(HEADER)
        for gsd, (t, iou) in zip((5, 10, 15), lawnmowers):
            f.write(f"dubai-tile-4,lawnmower,{gsd},{iou},{t},0\n")
        f.write(f"dubai-tile-4,adaptive,15,{adaptive[1]},{adaptive[0]},0\n")


def run(argv):
    saved = sys.argv
    sys.argv = ["backend_compare", *argv]
    try:
        return printed(lambda _: backend_compare.main(), [])[1]
    finally:
        sys.argv = saved


def main():
    with tempfile.TemporaryDirectory() as root:
        # a's curve: 0.5 at 100 s, 0.6 at 200 s; b's lies 0.1 below; each adaptive run beats its own by 0.01.
        write_run(root, "a-building-fly4", [(300, 0.65), (200, 0.6), (100, 0.5)], (150, 0.56))
        write_run(root, "b-building-fly4", [(300, 0.55), (200, 0.5), (100, 0.4)], (150, 0.46))
        text = run([root, "a", "b", "c"])
        if "| run | backend | IoU (time) | vs a curve | vs b curve |" not in text or "vs c curve" in text:
            sys.exit(f"c was not left out, or a and b not compared:\n{text}")
        for row in ("| building-fly4 | a | 0.5600 (150) | +0.0100 | +0.1100 |",
                    "| building-fly4 | b | 0.4600 (150) | -0.0900 | +0.0100 |"):
            if row not in text.splitlines():
                sys.exit(f"no row {row!r}:\n{text}")
        text = run([root, "a", "c"])
        if "nothing to compare" not in text:
            sys.exit(f"one backend flown was not said so:\n{text}")
    print("ok: backend_compare.py compares the backends that flew")


if __name__ == "__main__":
    main()
