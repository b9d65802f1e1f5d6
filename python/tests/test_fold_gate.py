#!/usr/bin/env python3
"""Self-test of fold_gate.py on synthetic runs (run by CTest; exit code != 0 on failure).

Four runs, each a folder with results.csv and its log as scripts/results.sh writes them, the kept
setting first in the log, every measure of every gate worked out by hand:
  - building, tile 1: folds +0.004 +0.006 +0.005 (every gate opens), margin +0.0120 (2 descents);
  - road, tile 2: folds +0.012 0 0 (one fold alone: mean = SE, the SE gate shut; most folds do
    not gain), margin −0.0040 (1 descent), non-adaptive the same, top level at 12.5 cm/px whose
    lawnmower is 0.0020 below the curve;
  - vegetation, tile 3: folds +0.010 +0.008 −0.003 (a fold lost; mean > SE; most gain), margin
    −0.0200 (3 descents);
  - water, tile 4: folds 0 0 0 (no descent), margin 0.
A folder without runs and an option are refused.
"""
import os
import tempfile

from tool_output import check, check_refused, printed

from adaptseg_tools import fold_gate

HEADER = ("field,strategy,gsd_cm,miou_interest,miou_all,time_total,time_flight,time_segmentation,time_planning,"
          "images,front_margin,descents,altitude_changes,curve_front_margin\n")


def write_run(root, name, folds, adaptive, descents, top_gsd=15.0, top_margin=0.0):
    path = os.path.join(root, name)
    os.makedirs(path)
    with open(path + ".log", "w") as f:
        mean = sum(folds) / len(folds)
        per = " ".join(f"{v:+.4f}" for v in folds)
        f.write(f"           tried front-aware z=0: front margin {mean:+.4f}, 3 descents, per field {per}\n")
        f.write("           tried front-aware z=2: front margin +0.0000, 0 descents, per field +0.0000 +0.0000 +0.0000\n")
    with open(os.path.join(path, "results.csv"), "w") as f:
        f.write(HEADER)
        for g, m in ((15.0, 0.0 if top_gsd != 15.0 else top_margin), (12.5, top_margin if top_gsd == 12.5 else 0.0)):
            f.write(f"x,lawnmower,{g:.3f},0.5,0.5,100,100,0,0,4,{m:.6f},0,0,0\n")
        for strategy in ("nonadaptive", "adaptive"):
            f.write(f"x,{strategy},{top_gsd:.3f},0.5,0.5,100,100,0,0,4,{adaptive:.6f},{descents},0,0\n")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        write_run(tmp, "net-building-tile-1", (0.004, 0.006, 0.005), 0.012, 2)
        write_run(tmp, "net-road-tile-2", (0.012, 0.0, 0.0), -0.004, 1, top_gsd=12.5, top_margin=-0.002)
        write_run(tmp, "net-vegetation-tile-3", (0.010, 0.008, -0.003), -0.020, 3)
        write_run(tmp, "net-water-tile-4", (0.0, 0.0, 0.0), 0.0, 0)
        text = printed(fold_gate.main, [tmp])[1]
        want = [
            "| building | 1 | front-aware z=0 | +0.0050 | 0.0006 | 3 | 0 | +0.0120 (2) |",
            "| road | 2 | front-aware z=0 | +0.0040 | 0.0040 | 1 | 0 | -0.0040 (1) |",
            "| vegetation | 3 | front-aware z=0 | +0.0050 | 0.0040 | 2 | 1 | -0.0200 (3) |",
            "| water | 4 | front-aware z=0 | +0.0000 | 0.0000 | 0 | 0 | +0.0000 (0) |",
            # as flown: +0.012 −0.004 −0.020 0; below the floor: road and vegetation.
            "| as flown | 1 | -0.0020 | -0.0030 | 2 | 6 |",
            # mean > SE shuts road (its top level's lawnmower, −0.0020, not below) and water.
            "| mean > SE | 1 | -0.0010 | -0.0025 | 1 | 5 |",
            # no fold lost shuts vegetation: +0.012 −0.004 0 0.
            "| no fold lost | 1 | +0.0000 | +0.0020 | 1 | 3 |",
            # most folds gain opens building and vegetation alone, as mean > SE here.
            "| most folds gain | 1 | -0.0010 | -0.0025 | 1 | 5 |",
        ]
        for row in want:
            check(row in text, f"no row {row!r}:\n{text}")
        empty = os.path.join(tmp, "empty")
        os.makedirs(empty)
        check_refused(fold_gate.main, [empty], "no runs", "a folder without runs")
    check_refused(fold_gate.main, ["--help"], "Usage", "an option")
    print("ok: fold_gate.py replays each gate as worked out by hand")


if __name__ == "__main__":
    main()
