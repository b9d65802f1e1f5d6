#!/usr/bin/env python3
"""Self-test of grid_replay.py on synthetic runs (run by CTest; exit code != 0 on failure).

A row flown with the slope poolings field-entropy,fields and the top levels undominated,hull at
z = 0 and 2, each run a folder and its log as scripts/results.sh writes them (the kept setting
first, then the search's order):
- building, tile 1: on both top levels `fields` beats `field-entropy` on every fold, and `hull`
  beats `undominated`: kept (0, fields, hull). With field-entropy alone the replay keeps
  (0, field-entropy, hull), which a second row flew (its log names no pooling: it tried one).
- road, tile 2: every setting at z = 0 and 2 alike (no descent), so z = 2 is kept (ties to the
  larger z); `fields` better on one fold alone (never beyond the noise, and marked near, as
  fold_choice marks it): field-entropy kept.
- water, tile 3: the log claims (0, fields, undominated), which its margins do not keep: a
  MISMATCH. Replayed with field-entropy alone it keeps a setting no row flew: "to fly".
With `--z-rule se` a z = 0 that wins on the folds' mean alone gives way to z = 2 (flown by a row
whose search kept no longest descent, which stands in). Then a run calibrated on two looks of
each of three fields (--calibration-network-each): the looks of one field are one ground, so a
difference the six looks would call beyond the noise is not (and is, where the six are six
fields).
"""
import os
import sys
import tempfile

from tool_output import check, check_refused, printed

from adaptseg_tools import grid_replay

ZERO = (0.0, 0.0, 0.0)


def write_run(root, name, trials, names_pooling=True, fields=None):
    """trials: [(z, pooling, top, folds)], the kept one first; fields: the calibration fields as
    the log's "calibrating on" line lists them (none listed where not given)."""
    os.makedirs(os.path.join(root, name))
    with open(os.path.join(root, name + ".log"), "w") as f:
        if fields:
            f.write(f"[   0.8 s] calibrating on {', '.join(fields)} ...\n")
        f.write("[   1.0 s] calibrated: 128 samples, front-aware z=0, train front margin +0.0000, 0 descents\n")
        for z, pooling, top, folds in trials:
            mean = sum(folds) / len(folds)
            per = " ".join(f"{v:+.4f}" for v in folds)
            slopes = f" slopes={pooling}" if names_pooling else ""
            f.write(f"           tried front-aware z={z:g}{slopes} top={top}: front margin {mean:+.4f}, 3 descents, "
                    f"per field {per}\n")


def grid(margins):
    """The search's order (pooling, then top level, then z) from {(pooling, top): folds at z=0}."""
    out = []
    for pooling in ("field-entropy", "fields"):
        for top in ("undominated", "hull"):
            out.append((0, pooling, top, margins[(pooling, top)]))
            out.append((2, pooling, top, ZERO))
    return out


def kept_first(trials, setting):
    kept = [t for t in trials if t[:3] == setting]
    return kept + [t for t in trials if t[:3] != setting]


def main():
    with tempfile.TemporaryDirectory() as tmp:
        a, b, out = (os.path.join(tmp, n) for n in ("a", "b", "out"))
        building = grid({("field-entropy", "undominated"): (0.001, 0.001, 0.000),
                         ("field-entropy", "hull"): (0.002, 0.003, 0.001),
                         ("fields", "undominated"): (0.003, 0.004, 0.002),
                         ("fields", "hull"): (0.006, 0.007, 0.005)})
        write_run(a, "net-building-tile-1", kept_first(building, (0, "fields", "hull")))
        # The second row tried field-entropy alone: its log names no pooling.
        write_run(b, "net-building-tile-1",
                  kept_first([t for t in building if t[1] == "field-entropy"], (0, "field-entropy", "hull")),
                  names_pooling=False)
        road = grid({("field-entropy", "undominated"): ZERO, ("field-entropy", "hull"): ZERO,
                     ("fields", "undominated"): (0.0, 0.009, 0.0), ("fields", "hull"): ZERO})
        write_run(a, "net-road-tile-2", kept_first(road, (2, "field-entropy", "undominated")))
        water = grid({("field-entropy", "undominated"): (0.004, 0.005, 0.003),
                      ("field-entropy", "hull"): (0.001, 0.000, 0.001),
                      ("fields", "undominated"): (0.001, 0.002, 0.000),
                      ("fields", "hull"): ZERO})
        write_run(a, "net-water-tile-3", kept_first(water, (0, "fields", "undominated")))

        # As flown: building and road replay to what they kept, water does not.
        text = printed(grid_replay.main, [a])[1]
        for row in ("| building | 1 | z=0 fields hull | z=0 fields hull (+0.0060) | DIR |",
                    "| road | 2 | z=2 field-entropy undominated | z=2 field-entropy undominated (+0.0000) (near) | DIR |",
                    "| water | 3 | z=0 fields undominated MISMATCH | z=0 field-entropy undominated (+0.0040) (changed)"):
            check(any(line.startswith(row) for line in text.splitlines()), f"no row {row!r}:\n{text}")
        check("1 whose replay as flown does not keep" in text, f"the mismatch not counted:\n{text}")

        # field-entropy alone: building moves to the setting row b flew, water to one nobody flew.
        to_fly = os.path.join(tmp, "to-fly.txt")
        text = printed(grid_replay.main, ["--slope-pooling", "field-entropy", "--out", out, "--to-fly", to_fly, a,
                                          f"b={b}"])[1]
        with open(to_fly) as f:
            check(f.read() == "net-water-tile-3\n", "the run to fly not listed in --to-fly's file")
        for row in ("| building | 1 | z=0 fields hull | z=0 field-entropy hull (+0.0020) (changed) | b |",
                    "| road | 2 | z=2 field-entropy undominated | z=2 field-entropy undominated (+0.0000) | DIR |",
                    "| water | 3 | z=0 fields undominated MISMATCH | z=0 field-entropy undominated (+0.0040) (changed) "
                    "| to fly |"):
            check(any(line.startswith(row) for line in text.splitlines()), f"no row {row!r}:\n{text}")
        check("2 of 3 runs change, 1 still to fly" in text, f"counts wrong:\n{text}")
        for name, source in (("net-building-tile-1", b), ("net-road-tile-2", a)):
            for link in (name, name + ".log"):
                target = os.path.realpath(os.path.join(out, link))
                check(target == os.path.realpath(os.path.join(source, link)), f"{link} links to {target}, want {source}")
        check(not os.path.lexists(os.path.join(out, "net-water-tile-3")), "a run to fly was linked")

        # z = 0 alone and the undominated top level alone: road keeps z = 0 (nothing to break the tie).
        text = printed(grid_replay.main, ["--z", "0", "--top-level", "undominated", a])[1]
        check(any(line.startswith("| road | 2 | z=2 field-entropy undominated | z=0 field-entropy undominated")
                  for line in text.splitlines()), f"z=0 not kept on road:\n{text}")
        check(any(line.startswith("| building | 1 | z=0 fields hull | z=0 fields undominated (+0.0030) (changed)")
                  for line in text.splitlines()), f"undominated not kept on building:\n{text}")

        # --calibration-network-each: two looks per field, one ground. `fields` beats
        # `field-entropy` by one standard error counted over the six looks, not over the three
        # grounds (detail::select_pooling averages a ground's looks first): field-entropy kept.
        c, d = (os.path.join(tmp, n) for n in ("c", "d"))
        base = (0.001,) * 6
        better = tuple(b + x for b, x in zip(base, (0.004, 0.004, 0.002, 0.002, -0.002, -0.002)))
        looks = grid({("field-entropy", "undominated"): base, ("field-entropy", "hull"): base,
                      ("fields", "undominated"): better, ("fields", "hull"): better})
        twins = ["dubai-tile-1", "dubai-tile-1", "dubai-tile-2", "dubai-tile-2", "dubai-tile-3", "dubai-tile-3"]
        write_run(c, "net-building-tile-4", kept_first(looks, (0, "field-entropy", "undominated")), fields=twins)
        text = printed(grid_replay.main, [c])[1]
        check("| building | 4 | z=0 field-entropy undominated | z=0 field-entropy undominated" in text,
              f"the looks of one field counted as several grounds:\n{text}")
        # The same margins from six fields: `fields` beats it.
        write_run(d, "net-building-tile-4", kept_first(looks, (0, "fields", "undominated")),
                  fields=[f"dubai-tile-{k}" for k in range(1, 7)])
        text = printed(grid_replay.main, [d])[1]
        check("| building | 4 | z=0 fields undominated | z=0 fields undominated" in text,
              f"six grounds not counted as six:\n{text}")

        # --z-rule se: z = 0 beats z = 2 on the mean of three folds (+0.0007) but not beyond one
        # standard error of the paired margins, so the rule keeps z = 2, as a search that kept no
        # limit among several flew it (its trials named "longest=any"), which stands in for it;
        # where z = 0 beats z = 2 on every fold (water, tile 3) the rule keeps z = 0 as well.
        f, g = (os.path.join(tmp, n) for n in ("f", "g"))
        noisy = grid({("field-entropy", "undominated"): (0.024, -0.019, -0.003), ("field-entropy", "hull"): ZERO,
                      ("fields", "undominated"): ZERO, ("fields", "hull"): ZERO})
        write_run(f, "net-vegetation-tile-5", kept_first(noisy, (0, "field-entropy", "undominated")))
        write_run(f, "net-water-tile-3", kept_first(water, (0, "field-entropy", "undominated")))
        write_run(g, "net-vegetation-tile-5", [(z, pooling, f"{top} longest=any", folds) for z, pooling, top, folds
                                              in kept_first(noisy, (2, "field-entropy", "undominated"))])
        text = printed(grid_replay.main, [f])[1]
        check("| vegetation | 5 | z=0 field-entropy undominated | z=0 field-entropy undominated (+0.0007) | DIR |"
              in text, f"the mean rule does not keep z = 0:\n{text}")
        text = printed(grid_replay.main, ["--z-rule", "se", f, f"g={g}"])[1]
        for row in ("| vegetation | 5 | z=0 field-entropy undominated | z=2 field-entropy undominated (+0.0000) "
                    "(changed) | g |",
                    "| water | 3 | z=0 field-entropy undominated | z=0 field-entropy undominated (+0.0040) | DIR |"):
            check(row in text, f"no row {row!r}:\n{text}")
        check_refused(grid_replay.main, ["--z-rule", "median", f], "mean or se", "an unknown --z-rule")

        # Nothing overwritten; a pooling never tried, or an empty list, refused.
        check_refused(grid_replay.main, ["--out", out, a], "not empty", "a filled OUT")
        check_refused(grid_replay.main, ["--slope-pooling", "cells", a], "was not tried", "a pooling never tried")
        check_refused(grid_replay.main, ["--z", "", a], "an empty list", "an empty --z")
        # A search that also tried the longest descent (--longest-descent, trials named
        # "... top=T longest=S") is not replayed.
        e = os.path.join(tmp, "e")
        write_run(e, "net-road-tile-2", [(z, pooling, f"{top} longest={'any' if z else 20}", folds)
                                         for z, pooling, top, folds in road])
        check_refused(grid_replay.main, [e], "longest descent", "a search with the longest descent")
    print("ok: grid_replay.py keeps what a smaller search would keep")
    return 0


if __name__ == "__main__":
    sys.exit(main())
