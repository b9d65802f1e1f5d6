#!/usr/bin/env python3
"""Self-test of cell_ceiling.py (run by CTest; exit code != 0 on failure).

1. A field whose slower lawnmower maps worse: its margins read the library's upper envelope, flat there until
   the curve climbs back through it.
2. One hand-made field, its three cells' margins after each, worked out by hand (the overhead charged once per
   region entered); the clairvoyant plan is the best prefix.
3. The top level a field's geometry flies: a finer one that is no slower replaces a coarser one.
4. Fixed plans on three hand-made fields: where every cell loses, each field keeps its top level alone
   (margin 0); where every cell gains, each descends into all its cells. A noisy ranking of correlation 1 is
   the perfect one; a rank correlation worked out by hand, with the gains and with another column; gains a line in an input ranked perfectly by the
   ridge fitted on the other fields (`learnt`).
5. main() on a hand-made model, cells and times: a row per field, the summary lines, --against, --sums, the overheads
   measured on a hand-made run's flown descents, or its candidates where none was flown (--overhead-from); its
   refusals (odd pairs, an unknown --rank or --against column, --noise out of (0, 1], cells of a field the model
   does not name).
6. Given the built adaptseg_mission (CTest passes it): tile 2's lawnmowers at 12.5 and 15 cm/px flown from
   the bundled field's geometry: four images each, 85.9 s and 102.4 s (the coarser one slower, so the fixed
   plans fly 12.5 there).
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml
from tool_output import check, check_refused, printed

from adaptseg_tools import REPO, cell_ceiling as cc


OVERHEAD = {5.0: 20.0}  # seconds per region entered, per finer GSD


def cell(region, gain, **extra):
    return {"region": str(region), "field_gain": gain, **extra}


def field(name="A", gains=(0.02, 0.05, -0.01), regions=(0, 0, 1)):
    f = cc.Field(name, {5.0: 0.5, 15.0: 0.3}, {5.0: (300.0, 30), 15.0: (100.0, 4)})
    f.cells[(15.0, 5.0)] = [cell(r, g, top_ambiguity=float(i)) for i, (r, g) in enumerate(zip(regions, gains))]
    return f


def envelope():
    # The 10 cm/px lawnmower (150 s) maps worse than the 15 cm/px one (100 s): the envelope stays at 0.3 until the
    # 10 -> 5 segment climbs through it (at 200 s), then follows the curve: 0.35 at 225 s, as front_margin reads it.
    f = cc.Field("D", {5.0: 0.5, 10.0: 0.2, 15.0: 0.3}, {5.0: (300.0, 30), 10.0: (150.0, 9), 15.0: (100.0, 4)})
    f.cells[(15.0, 5.0)] = [cell(0, 0.1)]
    check(f.top_margin(15.0) == 0.0 and math.isclose(f.top_margin(10.0), -0.1), "the top levels against the curve")
    # One cell: 100 s of top level, 115 s of overhead, 10 s an image: 225 s, mIoU 0.3 + 0.1.
    m = f.margins(15.0, 5.0, f.cells[(15.0, 5.0)], {5.0: 115.0})
    check(np.allclose(m, [0.4 - 0.35]), f"the margin at 225 s: {m}")
    print("ok: the curve's upper envelope, as front_margin reads it")


def margins():
    f = field()
    m = f.margins(15.0, 5.0, cc.ordered(f.cells[(15.0, 5.0)], "field_gain", None), OVERHEAD)
    # Best first: 0.05 (region 0), 0.02 (region 0), -0.01 (region 1); 10 s an image at 5 cm/px.
    # 1: t = 100 + 20 + 10 = 130, envelope 0.3 + 0.2 * 30 / 200 = 0.33, mIoU 0.35: +0.02.
    # 2: t = 140 (no new region), envelope 0.34, mIoU 0.37: +0.03.
    # 3: t = 100 + 40 + 30 = 170 (region 1 entered), envelope 0.37, mIoU 0.36: -0.01.
    check(np.allclose(m, [0.02, 0.03, -0.01]), f"margins {m}")
    check(math.isclose(cc.best_plan(f, "field_gain", OVERHEAD, None), 0.03), "the clairvoyant plan")
    # In the order of top_ambiguity (2, 1, 0): -0.01 first in region 1, then 0.05 and 0.02 in region 0.
    m = f.margins(15.0, 5.0, cc.ordered(f.cells[(15.0, 5.0)], "top_ambiguity", None), OVERHEAD)
    check(np.allclose(m, [0.3 - 0.01 - 0.33, 0.3 + 0.04 - (0.3 + 0.2 * 60 / 200), -0.01]), f"ranked margins {m}")
    lose = field(gains=(-0.01, -0.02, -0.03))
    check(cc.best_plan(lose, "field_gain", OVERHEAD, None) == 0.0, "a field where every cell loses: 0")
    print("ok: a hand-made field's margins and its clairvoyant plan")


def top_level():
    f = cc.Field("B", {5.0: 0.5, 12.5: 0.35, 15.0: 0.3}, {5.0: (300.0, 30), 12.5: (90.0, 4), 15.0: (100.0, 4)})
    f.cells[(15.0, 5.0)] = [cell(0, 0.01)]
    f.cells[(12.5, 5.0)] = [cell(0, 0.01)]
    check(f.top_for(15.0) == 12.5 and f.top_for(12.5) == 12.5, "the finer top level no slower is flown")
    f.times[12.5] = (110.0, 6)
    check(f.top_for(15.0) == 15.0, "a finer top level that is slower is not")
    print("ok: the top level the field's geometry flies")


def fixed():
    rng = np.random.default_rng(0)
    losing = [field(n, gains=(-0.01, -0.02, -0.03)) for n in "ABC"]
    for name, label, m in cc.fixed_plans(losing, "field_gain", OVERHEAD, rng):
        check(label == "top 15 alone" and m == 0.0, f"{name}: {label}, {m}")
    gaining = [field(n, gains=(0.2, 0.2, 0.2)) for n in "ABC"]
    for name, label, m in cc.fixed_plans(gaining, "field_gain", OVERHEAD, rng):
        # all three cells: t = 100 + 2 * 20 + 30 = 170, envelope 0.37, mIoU 0.3 + 0.6.
        check(label == "15 → 5, 100% of cells" and math.isclose(m, 0.9 - 0.37), f"{name}: {label}, {m}")
    mixed = [field(n, gains=g) for n, g in zip("ABC", [(0.05, -0.04, 0.01), (0.03, -0.02, 0.0), (0.04, 0.01, -0.05)])]
    realised = cc.with_noise(mixed, 1.0, rng)
    check(all(math.isclose(r, 1.0) for r in realised), f"correlation 1 realised {realised}")
    check(cc.fixed_plans(mixed, "noisy", OVERHEAD, rng) == cc.fixed_plans(mixed, "field_gain", OVERHEAD, rng),
          "a noisy ranking of correlation 1 is the perfect one")
    # field(): top_ambiguity 0, 1, 2 against gains 0.02, 0.05, -0.01 (ranks 1, 2, 0): correlation -0.5.
    check(math.isclose(cc.rank_correlation([field()], "top_ambiguity"), -0.5), "rank correlation")
    # Against another column: top_ambiguity 0, 1, 2 against relabelled 0.1, 0.3, 0.2 (ranks 0, 2, 1): 0.5.
    told = field()
    for c, r in zip(told.cells[(15.0, 5.0)], (0.1, 0.3, 0.2)):
        c["relabelled"] = r
    check(math.isclose(cc.rank_correlation([told], "top_ambiguity", "relabelled"), 0.5), "rank correlation, relabelled")
    # Gains a line in top_ambiguity on every field: the ridge fitted on the other fields ranks them perfectly.
    lines = [field(n, gains=tuple(0.01 * a + 0.003 * i for a in (2.0, 0.0, 1.0))) for i, n in enumerate("ABC")]
    for f in lines:
        for c, a in zip(f.cells[(15.0, 5.0)], (2.0, 0.0, 1.0)):
            c["top_ambiguity"], c["field_sigma"], c["top_gsd_cm"], c["sub_gsd_cm"] = a, 0.2, 15.0, 5.0
    cc.learn(lines)
    check(math.isclose(cc.rank_correlation(lines, "learnt"), 1.0), "the learnt ranking of a line")
    print("ok: fixed plans chosen on the other fields")


def run_main():
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        refs = [{"field": n, "gsd_cm": [5, 15], "miou": [0.5, 0.3]} for n in "ABC"]
        (tmp / "model.yaml").write_text(yaml.safe_dump({"interest": ["road"], "rule": {"reference": refs}}))
        gains = {"A": (0.02, 0.05, -0.01), "B": (0.03, -0.02, 0.0), "C": (0.04, 0.01, -0.05)}
        lines = ["field,region,top_gsd_cm,sub_gsd_cm,field_gain,top_ambiguity"]
        for n, g in gains.items():
            lines += [f"{n},{r},15,5,{v},{i}" for i, (r, v) in enumerate(zip((0, 0, 1), g))]
        (tmp / "cells.csv").write_text("\n".join(lines) + "\n")
        (tmp / "times.csv").write_text("field,gsd_cm,time_s,images\n" + "".join(
            f"{n},5,300,30\n{n},15,100,4\n" for n in "ABC"))
        args = [str(tmp / "model.yaml"), str(tmp / "cells.csv"), "--times", str(tmp / "times.csv")]
        rc, text = printed(cc.main, args + ["--rank", "field_gain,top_ambiguity,learnt", "--noise", "1", "--reps", "1"])
        check(rc is None, f"main returned {rc}")
        # A as in margins(); B's best first cell only meets the curve (0.33 at 130 s); C's first +0.01. The rank
        # correlations of top_ambiguity (0, 1, 2) with the gains: A -0.5, B -0.5, C -1 (mean -0.67).
        for row in ("| road | A | +0.0300 |", "| road | B | +0.0000 |", "| road | C | +0.0100 |"):
            check(row in text, f"'{row}' missing:\n{text}")
        for head in ("- clairvoyant: 2 of 3", "- random order, best stop:", "- fixed plan, field_gain:",
                     "- fixed plan, top_ambiguity:", "(correlation 1, rank correlation within a field 1.00)",
                     "- fixed plan, learnt:", "| class | top_ambiguity | learnt |", "| road | -0.67 |"):
            check(head in text, f"'{head}' missing:\n{text}")
        print("ok: main() on a hand-made calibration")
        rc, text = printed(cc.main, args + ["--rank", "top_ambiguity", "--against", "top_ambiguity"])
        check("Rank correlation with the cells' top_ambiguity within a field" in text and "| road | +1.00 |" in text,
              f"--against: a column against itself:\n{text}")
        check_refused(cc.main, args + ["--against", "nothing"], "--against: no column nothing", "an unknown target")
        rc, text = printed(cc.main, args + ["--sums", "--rank", "random"])
        check("| road | B | 15 → 5 | 3 | +0.0100 |" in text, f"--sums: B's cells sum to 0.03 - 0.02 + 0:\n{text}")
        # Flown descents: 50 s for 3 images and 40 s for 1 at 10 s an image: 20 and 30 s beyond (median 25).
        run = tmp / "run"
        run.mkdir()
        (run / "results.csv").write_text("field,strategy,gsd_cm,time_total,images\nA,lawnmower,5,300,30\n"
                                         "A,lawnmower,15,100,4\nA,adaptive,15,150,7\n")
        # A candidate not taken at 5 (9 images in 99 s: 9 s beyond) does not count where descents were flown;
        # at 15 none was flown: its candidate (1 image in 30 s at 25 s an image: 5 s beyond) gives the overhead.
        (run / "decisions.csv").write_text("strategy,action,gsd_cm,images,extra_time_s\nadaptive,descend,5,3,50\n"
                                           "adaptive,descend,5,1,40\nadaptive,continue,5,9,99\nnonadaptive,descend,5,1,90\n"
                                           "adaptive,continue,15,1,30\nadaptive,continue,,,\n")
        got = cc.measured_overheads([run])
        check(got == {5.0: {"flown": [20.0, 30.0], "candidates": [9.0]}, 15.0: {"flown": [], "candidates": [5.0]}},
              f"overheads {got}")
        rc, text = printed(cc.main, args + ["--overhead-from", str(run), "--rank", "random"])
        check("overhead at 5 cm/px: median +25.0 s over 2 flown descents" in text
              and "overhead at 15 cm/px: median +5.0 s over 1 candidates not taken (none flown)" in text,
              f"--overhead-from:\n{text}")
        print("ok: overheads measured on flown descents")
        check_refused(cc.main, args[:1], "MODEL CELLS pairs", "a model without its cells")
        check_refused(cc.main, args + ["--rank", "top_nothing"], "no column top_nothing", "an unknown column")
        check_refused(cc.main, args + ["--noise", "0"], "each in (0, 1]", "a correlation of 0")
        (tmp / "cells.csv").write_text(lines[0] + "\nD,0,15,5,0.01,0\n")
        check_refused(cc.main, args, "field D is not among", "cells of a field the model does not name")
        print("ok: the refusals")


def flown(mission: Path):
    times = cc.Times(None, mission, REPO / "examples" / "data")
    model = {"calibration": {"segmentation_time_s": 0.1}, "timing": {"max_speed_mps": 2, "max_accel_mps2": 2},
             "camera": {"image_width_px": 480, "image_height_px": 360, "sensor_width_mm": 4.8, "focal_length_mm": 5.5}}
    got = times("dubai-tile-2", [12.5, 15.0], model)
    check(got[12.5][1] == 4 and got[15.0][1] == 4, f"images {got}")
    check(abs(got[12.5][0] - 85.9) < 0.05 and abs(got[15.0][0] - 102.4) < 0.05, f"times {got}")
    print(f"ok: tile 2's lawnmowers flown by adaptseg_mission: {got}")


def main():
    envelope()
    margins()
    top_level()
    fixed()
    run_main()
    if len(sys.argv) > 1:
        flown(Path(sys.argv[1]))
    print("cell_ceiling: all checks passed")


if __name__ == "__main__":
    main()
