r"""What a calibration would keep with fewer settings to try, replayed from flown runs' logs.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.grid_replay [options] DIR [LABEL=DIR ...]

DIR holds the runs of one configuration of `scripts/results.sh loto` (adaptseg_evaluate output
folders ...-CLASS-tile-K and their logs ...-CLASS-tile-K.log) flown with a front-aware search
over z, slope poolings and top levels. Each log lists every setting its calibration tried, the
kept one first and then the rest in the search's order, with its mean front margin over the
training folds and each fold's ("tried front-aware z=Z slopes=P top=T: front margin M, N
descents, per field m1 m2 ..."). A calibration that tries fewer settings flies the same folds,
so what it keeps can be replayed from those lines, as detail::choose_setting decides: per
pooling and top level the z of best mean (ties to the larger z); per top level the first
pooling's unless another beats it by more than one standard error of their paired fold margins
(detail::select_pooling; of several, the best mean); of the top levels so kept, the first's
unless another beats it the same way. A row calibrated on several looks of each field
(--calibration-network-each; its "calibrating on" line names a field once per look) counts the
looks of one field as one ground, as the programs' CalibrationOptions::field_grounds do.

  --slope-pooling A,B   the poolings the replay tries, in this order (the first the default);
                        default: as flown
  --top-level A,B       the top-level choices, likewise
  --z A,B               the z values, likewise (their order does not matter)
  --z-rule RULE         how the replay keeps z per pooling and top level: `mean` (default), the
                        z of best mean fold margin, ties to the larger z; `se`, the largest z
                        unless another beats it by more than one standard error of their paired
                        fold margins (select_pooling's rule, in the order of z from the largest)
  --out OUT             one link per run (folder and log) to a flown run that kept the replayed
                        setting, from DIR or the LABEL=DIRs after it (each flown with the same
                        flags but the search's lists), so that `adaptseg_tools.loto_targets
                        replay=OUT` scores the replayed grid without flying it; OUT must be new
                        or empty
  --to-fly FILE         the runs still to fly, one folder name a line (e.g.
                        mobilenetv2-loto-building-tile-3), for flying those alone:
                          mkdir -p out/results/$CONFIG && CONFIG=... EXTRA=... PYTHONPATH=python \
                          /usr/bin/python3 -m adaptseg_tools.experiments --dry-run loto \
                          | grep -F -f <(sed 's|.*|/&.log|' FILE) | tr '\n' '\0' \
                          | nice xargs -0 -P 2 -I{} bash -c {}
                        (the dry run's commands of those runs; CONFIG a new folder, EXTRA the
                        smaller search's flags; then pass out/results/$CONFIG as a LABEL=DIR)

The flown order is read from the lines after the first (the search's order); a pooling or top
level tried with one z only and kept would be missing there, and is put first. Each run is
first replayed with the grid as flown: a run whose replay does not keep what its log says it
kept is marked "MISMATCH" (its replayed choice is then not to be trusted). The logs print
margins to four decimals: a comparison whose mean difference lies within 1e-4 of its standard
error, or two z values of equal printed mean and different folds, is marked "near" (rounding
may have decided it).

Prints, as Markdown, per run: the setting kept as flown, the setting the replay keeps (its mean
fold margin), and where a flown run kept that setting ("to fly" where none did), then the count
of runs that change and of those still to fly. The test run of a setting is the same whichever
list the search tried it among (the test flight reads only the kept setting and the model),
which is why a flown run that kept it stands in.
"""
import os
import re
import sys

from .fold_choice import choose as select, runs_of, tried_settings

# A trial's name (detail::z_text): its z, and its slope pooling, top level, finest descent GSD and
# longest descent where the search tried several.
SETTING = re.compile(r"front-aware z=(\S+?)(?: slopes=(\S+?))?(?: top=(\S+?))?"
                     r"(?: (finest=\S+?))?(?: (longest=\S+))?$")
CALIBRATING = re.compile(r"calibrating on (.*) \.\.\.$")


def fold_grounds(log):
    """Each training fold's ground, as the programs set CalibrationOptions::field_grounds: with
    --calibration-network-each one field's looks by several networks are listed one after
    another under one name ("calibrating on A, A, B, B, ..."), one ground; every other fold its
    own."""
    with open(log) as f:
        for line in f:
            m = CALIBRATING.search(line)
            if m:
                names = m.group(1).split(", ")
                return [next(j for j in range(k, -1, -1) if j == 0 or names[j - 1] != names[k]) for k in
                        range(len(names))]
    return None


class Trial:
    """One setting tried: z, pooling and top level (None where the search tried one alone and the
    log does not name it), the finest descent GSD and the longest descent where it tried several
    ("finest=G", "longest=S"), mean fold margin, fold margins."""

    def __init__(self, log, name, mean, folds):
        m = SETTING.fullmatch(name)
        if not m:
            sys.exit(f"{log}: a setting tried that is not the front-aware rule's: {name!r}")
        self.z, self.pooling, self.top = float(m.group(1)), m.group(2), m.group(3)
        self.finest, self.longest = m.group(4), m.group(5)
        self.mean, self.folds = mean, folds

    def setting(self):
        return (self.z, self.pooling, self.top)

    def as_tuple(self):
        """As fold_choice.choose takes a trial: (name, mean, descents, folds)."""
        return (None, self.mean, None, self.folds)


def read_trials(log):
    """The settings a run's log lists as tried, the kept one first."""
    out = [Trial(log, name, mean, folds) for name, mean, _, folds in tried_settings(log)]
    if any(t.finest or t.longest for t in out):
        sys.exit(f"{log}: the search also tried the finest descent GSD or the longest descent: not replayed")
    if not out or any(t.pooling is None or t.top is None for t in out):
        sys.exit(f"{log}: no 'tried front-aware z=.. slopes=.. top=..' line (a run still calibrating, or one "
                 "whose search tried a single slope pooling or top level?)")
    return out


def flew(log, trial):
    """Whether a flown run's log kept `trial`'s setting: its first `tried` line names the same z
    and, where it names them, the same pooling and top level (a search that tried one alone omits
    it), with the same mean and fold margins (the same setting flies the same folds), and no finest
    descent GSD or longest descent kept beside them (a search that tried several and kept none,
    "finest=any" or "longest=any", flies as one that tried none)."""
    name, mean, _, folds = next(tried_settings(log), (None, None, None, None))
    if name is None:
        return False
    kept = Trial(log, name, mean, folds)
    return (kept.z == trial.z and kept.pooling in (None, trial.pooling) and kept.top in (None, trial.top)
            and kept.finest in (None, "finest=any") and kept.longest in (None, "longest=any")
            and kept.mean == trial.mean and kept.folds == trial.folds)


def flown_order(trials, attribute):
    """The flown order of a dimension: first appearance after the kept trial, the kept one's
    value first where it appears only there."""
    order = list(dict.fromkeys(getattr(t, attribute) for t in trials[1:]))
    kept = getattr(trials[0], attribute)
    return order if kept in order else [kept] + order


def choose(trials, poolings, tops, zs=None, grounds=None, z_rule="mean"):
    """detail::choose_setting over the trials within the lists: (Trial kept, near). `z_rule`:
    "mean", per pooling and top level the z of best mean (ties to the larger z); "se", the largest
    z unless another beats it by more than one standard error (select(), in the order of z from the
    largest)."""
    near, of_levels = False, []
    for top in tops:
        of_level = []
        for pooling in poolings:
            group = [t for t in trials if t.pooling == pooling and t.top == top and (zs is None or t.z in zs)]
            if not group:
                continue
            if z_rule == "se":
                group = sorted(group, key=lambda t: -t.z)
                k, n = select([t.as_tuple() for t in group], grounds)
                best = group[k]
                near |= n
            else:
                best = group[0]
                for t in group[1:]:
                    if t.mean > best.mean or (t.mean == best.mean and t.z > best.z):
                        best = t
                near |= any(t is not best and t.mean == best.mean and t.folds != best.folds for t in group)
            of_level.append(best)
        if of_level:
            k, n = select([t.as_tuple() for t in of_level], grounds)
            near |= n
            of_levels.append(of_level[k])
    if not of_levels:
        return None, near
    k, n = select([t.as_tuple() for t in of_levels], grounds)
    return of_levels[k], near or n


def name(setting):
    z, pooling, top = setting
    return f"z={z:g} {pooling} {top}"


def parse_list(text, option):
    items = [s for s in text.split(",") if s]
    if not items:
        sys.exit(f"{option}: an empty list")
    return items


def main(argv):
    options = {"--slope-pooling": None, "--top-level": None, "--z": None, "--z-rule": "mean", "--out": None,
               "--to-fly": None}
    rest = []
    k = 0
    while k < len(argv):
        if argv[k] in options:
            if k + 1 >= len(argv):
                sys.exit(f"{argv[k]} needs a value")
            options[argv[k]] = argv[k + 1]
            k += 2
        elif argv[k].startswith("-"):
            sys.exit(f"unknown option {argv[k]}\n" + __doc__.split("\n\n")[1])
        else:
            rest.append(argv[k])
            k += 1
    if not rest:
        sys.exit(__doc__.split("\n\n")[1])
    poolings = tops = zs = None
    if options["--slope-pooling"] is not None:
        poolings = parse_list(options["--slope-pooling"], "--slope-pooling")
    if options["--top-level"] is not None:
        tops = parse_list(options["--top-level"], "--top-level")
    if options["--z"] is not None:
        try:
            zs = {float(v) for v in parse_list(options["--z"], "--z")}
        except ValueError:
            sys.exit(f"--z: numbers, got {options['--z']!r}")
    if options["--z-rule"] not in ("mean", "se"):
        sys.exit(f"--z-rule: mean or se, got {options['--z-rule']!r}")
    flown = [("", rest[0])]
    for c in rest[1:]:
        label, _, d = c.partition("=")
        if not d:
            sys.exit(f"expected LABEL=DIR after DIR, got {c!r}")
        flown.append((label, d))
    runs = [(label, d, runs_of(d)) for label, d in flown]
    out = options["--out"]
    if out:
        if os.path.exists(out) and os.listdir(out):
            sys.exit(f"{out} exists and is not empty")
        os.makedirs(out, exist_ok=True)

    unflown = []
    print("| class | tile | kept as flown | replay keeps (fold mean) | flown in |")
    print("| --- | ---: | --- | --- | --- |")
    changed = to_fly = mismatched = 0
    for key in sorted(runs[0][2]):
        log = os.path.join(runs[0][1], runs[0][2][key] + ".log")
        trials, grounds = read_trials(log), fold_grounds(log)
        flown_p, flown_t = flown_order(trials, "pooling"), flown_order(trials, "top")
        as_flown, _ = choose(trials, flown_p, flown_t, grounds=grounds)
        mismatch = as_flown.setting() != trials[0].setting()
        mismatched += mismatch
        want_p, want_t = poolings or flown_p, tops or flown_t
        for p in want_p:
            if p not in flown_p:
                sys.exit(f"{runs[0][2][key]}: slope pooling {p!r} was not tried")
        for t in want_t:
            if t not in flown_t:
                sys.exit(f"{runs[0][2][key]}: top level {t!r} was not tried")
        kept, near = choose(trials, want_p, want_t, zs, grounds, options["--z-rule"])
        if kept is None:
            sys.exit(f"{runs[0][2][key]}: no setting tried within the lists")
        where = None
        for label, d, of in runs:
            if key in of and flew(os.path.join(d, of[key] + ".log"), kept):
                where = (label or "DIR", d, of[key])
                break
        moved = kept.setting() != trials[0].setting()
        changed += moved
        to_fly += where is None
        if where is None:
            unflown.append(runs[0][2][key])
        if out and where:
            for n in (where[2], where[2] + ".log"):
                os.symlink(os.path.abspath(os.path.join(where[1], n)), os.path.join(out, n))
        print(f"| {key[0]} | {key[1]} | {name(trials[0].setting())}{' MISMATCH' if mismatch else ''} | "
              f"{name(kept.setting())} ({kept.mean:+.4f}){' (near)' if near else ''}"
              f"{' (changed)' if moved else ''} | {where[0] if where else 'to fly'} |")
    if options["--to-fly"]:
        with open(options["--to-fly"], "w") as f:
            f.writelines(n + "\n" for n in unflown)
    total = len(runs[0][2])
    print(f"\n{changed} of {total} runs change, {to_fly} still to fly; "
          f"{mismatched} whose replay as flown does not keep what they kept.")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
