#!/usr/bin/env python3
"""Self-test of two_looks.py (run by CTest; exit code != 0 on failure).

1. compare() on a hand-made field of eight pixels and two classes, every measure worked out by
   hand: the two maps' IoU, the pooled map (weights 1 / GSD), the union, the trim, the additions and
   removals with how often each is right, the bonuses and the break-even, the changes the top level was sure
   of; the guarded map (the top
   level's label where it is sure) at three thresholds; the closer look's changes of label (--flips); the changes gated by a check that is always
   right (`agreed`), and both fusions against a curve.
2. A lawnmower fused with itself changes nothing: pooled, union, trim, top and fine are one map, the
   bonuses 0, nothing added or removed.
3. The bundled leave-one-tile-out network of tile 1 on tile 1: its 15 cm/px lawnmower painted as
   log-probabilities gives each class the IoU its training recorded in model.yaml (within 0.002,
   as class_map's painter); main() with --bands 2 prints a row per class and the summary.
   With --loto, --check (its own set as the check) and --curve (the two lawnmowers themselves): the
   `agreed` columns, each margin over the curve equal to the bonus, and the two passes' table; with
   --guards, the guard table, its threshold 1 (no guard) the pooled map's mean gain over the top level.
4. Bad bands, an unknown class, an odd list of NETWORK FIELD, --check without --loto and a bad --curve
   and a guard outside (0, 1] are refused.

Part 3 needs torch, as eval_ensemble does: CTest's tools:two_looks is skipped (exit 77) without it.
"""

from __future__ import annotations

import math

import numpy as np
from tool_output import check, check_refused, printed, require_torch
from tool_output import two_class_log_probs as log_probs

from adaptseg_tools import two_looks


def hand_made():
    # truth:        1 1 1 1 0 0 0 0
    # top  (15):    1 1 0 0 1 0 0 0   sure 0.9 except pixels 2 and 4 (0.6)
    # fine (5):     1 0 1 1 1 1 0 0   sure 0.8
    truth = np.array([[1, 1, 1, 1, 0, 0, 0, 0]], np.uint8)
    top = log_probs([1, 1, 0, 0, 1, 0, 0, 0], 0.9)
    top[:, 0, 2] = np.log([0.6, 0.4])
    top[:, 0, 4] = np.log([0.4, 0.6])
    fine = log_probs([1, 0, 1, 1, 1, 1, 0, 0], 0.8)
    r = two_looks.compare(top, fine, 15.0, 5.0, truth, 1)
    # top: L at 0, 1, 4 → TP 2, FP 1, FN 2: IoU 2/5. fine: L at 0, 2, 3, 4, 5 → TP 3, FP 2, FN 1: 3/6.
    check(math.isclose(r["top"], 0.4) and math.isclose(r["fine"], 0.5), f"top {r['top']}, fine {r['fine']}")
    # pooled, per pixel log p / 15 + log p' / 5 (fine weighs three times): pixel 1, top sure L (0.9)
    # against fine's 0.8 for 0: ln 0.9/15 + ln 0.2/5 < ln 0.1/15 + ln 0.8/5, so 0; pixels 2, 3 the
    # fine look's L; 4, 5 L (fine says L); 0 L. Pooled L at 0, 2, 3, 4, 5 = fine: IoU 3/6.
    check(math.isclose(r["pooled"], 0.5), f"pooled {r['pooled']}")
    # union: L at 0..5 → TP 4, FP 2: IoU 4/6.
    check(math.isclose(r["union"], 4 / 6), f"union {r['union']}")
    # trim: pooled L where the top level said L too: 0 and 4 → TP 1, FP 1, FN 3: IoU 1/5.
    check(math.isclose(r["trim"], 0.2) and math.isclose(r["trim_bonus"], 0.2 - 0.5), f"trim {r}")
    # added (fine L, top not): 2, 3, 5 over 8 pixels, right at 2 and 3; removed (top L, fine not): 1, wrong.
    check(math.isclose(r["added"], 3 / 8) and math.isclose(r["added_right"], 2 / 3), f"added {r}")
    check(math.isclose(r["removed"], 1 / 8) and r["removed_right"] == 0.0, f"removed {r}")
    check(math.isclose(r["pooled_bonus"], 0.0) and math.isclose(r["union_bonus"], 4 / 6 - 0.5), f"bonuses {r}")
    check(math.isclose(r["break_even"], 0.4 / 1.4), f"break-even {r['break_even']}")
    # Ignored pixels count nowhere: the same with two more pixels the labels ignore.
    wide = np.concatenate([truth, np.array([[255, 255]], np.uint8)], axis=1)
    pad = np.log(np.full((2, 1, 2), 0.5, np.float32))
    r2 = two_looks.compare(np.concatenate([top, pad], 2), np.concatenate([fine, pad], 2), 15.0, 5.0, wide, 1)
    check(all(math.isclose(r[k], r2[k]) for k in ("top", "pooled", "union", "trim", "added", "removed")), f"{r2}")
    # A check network that is always right gates the pooled map's changes: pixel 1 (pooled 0, check 1) keeps
    # the top level's L, 3 (pooled L, check L) takes L, 4 (pooled L, check 0) keeps the top's L, 5 (pooled L,
    # check 0) keeps the top's 0: L at 0..4, TP 4, FP 1: IoU 4/5. Against a curve whose best lawnmower has 0.6:
    # pooled 0.5 - 0.6, agreed 0.8 - 0.6.
    r3 = two_looks.compare(top, fine, 15.0, 5.0, truth, 1, check_labels=truth.copy(), curve_best=0.6)
    check(math.isclose(r3["agreed"], 0.8) and math.isclose(r3["agreed_bonus"], 0.3), f"agreed {r3}")
    check(math.isclose(r3["pooled_over_curve"], -0.1) and math.isclose(r3["agreed_over_curve"], 0.2), f"over {r3}")
    check("agreed" not in r and "pooled_over_curve" not in r, "no check, no curve: neither measure")
    # The guard: the top level's own probability is 0.9 at every pixel but 2 and 4 (0.6). At 0.75 the top's label
    # stays at the sure pixels and the pooled one is taken at 2 and 4 (both L): L at 0, 1, 2, 4, TP 3, FP 1, FN 1:
    # IoU 3/5, bonus 0.6 - 0.5. At 1 nothing is sure (the pooled map, 0.5); at 0.5 everything is (the top's, 0.4).
    check(math.isclose(r["guarded"], 0.6) and math.isclose(r["guarded_bonus"], 0.1), f"guarded {r}")
    # The closer look changes pixels 1, 2, 3 and 5; the top level was sure (0.9 > 0.75) of 1, 3 and 5.
    check(math.isclose(r["sure_changes"], 0.75), f"sure changes {r['sure_changes']}")
    r4 = two_looks.compare(top, fine, 15.0, 5.0, truth, 1, guards=(1.0, 0.75, 0.5))
    check(np.allclose(r4["guard_gains"], [0.1, 0.2, 0.0]), f"guard gains {r4['guard_gains']}")
    check("guard_gains" not in r, "no guards, no guard gains")
    # The closer look's changes of label: 0 → 1 at pixels 2, 3, 5 (truly 1 at 2 and 3; the top sure 0.6, 0.9,
    # 0.9, the fine 0.8), 1 → 0 at pixel 1 (truly 1: wrong; 0.9 and 0.8).
    f = two_looks.flips(top, fine, truth, ["c0", "c1"], ["c1"])
    want = [("c0", "c1", 3 / 8, 2 / 3, 1 / 3, 0.9, 0.8), ("c1", "c0", 1 / 8, 0.0, 1.0, 0.9, 0.8)]
    check(len(f) == 2 and all(x[:2] == w[:2] and np.allclose(x[2:], w[2:]) for x, w in zip(f, want)), f"flips {f}")
    print("ok: the hand-made field's measures")


def main():
    hand_made()
    require_torch()
    from adaptseg_tools import REPO
    from adaptseg_tools.eval_ensemble import load_member
    from adaptseg_tools.training.fields import load_field
    import yaml

    net = REPO / "examples" / "models" / "mobilenetv2-dubai-loto" / "tile-1"
    fdir = REPO / "examples" / "data" / "dubai-tile-1"
    field = load_field(fdir)
    model, spec, meta = load_member(net)
    lp = two_looks.painted_log_probabilities(model, spec, meta, field, 3 * field.gsd_cm)
    record = next(b for b in yaml.safe_load((net / "model.yaml").read_text())["validation"]["bands"]
                  if b["gsd_factor"] == 3.0)
    for c, name in enumerate(field.classes):
        r = two_looks.compare(lp, lp, 15.0, 15.0, field.labels, c)
        check(abs(r["top"] - record["iou_ortho"][c]) < 0.002,
              f"{name}: painted IoU {r['top']:.4f} against the recorded {record['iou_ortho'][c]:.4f}")
        check(r["top"] == r["fine"] == r["pooled"] == r["union"] == r["trim"] and r["added"] == r["removed"] == 0.0
              and r["pooled_bonus"] == r["union_bonus"] == r["trim_bonus"] == 0.0,
              f"{name}: a lawnmower fused with itself: {r}")
    print("ok: tile 1's lawnmower: the recorded IoU; fused with itself, the same map")

    rc, text = printed(two_looks.main, [str(net), str(fdir), "--bands", "2"])
    check(rc is None, f"main returned {rc}")
    for name in ("building", "road", "vegetation", "water"):
        check(f"| {name} | dubai-tile-1 | 15 → 10 |" in text, f"no row for {name}:\n{text}")
        check(f"| {name} | 10 | 1 |" in text, f"no summary for {name}:\n{text}")
    print("ok: main prints a row and a summary per class")

    # Tile 1 by its own network as the check, the curve the top and finer lawnmowers themselves: the margin over
    # the curve is the bonus, and the two passes' choice needs other fields (one field: none listed).
    loto = str(REPO / "examples" / "models" / "mobilenetv2-dubai-loto")
    rc, text = printed(two_looks.main, ["--loto", loto, "--tiles", "1", "--bands", "2", "--check", loto, "--curve", "2,3"])
    check(rc is None and "| agreed | bonus pooled |" in text and "over curve agreed" in text, f"columns:\n{text}")
    for line in text.splitlines():
        if line.startswith("| building | tile 1 |"):
            cols = [c.strip() for c in line.split("|")]
            check(abs(float(cols[11]) - float(cols[16])) < 0.0006, f"pooled bonus {cols[11]} against over curve {cols[16]}")
    check("Two passes, the finer GSD chosen on the other fields" in text, f"no two-pass table:\n{text}")
    print("ok: --check and --curve on tile 1")

    rc, text = printed(two_looks.main, [str(net), str(fdir), "--bands", "2", "--guards", "1,0.75", "--flips"])
    check("| dubai-tile-1 | 15 → 10 | " in text.split("The closer look's changes of label")[-1], f"no flips:\n{text}")
    rows = [[c.strip() for c in line.split("|")] for line in text.splitlines() if "| dubai-tile-1 | 15 → 10 |" in line]
    rows = [c for c in rows if c[1] in ("building", "road", "vegetation", "water")]  # not the --flips rows
    pooled_gain = np.mean([float(c[6]) - float(c[4]) for c in rows])
    table = next(line for line in text.splitlines() if line.startswith("| all fields |"))
    check(rc is None and len(rows) == 4 and abs(float(table.split("|")[2]) - pooled_gain) < 0.001,
          f"threshold 1 against the pooled map's mean gain {pooled_gain:+.4f}:\n{text}")
    print("ok: --guards")

    check_refused(two_looks.main, [str(net), str(fdir), "--bands", "3"], "below --top", "a band as coarse as the top")
    check_refused(two_looks.main, [str(net), str(fdir), "--classes", "forest"], "no class forest", "an unknown class")
    check_refused(two_looks.main, [str(net)], "NETWORK FIELD", "a network without its field")
    check_refused(two_looks.main, [str(net), str(fdir), "--check", loto], "--check needs --loto", "--check on pairs")
    check_refused(two_looks.main, [str(net), str(fdir), "--curve", "2,x"], "comma-separated", "a bad --curve")
    check_refused(two_looks.main, [str(net), str(fdir), "--guards", "0.8,1.5"], "each must be in (0, 1]", "a guard above 1")
    print("two_looks: all checks passed")


if __name__ == "__main__":
    main()
