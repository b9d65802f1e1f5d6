"""Fields and the simulated camera, as the network sees them in training and validation: mirrors
adaptseg's Field, SimulatedSensor (include/adaptseg/vision/simulated_sensor.hpp) and
OracleSegmenter (include/adaptseg/vision/oracle_segmenter.hpp), and LawnmowerPlanner's footprints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from ..fieldio import IGNORE


@dataclass
class FieldData:
    name: str
    gsd_cm: float
    labels: np.ndarray  # HxW uint8
    image: np.ndarray   # HxWx3 uint8 BGR
    classes: list[str]
    ignore: int


def load_field(directory: Path) -> FieldData:
    meta = yaml.safe_load((directory / "field.yaml").read_text())
    labels = cv2.imread(str(directory / meta["labels"]), cv2.IMREAD_UNCHANGED)
    if labels is None or labels.ndim != 2 or labels.dtype != np.uint8:
        raise SystemExit(f"{directory}: cannot read an 8-bit label map {meta['labels']}")
    if "image" not in meta:
        raise SystemExit(f"{directory}: the field has no RGB image; it cannot train a network")
    image = cv2.imread(str(directory / meta["image"]), cv2.IMREAD_COLOR)
    if image is None or image.shape[:2] != labels.shape:
        raise SystemExit(f"{directory}: cannot read {meta['image']} or its size differs from the labels")
    ignore = int(meta.get("ignore_label", 255))
    if ignore != IGNORE:
        labels = labels.copy()
        valid = labels != ignore
        labels[~valid] = IGNORE  # one ignore value in training: 255
    classes = [c["name"] for c in meta["classes"]]
    return FieldData(meta["name"], float(meta["gsd_cm"]), labels, image, classes, ignore)


def lround(v: float) -> int:
    """std::lround: half away from zero (Python's round() is half-to-even)."""
    return int(math.copysign(math.floor(abs(v) + 0.5), v))


def crop_fill(src: np.ndarray, c0: int, r0: int, w: int, h: int, fill) -> np.ndarray:
    """src[r0:r0+h, c0:c0+w] with `fill` outside src (SimulatedSensor::crop)."""
    out = np.empty((h, w) + src.shape[2:], src.dtype)
    out[...] = fill
    H, W = src.shape[:2]
    a0, a1 = max(c0, 0), min(c0 + w, W)
    b0, b1 = max(r0, 0), min(r0 + h, H)
    if a1 > a0 and b1 > b0:
        out[b0 - r0:b1 - r0, a0 - c0:a1 - c0] = src[b0:b1, a0:a1]
    return out


def oracle_labels(gt: np.ndarray, size_wh: tuple[int, int], num_classes: int) -> np.ndarray:
    """OracleSegmenter::segment: area-weighted majority per camera pixel, ignore not voting,
    ties to the lower index, 255 where no valid pixel."""
    w, h = size_wh
    if gt.shape[1] == w and gt.shape[0] == h:
        return gt.copy()
    best = np.zeros((h, w), np.float32)
    out = np.full((h, w), IGNORE, np.uint8)
    for c in range(num_classes):
        ind = gt == c
        if not ind.any():
            continue
        votes = cv2.resize(ind.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
        better = votes > best
        best[better] = votes[better]
        out[better] = c
    return out


def capture(field: FieldData, c0: int, r0: int, fw: int, fh: int, cam_wh: tuple[int, int]):
    """Camera image (BGR, cam size) and oracle target of the footprint rect (c0, r0, fw, fh)."""
    rgb = crop_fill(field.image, c0, r0, fw, fh, 0)
    rgb = cv2.resize(rgb, cam_wh, interpolation=cv2.INTER_AREA)
    gt = crop_fill(field.labels, c0, r0, fw, fh, IGNORE)
    return rgb, oracle_labels(gt, cam_wh, len(field.classes)), gt


def lawnmower_rects(field: FieldData, gsd_cm: float, cam_wh: tuple[int, int]):
    """Footprint pixel rects of LawnmowerPlanner::plan(field.area(), gsd) snapped by
    Field::pixel_rect (order does not matter for metrics)."""
    H, W = field.labels.shape
    g0 = field.gsd_cm
    fw_m, fh_m = cam_wh[0] * gsd_cm / 100.0, cam_wh[1] * gsd_cm / 100.0
    area_w, area_h = W * g0 / 100.0, H * g0 / 100.0
    nx = max(1, math.ceil(area_w / fw_m - 1e-9))
    ny = max(1, math.ceil(area_h / fh_m - 1e-9))
    s = 100.0 / g0
    rects = []
    for row in range(ny):
        y0 = row * fh_m
        for col in range(nx):
            x0 = col * fw_m
            c0, c1 = lround(x0 * s), lround((x0 + fw_m) * s)
            r0, r1 = lround(H - (y0 + fh_m) * s), lround(H - y0 * s)
            rects.append((c0, r0, c1 - c0, r1 - r0))
    return rects
