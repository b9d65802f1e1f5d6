"""How far a training field's fold margin moves with which other fields its model was fitted on.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fold_composition [--z Z] CALIBRATION.log ROWDIR
       PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fold_composition --looks ROWDIR

CALIBRATION.log is adaptseg_calibrate's output for one class of interest on all six Dubai tiles
(`bash scripts/loto.sh decision` writes out/loto/decision-CLASS.log): each setting's margin on
every field, the field flown with the model fitted on the other five. ROWDIR holds the same
class's 24 runs of `scripts/results.sh loto` (adaptseg_evaluate logs ...-CLASS-tile-K.log):
test tile K's calibration flew each of its five training fields with the model fitted on the
other four. So each field j is flown, per setting, by six models: one fitted on the five other
tiles, and five fitted on four of them (one per left-out test tile K != j), the same in all but
which one other field each leaves out.

Prints, as Markdown, per slope pooling at confidence level Z (default 0, the setting that
descends most) and per field: its margin under the five-field model, under each four-field
model (by the tile K it lacks), and their range; then per pooling the mean margin of each kind
of model. A field whose margin swings by more than the differences the search's choices turn on
(fold means of a few thousandths) is flown by a decision that hangs on which fields calibrated it.

--looks ROWDIR: a row flown with --calibration-network-each, each of the five training tiles
segmented by several networks that never saw it (their looks adjacent in each setting's fold
margins, under one model fitted on the other tiles' looks): per class, over every setting and
training tile where a look's margin is not 0, how far the other looks' margins differ from the
first's (pairs; differing by more than 0.005; of opposite signs beyond 0.001; the mean absolute
difference; their correlation). What the network's own draw on a field does to its fold margin.
"""
import argparse
import os
import re
import statistics
import sys

from .fold_choice import tried_settings
from .fold_table import read

SETTING = re.compile(r"^front-aware z=(\S+) slopes=([a-z-]+)(?: finest=(\S+))?$")
RUN = re.compile(r"-(building|road|vegetation|water)-tile-([1-9])\.log$")
TILES = [1, 2, 3, 4, 5, 6]
TRAINING_TILES = len(TILES) - 1


def settings_at(settings, z):
    """{pooling: fold margins} of the (name, mean, descents, folds) `settings` at `z`, no limit."""
    out = {}
    for name, *_, folds in settings:
        m = SETTING.match(name)
        if m and float(m.group(1)) == z and m.group(3) in (None, "any"):
            out[m.group(2)] = folds
    return out


def six_field(path, z):
    """{pooling: [margin of tile 1..6]} of the calibration on all six tiles, at `z`."""
    out = settings_at([(name, mean, descents, folds) for name, _, mean, descents, folds in read(path)], z)
    bad = [p for p, v in out.items() if len(v) != len(TILES)]
    if not out or bad:
        sys.exit(f"{path}: no setting at z={z} with a margin for each of six fields (adaptseg_calibrate's "
                 "output on the six tiles, with slope poolings?)")
    return out


def row_of(directory, cls, z):
    """{(pooling, test tile K): [margin of each training tile, tiles in order without K]}."""
    out = {}
    for name in os.listdir(directory):
        m = RUN.search(name)
        if m and m.group(1) == cls:
            for pooling, folds in settings_at(tried_settings(os.path.join(directory, name)), z).items():
                out[(pooling, int(m.group(2)))] = folds
    if not out:
        sys.exit(f"no {cls} run's log with settings at z={z} in {directory}")
    return out


def look_pairs(directory):
    """{class: [(first look's margin, another look's margin)]} over every run, setting and
    training tile of a row calibrated with several looks per tile."""
    out = {}
    for name in sorted(os.listdir(directory)):
        m = RUN.search(name)
        if not m:
            continue
        for _, _, _, folds in tried_settings(os.path.join(directory, name)):
            looks = len(folds) // TRAINING_TILES
            if looks < 2 or len(folds) % TRAINING_TILES:
                sys.exit(f"{name}: {len(folds)} fold margins, not several looks of each of "
                         f"{TRAINING_TILES} training tiles (a row flown with --calibration-network-each?)")
            for t in range(TRAINING_TILES):
                group = folds[t * looks:(t + 1) * looks]
                out.setdefault(m.group(1), []).extend(
                    (group[0], v) for v in group[1:] if group[0] != 0.0 or v != 0.0)
    if not out:
        sys.exit(f"no run's log (...-CLASS-tile-K.log) in {directory}")
    return out


def print_looks(directory):
    pairs = look_pairs(directory)
    print("| class | pairs of looks | differ by > 0.005 | opposite signs beyond 0.001 | mean abs difference "
          "| correlation |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for cls in sorted(pairs) + ["all"]:
        p = [x for v in pairs.values() for x in v] if cls == "all" else pairs[cls]
        if not p:
            continue
        a, b = [x for x, _ in p], [y for _, y in p]
        far = sum(abs(x - y) > 0.005 for x, y in p)
        flips = sum((x > 0.001 and y < -0.001) or (x < -0.001 and y > 0.001) for x, y in p)
        mad = statistics.mean(abs(x - y) for x, y in p)
        corr = (f"{statistics.correlation(a, b):+.2f}" if len(p) >= 2 and len(set(a)) > 1 and len(set(b)) > 1
                else "—")
        print(f"| {cls} | {len(p)} | {far} | {flips} | {mad:.4f} | {corr} |")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--z", type=float, default=0.0)
    parser.add_argument("--looks", metavar="ROWDIR", help="a row flown with --calibration-network-each")
    parser.add_argument("calibration", nargs="?")
    parser.add_argument("row", nargs="?")
    args = parser.parse_args(argv)
    if args.looks:
        if args.calibration:
            sys.exit("--looks takes the row alone")
        print_looks(args.looks)
        return
    if not args.row:
        sys.exit("expected CALIBRATION.log ROWDIR (or --looks ROWDIR)")
    m = re.search(r"decision-(building|road|vegetation|water)\.log$", args.calibration)
    if not m:
        sys.exit(f"{args.calibration}: expected a decision-CLASS.log of scripts/loto.sh decision")
    cls = m.group(1)
    six = six_field(args.calibration, args.z)
    row = row_of(args.row, cls, args.z)
    for pooling, five in six.items():
        print(f"\n{cls}, slopes={pooling}, z={args.z:g}\n")
        print("| field | five-field model | four-field models (without tile K) | range |")
        print("| ---: | ---: | --- | ---: |")
        fours_all = []
        for j in TILES:
            fours = []
            for k in TILES:
                per = row.get((pooling, k))
                if k == j or per is None:
                    continue
                fours.append((k, per[[t for t in TILES if t != k].index(j)]))
            fours_all += [v for _, v in fours]
            values = [five[j - 1]] + [v for _, v in fours]
            cells = ", ".join(f"{v:+.4f} (K={k})" for k, v in fours)
            print(f"| {j} | {five[j - 1]:+.4f} | {cells} | {max(values) - min(values):.4f} |")
        if fours_all:
            print(f"\nmean: five-field {statistics.mean(five):+.4f}, four-field {statistics.mean(fours_all):+.4f}")


if __name__ == "__main__":
    main(sys.argv[1:])
