#!/usr/bin/env python3
"""Self-test of class_map.py (run by CTest; exit code != 0 on failure), on a bundled network and
its real held-out tile.

1. The bundled leave-one-tile-out network of tile 1 (model.onnx through OpenCV's DNN module), its
   top-level lawnmower (15 cm/px, four images) painted into tile 1's frame: every labelled pixel
   gets a label, the classes' predictions partition the labelled ground, and each class's IoU is
   within 0.002 of the IoU its training recorded in model.yaml from the PyTorch weights; the four
   images' own counts (predicted and true per class) add up to the map's.
2. The picture: the field and one panel at full resolution (--scale 1), its green pixels the
   hits, its red the false positives, its orange the misses of the class; --images 2 lists two.
3. An unknown class, bad bands and a negative --images are refused.

Needs torch, as eval_ensemble does: CTest's tools:class_map is skipped (exit 77) without it.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from tool_output import check, printed, require_torch

require_torch()

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from adaptseg_tools import REPO, class_map  # noqa: E402
from adaptseg_tools.eval_ensemble import load_member  # noqa: E402
from adaptseg_tools.fieldio import IGNORE  # noqa: E402
from adaptseg_tools.training.fields import load_field  # noqa: E402


def refused(argv, fragment):
    try:
        class_map.main(argv)
    except SystemExit as e:
        check(fragment in str(e.code), f"{argv}: '{e.code}' lacks '{fragment}'")
        print(f"ok: refused: {e.code}")
        return
    check(False, f"{argv} was not refused")


def main():
    net = REPO / "examples" / "models" / "mobilenetv2-dubai-loto" / "tile-1"
    fdir = REPO / "examples" / "data" / "dubai-tile-1"
    field = load_field(fdir)
    model, spec, meta = load_member(net)
    images = []
    labels = class_map.painted_labels(model, spec, meta, field, 3 * field.gsd_cm, images)
    valid = field.labels != IGNORE
    check(not (labels[valid] == IGNORE).any(), "a labelled pixel got no label from the lawnmower")
    record = next(b for b in yaml.safe_load((net / "model.yaml").read_text())["validation"]["bands"]
                  if b["gsd_factor"] == 3.0)
    predicted = 0
    for c, name in enumerate(field.classes):
        n = class_map.class_counts(labels, field.labels, c)
        predicted += n["hit"] + n["false"]
        iou = n["hit"] / max(1, n["hit"] + n["false"] + n["miss"])
        check(abs(iou - record["iou_ortho"][c]) < 0.002,
              f"{name}: painted IoU {iou:.4f} against the recorded {record['iou_ortho'][c]:.4f}")
        print(f"ok: {name}: IoU {iou:.4f} (recorded {record['iou_ortho'][c]:.4f})")
    check(predicted == int(valid.sum()), f"the classes' predictions cover {predicted} of {int(valid.sum())} pixels")
    # The four footprints tile the field without overlap at 15 cm/px: the images' counts are the map's.
    check(len(images) == 4 and sum(m["pixels"] for m in images) == int(valid.sum()), f"{len(images)} images")
    for c in range(len(field.classes)):
        n = class_map.class_counts(labels, field.labels, c)
        check(sum(int(m["predicted"][c]) for m in images) == n["hit"] + n["false"], f"class {c}: images' predictions")
        check(sum(int(m["true"][c]) for m in images) == n["hit"] + n["miss"], f"class {c}: images' labels")
    check(all(0.2 <= m["confidence"] <= 1.0 for m in images), "mean top probabilities")
    print("ok: the images' counts add up to the map's")

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "map.png"
        rc, text = printed(class_map.main, [str(net), str(fdir), "--class", "road", "--bands", "3", "--scale", "1",
                                            "--images", "2", "--out", str(out)])
        check(rc is None, f"class_map returned {rc}")
        rows = [line for line in text.splitlines() if re.match(r"\| -?\d+ \| -?\d+ \| ", line)]
        check(len(rows) == 2, f"--images 2 listed {len(rows)} images:\n{text}")
        pic = cv2.imread(str(out), cv2.IMREAD_COLOR)
        h, w = field.labels.shape
        check(pic is not None and pic.shape == (h, 2 * w, 3), f"picture shape {None if pic is None else pic.shape}")
        right = pic[:, w:]
        n = class_map.class_counts(labels, field.labels, field.classes.index("road"))
        for key, colour in (("hit", class_map.HIT), ("false", class_map.FALSE), ("miss", class_map.MISS)):
            count = int((right == np.array(colour, np.uint8)).all(axis=2).sum())
            check(count == n[key], f"{key}: {count} pixels of its colour, {n[key]} counted")
        print("ok: the picture's colours count the hits, false positives and misses")

    refused([str(net), str(fdir), "--class", "forest"], "not a class")
    refused([str(net), str(fdir), "--class", "road", "--bands", "0"], "positive")
    refused([str(net), str(fdir), "--class", "road", "--images", "-1"], "not negative")
    refused([str(net), str(fdir), "--class", "road", "--bands", "x"], "comma-separated")
    print("class_map: all checks passed")


if __name__ == "__main__":
    main()
