#!/usr/bin/env python3
"""Self-test of scale_response.py (run by CTest; exit code != 0 on failure), on a bundled network
and its real held-out tile.

1. The bundled leave-one-tile-out network of tile 1 (model.onnx only, run through OpenCV's DNN
   module, eval_ensemble.load_member) maps tile 1's top-level lawnmower (15 cm/px, four images) with
   the per-class IoU its training recorded in model.yaml from the PyTorch weights (within 0.002),
   and the rises are that file's own differences.
2. A coarser look moves the map: more at 3x than at 1.5x in the mean over the classes, and the map
   of the image degraded 1.5x differs from the top level's somewhere.
3. The rank correlation: +1 and -1 on monotone pairs, ties sharing a rank, nan under three pairs.
4. Factors <= 1 are refused.

Needs torch (Debian python3-torch), as eval_ensemble does: CTest's tools:scale_response is skipped
(exit 77) where it is missing.
"""

from __future__ import annotations

import math

from tool_output import check, require_torch

require_torch()

import yaml  # noqa: E402

from adaptseg_tools import REPO, scale_response  # noqa: E402


def main():
    net = REPO / "examples" / "models" / "mobilenetv2-dubai-loto" / "tile-1"
    check(not (net / "model.pt").exists(), f"{net} should ship its model.onnx alone (the case tested)")
    out = scale_response.measure(net, REPO / "examples" / "data" / "dubai-tile-1", [1.5, 3.0])
    meta = yaml.safe_load((net / "model.yaml").read_text())
    top = next(b for b in meta["validation"]["bands"] if b["gsd_factor"] == 3.0)
    check(out["images"] == top["images"], f"images {out['images']} != model.yaml's {top['images']}")
    for c, row in enumerate(out["per_class"]):
        check(abs(row["iou_top"] - top["iou_ortho"][c]) < 0.002,
              f"class {c}: IoU {row['iou_top']:.4f} against the recorded {top['iou_ortho'][c]:.4f}")
        ten = next(b for b in meta["validation"]["bands"] if b["gsd_factor"] == 2.0)
        check(abs(row["rise_2"] - (ten["iou_ortho"][c] - top["iou_ortho"][c])) < 1e-12, f"class {c}: rise to 10 cm/px")
    moved = {f: sum(r[f"moved_{f:g}"] for r in out["per_class"]) / len(out["per_class"]) for f in (1.5, 3.0)}
    check(0 < moved[1.5] < moved[3.0], f"mean moved {moved}: a coarser look should move the map more")

    rc = scale_response.rank_correlation
    check(abs(rc([1, 2, 3, 4], [10, 20, 30, 40]) - 1) < 1e-12, "monotone: +1")
    check(abs(rc([1, 2, 3, 4], [4, 3, 2, 1]) + 1) < 1e-12, "reversed: -1")
    check(abs(rc([1, 1, 2, 3], [1, 2, 3, 4]) - 0.9486832980505138) < 1e-9, "ties share their mean rank")
    check(math.isnan(rc([1, 2, math.nan], [1, 2, 3])), "two pairs: nan")
    try:
        scale_response.main([str(net.parent), "--factors", "1,2"])
        check(False, "--factors 1,2 accepted")
    except SystemExit as e:
        check("must be > 1" in str(e), f"refusal: {e}")
    print("scale_response: all checks passed")


if __name__ == "__main__":
    main()
