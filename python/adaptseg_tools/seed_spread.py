"""How much of a tile's lawnmower curve is the tile's, and how much the network's seed.

Reads the held-out scores of two or more bundled sets of the leave-one-tile-out networks (each
SET a folder of tile-<k>/held_out_eval.json, as `scripts/loto.sh bundle` or `stage` leaves
them: the field's class IoU of whole-field lawnmowers at 5, 10 and 15 cm/px by the network that
never saw the tile) and prints, per class, the rise of the field's IoU from the top level (15
cm/px) to each finer GSD, IoU(g) - IoU(15), per tile and set; then, over the tiles where every set
scores the class at both GSDs:

- between seeds: the sets' spread about their tile's mean, pooled over the tiles (the standard
  deviation of one set's rise about the tile's mean over sets);
- between tiles: the spread of the tiles' means over sets, less what the spread between seeds
  makes of a mean of n sets (a standard deviation, 0 where the seeds explain it all);
- sign: on how many tiles every set's rise has the sign of their mean.

A rise that is the tile's (between tiles large, between seeds small, one sign) is what a
calibration on other tiles can carry to a new one; one that moves with the seed as much as from
tile to tile is the network's, and a decision calibrated on one seed's networks learns its noise.

  seed_spread.py SET SET [SET...]
"""
import json
import math
import sys
from pathlib import Path

TOP_GSD = 15.0


def held_out_curves(folder: Path):
    """{tile: (classes, {gsd_cm: [IoU or None per class]})} of every tile-<k> in `folder`."""
    out = {}
    for sub in sorted(folder.glob("tile-*")):
        path = sub / "held_out_eval.json"
        if not path.is_file():
            continue
        d = json.loads(path.read_text())
        ((_, bands),) = d["fields"].items()
        (member,) = d["members"]
        out[sub.name] = (d["classes"], {float(b["gsd_cm"]): b[member]["iou"] for b in bands.values()})
    if not out:
        raise SystemExit(f"seed_spread: no tile-*/held_out_eval.json in {folder}")
    return out


def spread(rises):
    """(between seeds, between tiles, tiles with one sign) of {tile: [rise per set]}."""
    n_sets = len(next(iter(rises.values())))
    ss = sum((r - sum(rs) / n_sets) ** 2 for rs in rises.values() for r in rs)
    dof = len(rises) * (n_sets - 1)
    within = math.sqrt(ss / dof)
    means = [sum(rs) / n_sets for rs in rises.values()]
    grand = sum(means) / len(means)
    var_means = sum((m - grand) ** 2 for m in means) / (len(means) - 1) if len(means) > 1 else 0.0
    between = math.sqrt(max(0.0, var_means - within * within / n_sets))
    one_sign = sum(all((r > 0) == (sum(rs) > 0) and r != 0 for r in rs) for rs in rises.values())
    return within, between, one_sign


def main(argv):
    if len(argv) < 2 or any(a.startswith("-") for a in argv):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    sets = [held_out_curves(Path(a)) for a in argv]
    tiles = sorted(set.intersection(*(set(s) for s in sets)), key=lambda t: (len(t), t))
    if not tiles:
        raise SystemExit("seed_spread: no tile is in every set")
    classes = sets[0][tiles[0]][0]
    for s in sets:
        for t in tiles:
            if s[t][0] != classes:
                raise SystemExit(f"seed_spread: {t}'s classes differ between the sets")
    gsds = sorted(set.intersection(*(set(s[t][1]) for s in sets for t in tiles)))
    if TOP_GSD not in gsds:
        raise SystemExit(f"seed_spread: not every tile is scored at {TOP_GSD:g} cm/px")
    finer = [g for g in gsds if g < TOP_GSD]
    print(f"sets: {', '.join(argv)}; tiles in every set: {', '.join(tiles)}\n")
    print("| class | rise | " + " | ".join(tiles) + " | between seeds | between tiles | one sign |")
    print("| --- | --- |" + " --- |" * len(tiles) + " ---: | ---: | ---: |")
    for c, name in enumerate(classes):
        for g in finer:
            rises, cells = {}, []
            for t in tiles:
                vals = [(s[t][1][g][c], s[t][1][TOP_GSD][c]) for s in sets]
                if any(a is None or b is None for a, b in vals):
                    cells.append("-")
                    continue
                rises[t] = [a - b for a, b in vals]
                cells.append(" / ".join(f"{r:+.3f}" for r in rises[t]))
            if not rises:
                continue
            within, between, one_sign = spread(rises)
            print(f"| {name} | {TOP_GSD:g} → {g:g} | " + " | ".join(cells) +
                  f" | {within:.3f} | {between:.3f} | {one_sign} of {len(rises)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
