#!/usr/bin/env python3
"""Self-test of seed_spread.py on two synthetic sets of held-out scores (run by CTest; exit code
!= 0 on failure).

Classes a and b, every IoU 0.5 at 15 and 5 cm/px (rise 15 -> 5: 0 everywhere: no sign, no spread).
Class a at 10 cm/px rises +0.10 / +0.12 (set 1 / set 2) on tile-1, -0.05 / -0.03 on tile-2, +0.20 /
+0.22 on tile-3: each set 0.01 from its tile's mean, so between seeds sqrt(6 * 0.01^2 / 3) = 0.014;
the tiles' means 0.11, -0.04, 0.21 spread with variance 0.015833, less 0.0002 / 2: between tiles
0.125; one sign on all three. Class b rises +0.1 in both sets on tiles 1 and 3 and is not scored
by set 2 on tile 2 ("-", left out): no spread, 2 of 2. Tile 4, in set 1 only, is not compared.
"""
import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

from adaptseg_tools import seed_spread

RISE_A = {1: (0.10, 0.12), 2: (-0.05, -0.03), 3: (0.20, 0.22), 4: (0.0, None)}


def write_set(root: Path, s: int):
    for tile, rises in RISE_A.items():
        if rises[s] is None:
            continue
        b10 = None if (s == 1 and tile == 2) else 0.6
        b = {"gsd_cm": 15.0, "m": {"iou": [0.5, 0.5 if b10 else None]}}
        bands = {"1.0": {"gsd_cm": 5.0, "m": {"iou": [0.5, 0.5 if b10 else None]}},
                 "2.0": {"gsd_cm": 10.0, "m": {"iou": [0.5 + rises[s], b10]}},
                 "3.0": b}
        d = {"classes": ["a", "b"], "members": {"m": "x"}, "fields": {f"dubai-tile-{tile}": bands}}
        (root / f"tile-{tile}").mkdir(parents=True)
        (root / f"tile-{tile}" / "held_out_eval.json").write_text(json.dumps(d))


def main():
    with tempfile.TemporaryDirectory() as tmp:
        sets = [Path(tmp) / "s0", Path(tmp) / "s1"]
        for s, root in enumerate(sets):
            write_set(root, s)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            rc = seed_spread.main([str(p) for p in sets])
        text = out.getvalue()
        want = ["tiles in every set: tile-1, tile-2, tile-3\n",
                "| a | 15 → 5 | +0.000 / +0.000 | +0.000 / +0.000 | +0.000 / +0.000 | 0.000 | 0.000 | 0 of 3 |",
                "| a | 15 → 10 | +0.100 / +0.120 | -0.050 / -0.030 | +0.200 / +0.220 | 0.014 | 0.125 | 3 of 3 |",
                "| b | 15 → 10 | +0.100 / +0.100 | - | +0.100 / +0.100 | 0.000 | 0.000 | 2 of 2 |"]
        if rc != 0 or any(w not in text for w in want):
            sys.exit(f"seed_spread printed (rc {rc}):\n{text}\nwanted the lines:\n" + "\n".join(want))
        print("ok: seed_spread parts each tile's rise between the seeds and between the tiles")
        with contextlib.redirect_stderr(io.StringIO()):
            if seed_spread.main([str(sets[0])]) != 2:
                sys.exit("seed_spread with one set: exit code not 2")
        print("ok: one set is refused with the usage")


if __name__ == "__main__":
    main()
