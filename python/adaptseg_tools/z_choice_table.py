"""How much the choice of the front-aware rule's confidence level z can buy.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.z_choice_table DIR

DIR holds, per run NAME (written by `bash scripts/results.sh z-choice`):
  NAME.trials.txt  adaptseg_calibrate's output: per z, the mean and worst front margin over the
                   training folds (where it tried several slope poolings, those of the one it
                   chose: the model the test field is flown with);
  NAME.zZ/         adaptseg_evaluate's output with the run's model, its z replaced by Z.
Prints, as Markdown, per way of choosing z (on the training folds only, a fixed z, and the best
z per run read off the test field, which no rule can know: the ceiling), the runs with margin
> 0 and >= -0.002, the median, mean and smallest margin of adaptive; then per run the training
folds' mean / worst margin and the test margin (descents) for every z.
"""
import csv
import glob
import os
import re
import statistics
import sys

ZS = ["0", "0.5", "1", "1.5", "2"]


def load(root):
    runs = []
    for path in sorted(glob.glob(os.path.join(root, "*.trials.txt"))):
        name = os.path.basename(path)[: -len(".trials.txt")]
        folds = {}
        chosen = None  # adaptseg_calibrate lists the chosen setting first
        pooling = None  # the chosen slope pooling, where several were tried: its trials only
        with open(path) as f:
            for line in f:
                m = re.match(r"\s+front-aware z=(\S+)(?: slopes=(\S+))?\s+\S+\s+\S+\s+(\S+)\s+(\S+)\s+\d+", line)
                if m:
                    if chosen is None:
                        chosen, pooling = m.group(1), m.group(2)
                    if m.group(2) == pooling:
                        folds[m.group(1)] = (float(m.group(3)), float(m.group(4)))
        test = {}
        for z in ZS:
            with open(os.path.join(root, f"{name}.z{z}", "results.csv"), newline="") as f:
                row = next(r for r in csv.DictReader(f) if r["strategy"] == "adaptive")
            test[z] = (float(row["front_margin"]), int(row["descents"]))
        if set(folds) != set(ZS):  # before "chosen" is added
            sys.exit(f"{path}: expected the trials of z = {', '.join(ZS)}")
        folds["chosen"] = chosen
        runs.append((name, folds, test))
    if not runs:
        sys.exit(f"no *.trials.txt in {root}")
    return runs


def by_worst(folds):  # best worst fold, then best mean, then smaller z (margins as printed: 4 decimals)
    return max(ZS, key=lambda z: (folds[z][1], folds[z][0], -float(z)))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    runs = load(sys.argv[1])
    rules = [("best mean over the folds, ties to the larger z (calibrate's choice)", lambda f, t: f["chosen"]),
             ("best worst fold", lambda f, t: by_worst(f))]
    rules += [(f"fixed z = {z}", lambda f, t, z=z: z) for z in ZS]
    rules.append(("best z per run on the test field (ceiling)", lambda f, t: max(ZS, key=lambda z: t[z][0])))
    print("| z chosen by | runs | margin > 0 | margin >= -0.002 | median | mean | smallest |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for label, rule in rules:
        m = [test[rule(folds, test)][0] for _, folds, test in runs]
        print(f"| {label} | {len(m)} | {sum(x > 0 for x in m)} | {sum(x >= -0.002 for x in m)} | "
              f"{statistics.median(m):+.4f} | {statistics.mean(m):+.4f} | {min(m):+.4f} |")
    print()
    print("| run | " + " | ".join(f"z = {z}: folds mean / worst -> test (descents)" for z in ZS) + " |")
    print("| --- |" + " --- |" * len(ZS))
    for name, folds, test in runs:
        cells = [f"{folds[z][0]:+.4f} / {folds[z][1]:+.4f} -> {test[z][0]:+.4f} ({test[z][1]})" for z in ZS]
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
