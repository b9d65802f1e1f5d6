#!/usr/bin/python3
"""Writes the ERFNet backend's test fixture (tests/data/erfnet/) from the trained model, and
measures the model on the held-out test field (dubai-tile-6) with PyTorch.

The fixture is one camera image of the test field, rendered exactly as adaptseg's
SimulatedSensor does (lawnmower footprint at GSD factor --gsd-factor, INTER_AREA to the
camera size), and PyTorch's output on it, computed from examples/models/erfnet-dubai/model.pt
(the weights exported to model.onnx):

  camera.png           the camera image (BGR PNG, lossless), 480x360
  logits_stride4.f32   logits at every 4th row and column: float32 little-endian, C x 90 x 120
  labels_torch.png     PyTorch's argmax at full resolution (8-bit PNG)
  fixture.yaml         what the files are, where the image comes from, measured numbers

tests/test_erfnet_segmenter.cpp compares OnnxSegmenter's output with these.

Usage: PYTHONPATH=python /usr/bin/python3 tests/tools/make_erfnet_fixture.py [--model-dir DIR] [--field DIR]
"""

from __future__ import annotations

import argparse
import datetime
from pathlib import Path

import cv2
import numpy as np
import torch
import yaml

REPO = Path(__file__).resolve().parents[2]
from adaptseg_tools.fieldio import IGNORE
from adaptseg_tools.training.fields import FieldData, capture, lawnmower_rects, load_field, lround
from adaptseg_tools.training.models import load_exported
from adaptseg_tools.training.network_path import logits_to, to_network_size, to_tensor
from adaptseg_tools.training.validation import evaluate

# The sub-field of the test field on which tests/test_erfnet_segmenter.cpp checks the mIoU at
# the finest GSD (fractions x0, y0, x1, y1; Field::sub_field). Kept small: 8 images.
TEST_REGION = (0.0, 0.0, 0.37, 0.57)


def sub_field(f: FieldData, region) -> FieldData:
    H, W = f.labels.shape
    x0, y0, x1, y1 = region
    c0, c1 = lround(x0 * W), lround(x1 * W)
    r0, r1 = lround(y0 * H), lround(y1 * H)
    return FieldData(f.name + str(list(region)), f.gsd_cm, f.labels[r0:r1, c0:c1].copy(),
                        f.image[r0:r1, c0:c1].copy(), f.classes, f.ignore)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model-dir", default=str(REPO / "examples" / "models" / "erfnet-dubai"))
    ap.add_argument("--field", default=str(REPO / "examples" / "data" / "dubai-tile-6"))
    ap.add_argument("--out", default=str(REPO / "tests" / "data" / "erfnet"))
    ap.add_argument("--gsd-factor", type=float, default=1.5)
    ap.add_argument("--bands", default="1,1.5,2,2.5,3")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)

    model_dir = Path(args.model_dir)
    model, spec, meta = load_exported(model_dir)
    field = load_field(Path(args.field))
    if field.classes != meta["classes"]:
        raise SystemExit(f"classes differ: field {field.classes} vs model {meta['classes']}")
    nc = len(meta["classes"])
    cam = spec.camera_wh
    field_dir = Path(args.field).resolve().name
    if field_dir in meta["training"]["fields"] or field_dir == meta["training"]["validation_field"]:
        raise SystemExit(f"{field_dir} was used in training or validation; it is not a test field")

    # --- the fixture image: the lawnmower image (inside the orthomosaic, no black pixel) with
    # the most classes, ties to the larger share of the rarest class present.
    best = None
    for i, (c0, r0, fw, fh) in enumerate(lawnmower_rects(field, field.gsd_cm * args.gsd_factor, cam)):
        H, W = field.labels.shape
        if c0 < 0 or r0 < 0 or c0 + fw > W or r0 + fh > H:
            continue
        rgb, target, _ = capture(field, c0, r0, fw, fh, cam)
        if (rgb == 0).all(axis=2).any():
            continue
        counts = np.bincount(target[target != IGNORE], minlength=nc)
        present = counts[counts > 0]
        key = (len(present), present.min() / counts.sum())
        if best is None or key > best[0]:
            best = (key, i, (c0, r0, fw, fh), rgb)
    if best is None:
        raise SystemExit("no lawnmower image lies fully inside the field")
    _, index, rect, rgb = best
    # What the backend computes: the network on its input size, logits resampled to the camera's.
    x = torch.from_numpy(to_tensor(to_network_size(rgb, spec.input_wh), spec.mean, spec.std))[None]
    with torch.no_grad():
        net_logits = model(x)
        logits = logits_to(net_logits, (cam[1], cam[0]))[0].numpy().astype(np.float32)
    labels = logits.argmax(0).astype(np.uint8)

    net = cv2.dnn.readNetFromONNX(str(model_dir / "model.onnx"))
    net.setInput(x.numpy())
    cv_net_logits = net.forward()
    cv_diff = float(np.abs(cv_net_logits - net_logits.numpy()).max())
    cv_logits = logits_to(torch.from_numpy(cv_net_logits), (cam[1], cam[0]))[0].numpy()
    cv_agree = float((cv_logits.argmax(0) == labels).mean())
    margin = np.sort(logits, axis=0)
    min_margin = float((margin[-1] - margin[-2]).min())

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out / "camera.png"), rgb, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    cv2.imwrite(str(out / "labels_torch.png"), labels, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    sub = np.ascontiguousarray(logits[:, ::4, ::4])
    sub.astype("<f4").tofile(out / "logits_stride4.f32")

    # --- test-field metrics with PyTorch (= OpenCV DNN up to ~1e-5 in the logits)
    bands = [float(v) for v in args.bands.split(",")]
    full = evaluate(model, field, bands, spec)
    region = sub_field(field, TEST_REGION)
    test_region = evaluate(model, region, [1.0], spec)[1.0]

    fixture = {
        "description": "ERFNet backend fixture: one camera image of the held-out test field and "
                       "PyTorch's logits / labels on it (tests/tools/make_erfnet_fixture.py)",
        "model": str(model_dir.relative_to(REPO)) if model_dir.is_relative_to(REPO) else str(model_dir),
        "model_date": meta["training"]["date"],
        "field": field.name,
        "gsd_factor": args.gsd_factor,
        "gsd_cm": field.gsd_cm * args.gsd_factor,
        "lawnmower_index": index,
        "footprint_px": {"x": rect[0], "y": rect[1], "width": rect[2], "height": rect[3]},
        "image": {"file": "camera.png", "width": cam[0], "height": cam[1], "channels": "BGR"},
        "logits": {"file": "logits_stride4.f32", "dtype": "float32 little-endian",
                   "shape": list(sub.shape), "stride": 4,
                   "meaning": "logits[c][4*i][4*j] of the 1xCxHxW network output, C-order"},
        "labels": {"file": "labels_torch.png", "meaning": "argmax over classes, full resolution"},
        "checked_at_export": {"opencv_python_vs_torch_max_abs_diff": cv_diff,
                              "opencv_python_argmax_agreement": cv_agree,
                              "min_top2_logit_margin": min_margin},
        "torch_version": str(torch.__version__),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "test_field_miou": {
            "metric": "mIoU over all classes, vs orthomosaic labels (adaptseg::image_confusion), "
                      "and vs the oracle at camera resolution",
            "whole_field": [{"gsd_factor": k, "images": v["images"], "miou_ortho": round(v["miou_ortho"], 4),
                             "miou_camera": round(v["miou_camera"], 4)} for k, v in full.items()],
            "test_region": {"region": list(TEST_REGION), "gsd_factor": 1.0, "images": test_region["images"],
                            "miou_ortho": round(test_region["miou_ortho"], 4),
                            "miou_camera": round(test_region["miou_camera"], 4)},
        },
    }
    (out / "fixture.yaml").write_text(yaml.safe_dump(fixture, sort_keys=False, default_flow_style=None, width=100))
    print(yaml.safe_dump(fixture, sort_keys=False, default_flow_style=None, width=100))


if __name__ == "__main__":
    main()
