#!/usr/bin/env python3
"""Self-test of loto_targets.py on synthetic runs (run by CTest; exit code != 0 on failure).

Four runs of a configuration and the oracle's of the same folds, named as scripts/results.sh
names them, with margins chosen so that every target's count is known: two runs above +0.001,
one below max(non-adaptive, 0) - 0.002, three descents whose forecasts and realised gains are
proportional (correlation +1), and the oracle above 0 in two of the three runs where some
strategy beats the curve. The same four runs flown again (a second seed's networks) pool with
the first as one configuration of eight runs, and a folder of other runs is refused for it.
Side by side the two flights reach +0.001 together in two runs of four.
"""
import os
import sys
import tempfile

from tool_output import check_refused, printed

from adaptseg_tools import loto_targets

RESULTS = "strategy,field,front_margin,descents,time_total,altitude_changes\n"
DECISIONS = "strategy,action,forecast_field_gain,realised_field_gain\n"


def write_run(root, name, adaptive, nonadaptive, descents=()):
    d = os.path.join(root, name)
    os.makedirs(d)
    field = "dubai-tile-" + name.rsplit("-", 1)[1]
    with open(os.path.join(d, "results.csv"), "w") as f:
        f.write(RESULTS)
        f.write(f"lawnmower,{field},0,0,100,0\n")
        f.write(f"adaptive,{field},{adaptive},{len(descents)},120,{2 * len(descents)}\n")
        f.write(f"nonadaptive,{field},{nonadaptive},0,100,0\n")
    with open(os.path.join(d, "decisions.csv"), "w") as f:
        f.write(DECISIONS)
        for forecast, realised in descents:
            f.write(f"adaptive,descend,{forecast},{realised}\n")
        f.write("adaptive,stay,,\n")


def check_targets(argv, want, row, what):
    """Runs loto_targets on `argv` and exits unless its summary row's cells are `want` (label,
    runs, > +0.001, median, mean, below, descents, correlation, oracle where beatable) and its
    per-run rows include `row` (`what`: that row, in the message)."""
    text = printed(loto_targets.main, argv)[1]
    lines = text.splitlines()
    summary = [c.strip() for c in lines[2].strip("|").split("|")]
    if summary != want:
        sys.exit(f"summary {summary}, want {want}\n{text}")
    if row not in lines:
        sys.exit(f"no per-run row for {what}:\n{text}")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        loto, oracle = os.path.join(tmp, "loto"), os.path.join(tmp, "oracle")
        write_run(loto, "mobilenetv2-loto-building-tile-1", 0.004, 0.0, [(0.01, 0.02), (0.02, 0.04)])
        write_run(loto, "mobilenetv2-loto-road-tile-1", 0.0015, 0.0, [(0.03, 0.06)])
        write_run(loto, "mobilenetv2-loto-water-tile-2", -0.003, -0.0005)  # below max(-0.0005, 0) - 0.002
        write_run(loto, "mobilenetv2-loto-water-tile-3", 0.0007, 0.0)
        write_run(oracle, "dubai-building-tile-1", 0.01, 0.01)
        write_run(oracle, "dubai-road-tile-1", -0.001, -0.001)  # beatable (loto's +0.0015), oracle not > 0
        write_run(oracle, "dubai-water-tile-2", 0.0, 0.0)  # nobody beats the curve here
        write_run(oracle, "dubai-water-tile-3", 0.002, 0.002)
        check_targets(["--oracle", oracle, f"base={loto}"],
                      ["base", "4", "2", "+0.0011", "+0.0008", "1", "3", "+1.00", "2 of 3"],
                      "| water | 2 | -0.0030 (0) | +0.0000 (0) |", "water on tile 2")
        # Pooled with a second flight of the same four runs: eight runs, each counted once.
        again = os.path.join(tmp, "again")
        write_run(again, "mobilenetv2-loto-building-tile-1", -0.001, 0.0, [(0.01, 0.01)])
        write_run(again, "mobilenetv2-loto-road-tile-1", 0.003, 0.0, [(0.02, 0.04)])
        write_run(again, "mobilenetv2-loto-water-tile-2", 0.0, 0.0)
        write_run(again, "mobilenetv2-loto-water-tile-3", 0.0005, 0.0)
        # margins 0.004 0.0015 -0.003 0.0007 / -0.001 0.003 0 0.0005: three above, median
        # +0.0006, mean +0.0007, one below (water 2 of the first), five descents; beatable in both
        # flights: building 1 and water 3 (the oracle's) and road 1, the oracle above 0 in four.
        check_targets(["--oracle", oracle, f"both={loto}+{again}"],
                      ["both", "8", "3", "+0.0006", "+0.0007", "1", "5", "+0.98", "4 of 6"],
                      "| road | 1 | +0.0015 (1) / +0.0030 (1) | -0.0010 (0) |", "pooled road on tile 1")
        # Side by side, each run's best over the two: building 1 (+0.004) and road 1 (+0.003)
        # above +0.001, water 2 (0) and water 3 (+0.0007) in none.
        text = printed(loto_targets.main, [f"base={loto}", f"again={again}"])[1]
        want = ("any configuration above +0.001: 2 of 4 runs (each run's best adaptive margin over "
                "the configurations); in none: water 2, water 3")
        if want not in text.splitlines():
            sys.exit(f"no line {want!r}:\n{text}")
        if "any configuration" in printed(loto_targets.main, [f"base={loto}"])[1]:
            sys.exit("one configuration printed what several reach together")
        other = os.path.join(tmp, "other")
        write_run(other, "mobilenetv2-loto-building-tile-2", 0.0, 0.0)
        check_refused(loto_targets.main, [f"x={loto}+{other}"], "other runs", "a pool of different runs")
        # A folder without runs named ...-CLASS-tile-K is refused, naming it.
        empty = os.path.join(tmp, "empty")
        os.makedirs(empty)
        check_refused(loto_targets.main, [f"x={empty}"], "no runs named", "an empty folder")
    print("ok: loto_targets.py counts every target")


if __name__ == "__main__":
    main()
