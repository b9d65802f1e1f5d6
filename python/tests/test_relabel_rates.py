#!/usr/bin/env python3
"""Self-test of relabel_rates.py on a synthetic cell-samples CSV (run by CTest; exit code != 0 on
failure): two fields whose closer looks add L right 60 % of the time and remove it right 80 %,
every cell's field gain (ΔTP − IoU·ΔFP) / U exactly (U 500, IoU 0.6). With either field left out
the other's cells give p_a 0.60 and p_r 0.80, and the signed forecast is each cell's gain:
field a +0.0720 and +0.0560 (summed +0.1280), field b +0.1440, +0.0280 and +0.0640 (+0.2360,
correlation +1.00). A cell seen from another top level is left out by --top 15; a CSV without the
added and removed columns is refused.
"""
import os
import tempfile

from tool_output import check, check_on_csv, printed

from adaptseg_tools import relabel_rates

HEAD = "field,top_gsd_cm,sub_gsd_cm,field_px,relabelled,field_gain,delta_tp,field_tp,field_fp,field_fn,added,removed\n"
CELLS = HEAD + """a,15,5,1000,0.1,0.072,60,300,100,100,0.1,0
a,15,5,1000,0.1,0.056,-20,300,100,100,0,0.1
b,15,5,1000,0.2,0.144,120,300,100,100,0.2,0
b,15,5,1000,0.05,0.028,-10,300,100,100,0,0.05
b,15,5,1000,0.1,0.064,20,300,100,100,0.05,0.05
b,10,5,1000,0.1,-0.5,-100,300,100,100,0,0.1
"""


def main():
    check_on_csv(relabel_rates.main, CELLS, ["--top", "15"],
                 ("| 5 | a | 2 | 0.60 | 0.80 | +nan | +nan | +0.1280 | +0.1280 |",
                  "| 5 | b | 3 | 0.60 | 0.80 | +1.00 |", "| +0.2360 | +0.2360 |",
                  "| 5 | 5 | +1.00 |"))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "old.csv")
        with open(path, "w") as f:
            f.write("field,top_gsd_cm,sub_gsd_cm,field_px,relabelled,field_gain\na,15,5,1,0,0\n")
        rc, _ = printed(relabel_rates.main, [path])
        check(rc == 2, f"a CSV without added and removed: exit {rc}, want 2")
    print("ok: relabel_rates.py fits the closer look's rates with each field left out and forecasts the other's cells")


if __name__ == "__main__":
    main()
