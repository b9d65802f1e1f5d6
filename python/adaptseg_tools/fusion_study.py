"""What pooling the looks would give a descent, measured on whole fields: per tile, the network
that never saw it flies whole-field lawnmowers at the top level (15 cm/px) and at a finer GSD
(5 or 10 cm/px), and the class of interest is scored on three maps of the same images:

- top: the top-level lawnmower alone;
- finest: the finer lawnmower written over it (MapFusion::finest, the paper's fusion; where the
  finer images cover the field, the finer map);
- pooled: both pooled as MapFusion::pooled pools them (per pixel, argmax over classes of the sum
  over images of log(max(p_c, 1/256)) / GSD).

The whole field re-mapped is every descent at once: the numbers say what the map's rule makes
of two looks at a pixel, not what a decision earns. Each network runs its bundled ONNX through
OpenCV DNN on the C++ backend's path (resampled to its input, logits back to the camera size,
softmax of logits / its model.yaml temperature); footprints and images as LawnmowerPlanner and
SimulatedSensor make them (train_segnet.py), labels scored at orthomosaic resolution.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.fusion_study \\
      [--networks examples/models/mobilenetv2-dubai-loto] [--tiles 1,2,3,4,5,6] [--fine 1,2]
  (NETWORKS/tile-k flies examples/data/dubai-tile-k; --fine: GSD factors of the finer look, the
  top level at 3)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np
import torch
import yaml

from . import REPO
from .fieldio import IGNORE
from .training.fields import FieldData, capture, lawnmower_rects, load_field
from .training.network_path import logits_to, to_network_size, to_tensor
FLOOR = 1.0 / 256.0  # SemanticMap::kPooledFloor
TOP = 3.0            # the top level's GSD factor (15 cm/px on the 5 cm/px Dubai tiles)
INTEREST = ("building", "road", "vegetation", "water")


class OnnxNetwork:
    """A bundled network (model.onnx, model.yaml) on the C++ backend's path."""

    def __init__(self, model_dir: Path):
        meta = yaml.safe_load((model_dir / "model.yaml").read_text())
        self.net = cv2.dnn.readNetFromONNX(str(model_dir / "model.onnx"))
        self.input_wh = (meta["input"]["width"], meta["input"]["height"])
        self.camera_wh = tuple(meta["training"]["camera"])
        self.mean = np.array(meta["input"]["mean"])
        self.std = np.array(meta["input"]["std"])
        self.temperature = float(meta.get("temperature", 1.0))
        self.classes = meta["classes"]

    def probabilities(self, bgr: np.ndarray) -> np.ndarray:
        """C x H x W class probabilities of a camera image."""
        x = to_tensor(to_network_size(bgr, self.input_wh), self.mean, self.std)[None]
        self.net.setInput(x)
        logits = logits_to(torch.from_numpy(self.net.forward().copy()), bgr.shape[:2])[0]
        return torch.softmax(logits / self.temperature, dim=0).numpy()


def lawnmower_map(network: OnnxNetwork, field: FieldData, factor: float) -> np.ndarray:
    """C x H x W probabilities on the orthomosaic grid of a whole-field lawnmower (nearest
    neighbour, later images over earlier; 0 where no image looked)."""
    h, w = field.labels.shape
    out = np.zeros((len(network.classes), h, w), np.float32)
    for (c0, r0, fw, fh) in lawnmower_rects(field, field.gsd_cm * factor, network.camera_wh):
        rgb, _, _ = capture(field, c0, r0, fw, fh, network.camera_wh)
        p = network.probabilities(rgb)
        x0, y0, x1, y1 = max(c0, 0), max(r0, 0), min(c0 + fw, w), min(r0 + fh, h)
        if x1 <= x0 or y1 <= y0:
            continue
        for c in range(len(p)):
            up = cv2.resize(p[c], (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
            out[c, y0:y1, x0:x1] = up[y0 - r0:y1 - r0, x0 - c0:x1 - c0]
    return out


def iou(pred: np.ndarray, truth: np.ndarray, c: int) -> float:
    valid = truth != IGNORE
    p, t = (pred == c) & valid, (truth == c) & valid
    union = (p | t).sum()
    return float((p & t).sum() / union) if union else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--networks", default=str(REPO / "examples" / "models" / "mobilenetv2-dubai-loto"))
    ap.add_argument("--tiles", default="1,2,3,4,5,6")
    ap.add_argument("--fine", default="1,2", help="GSD factors of the finer look")
    args = ap.parse_args()
    cv2.setNumThreads(2)
    torch.set_num_threads(2)
    fines = [float(v) for v in args.fine.split(",")]
    rows = []
    for k in (int(v) for v in args.tiles.split(",")):
        network = OnnxNetwork(Path(args.networks) / f"tile-{k}")
        field = load_field(REPO / "examples" / "data" / f"dubai-tile-{k}")
        top = lawnmower_map(network, field, TOP)
        for factor in fines:
            fine = lawnmower_map(network, field, factor)
            seen = fine.sum(0) > 0
            finest = np.where(seen, fine.argmax(0), top.argmax(0))
            pooled = (np.log(np.maximum(top, FLOOR)) / (TOP * field.gsd_cm)
                      + np.log(np.maximum(fine, FLOOR)) / (factor * field.gsd_cm)).argmax(0)
            for name in INTEREST:
                c = field.classes.index(name)
                if not (field.labels == c).any():
                    continue
                rows.append((k, name, factor, factor * field.gsd_cm, iou(top.argmax(0), field.labels, c),
                             iou(finest, field.labels, c), iou(pooled, field.labels, c)))
        print(f"dubai-tile-{k}: done", file=sys.stderr, flush=True)
    print("| tile | class | finer look | top | finest | pooled | pooled − finest | pooled − max(top, finest) |")
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for k, name, _, g, a, b, p in rows:
        print(f"| {k} | {name} | {g:g} cm/px | {a:.3f} | {b:.3f} | {p:.3f} | {p - b:+.3f} | {p - max(a, b):+.3f} |")
    for factor in fines:
        sel = [r for r in rows if r[2] == factor]
        d_fine = np.array([r[6] - r[5] for r in sel])
        d_best = np.array([r[6] - max(r[4], r[5]) for r in sel])
        print(f"\nfiner look x{factor:g} the field's GSD, {len(sel)} (tile, class): pooled − finest mean {d_fine.mean():+.4f}, "
              f"> +0.001 in {int((d_fine > 0.001).sum())}, < −0.001 in {int((d_fine < -0.001).sum())}; "
              f"pooled − max(top, finest) mean {d_best.mean():+.4f}, > +0.001 in {int((d_best > 0.001).sum())}")


if __name__ == "__main__":
    main()
