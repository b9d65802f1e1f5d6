#!/usr/bin/env python3
"""Self-test of fold_composition.py on synthetic logs (run by CTest; exit code != 0 on failure).

A calibration on six tiles whose field j has margin j/1000 under the five-field model, and six
leave-one-tile-out runs whose calibration for test tile K flies field j at j/1000 + K/5000: the
table must pair each field with the four-field margins of the five runs that trained on it, in
the order of their training tiles, and give their range; with --looks, a row of two looks per
training tile must pair each tile's looks.
"""
import os
import sys
import tempfile

from tool_output import check_refused, printed

from adaptseg_tools import fold_composition


def main():
    with tempfile.TemporaryDirectory() as tmp:
        calibration = os.path.join(tmp, "decision-road.log")
        with open(calibration, "w") as f:
            f.write("  setting  time [s]  mIoU  front margin  worst margin descents  per field\n")
            per = " ".join(f"{j / 1000:+.4f}" for j in range(1, 7))
            f.write(f"  front-aware z=0 slopes=cells   100.0   0.5000   +0.0035   +0.0010   4  {per}\n")
            f.write(f"  front-aware z=2 slopes=cells   100.0   0.5000   +0.0000   +0.0000   0  {'+0.0000 ' * 6}\n")
        row = os.path.join(tmp, "row")
        os.makedirs(row)
        for k in range(1, 7):
            per = " ".join(f"{j / 1000 + k / 5000:+.4f}" for j in range(1, 7) if j != k)
            with open(os.path.join(row, f"net-road-tile-{k}.log"), "w") as f:
                f.write(f"           tried front-aware z=0 slopes=cells finest=any: front margin +0.0030, 3 descents, "
                        f"per field {per}\n")
        text = printed(fold_composition.main, [calibration, row])[1]
        # Field 3 under the models without tiles 1, 2, 4, 5, 6: 0.003 + K/5000; the range 0.0012.
        want = ("| 3 | +0.0030 | +0.0032 (K=1), +0.0034 (K=2), +0.0038 (K=4), +0.0040 (K=5), +0.0042 (K=6) "
                "| 0.0012 |")
        if want not in text.splitlines():
            sys.exit(f"no row {want!r}:\n{text}")
        if "mean: five-field +0.0035, four-field +0.0042" not in text:
            sys.exit(f"wrong means:\n{text}")
        # A log that is not a six-tile calibration is refused, naming it.
        check_refused(fold_composition.main, [os.path.join(row, "net-road-tile-1.log"), row], "decision-CLASS.log",
                      "a run's log as a six-tile calibration")
        # --looks: a row whose training tiles were each seen by two networks (adjacent margins).
        looks = os.path.join(tmp, "looks")
        os.makedirs(looks)
        with open(os.path.join(looks, "net-road-tile-1.log"), "w") as f:
            # Tile pairs: (+0.0100, +0.0020) differ by 0.008; (+0.0030, -0.0030) opposite signs;
            # (0, 0) left out; (+0.0010, +0.0012); (-0.0040, -0.0010).
            f.write("           tried front-aware z=0 slopes=cells: front margin +0.0010, 3 descents, per field "
                    "+0.0100 +0.0020 +0.0030 -0.0030 +0.0000 +0.0000 +0.0010 +0.0012 -0.0040 -0.0010\n")
        text = printed(fold_composition.main, ["--looks", looks])[1]
        # Four pairs, two beyond 0.005 (0.008, 0.006), one of opposite signs, mean |d| (0.008 + 0.006 + 0.0002 +
        # 0.003) / 4.
        if "| road | 4 | 2 | 1 | 0.0043 |" not in text:
            sys.exit(f"wrong looks row:\n{text}")
        # One look per tile (an ordinary row) is refused, naming the option the row needs.
        check_refused(fold_composition.main, ["--looks", row], "--calibration-network-each",
                      "a row of one look per tile")
    print("ok: fold_composition.py pairs each field's margins, and the looks of one field")


if __name__ == "__main__":
    main()
