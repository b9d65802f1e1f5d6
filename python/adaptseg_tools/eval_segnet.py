"""Acceptance tables of a bundled segmentation network: per-class IoU and mIoU per GSD band,
field-level and per image, on the fields given (default: dubai-tile-4, the validation tile, and
dubai-tile-6, the test tile).

Every band is a whole-field lawnmower at that GSD (footprints as adaptseg's LawnmowerPlanner
places them, images rendered as its SimulatedSensor renders them); the network runs on the path
of the C++ backend (resampled to its input size, logits back to the camera size, argmax) in
PyTorch on the weights model.onnx was exported from. Labels are scored against the
orthomosaic labels at orthomosaic resolution (adaptseg::image_confusion):

- field: the confusion matrix summed over the band's images; IoU per class, and mIoU over the
  classes present in truth or prediction (ConfusionMatrix::miou_all);
- per image: for each class, the mean IoU of that class over the images whose valid ground is
  at least --min-share that class (the images that contain it; IoU over L = {class}, as
  adaptseg_evaluate's per-image mIoU over L), with the image count.

Prints markdown tables; --json also writes the numbers.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.eval_segnet --model-dir examples/models/mobilenetv2-dubai \\
      [--fields examples/data/dubai-tile-4,examples/data/dubai-tile-6] [--bands 1,1.5,2,2.5,3] \\
      [--json out.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np
import torch

from . import REPO
from .fieldio import IGNORE
from .training.fields import FieldData, load_field
from .training.models import load_exported
from .training.validation import evaluate, miou


def evaluate_field(model, spec, field: FieldData, bands, min_share: float):
    """training.validation.evaluate's field-level numbers per band, and per class the IoU of each
    image whose valid ground is at least `min_share` that class."""
    nc = len(field.classes)
    per_image = {fac: [[] for _ in range(nc)] for fac in bands}

    def on_image(fac, gt, image_cm):
        valid = gt != IGNORE
        counts = np.bincount(gt[valid].astype(np.int64), minlength=nc)
        _, iou = miou(image_cm)
        for c in range(nc):
            if counts[c] >= min_share * valid.sum():
                per_image[fac][c].append(iou[c])

    bands_result = evaluate(model, field, bands, spec, on_image=on_image)
    return {fac: {"gsd_cm": r["gsd_cm"], "images": r["images"], "miou": r["miou_ortho"], "iou": r["iou_ortho"],
                  "per_image_iou_mean": [float(np.mean(v)) if v else None for v in per_image[fac]],
                  "per_image_count": [len(v) for v in per_image[fac]]}
            for fac, r in bands_result.items()}


def fmt(v) -> str:
    return "–" if v is None else f"{v:.3f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model-dir", required=True)
    ap.add_argument("--fields", default=",".join(str(REPO / "examples" / "data" / f"dubai-tile-{k}") for k in (4, 6)))
    ap.add_argument("--bands", default="1,1.5,2,2.5,3", help="GSD factors of the fields' GSD")
    ap.add_argument("--min-share", type=float, default=0.05,
                    help="per-image IoU of a class over the images whose valid ground is at least this share of it")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)

    model, spec, meta = load_exported(Path(args.model_dir))
    bands = [float(v) for v in args.bands.split(",")]
    results = {}
    for fdir in args.fields.split(","):
        field = load_field(Path(fdir))
        if field.classes != meta["classes"]:
            raise SystemExit(f"{fdir}: classes {field.classes} differ from the model's {meta['classes']}")
        role = ("training" if Path(fdir).name in meta["training"]["fields"] else
                "validation" if Path(fdir).name == meta["training"]["validation_field"] else "test")
        results[field.name] = {"role": role, "bands": evaluate_field(model, spec, field, bands, args.min_share)}

    classes = meta["classes"]
    print(f"model {Path(args.model_dir).name}; per-image IoU over images with >= {args.min_share:.0%} of the class")
    for name, r in results.items():
        print(f"\n**{name}** ({r['role']}), field level: IoU per class and mIoU\n")
        print("| GSD [cm/px] | images | " + " | ".join(classes) + " | mIoU |")
        print("| ---: | ---: | " + " | ".join("---:" for _ in classes) + " | ---: |")
        for b in r["bands"].values():
            print(f"| {b['gsd_cm']:.1f} | {b['images']} | " + " | ".join(fmt(v) for v in b["iou"]) +
                  f" | **{b['miou']:.3f}** |")
        print(f"\n**{name}** ({r['role']}), per image: mean IoU of each class over the images that contain it (n)\n")
        print("| GSD [cm/px] | " + " | ".join(classes) + " |")
        print("| ---: | " + " | ".join("---:" for _ in classes) + " |")
        for b in r["bands"].values():
            cells = [f"{fmt(m)} ({n})" for m, n in zip(b["per_image_iou_mean"], b["per_image_count"])]
            print(f"| {b['gsd_cm']:.1f} | " + " | ".join(cells) + " |")
        # Which classes gain from altitude: per-image IoU at the finest band above the coarsest.
        first, last = r["bands"][bands[0]], r["bands"][bands[-1]]
        rising = [c for k, c in enumerate(classes)
                  if first["per_image_iou_mean"][k] is not None and last["per_image_iou_mean"][k] is not None
                  and first["per_image_iou_mean"][k] > last["per_image_iou_mean"][k]]
        print(f"\nper-image IoU higher at {first['gsd_cm']:.1f} than at {last['gsd_cm']:.1f} cm/px: "
              f"{len(rising)} of {len(classes)} classes ({', '.join(rising) or 'none'}); "
              f"field mIoU {first['miou']:.3f} vs {last['miou']:.3f} ({first['miou'] - last['miou']:+.3f})")
    if args.json:
        Path(args.json).write_text(json.dumps({"model": str(args.model_dir), "min_share": args.min_share,
                                               "classes": classes, "fields": results}, indent=2) + "\n")


if __name__ == "__main__":
    main()
