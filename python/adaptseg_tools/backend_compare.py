"""Which backend gives the better map per second: runs of the same experiment (field, class of
interest, calibration) flown with different segmentation backends, each measured against every
backend's lawnmower curve. A NET with no run under ROOT is left out (named on standard error); with
fewer than two flown, it says so and compares nothing.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.backend_compare ROOT NET [NET...]

ROOT holds adaptseg_evaluate output directories named NET-<class>-fly<tile> (bash
scripts/results.sh network). For every (class, tile) that all NETs flew, and every NET, the
adaptive mission's IoU of the class of interest and its time; then its front margin against each
NET's lawnmower curve (the upper envelope of (time, IoU) over the lawnmower GSDs, linearly
interpolated at the mission's time, flat beyond the ends: adaptseg::front_margin). The first
NET's row against its own curve is its usual margin; against another NET's curve it says whether
flying NET beats anything the other backend can fly in the same time. A last table does the same
for the lawnmowers themselves: each NET's lawnmower at each GSD against the best other NET's
curve at its time.
"""
import os
import statistics
import sys
from collections import defaultdict

from .lawnmower_envelope import envelope_at, upper_envelope
from .sweep_table import read_csv


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    root, nets = sys.argv[1], sys.argv[2:]
    runs = defaultdict(dict)
    for name in sorted(os.listdir(root)):
        path = os.path.join(root, name, "results.csv")
        for net in nets:
            if name.startswith(net + "-") and os.path.isfile(path):
                case = name[len(net) + 1:]
                if "-fly" in case and not any(n != net and name.startswith(n + "-") and len(n) > len(net) for n in nets):
                    runs[case][net] = read_csv(path)
    # A backend with no run under ROOT (scripts/results.sh network with NETS=... flies a subset) is
    # left out, so that the others are still compared; with fewer than two there is nothing to.
    flown = [n for n in nets if any(n in by_net for by_net in runs.values())]
    if len(flown) < len(nets):
        print(f"no runs of {[n for n in nets if n not in flown]} under {root}: left out", file=sys.stderr)
    nets = flown
    if len(nets) < 2:
        print(f"fewer than two backends flown under {root} ({nets}): nothing to compare")
        return
    cases = [c for c in sorted(runs) if all(n in runs[c] and any(r["strategy"] == "adaptive" for r in runs[c][n])
                                            for n in nets)]
    if not cases:
        sys.exit(f"no (class, tile) flown by all of {nets} under {root}")
    curves = {c: {n: upper_envelope([(float(r["time_total"]), float(r["miou_interest"]))
                               for r in runs[c][n] if r["strategy"] == "lawnmower"]) for n in nets} for c in cases}
    print("Adaptive missions: IoU of the class of interest (time [s]), and front margin against each "
          "backend's lawnmower curve\n")
    print("| run | backend | IoU (time) | " + " | ".join(f"vs {n} curve" for n in nets) + " |")
    print("| --- | --- | ---: | " + " | ".join("---:" for _ in nets) + " |")
    margins = defaultdict(list)
    for c in cases:
        for n in nets:
            a = next(r for r in runs[c][n] if r["strategy"] == "adaptive")
            t, m = float(a["time_total"]), float(a["miou_interest"])
            row = []
            for o in nets:
                d = m - envelope_at(curves[c][o], t)
                margins[(n, o)].append(d)
                row.append(f"{d:+.4f}")
            print(f"| {c} | {n} | {m:.4f} ({t:.0f}) | " + " | ".join(row) + " |")
    print("\n| backend | " + " | ".join(f"vs {o}: > 0, median, mean" for o in nets) + " |")
    print("| --- | " + " | ".join("---:" for _ in nets) + " |")
    for n in nets:
        cells = []
        for o in nets:
            v = margins[(n, o)]
            cells.append(f"{sum(x > 0 for x in v)}/{len(v)}, {statistics.median(v):+.4f}, {statistics.mean(v):+.4f}")
        print(f"| {n} | " + " | ".join(cells) + " |")
    print("\nLawnmowers: each backend's lawnmower at each GSD against the best other backend's curve at "
          "its time (> 0: better map for the time than any other backend can fly)\n")
    print("| backend | GSD [cm/px] | runs | > 0 | median | mean |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for n in nets:
        by_gsd = defaultdict(list)
        for c in cases:
            for r in runs[c][n]:
                if r["strategy"] != "lawnmower":
                    continue
                t, m = float(r["time_total"]), float(r["miou_interest"])
                best_other = max(envelope_at(curves[c][o], t) for o in nets if o != n)
                by_gsd[float(r["gsd_cm"])].append(m - best_other)
        for g in sorted(by_gsd):
            v = by_gsd[g]
            print(f"| {n} | {g:.1f} | {len(v)} | {sum(x > 0 for x in v)} | {statistics.median(v):+.4f} | "
                  f"{statistics.mean(v):+.4f} |")


if __name__ == "__main__":
    main()
