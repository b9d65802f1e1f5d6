#!/usr/bin/env python3
"""Self-test of entropy_slopes.py --covariates on a synthetic cell-samples CSV (run by CTest; exit
code != 0 on failure).

Four fields of one cell each (input sigma 1, field share and sigma 1, so the normalised gain is
the field gain and each field's own slope its cell's gain): a, b, c, d at mean top-level entropy
0.2, 0.4, 0.6, 0.8 with slopes -1, 1, 3, 5. The entropy orders the slopes exactly (rank correlation
+1.00); the line fitted on the other three forecasts b, c and d with their sign and a, whose
entropy lies below the others' range (read at 0.4: +1), with the wrong one: 3 of 4. Sigma and the
field's sigma do not spread: no correlation, and the mean of the others' slopes forecast for
each, right but for a.

--within on sub-fields t1[a], t1[b], t2[a], t2[b] of one cell each (slopes 1, 3, 5, 7) but t1[a],
of two cells whose gains 0 and 2 make its slope 1 with sampling variance ((-1)^2 + 1^2) / 2^2 =
0.5: within the fields ((1-2)^2 + (3-2)^2 + (5-6)^2 + (7-6)^2) / 2 = 2, less the mean sampling
variance 0.125, 1.875 (sd 1.369); between, the means 2 and 6 spread 8, less 2 / 2, 7 (sd 2.646);
sampling sd 0.354; local share 1.875 / 8.875 = 0.21.
"""
from tool_output import check_on_csv

from adaptseg_tools import entropy_slopes

CELLS = """field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,field_gain,top_sigma,top_entropy
a,0,15,10,100,1,1,-1,1,0.2
b,0,15,10,100,1,1,1,1,0.4
c,0,15,10,100,1,1,3,1,0.6
d,0,15,10,100,1,1,5,1,0.8
"""

SUB_FIELDS = """field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,field_gain,top_sigma,top_entropy
t1[a],0,15,10,100,1,1,0,1,0.2
t1[a],1,15,10,100,1,1,2,1,0.2
t1[b],0,15,10,100,1,1,3,1,0.4
t2[a],0,15,10,100,1,1,5,1,0.6
t2[b],0,15,10,100,1,1,7,1,0.8
"""


def main():
    check_on_csv(entropy_slopes.main, CELLS, ["sigma", "--covariates"],
                 ("| top -> descent [cm/px] | sigma | entropy | field_sigma |",
                  "| 15 -> 10 | no spread (3/4) | +1.00 (3/4) | no spread (3/4) |"))
    print("ok: entropy_slopes.py --covariates ranks the fields' slopes by each field-level covariate")
    check_on_csv(entropy_slopes.main, SUB_FIELDS, ["sigma", "--within"],
                 ("| 15 -> 10 | 4 | +4.000 | 2.646 | 1.369 | 0.354 | 0.21 |",))
    print("ok: entropy_slopes.py --within parts the sub-fields' slopes between and within their fields")


if __name__ == "__main__":
    main()
