"""Which of several flown configurations the training folds would keep, run by run, without flying.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fold_choice OUT LABEL=DIR LABEL=DIR [...]

Each DIR holds the 24 runs of one configuration of `scripts/results.sh loto` (adaptseg_evaluate
output folders ...-CLASS-tile-K and their logs ...-CLASS-tile-K.log). Each log lists the
settings its calibration tried, the one kept first, with each training fold's front margin
("tried ...: front margin M, N descents, per field m1 m2 ..."). Where the configurations differ
only in a dimension of the search (a candidate limit, an option), a calibration that tried
both would fly the same folds, so what it keeps can be read off the logs: the first
configuration's kept setting, unless another's beats it on the folds by more than one standard
error of their paired margins (detail::select_pooling's rule, a difference on one fold alone
never enough; of several, the best mean). The test run is then that configuration's, flown.

Writes OUT/ with one link per run to the kept configuration's folder (and its log), so that
`adaptseg_tools.loto_targets kept=OUT` scores the choice on the 24 runs, and prints, as
Markdown, per run the configuration kept and each configuration's kept setting with its mean
fold margin. The logs print margins to four decimals: a comparison of settings that differ on
some fold, with the mean difference within 1e-4 of its standard error, is marked "near"
(rounding may have decided it).
"""
import os
import re
import sys

from .fold_table import beats, paired_difference

RUN = re.compile(r"(building|road|vegetation|water)-tile-([1-9])$")
TRIED = re.compile(r"tried (.+?): front margin ([-+\d.]+), (\d+) descents, per field (.*)$")


def tried_settings(log):
    """Every setting an adaptseg_evaluate log lists as tried, the kept one first: (name, mean fold
    margin, descents, [fold margins])."""
    with open(log) as f:
        for line in f:
            m = TRIED.search(line)
            if m:
                yield m.group(1), float(m.group(2)), int(m.group(3)), [float(v) for v in m.group(4).split()]


def kept_trial(log):
    """The kept setting of a run's log (tried_settings()' first)."""
    kept = next(tried_settings(log), None)
    if kept is None:
        sys.exit(f"{log}: no 'tried ...' line (an adaptseg_evaluate log of a calibrated run?)")
    return kept


def near_tie(first, other, grounds=None):
    """Whether the settings differ on some fold and their mean difference lies within the logs'
    rounding (1e-4) of its standard error, so that the four printed decimals may decide;
    `grounds` as fold_table.paired_difference."""
    if len(first) != len(other) or len(first) < 2 or first == other:
        return False
    mean, se = paired_difference(other, first, grounds)
    return abs(mean - se) < 1e-4


def choose(trials, grounds=None):
    """Index kept among `trials` (each (name, mean, descents, folds)), the first the default, and
    whether any comparison was near; `grounds` as fold_table.paired_difference."""
    best, near = 0, False
    for k in range(1, len(trials)):
        near |= near_tie(trials[0][3], trials[k][3], grounds)
        if beats(trials[k][3], trials[0][3], grounds) and trials[k][1] > trials[best][1]:
            best = k
    return best, near


def runs_of(directory):
    out = {}
    for d in os.listdir(directory):
        m = RUN.search(d)
        if m and os.path.isdir(os.path.join(directory, d)):
            out[(m.group(1), int(m.group(2)))] = d
    if not out:
        sys.exit(f"no runs named ...-CLASS-tile-K in {directory}")
    return out


def main(argv):
    if len(argv) < 3 or argv[0].startswith("-"):
        sys.exit(__doc__.split("\n\n")[1])
    out, configs = argv[0], []
    for c in argv[1:]:
        label, _, d = c.partition("=")
        if not d:
            sys.exit(f"expected LABEL=DIR, got {c!r}")
        configs.append((label, d, runs_of(d)))
    keys = sorted(set.intersection(*(set(r) for _, _, r in configs)))
    if os.path.exists(out) and os.listdir(out):
        sys.exit(f"{out} exists and is not empty")
    os.makedirs(out, exist_ok=True)
    print("| class | tile | kept |" + "".join(f" {label}: kept setting (fold mean) |" for label, _, _ in configs))
    print("| --- | ---: | --- |" + " --- |" * len(configs))
    for key in keys:
        trials = [kept_trial(os.path.join(d, runs[key] + ".log")) for _, d, runs in configs]
        k, near = choose(trials)
        label, d, runs = configs[k]
        for name in (runs[key], runs[key] + ".log"):
            os.symlink(os.path.abspath(os.path.join(d, name)), os.path.join(out, name))
        cells = "".join(f" {t[0]} ({t[1]:+.4f}) |" for t in trials)
        print(f"| {key[0]} | {key[1]} | {label}{' (near)' if near else ''} |{cells}")


if __name__ == "__main__":
    main(sys.argv[1:])
