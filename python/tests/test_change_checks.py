#!/usr/bin/env python3
"""Self-test of change_checks.py on a synthetic cell-samples CSV (run by CTest; exit code != 0 on
failure). Three fields' 5 cm/px cells (U 500, IoU 0.6):
- a: 100 px added, 60 right, 50 confirmed (40 of them right); 100 removed, 80 right, 50
  confirmed (40 right). Linear gains: all (40 + 0.6·40) / 500 = +0.1280, confirmed only
  (30 + 0.6·30) / 500 = +0.0960, removals only +0.0560, additions only +0.0720.
- b: 200 added, 40 right, 100 confirmed (20 right): all −0.1120, confirmed only −0.0560.
- c: 100 added, 90 right, 80 confirmed (all right): all +0.1680, confirmed only +0.1600.
Over the fields the share of additions confirmed (0.5, 0.5, 0.8) and right (0.6, 0.2, 0.9)
correlate at +0.82; confirmed only beats all on b alone. Over the three cells (field share 0.1
each) the field gains (+0.12, −0.10, +0.17) correlate with the relabelled shares (0.3, 0.2, 0.1)
at −0.17, with the confirmed ones (0.10, 0.10, 0.08) at −0.64 and with the right ones (0.14,
0.04, 0.09) at +0.77. A 10 cm/px cell without a coarser check
(nan) and a cell seen from another top level (left out by --top 15) change nothing; a CSV without
the check columns is refused. The same columns named as the frame check's (`--check reframed`)
give the same rows.
"""
import os
import tempfile

from tool_output import check, check_on_csv, printed

from adaptseg_tools import change_checks

HEAD = ("field,top_gsd_cm,sub_gsd_cm,field_px,field_share,relabelled,field_gain,field_tp,field_fp,field_fn,added,removed,added_right,"
        "removed_right,added_confirmed,removed_confirmed,added_confirmed_right,removed_confirmed_right\n")
CELLS = HEAD + """a,15,5,1000,0.1,0.3,0.12,300,100,100,0.1,0.1,0.06,0.08,0.05,0.05,0.04,0.04
b,15,5,1000,0.1,0.2,-0.1,300,100,100,0.2,0,0.04,0,0.1,0,0.02,0
c,15,5,1000,0.1,0.1,0.17,300,100,100,0.1,0,0.09,0,0.08,0,0.08,0
a,15,10,1000,0.1,0.2,0.5,300,100,100,0.1,0.1,0.1,0.1,nan,nan,nan,nan
a,10,5,1000,0.1,0.5,0.5,300,100,100,0.5,0,0,0,0.5,0,0,0
"""


def main():
    check_on_csv(change_checks.main, CELLS, ["--top", "15"],
                 ("| 5 | a | 1 | 100 | 0.60 | 0.50 | 0.80 | 0.40 | 100 | 0.80 | 0.50 | 0.80 | 0.80 "
                  "| +0.1280 | +0.0960 | +0.0560 | +0.0720 | +0.1200 |",
                  "| 5 | b | 1 | 200 | 0.20 | 0.50 | 0.20 | 0.20 | 0 | nan | nan | nan | nan "
                  "| -0.1120 | -0.0560 | +0.0000 | -0.1120 | -0.1000 |",
                  "| 5 | c | 1 | 100 | 0.90 | 0.80 | 1.00 | 0.50 |", "| +0.1680 | +0.1600 |",
                  "| 5 | added | 3 | +0.82 | 1 of 3 |", "| 5 | removed | 1 | +nan | 1 of 3 |",
                  "| 5 | a | 1 | +nan | +nan | +nan |", "| 5 | all | 3 | -0.17 | -0.64 | +0.77 |"))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "old.csv")
        with open(path, "w") as f:
            f.write("field,top_gsd_cm,sub_gsd_cm,field_px,field_gain,field_tp,field_fp,field_fn,added,removed\n"
                    "a,15,5,1,0,1,0,0,0,0\n")
        rc, _ = printed(change_checks.main, [path])
        check(rc == 2, f"a CSV without the check columns: exit {rc}, want 2")
    # The frame check read from its own columns: the confirmed ones renamed give the same rows;
    # without them (the CSV above has none) --check reframed is refused, as is an unknown check.
    head, *rows = CELLS.splitlines(keepends=True)
    head = head.replace("_confirmed", "_reframed")
    check_on_csv(change_checks.main, head + "".join(rows), ["--top", "15", "--check", "reframed"],
                 ("| 5 | a | 1 | 100 | 0.60 | 0.50 | 0.80 | 0.40 |", "| 5 | all | 3 | -0.17 | -0.64 | +0.77 |"))
    for args in (["--check", "reframed"], ["--check", "shifted"]):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "cells.csv")
            with open(path, "w") as f:
                f.write(CELLS)
            rc, _ = printed(change_checks.main, [path, *args])
            check(rc == 2, f"{args} on a CSV without its columns: exit {rc}, want 2")
    print("ok: change_checks.py splits a closer look's changes by the truth and by a coarser look's confirmation")


if __name__ == "__main__":
    main()
