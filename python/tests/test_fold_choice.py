#!/usr/bin/env python3
"""Self-test of fold_choice.py on synthetic runs (run by CTest; exit code != 0 on failure).

Two configurations of three runs, each run a folder and its log as scripts/results.sh writes
them, the kept setting first in the log: on building, tile 1 the second beats the first on
every fold (kept); on road, tile 2 it is better on one fold alone (a tie: the first kept, marked near); on
water, tile 3 it is worse (the first kept). The links in OUT point at the kept configuration's
folder and log.
"""
import os
import sys
import tempfile

from tool_output import check_refused, printed

from adaptseg_tools import fold_choice


def write_run(root, name, kept, other=(0.0, 0.0, 0.0)):
    os.makedirs(os.path.join(root, name))
    with open(os.path.join(root, name + ".log"), "w") as f:
        f.write("[   1.0 s] calibrated: 128 samples, front-aware z=0, train front margin +0.0000, 0 descents\n")
        for z, folds in ((0, kept), (2, other)):
            mean = sum(folds) / len(folds)
            per = " ".join(f"{v:+.4f}" for v in folds)
            f.write(f"           tried front-aware z={z}: front margin {mean:+.4f}, 3 descents, per field {per}\n")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        a, b, out = (os.path.join(tmp, n) for n in ("a", "b", "out"))
        write_run(a, "net-building-tile-1", (0.001, 0.002, 0.0))
        write_run(b, "net-building-tile-1", (0.004, 0.006, 0.003))
        write_run(a, "net-road-tile-2", (0.001, 0.002, 0.0))
        write_run(b, "net-road-tile-2", (0.001, 0.012, 0.0))  # one fold alone
        write_run(a, "net-water-tile-3", (0.001, 0.002, 0.0))
        write_run(b, "net-water-tile-3", (-0.001, 0.0, -0.002))
        text = printed(fold_choice.main, [out, f"a={a}", f"b={b}"])[1]
        want = {"net-building-tile-1": b, "net-road-tile-2": a, "net-water-tile-3": a}
        for name, source in want.items():
            for link in (name, name + ".log"):
                target = os.path.realpath(os.path.join(out, link))
                if target != os.path.realpath(os.path.join(source, link)):
                    sys.exit(f"{link} links to {target}, want {source}:\n{text}")
        for row in ("| building | 1 | b |", "| road | 2 | a (near) |", "| water | 3 | a |"):
            if not any(line.startswith(row) for line in text.splitlines()):
                sys.exit(f"no row {row!r}:\n{text}")
        # OUT must be new or empty: nothing is overwritten.
        check_refused(fold_choice.main, [out, f"a={a}", f"b={b}"], "not empty", "a filled OUT")
    print("ok: fold_choice.py keeps what the folds would keep")


if __name__ == "__main__":
    main()
