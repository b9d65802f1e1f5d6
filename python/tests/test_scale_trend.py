#!/usr/bin/env python3
"""Self-test of scale_trend.py (run by CTest; exit code != 0 on failure).

1. field_measures() on a hand-made field of eight pixels in two cells, every measure worked out by
   hand: each cell's gain (the field's IoU with that cell pooled, less the top level's), its
   ambiguity, unsure, scale and relabelled shares, its region; the field's pooled gain, the share whose
   label moved from the coarser look to the top level, how much of that the coarser look was
   sure of, and the sure changes of the closer look. Ignored pixels count nowhere, and a cell
   without labelled pixels is left out. region_of() inside a footprint and nearest to one.
2. The bundled leave-one-tile-out network of tile 1 on tile 1: the field gain equals two_looks'
   pooled map less the top level's on the same painted maps; main() prints a row per class and
   the summary, and --cells-csv writes each class's cells (as many as the row counts, their
   gains within the IoU's range).
3. A coarser look not above 1, a closer look not below the top level, a bad number and a missing
   network are refused.

Part 2 needs torch, as eval_ensemble does: CTest's tools:scale_trend is skipped (exit 77) without it.
"""

from __future__ import annotations

import csv
import math
import tempfile
from pathlib import Path

import numpy as np
from tool_output import check, check_refused, printed, require_torch
from tool_output import two_class_log_probs as log_probs

from adaptseg_tools import scale_trend, two_looks


def hand_made():
    # truth:        1 1 1 1 | 0 0 0 0      cells A = pixels 0-3, B = 4-7
    # coarse (30):  1 0 0 0 | 1 0 0 0      sure 0.9
    # top  (15):    1 1 0 0 | 1 0 0 0      sure 0.9 except pixels 2 and 4 (0.6)
    # fine (5):     1 0 1 1 | 1 1 0 0      sure 0.8
    truth = np.array([[1, 1, 1, 1, 0, 0, 0, 0]], np.uint8)
    coarse = log_probs([1, 0, 0, 0, 1, 0, 0, 0], 0.9)
    top = log_probs([1, 1, 0, 0, 1, 0, 0, 0], 0.9)
    top[:, 0, 2] = np.log([0.6, 0.4])
    top[:, 0, 4] = np.log([0.4, 0.6])
    fine = log_probs([1, 0, 1, 1, 1, 1, 0, 0], 0.8)
    cells = [(0, 0, 4, 1), (4, 0, 4, 1)]
    r = scale_trend.field_measures(coarse, top, fine, 15.0, 5.0, truth, 1, cells, [(0, 0, 5, 1), (5, 0, 3, 1)])
    a, b = r["cell_rows"]
    # Top: L at 0, 1, 4: TP 2, FP 1, FN 2, IoU 2/5. Pooled (two_looks' hand-made field): L at 0, 2, 3, 4, 5.
    # A pooled: L at 0, 2, 3 and the top's 4: TP 3, FP 1, FN 1, IoU 3/5: gain +1/5.
    # B pooled: the top's L at 0, 1 and 4, 5: TP 2, FP 2, FN 2, IoU 2/6: gain 1/3 − 2/5.
    check(math.isclose(a["gain"], 0.2) and math.isclose(b["gain"], 1 / 3 - 0.4), f"cell gains {a}, {b}")
    # The whole field pooled: TP 3, FP 2, FN 1, IoU 1/2: +0.1.
    check(math.isclose(r["field_gain"], 0.1), f"field gain {r['field_gain']}")
    # Unsure: 1 − 0.9 at every pixel but 2 (A) and 4 (B), 1 − 0.6: 0.7 / 4 in each cell.
    check(math.isclose(a["unsure"], 0.175, rel_tol=1e-6) and math.isclose(b["unsure"], 0.175, rel_tol=1e-6),
          f"unsure {a['unsure']}, {b['unsure']}")
    # Ambiguity: the top level's p_L in (0.2, 0.8) at pixels 2 (0.4) and 4 (0.6) alone: 1/4 in each cell.
    check(math.isclose(a["ambiguity"], 0.25) and math.isclose(b["ambiguity"], 0.25), f"ambiguity {a}, {b}")
    # Coarse → top moves pixel 1 alone (0 → L): A 1/4, B 0; the field 1/8, the coarser look sure there.
    check(math.isclose(a["scale"], 0.25) and b["scale"] == 0.0, f"scale {a['scale']}, {b['scale']}")
    check(math.isclose(r["scale_share"], 1 / 8) and r["scale_sure"] == 1.0, f"scale share {r}")
    # Top → fine moves 1, 2, 3 (A) and 5 (B); the top level sure (0.9) of 1, 3 and 5.
    check(math.isclose(a["relabelled"], 0.75) and math.isclose(b["relabelled"], 0.25), f"relabelled {a}, {b}")
    check(math.isclose(r["sure_changes"], 0.75), f"sure changes {r['sure_changes']}")
    # Regions: A's centre (2) in the first footprint, B's (6) in the second. Two cells: no rank correlation.
    check(a["region"] == 0 and b["region"] == 1 and r["cells"] == 2, f"regions {a['region']}, {b['region']}")
    check(all(math.isnan(v) for v in r["rho"].values()), f"rho of two cells {r['rho']}")
    # Two more pixels the labels ignore, in a third cell: the measures are the same, that cell left out.
    wide = np.concatenate([truth, np.array([[255, 255]], np.uint8)], axis=1)
    pad = np.log(np.full((2, 1, 2), 0.5, np.float32))
    r2 = scale_trend.field_measures(*(np.concatenate([x, pad], 2) for x in (coarse, top, fine)), 15.0, 5.0, wide, 1,
                                    cells + [(8, 0, 2, 1)])
    check(r2["cells"] == 2 and all(math.isclose(r[k], r2[k]) for k in ("field_gain", "scale_share", "sure_changes")),
          f"ignored pixels: {r2}")
    check(r2["cell_rows"][0]["region"] == -1, "no footprints, no region")
    # A centre outside every footprint takes the nearest.
    check(scale_trend.region_of((0, 0, 4, 1), [(0, 0, 2, 1), (6, 0, 2, 1)]) == 0, "nearest footprint")
    check(scale_trend.region_of((4, 0, 4, 1), [(0, 0, 2, 1), (6, 0, 2, 1)]) == 1, "the footprint holding the centre")
    print("ok: the hand-made field's measures")


def main():
    hand_made()
    require_torch()
    from adaptseg_tools import REPO
    from adaptseg_tools.eval_ensemble import load_member
    from adaptseg_tools.training.fields import lawnmower_rects, load_field

    loto = REPO / "examples" / "models" / "mobilenetv2-dubai-loto"
    field = load_field(REPO / "examples" / "data" / "dubai-tile-1")
    model, spec, meta = load_member(loto / "tile-1")
    lps = [two_looks.painted_log_probabilities(model, spec, meta, field, f * field.gsd_cm) for f in (6, 3, 2)]
    rects = lawnmower_rects(field, 2 * field.gsd_cm, tuple(spec.camera_wh))
    for c, name in enumerate(field.classes):
        r = scale_trend.field_measures(*lps, 15.0, 10.0, field.labels, c, rects)
        t = two_looks.compare(lps[1], lps[2], 15.0, 10.0, field.labels, c)
        if math.isnan(t["top"]):
            continue
        check(abs(r["field_gain"] - (t["pooled"] - t["top"])) < 1e-9,
              f"{name}: field gain {r['field_gain']} against two_looks' {t['pooled'] - t['top']}")
    print("ok: tile 1's field gain is two_looks' pooled map less the top level's")

    with tempfile.TemporaryDirectory() as tmp:
        rc, text = printed(scale_trend.main, ["--loto", str(loto), "--tiles", "1", "--fine", "2",
                                              "--cells-csv", f"{tmp}/cells"])
        check(rc is None, f"main returned {rc}")
        for name in ("building", "road", "vegetation", "water"):
            row = next((line for line in text.splitlines() if line.startswith(f"| {name} | tile 1 | 15 → 10 |")), None)
            check(row is not None, f"no row for {name}:\n{text}")
            check(f"| {name} | 1 |" in text, f"no summary for {name}:\n{text}")
            with open(Path(tmp) / f"cells-{name}.csv", newline="") as f:
                cells = list(csv.DictReader(f))
            check(len(cells) == int(row.split("|")[4]), f"{name}: {len(cells)} cells written, the row says {row}")
            check(all(c["field"] == "dubai-tile-1" and c["top_gsd_cm"] == "15" and c["sub_gsd_cm"] == "10"
                      and -1 <= float(c["field_gain"]) <= 1 and 0 <= float(c["top_scale"]) <= 1 for c in cells),
                  f"{name}: cells {cells[:2]}")
    print("ok: main prints a row and a summary per class, and writes the cells")

    check_refused(scale_trend.main, ["--loto", str(loto), "--coarse", "1"], "must be above 1", "a coarser look of 1")
    check_refused(scale_trend.main, ["--loto", str(loto), "--fine", "3"], "below each --top", "a fine look at the top")
    check_refused(scale_trend.main, ["--loto", str(loto), "--top", "3,x"], "comma-separated numbers", "a bad --top")
    check_refused(scale_trend.main, ["--loto", str(loto), "--tiles", "9"], "no model.yaml", "a missing network")
    print("scale_trend: all checks passed")


if __name__ == "__main__":
    main()
