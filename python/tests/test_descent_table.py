#!/usr/bin/env python3
"""Self-test of descent_table.py's plain table, --curve, --hindsight (--gsd, --max-extra), --images
and --relabelled on a synthetic run (run by CTest; exit code != 0 on failure).

Each descent's row: its gains, pixels and the change of its region's σ. One field whose
lawnmowers map L at 0.50 in 100 s and 0.60 in 200 s (the real curve rises 0.001 per second),
flown from the first by a mission with two descents: one gains 0.02 in 10 s (it beats the
curve), the other 0.001 in 20 s (it does not). In hindsight the first alone ends +0.0100 above
the curve (0.52 at 110 s against 0.51), both together −0.0090; the first's real rise over its
seconds is 0.0100, against a predicted 0.0040. The first relabels twice its forecast share, the
second half of it: log ratios ±0.693, variance 0.961 within the run.
"""
import contextlib
import io
import os
import sys
import tempfile

from tool_output import printed

from adaptseg_tools import descent_table

RESULTS = """field,strategy,gsd_cm,miou_interest,time_total,front_margin
f,lawnmower,15,0.50,100,0
f,lawnmower,10,0.60,200,0
f,adaptive,15,0.521,130,-0.009
"""
COLUMNS = ("field,strategy,decision,action,gsd_cm,images,extra_time_s,forecast_field_gain,realised_field_gain,"
           "realised_region_delta_miou,realised_delta_tp,realised_delta_fp,forecast_curve_rise,forecast_end_s,"
           "sigma,observed_sigma_sub,forecast_relabelled_interest,observed_relabelled_interest\n")
DECISIONS = COLUMNS + """f,adaptive,0,descend,10,2,10,0.015,0.02,-0.05,100,-10,0.004,110,0.10,0.12,0.1,0.2
f,adaptive,1,continue,,,,,,,,,,,0.2,,,
f,adaptive,2,descend,10,2,20,0.006,0.001,-0.01,5,3,0.005,130,0.30,0.25,0.1,0.05
"""
# Per image: a top-level image (σ 0.10, truth 0.05), a descent of two images under it, one that
# sees what the ground truth shows (σ 0.20, truth 0.16: jump +0.10) and one that writes the class
# where it is absent (σ 0.60, truth 0.00: jump +0.50); the nonadaptive strategy's row is left out.
PER_IMAGE = """field,strategy,gsd_cm,image,level,image_gsd_cm,sigma,image_miou_interest,image_miou_all,truth_sigma
f,nonadaptive,15,0,0,15,0.9,0,0,0.9
f,nonadaptive,15,1,1,10,0.1,0,0,0.9
f,adaptive,15,0,0,15,0.10,0,0,0.05
f,adaptive,15,1,1,10,0.20,0,0,0.16
f,adaptive,15,2,1,10,0.60,0,0,0.00
"""


def table(args):
    return printed(descent_table.main, args)[1]


def main():
    with tempfile.TemporaryDirectory() as tmp:
        run = os.path.join(tmp, "run")
        os.makedirs(run)
        with open(os.path.join(run, "results.csv"), "w") as f:
            f.write(RESULTS)
        with open(os.path.join(run, "decisions.csv"), "w") as f:
            f.write(DECISIONS)
        with open(os.path.join(run, "per_image.csv"), "w") as f:
            f.write(PER_IMAGE)
        # Each descent: gains, what it changed in pixels, and the region's σ after it minus before.
        plain = table([run])
        for want in ("| run | 0 | 10 | 2 | +0.0150 | +0.0200 | +0.0500 | +100 | -10 | +0.020 |",
                     "| run | 2 | 10 | 2 | +0.0060 | +0.0010 | +0.0100 | +5 | +3 | -0.050 |"):
            if want not in plain:
                sys.exit(f"table: no row {want}:\n{plain}")
        if "false positives added in 1 descents, misses corrected (ΔTP > 0) in 2" not in plain:
            sys.exit(f"table summary:\n{plain}")
        # With the gain inside the region (adaptseg_evaluate since 2026-12-06): one more column,
        # and how much of the realised gain came from where the images overhang the region.
        inside = os.path.join(tmp, "inside")
        os.makedirs(inside)
        with open(os.path.join(inside, "decisions.csv"), "w") as f:
            lines = DECISIONS.splitlines()
            f.write(lines[0] + ",realised_field_gain_region\n" + lines[1] + ",0.012\n" + lines[2] + ",\n" +
                    lines[3] + ",-0.002\n")
        split = table([inside])
        if "| inside | 0 | 10 | 2 | +0.0150 | +0.0200 | +0.0120 | +0.0500 | +100 | -10 | +0.020 |" not in split:
            sys.exit(f"table with the gain inside the region: no row for the first descent:\n{split}")
        if "realised +0.0100 of +0.0210 in all (where the images overhang: +0.0110)" not in split:
            sys.exit(f"table with the gain inside the region: summary:\n{split}")
        if "| 10 | 2 | 2 | +0.0210 | +0.0210 | +0.0100 |" not in split:
            sys.exit(f"table with the gain inside the region: the sums of the two 10 cm/px descents:\n{split}")
        if "| 10 | 2 | 2 | +0.0210 | +0.0210 |" not in plain or "Σ inside" in plain:
            sys.exit(f"table: the sums of the two 10 cm/px descents, without the gain inside the region:\n{plain}")
        if "of which inside the region" in plain:
            sys.exit("table: a column for the gain inside the region where decisions.csv has none")
        hindsight = table(["--hindsight", run])
        if "| run | 2 | -0.0090 | 1 | +0.0100 |" not in hindsight:
            sys.exit(f"hindsight: the first descent alone should end +0.0100 above the curve:\n{hindsight}")
        if "1 runs: 0 above +0.001 as flown, 1 with their best descents only" not in hindsight:
            sys.exit(f"hindsight summary:\n{hindsight}")
        # Both descents are to 10 cm/px: alone they end where the mission did.
        alone = table(["--hindsight", "--gsd", "10", run])
        if "| run | 2 | -0.0090 | 1 | +0.0100 | -0.0090 |" not in alone:
            sys.exit(f"hindsight --gsd 10: the descents to 10 cm/px alone should end at -0.0090:\n{alone}")
        if "| run | 2 | -0.0090 | 1 | +0.0100 | +0.0000 |" not in table(["--hindsight", "--gsd", "5", run]):
            sys.exit("hindsight --gsd 5: no descent to 5 cm/px should leave the top-level lawnmower, margin 0")
        # The first descent took 10 s, the second 20 s: a cap of 10 s keeps the first alone.
        capped = table(["--hindsight", "--max-extra", "10", run])
        if "| run | 2 | -0.0090 | 1 | +0.0100 | +0.0100 |" not in capped:
            sys.exit(f"hindsight --max-extra 10: the first descent alone should end at +0.0100:\n{capped}")
        if "1 with their descents of at most 10 s alone" not in capped:
            sys.exit(f"hindsight --max-extra summary:\n{capped}")
        both = table(["--hindsight", "--gsd", "10", "--max-extra", "5", run])
        if "| run | 2 | -0.0090 | 1 | +0.0100 | +0.0000 |" not in both:
            sys.exit(f"hindsight --gsd 10 --max-extra 5: no descent is that short, margin 0:\n{both}")
        for wrong in (["--max-extra", "10", run], ["--hindsight", "--max-extra", "-1", run]):
            try:
                with contextlib.redirect_stderr(io.StringIO()):
                    descent_table.main(wrong)
                sys.exit(f"{wrong}: should be refused")
            except SystemExit as e:
                if e.code != 2:
                    raise
        curve = table(["--curve", run])
        # decision, GSD, extra time, end, forecast gain, predicted rise, real rise, margins
        want = "| run | 0 | 10 | 10.0 | 110.0 | +0.0150 | +0.0040 | +0.0100 | +0.0110 | +0.0100 |"
        if want not in curve:
            sys.exit(f"curve: no row {want}:\n{curve}")
        if "1 of 2 gained more than the real curve rose in their seconds" not in curve:
            sys.exit(f"curve summary:\n{curve}")
        # The second descent: forecast 0.006 − 0.005, realised 0.001 − 0.020 over [110, 130] s.
        if "margins: forecast +0.0120 in all against realised -0.0090" not in curve:
            sys.exit(f"curve margins:\n{curve}")
        images = table(["--images", run])
        rows = [line for line in images.splitlines() if line.startswith("| run |") and "σ" not in line]
        if rows != ["| run | 2 | 10 | 0.600 | 0.100 | +0.500 | 0.000 | 0.050 |",
                    "| run | 1 | 10 | 0.200 | 0.100 | +0.100 | 0.160 | 0.050 |"]:
            sys.exit(f"images: the two descent images, largest jump first:\n{images}")
        if "jump above 0.2: 1 of 2 descent images, of which 1 with a ground-truth rise below half the jump" not in images:
            sys.exit(f"images summary:\n{images}")
        relabelled = table(["--relabelled", run])
        if "| run | 2.00 / 1.33, 0.50 / 0.17 |" not in relabelled:
            sys.exit(f"relabelled: the run's two ratios:\n{relabelled}")
        if "2 descents: variance of log(relabelled / forecast) 0.961 over all, 0.961 within the runs" not in relabelled:
            sys.exit(f"relabelled summary:\n{relabelled}")
    print("ok: descent_table.py sets each descent against the real curve and finds the best in hindsight")


if __name__ == "__main__":
    main()
