#!/usr/bin/env python3
"""Self-test of jump_table.py on a synthetic cell-samples CSV (run by CTest; exit code != 0 on
failure): two fields, the bound learned with each left out as the library's jump_bound() learns
it (tests/test_cell_gain_model.cpp checks the same rule in C++).

Field a: cells jumping +0.6 (gain -0.02), +0.4 (+0.005), +0.3 (-0.01), +0.1 (+0.03); field b: one
cell, 0.0 (+0.01). With b left out: from the largest jump down the sums are -0.02, -0.015, -0.025
(the lowest): three refused, the bound halfway between +0.3 and +0.1, 0.200. With a left out: one
cell, no guard.

With --drops the same cells mirrored (the finer image's σ below the top-level one's by 0.6, 0.4,
0.3 and 0.1): the same bound on the drops, and the cells losing true positives counted.
"""
from tool_output import check_on_csv

from adaptseg_tools import jump_table

CELLS = """field,region,sub_gsd_cm,field_px,field_gain,delta_fp,top_sigma,fine_sigma
a,0,5,100,-0.02,500,0.1,0.7
a,0,5,100,0.005,10,0.0,0.4
a,1,5,100,-0.01,300,0.2,0.5
a,1,5,100,0.03,-40,0.3,0.4
b,0,5,100,0.01,0,0.5,0.5
b,0,5,100,-1.0,0,0.5,
"""

DROPS = """field,region,sub_gsd_cm,field_px,field_gain,delta_tp,top_sigma,fine_sigma
a,0,5,100,-0.02,-300,0.7,0.1
a,0,5,100,0.005,0,0.4,0.0
a,1,5,100,-0.01,40,0.5,0.2
a,1,5,100,0.03,20,0.4,0.3
b,0,5,100,0.01,0,0.5,0.5
"""


def main():
    check_on_csv(jump_table.main, CELLS, [],
                 ("| a | 4 | +0.600 |", "| b | 0.200 | 3 | -0.0250 |", "| a | inf | 0 | +0.0000 |",
                  "| (0.3, inf] | 2 | -0.0150 | 1 | 2 |"))
    check_on_csv(jump_table.main, DROPS, ["--drops"],
                 ("| field | cells | largest drop over the cell's top-level σ | over the region's |",
                  "| a | 4 | +0.600 |", "| b | 0.200 | 3 | -0.0250 |", "| a | inf | 0 | +0.0000 |",
                  "| (0.3, inf] | 2 | -0.0150 | 1 | 1 |"))
    print("ok: jump_table.py learns the jump guard's bound with each field left out, on jumps and on drops")


if __name__ == "__main__":
    main()
