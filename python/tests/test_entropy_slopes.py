#!/usr/bin/env python3
"""Self-test of entropy_slopes.py --covariates and --within on synthetic cell-samples CSVs (run by
CTest; exit code != 0 on failure).

Four fields of one cell each (input sigma 1, field share and sigma 1, so the normalised gain is
the field gain and each field's own slope its cell's gain): a, b, c, d at mean top-level entropy
0.2, 0.4, 0.6, 0.8 with slopes -1, 1, 3, 5. The entropy orders the slopes exactly (rank correlation
+1.00); the line fitted on the other three forecasts b, c and d with their sign and a, whose
entropy lies below the others' range (read at 0.4: +1), with the wrong one: 3 of 4. Sigma and the
field's sigma do not spread: no correlation, and the mean of the others' slopes forecast for
each, right but for a.

--within on sub-fields t1[a], t1[b], t2[a], t2[b] of six cells each (input 1, so a sub-field's slope
is the mean of its cells' gains). LOCAL: each sub-field's cells all gain its slope, 1, 3, 5, 7: the
sub-fields differ within their fields (pooled variance 2) where cells dealt at random differ far
less, and no deal of the 200 spreads as far (p = 1/201); between the fields the means 2 and 6 spread
8, less 2 / 2, 7 (sd 2.646). NONE: every sub-field of t1 holds gains 1 and 3 alike (t2: 5 and 7), so
the sub-fields do not differ at all and every deal spreads at least as far (p = 1, within 0); between,
8 (sd 2.828); local share 0. A fifth sub-field t2[c] whose cells' input is 0 has no slope and is left out.
"""
import sys

from tool_output import check_on_csv

from adaptseg_tools import entropy_slopes

CELLS = """field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,field_gain,top_sigma,top_entropy
a,0,15,10,100,1,1,-1,1,0.2
b,0,15,10,100,1,1,1,1,0.4
c,0,15,10,100,1,1,3,1,0.6
d,0,15,10,100,1,1,5,1,0.8
"""

HEADER = "field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,field_gain,top_sigma,top_entropy\n"


def sub_fields(gains):
    """A cells CSV of sub-fields {name: [gain of each cell]} (input 1), and t2[c] of input 0."""
    rows = [f"{n},{i},15,10,100,1,1,{g},1,0.5" for n, gs in gains.items() for i, g in enumerate(gs)]
    return HEADER + "\n".join(rows + ["t2[c],0,15,10,100,1,1,9,0,0.5"]) + "\n"


LOCAL = sub_fields({"t1[a]": [1] * 6, "t1[b]": [3] * 6, "t2[a]": [5] * 6, "t2[b]": [7] * 6})
NONE = sub_fields({"t1[a]": [1, 3] * 3, "t1[b]": [3, 1] * 3, "t2[a]": [5, 7] * 3, "t2[b]": [7, 5] * 3})


def within_row(csv_text):
    """The --within row of 15 -> 10 as numbers: sub-fields, mean, between, within, sampling, p."""
    text = check_on_csv(entropy_slopes.main, csv_text, ["sigma", "--within"], ("| 15 -> 10 |",))
    row = next(line for line in text.splitlines() if line.startswith("| 15 -> 10 |"))
    cells = [c.strip() for c in row.strip("|").split("|")][1:]
    return [float(c) for c in cells[:6]], cells[6]


def main():
    check_on_csv(entropy_slopes.main, CELLS, ["sigma", "--covariates"],
                 ("| top -> descent [cm/px] | sigma | entropy | field_sigma |",
                  "| 15 -> 10 | no spread (3/4) | +1.00 (3/4) | no spread (3/4) |"))
    print("ok: entropy_slopes.py --covariates ranks the fields' slopes by each field-level covariate")
    (n, mean, between, within, sampling, p), share = within_row(LOCAL)
    if (n, mean, round(between, 3), round(p, 3)) != (4, 4.0, 2.646, 0.005) or not within > sampling or share == "0.00":
        sys.exit(f"--within on sub-fields that differ: {n}, {mean}, {between}, {within}, {sampling}, {p}, {share}")
    (n, mean, between, within, sampling, p), share = within_row(NONE)
    if (n, mean, round(between, 3), within, p, share) != (4, 4.0, 2.828, 0.0, 1.0, "0.00"):
        sys.exit(f"--within on sub-fields alike: {n}, {mean}, {between}, {within}, {sampling}, {p}, {share}")
    print("ok: entropy_slopes.py --within parts the sub-fields' slopes between and within their fields")


if __name__ == "__main__":
    main()
