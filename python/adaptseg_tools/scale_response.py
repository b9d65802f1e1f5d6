"""Whether a field's response to a coarser look forecasts its gain from a closer one.

The decision lacks each new field's own rise of the class IoU below the top level (the in-sample
ceiling of docs/results.md, "Leave one tile out"). The UAV cannot look closer before it descends,
but it can look coarser: each top-level image degraded to a GSD `f` times the top level's
(resampled down with INTER_AREA and back up bilinearly, the same footprint) and segmented again.
How far the network's map of a class moves under that (label-free: 1 - IoU of the class between
the top-level map and the degraded one) and how far its IoU against the labels falls are
measured per field, and ranked against the field's real rise from the top level (15 cm/px) to
12.5, 10 and 5 cm/px, read from the network's own held-out scores (model.yaml's validation bands,
the whole-field lawnmowers of train_segnet).

Each SET is a folder of leave-one-tile-out networks (SET/tile-k, k = 1..6, each scored on the
tile it never saw, e.g. examples/models/mobilenetv2-dubai-loto); tile k is segmented by
SET/tile-k, from its model.pt where the folder has one, else from its model.onnx through OpenCV's
DNN module, the C++ backend's runtime (eval_ensemble.load_member).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.scale_response SET [SET ...] \\
      [--factors 1.5,2,3] [--tiles 1,2,3,4,5,6] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import cv2
import numpy as np
import torch

from . import REPO
from .eval_ensemble import load_member, member_probabilities
from .fieldio import IGNORE
from .proxy_table import spearman
from .training.fields import capture, lawnmower_rects, load_field
from .training.validation import confusion, miou

TOP = 3.0  # the top level, as a factor of the fields' GSD (15 cm/px on the Dubai tiles)
RISES = (2.5, 2.0, 1.0)  # 12.5, 10 and 5 cm/px


def class_ious(cm: np.ndarray) -> list[float]:
    """Per class IoU (nan where the class is in neither truth nor prediction)."""
    return [math.nan if v is None else v for v in miou(cm)[1]]


def degrade(bgr: np.ndarray, factor: float) -> np.ndarray:
    """The image as a camera `factor` times coarser would see the same footprint, at the same size."""
    h, w = bgr.shape[:2]
    small = cv2.resize(bgr, (max(1, round(w / factor)), max(1, round(h / factor))), interpolation=cv2.INTER_AREA)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def measure(model_dir: Path, field_dir: Path, factors: list[float]) -> dict:
    """One network on one field: per class its top-level IoU, its held-out rises and, per factor,
    the label-free disagreement and the fall of the IoU under degradation."""
    model, spec, meta = load_member(model_dir)
    field = load_field(field_dir)
    if field.classes != meta["classes"]:
        raise SystemExit(f"{field_dir}: classes {field.classes} differ from {model_dir}'s {meta['classes']}")
    bands = {float(b["gsd_factor"]): b["iou_ortho"] for b in meta.get("validation", {}).get("bands", [])}
    missing = [f for f in (TOP,) + RISES if f not in bands]
    if missing or meta["validation"].get("field") != field.name:
        raise SystemExit(f"{model_dir}/model.yaml: no held-out scores on {field.name} at GSD factors {missing or list(RISES)}")
    nc = len(meta["classes"])
    top = np.zeros((nc, nc + 1), np.int64)
    truth = {f: np.zeros((nc, nc + 1), np.int64) for f in factors}
    moved = {f: np.zeros((nc, nc + 1), np.int64) for f in factors}
    images = 0
    for (c0, r0, fw, fh) in lawnmower_rects(field, field.gsd_cm * TOP, spec.camera_wh):
        rgb, _, gt = capture(field, c0, r0, fw, fh, spec.camera_wh)
        if (gt != IGNORE).sum() == 0:
            continue

        def labels(img):
            lab = member_probabilities(model, spec, meta, img).argmax(0).astype(np.uint8)
            return cv2.resize(lab, (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)

        at_top = labels(rgb)
        top += confusion(gt, at_top, nc)
        for f in factors:
            coarse = labels(degrade(rgb, f))
            truth[f] += confusion(gt, coarse, nc)
            moved[f] += confusion(np.where(gt == IGNORE, IGNORE, at_top).astype(np.uint8), coarse, nc)
        images += 1
    iou_top = class_ious(top)
    out = {"field": field.name, "network": str(model_dir), "images": images, "classes": meta["classes"], "per_class": []}
    for c in range(nc):
        row = {"iou_top": iou_top[c], "iou_top_held_out": bands[TOP][c]}
        for g in RISES:
            row[f"rise_{g:g}"] = (math.nan if bands[g][c] is None or bands[TOP][c] is None
                                  else bands[g][c] - bands[TOP][c])
        for f in factors:
            row[f"moved_{f:g}"] = 1.0 - class_ious(moved[f])[c]
            row[f"fall_{f:g}"] = iou_top[c] - class_ious(truth[f])[c]
        out["per_class"].append(row)
    return out


def rank_correlation(x: list[float], y: list[float]) -> float:
    """Spearman's rho (proxy_table.spearman) over the pairs where both are numbers."""
    pairs = [(a, b) for a, b in zip(x, y) if not (math.isnan(a) or math.isnan(b))]
    return spearman([p[0] for p in pairs], [p[1] for p in pairs])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sets", nargs="+", help="folders of leave-one-tile-out networks (SET/tile-k)")
    ap.add_argument("--factors", default="1.5,2,3", help="degradations, as multiples of the top level's GSD (> 1)")
    ap.add_argument("--tiles", default="1,2,3,4,5,6")
    ap.add_argument("--fields", default=str(REPO / "examples" / "data"), help="folder of the dubai-tile-k fields")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    factors = [float(v) for v in args.factors.split(",")]
    if any(f <= 1 for f in factors):
        raise SystemExit(f"--factors {args.factors}: each must be > 1 (a coarser look)")
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)

    results = {}
    for s in args.sets:
        results[s] = []
        for k in args.tiles.split(","):
            d = Path(s) / f"tile-{k}"
            if (d / "model.onnx").is_file() or (d / "model.pt").is_file():
                results[s].append(measure(d, Path(args.fields) / f"dubai-tile-{k}", factors))
        if len(results[s]) < 3:
            raise SystemExit(f"{s}: {len(results[s])} networks of tile-1 .. tile-6; at least three are needed")
    classes = results[args.sets[0]][0]["classes"]
    measures = [f"moved_{f:g}" for f in factors] + [f"fall_{f:g}" for f in factors]
    rises = [f"rise_{g:g}" for g in RISES]
    print("Rank correlation over the tiles, each measure of the top level's response to a coarser look "
          "against the tile's rise from 15 cm/px to 12.5 / 10 / 5 cm/px (moved: label-free; fall: against the labels)\n")
    print("| class | set (tiles) | " + " | ".join(measures) + " |")
    print("| --- | --- | " + " | ".join("---:" for _ in measures) + " |")
    for c, name in enumerate(classes):
        for s, fields in results.items():
            rows = [f["per_class"][c] for f in fields]
            cells = [" / ".join(f"{rank_correlation([r[m] for r in rows], [r[g] for r in rows]):+.2f}" for g in rises)
                     for m in measures]
            print(f"| {name} | {Path(s).name} ({len(fields)}) | " + " | ".join(cells) + " |")
    print("\nPer tile (the first set): IoU at the top level, rises to 12.5 / 10 / 5 cm/px, and per factor moved / fall\n")
    for c, name in enumerate(classes):
        for f in results[args.sets[0]]:
            r = f["per_class"][c]
            print(f"{name:10s} {f['field']}: IoU {r['iou_top']:.3f}, rises " + " / ".join(f"{r[g]:+.3f}" for g in rises)
                  + ", " + ", ".join(f"x{x:g} {r[f'moved_{x:g}']:.3f} / {r[f'fall_{x:g}']:+.3f}" for x in factors))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
