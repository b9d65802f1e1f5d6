"""Where a network puts a class on a field, against the field's labels: a picture to look at.

Each band is a whole-field lawnmower at that GSD, each image segmented on the C++ backend's path
(eval_ensemble.member_probabilities: the network's model.pt in PyTorch, or its model.onnx through
OpenCV's DNN module) and its labels painted into the field's frame, a later image over an earlier
one where footprints overlap. Prints per band the class's IoU on that map (on the bundled tiles the
IoU eval_ensemble and the networks' model.yaml record), the share of the field's labelled ground it
predicts and the share it truly covers; writes one picture: the orthomosaic beside one panel
per band, hits green, false positives red, misses orange, the rest grey, scaled down by --scale.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.class_map \\
      examples/models/mobilenetv2-dubai-loto/tile-5 examples/data/dubai-tile-5 \\
      --class vegetation [--bands 1,3] [--scale 4] [--out out/class_map.png]
(the network that never saw tile 5 on tile 5: the vegetation it writes at 5 cm/px on the shallow
sea). Needs torch, as eval_ensemble does.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np
import torch

from .eval_ensemble import load_member, member_probabilities
from .fieldio import IGNORE
from .training.fields import capture, lawnmower_rects, load_field

HIT, FALSE, MISS, REST = (0, 200, 0), (0, 0, 255), (0, 128, 255), (40, 40, 40)  # BGR


def painted_labels(model, spec, meta, field, gsd_cm: float, images: list | None = None) -> np.ndarray:
    """The field's frame (its labels' shape) with each lawnmower image's labels at `gsd_cm`
    painted in, in flight order; IGNORE where no image fell. With `images`, appends per image
    with labelled ground its footprint's origin (c0, r0, field pixels), the number of its labelled
    field pixels the network gives each class (`predicted`) and the labels give each class
    (`true`), and the mean top-class probability over them (`confidence`)."""
    out = np.full(field.labels.shape, IGNORE, np.uint8)
    h, w = out.shape
    nc = len(field.classes)
    for (c0, r0, fw, fh) in lawnmower_rects(field, gsd_cm, tuple(spec.camera_wh)):
        bgr, _, truth = capture(field, c0, r0, fw, fh, tuple(spec.camera_wh))
        prob = member_probabilities(model, spec, meta, bgr)
        lab = cv2.resize(prob.argmax(0).astype(np.uint8), (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
        valid = truth != IGNORE  # the footprint's labels, at the field's resolution as `lab`
        if images is not None and valid.any():
            top = cv2.resize(prob.max(0).astype(np.float32), (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
            images.append({"c0": c0, "r0": r0, "pixels": int(valid.sum()),
                           "predicted": np.bincount(lab[valid], minlength=nc)[:nc],
                           "true": np.bincount(truth[valid], minlength=nc)[:nc],
                           "confidence": float(top[valid].mean())})
        ra, ca, rb, cb = max(r0, 0), max(c0, 0), min(r0 + fh, h), min(c0 + fw, w)
        out[ra:rb, ca:cb] = lab[ra - r0:rb - r0, ca - c0:cb - c0]
    return out


def class_counts(labels: np.ndarray, truth: np.ndarray, cls: int) -> dict:
    """Hits, false positives and misses of class `cls` over the labelled ground."""
    valid = truth != IGNORE
    pred, true = (labels == cls) & valid, (truth == cls) & valid
    return {"hit": int((pred & true).sum()), "false": int((pred & ~true).sum()),
            "miss": int((~pred & true).sum()), "ground": int(valid.sum())}


def panel(labels: np.ndarray, truth: np.ndarray, cls: int) -> np.ndarray:
    """BGR picture of class `cls`: hits, false positives, misses, the rest (field resolution)."""
    valid = truth != IGNORE
    pred, true = (labels == cls) & valid, (truth == cls) & valid
    out = np.empty(truth.shape + (3,), np.uint8)
    out[:] = REST
    out[pred & true], out[pred & ~true], out[~pred & true] = HIT, FALSE, MISS
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("network", help="a network folder (model.yaml with model.pt or model.onnx)")
    ap.add_argument("field", help="a field folder (field.yaml)")
    ap.add_argument("--class", dest="cls", required=True, help="a class name of the field")
    ap.add_argument("--bands", default="1,3", help="GSD factors of the field's GSD (default 1,3)")
    ap.add_argument("--scale", type=int, default=4, help="the picture's reduction (default 4)")
    ap.add_argument("--out", default="out/class_map.png")
    ap.add_argument("--images", type=int, default=0, metavar="N",
                    help="also list per band the N images whose share of the class most exceeds the truth's")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    field = load_field(Path(args.field))
    if args.cls not in field.classes:
        raise SystemExit(f"--class {args.cls}: not a class of {args.field} ({', '.join(field.classes)})")
    try:
        bands = [float(v) for v in args.bands.split(",")]
    except ValueError:
        raise SystemExit(f"--bands {args.bands}: comma-separated numbers") from None
    if not bands or min(bands) <= 0 or args.scale < 1 or args.images < 0:
        raise SystemExit("--bands must be positive factors, --scale at least 1 and --images not negative")
    model, spec, meta = load_member(Path(args.network))
    if meta["classes"] != field.classes:
        raise SystemExit(f"{args.network}: classes {meta['classes']} differ from the field's {field.classes}")
    cls = field.classes.index(args.cls)

    def small(img):
        return cv2.resize(img, None, fx=1 / args.scale, fy=1 / args.scale, interpolation=cv2.INTER_AREA)

    panels, listed = [small(field.image)], {}
    print(f"| {field.name}, {args.cls} | IoU | predicted share | true share |")
    print("| --- | ---: | ---: | ---: |")
    for fac in bands:
        gsd = field.gsd_cm * fac
        images = []
        labels = painted_labels(model, spec, meta, field, gsd, images)
        n = class_counts(labels, field.labels, cls)
        iou = n["hit"] / max(1, n["hit"] + n["false"] + n["miss"])
        print(f"| {gsd:g} cm/px | {iou:.3f} | {(n['hit'] + n['false']) / n['ground']:.4f} | "
              f"{(n['hit'] + n['miss']) / n['ground']:.4f} |")
        panels.append(small(panel(labels, field.labels, cls)))
        listed[gsd] = sorted(images, key=lambda m: (m["true"][cls] - m["predicted"][cls]) / m["pixels"])[:args.images]
    for gsd, images in listed.items():
        if not images:
            continue
        print(f"\n{gsd:g} cm/px, the {len(images)} images whose share of {args.cls} most exceeds the truth's "
              f"(footprint origin in field pixels; the class the labels give most of the image):")
        print(f"| c0 | r0 | predicted {args.cls} | true {args.cls} | mostly, truly | mean top probability |")
        print("| ---: | ---: | ---: | ---: | --- | ---: |")
        for m in images:
            top = int(np.argmax(m["true"]))
            print(f"| {m['c0']} | {m['r0']} | {m['predicted'][cls] / m['pixels']:.2f} | {m['true'][cls] / m['pixels']:.2f} | "
                  f"{field.classes[top]} {m['true'][top] / m['pixels']:.2f} | {m['confidence']:.2f} |")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), np.concatenate(panels, axis=1))
    print(f"\n{out}: the field, then per band hits green, false positives red, misses orange")


if __name__ == "__main__":
    main()
