"""The training folds of calibrations that differ in one choice, side by side.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fold_table DIR

DIR holds adaptseg_calibrate outputs named RUN.CHOICE.txt (written by `bash scripts/results.sh
all-tiles`: RUN a network or the oracle and a class, CHOICE e.g. a slope pooling tried alone).
Each lists the settings tried with their mean front margin over the training folds (each
training field flown with the model fitted without it) and each fold's margin, the chosen one
first. Prints, as Markdown, per run and choice: the setting chosen, its mean margin and
descents, and each fold's margin at z = 0 (the setting that descends most), and which choice a
calibration trying all of them keeps: the first, unless another's chosen setting beats it by
more than one standard error of their paired fold margins (as detail::select_pooling does;
of several, the best mean); then per choice the mean over the runs of the chosen setting's
margin. The kept choice's mean is optimistic: picked on the same folds.

  --order A,B   the choices, the first the default (default: sorted names; cells before fields,
                as calibration orders the slope poolings)
"""
import glob
import os
import re
import sys

LINE = re.compile(r"\s+(front-aware z=(\S+)(?: slopes=\S+)?)\s+\S+\s+\S+\s+(\S+)\s+\S+\s+(\d+)\s+(.*)$")


def read(path):
    """The settings of one calibration output, the chosen first: (name, z, mean, descents, folds)."""
    out = []
    with open(path) as f:
        for line in f:
            m = LINE.match(line.rstrip("\n"))
            if m:
                folds = [float(v) for v in m.group(5).split()]
                out.append((m.group(1), float(m.group(2)), float(m.group(3)), int(m.group(4)), folds))
    if not out:
        sys.exit(f"{path}: no front-aware setting listed (an adaptseg_calibrate output?)")
    return out


def paired_difference(folds, first, grounds=None):
    """The mean of `folds` − `first` (paired, one margin per fold) and its standard error. With
    `grounds` (each fold's ground, CalibrationOptions::field_grounds: the looks of one field by
    several networks), one difference per ground, its folds' mean, as detail::select_pooling
    counts them; the standard error is infinite for fewer than two."""
    d = [a - b for a, b in zip(folds, first)]
    if grounds and len(grounds) == len(d):
        by_ground = {}
        for g, x in zip(grounds, d):
            by_ground.setdefault(g, []).append(x)
        d = [sum(v) / len(v) for _, v in sorted(by_ground.items())]
    n = len(d)
    mean = sum(d) / n
    if n < 2:
        return mean, float("inf")
    return mean, (sum((x - mean) ** 2 for x in d) / (n - 1) / n) ** 0.5


def beats(folds, first, grounds=None):
    """Whether `folds` beat `first` (paired) by more than one standard error of the differences,
    as detail::select_pooling decides: by a relative 1e-9 more, so that a difference on one fold
    alone (mean and standard error then equal) is never enough; `grounds` as paired_difference."""
    if len(folds) != len(first) or len(folds) < 2:
        return False
    mean, se = paired_difference(folds, first, grounds)
    return mean > se * (1.0 + 1e-9)


def main():
    args = sys.argv[1:]
    order = None
    if len(args) >= 2 and args[0] == "--order":
        order = args[1].split(",")
        args = args[2:]
    if len(args) != 1:
        sys.exit(__doc__)
    runs = {}
    for path in sorted(glob.glob(os.path.join(args[0], "*.txt"))):
        run, choice = os.path.basename(path)[: -len(".txt")].rsplit(".", 1)
        runs.setdefault(run, {})[choice] = read(path)
    if not runs:
        sys.exit(f"no RUN.CHOICE.txt in {args[0]}")
    choices = order or sorted({c for r in runs.values() for c in r})
    print("| run | choice | chosen | mean fold margin | descents | folds at z = 0 |")
    print("| --- | --- | --- | ---: | ---: | --- |")
    totals = {c: [] for c in choices + ["chosen by the folds"]}
    for run, by_choice in sorted(runs.items()):
        if set(by_choice) != set(choices):
            sys.exit(f"{run}: expected the choices {', '.join(choices)}, found {', '.join(sorted(by_choice))}")
        best = None
        for c in choices:
            name, z, mean, descents, folds = by_choice[c][0]
            zero = next((t for t in by_choice[c] if t[1] == 0.0), None)
            at_zero = " ".join(f"{v:+.4f}" for v in zero[4]) if zero else ""
            print(f"| {run} | {c} | {name} | {mean:+.4f} | {descents} | {at_zero} |")
            totals[c].append(mean)
            first = by_choice[choices[0]][0][4]
            if best is None or (beats(folds, first) and mean > best[1]):
                best = (c, mean)
        totals["chosen by the folds"].append(best[1])
        print(f"| {run} | chosen by the folds | {best[0]} | {best[1]:+.4f} | | |")
    print()
    print("| choice | runs | mean of the chosen settings' fold margins |")
    print("| --- | ---: | ---: |")
    for c, v in totals.items():
        print(f"| {c} | {len(v)} | {sum(v) / len(v):+.4f} |")


if __name__ == "__main__":
    main()
