"""Whether a second, coarser look tells which of a closer look's changes are right (issue 53, item
3: a label-free sign, on a field nobody tuned for, of whether a descent's relabelling is gain).
Reads calibration's cell samples (`adaptseg_calibrate --cell-samples-csv`): per cell the shares of
its field pixels that the closer look moved into L (`added`) and out of it (`removed`), of those
the ones the ground truth agrees with (`added_right`, `removed_right`), the ones the region's look
at twice the cell's GSD also made (`added_confirmed`, `removed_confirmed`; no truth needed) and
the confirmed ones that are right (`added_confirmed_right`, `removed_confirmed_right`). With
`--check reframed` the check is instead the region flown again in frames shifted half a footprint
along the rows, the same ground at the same GSD in another image's context (`*_reframed` columns,
`adaptseg_calibrate --frame-check`).

Per finer GSD whose cells have the check and per field, for additions and for removals: the pixels
changed, the share that is right, the share the coarser look confirms, and the share right among
the confirmed and among the unconfirmed changes. Then what the field's IoU of L gains, summed over
its cells each re-mapped alone, in the linear exchange (ΔTP − IoU·ΔFP) / U of its top-level map
(U = TP + FP + FN): with every change kept (`all`), with only the confirmed ones, with only the
removals, with only the additions. Last, over the fields, the correlation between the share
confirmed and the share right (can a flight read a field's rightness off the confirmation?), and
over the cells, per field and over all, the correlation of a cell's field gain with its relabelled
share, its confirmed share and, for reference, its right share (each times the cell's field
share): does the confirmation forecast a cell's gain better than the relabelling it checks?

Usage: change_checks.py CELLS_CSV [--top GSD] [--check confirmed|reframed]   (--top: only the cells seen from that top level)
"""

from __future__ import annotations

import csv
import math
import sys
from collections import defaultdict

from .descent_table import correlation

CHECKS = ("confirmed", "reframed")


def columns(check: str) -> tuple[str, ...]:
    """The CSV columns read with `check` (one of CHECKS) as the confirming look."""
    return ("added", "removed", "added_right", "removed_right", f"added_{check}", f"removed_{check}",
            f"added_{check}_right", f"removed_{check}_right")


def usage() -> int:
    print(__doc__.strip().splitlines()[-1], file=sys.stderr)
    return 2


def totals(rows: list[dict], top: float | None, check: str = "confirmed") -> dict:
    """(sub GSD, field) -> pixel sums of the check's columns (named as the `confirmed` ones) and
    of the linear gains, over its cells."""
    names = columns(check)
    out: dict = defaultdict(lambda: defaultdict(float, per_cell=[]))
    for r in rows:
        if top is not None and abs(float(r["top_gsd_cm"]) - top) > 1e-6:
            continue
        v = {k: float(r[n]) * float(r["field_px"]) for k, n in zip(columns("confirmed"), names)}
        if math.isnan(v["added_confirmed"]) or not float(r["field_px"]) > 0:
            continue
        tp, fp, fn = (float(r[k]) for k in ("field_tp", "field_fp", "field_fn"))
        union = tp + fp + fn
        if not union > 0:
            continue
        iou = tp / union

        def gain(a_right: float, a_wrong: float, r_right: float, r_wrong: float) -> float:
            # right additions are TP (from FN), wrong ones FP; right removals drop an FP, wrong ones a TP
            return ((a_right - r_wrong) - iou * (a_wrong - r_right)) / union

        t = out[(float(r["sub_gsd_cm"]), r["field"])]
        t["cells"] += 1
        for k in columns("confirmed"):
            t[k] += v[k]
        a_r, r_r = v["added_right"], v["removed_right"]
        a_w, r_w = v["added"] - a_r, v["removed"] - r_r
        ca_r, cr_r = v["added_confirmed_right"], v["removed_confirmed_right"]
        ca_w, cr_w = v["added_confirmed"] - ca_r, v["removed_confirmed"] - cr_r
        t["all"] += gain(a_r, a_w, r_r, r_w)
        t["confirmed"] += gain(ca_r, ca_w, cr_r, cr_w)
        t["removals"] += gain(0.0, 0.0, r_r, r_w)
        t["additions"] += gain(a_r, a_w, 0.0, 0.0)
        t["measured"] += float(r["field_gain"])
        share = float(r["field_share"])
        t["per_cell"].append((float(r["field_gain"]), float(r["relabelled"]) * share,
                              (v["added_confirmed"] + v["removed_confirmed"]) / float(r["field_px"]) * share,
                              (a_r + r_r) / float(r["field_px"]) * share))
    return out


def ratio(a: float, b: float) -> float:
    return a / b if b > 0 else math.nan


def main(argv: list[str]) -> int:
    top, check = None, "confirmed"
    for flag in ("--top", "--check"):
        if flag in argv:
            i = argv.index(flag)
            if i + 1 >= len(argv):
                return usage()
            if flag == "--top":
                top = float(argv[i + 1])
            else:
                check = argv[i + 1]
            argv = argv[:i] + argv[i + 2:]
    if len(argv) != 1 or check not in CHECKS:
        return usage()
    with open(argv[0], newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [k for k in columns(check) + ("field_px", "field_share", "relabelled", "field_gain", "field_tp", "field_fp",
                                                 "field_fn")
               if rows and k not in rows[0]]
    if missing:
        print(f"change_checks: {argv[0]} has no column {', '.join(missing)} "
              "(written by adaptseg_calibrate --cell-samples-csv since the checks were added)", file=sys.stderr)
        return 2
    t = totals(rows, top, check)
    if not t:
        print(f"change_checks: no cell has a {check} check (twice its GSD not a candidate, or no --frame-check)",
              file=sys.stderr)
        return 2
    print("| GSD | field | cells | added px | right | confirmed | right if confirmed | right if not "
          "| removed px | right | confirmed | right if confirmed | right if not "
          "| gain all | confirmed only | removals only | additions only | measured |")
    print("|" + " --- |" * 18)
    spread: dict = defaultdict(list)
    for (g, field), v in sorted(t.items()):
        cells = [f"{g:g}", field, str(int(v["cells"]))]
        for side in ("added", "removed"):
            n, right, conf, conf_right = (v[side], v[side + "_right"], v[side + "_confirmed"],
                                          v[side + "_confirmed_right"])
            p_right, p_conf = ratio(right, n), ratio(conf, n)
            cells += [f"{n:.0f}", f"{p_right:.2f}", f"{p_conf:.2f}", f"{ratio(conf_right, conf):.2f}",
                      f"{ratio(right - conf_right, n - conf):.2f}"]
            spread[(g, side)].append((p_conf, p_right))
        cells += [f"{v[k]:+.4f}" for k in ("all", "confirmed", "removals", "additions", "measured")]
        print("| " + " | ".join(cells) + " |")
    print()
    print("| GSD | changes | fields | corr(share confirmed, share right) | confirmed only > all |")
    print("| --- | --- | --- | --- | --- |")
    for (g, side), pairs in sorted(spread.items()):
        pairs = [p for p in pairs if not (math.isnan(p[0]) or math.isnan(p[1]))]
        better = sum(1 for (gg, _), v in t.items() if gg == g and v["confirmed"] > v["all"])
        fields = sum(1 for gg, _ in t if gg == g)
        r = correlation([p[0] for p in pairs], [p[1] for p in pairs])
        print(f"| {g:g} | {side} | {len(pairs)} | {r:+.2f} | {better} of {fields} |")
    print()
    print("| GSD | field | cells | corr(gain, relabelled) | corr(gain, confirmed) | corr(gain, right) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for g in sorted({gg for gg, _ in t}):
        groups = [(field, v["per_cell"]) for (gg, field), v in sorted(t.items()) if gg == g]
        groups.append(("all", [c for _, cells in groups for c in cells]))
        for field, cells in groups:
            gain = [c[0] for c in cells]
            rs = [correlation([c[k] for c in cells], gain) for k in (1, 2, 3)]
            print(f"| {g:g} | {field} | {len(cells)} | " + " | ".join(f"{r:+.2f}" for r in rs) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
