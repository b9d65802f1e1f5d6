#!/usr/bin/env python3
"""Converts a WeedMap orthomosaic ground-truth PNG into an adaptseg field directory.

Usage:
  /usr/bin/python3 examples/tools/convert_weedmap.py \
      --input ../shared/data/weedmap-rededge-000/first000_gt.png --out examples/data/weedmap-000

The WeedMap label PNGs colour soil black, crop green and weed red, and the area outside the
field is black as well: there is no validity mask. The field boundary is therefore taken as
the minimum-area rectangle (cv2.minAreaRect) around every vegetation pixel (crop or weed),
after dropping vegetation components smaller than --min-component px so that stray specks
cannot widen it. The image is rotated by that rectangle's angle with nearest-neighbour
sampling (labels are never interpolated), so that the field is axis-aligned, and cropped to
the rectangle; inside it black is soil, and what the rotation brings in from outside the
original image is marked ignore (255). A preview with the boundary drawn is written with
--preview.
"""
import argparse
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fieldio import IGNORE, write_field  # noqa: E402

CLASSES = [("soil", (0, 0, 0)), ("crop", (0, 255, 0)), ("weed", (255, 0, 0))]


def colour_labels(rgb):
    """RGB label image -> class indices; colours other than the three are an error."""
    labels = np.full(rgb.shape[:2], IGNORE, np.uint8)
    for index, (_, colour) in enumerate(CLASSES):
        labels[np.all(rgb == np.array(colour, np.uint8), axis=2)] = index
    unknown = int((labels == IGNORE).sum())
    if unknown:
        raise ValueError(f"{unknown} pixels have colours other than black, green and red")
    return labels


def field_rectangle(labels, min_component):
    """minAreaRect around the vegetation pixels of components of at least min_component px."""
    veg = (labels > 0).astype(np.uint8)
    n, comp, stats, _ = cv2.connectedComponentsWithStats(veg, connectivity=8)
    keep = np.zeros(n, bool)
    keep[1:] = stats[1:, cv2.CC_STAT_AREA] >= min_component
    pts = np.column_stack(np.nonzero(keep[comp]))[:, ::-1].astype(np.float32)  # (x, y)
    if len(pts) < 3:
        raise ValueError("no vegetation found: cannot locate the field")
    return cv2.minAreaRect(pts)


def rotate_to_axis(labels, rect):
    """Rotates so that rect is axis-aligned and crops to it; outside the source -> IGNORE."""
    (cx, cy), (w, h), angle = rect
    out_w, out_h = int(round(w)), int(round(h))
    m = cv2.getRotationMatrix2D((cx, cy), angle, 1.0)
    m[0, 2] += out_w / 2.0 - cx
    m[1, 2] += out_h / 2.0 - cy
    inside = cv2.warpAffine(np.ones_like(labels), m, (out_w, out_h), flags=cv2.INTER_NEAREST, borderValue=0)
    out = cv2.warpAffine(labels, m, (out_w, out_h), flags=cv2.INTER_NEAREST, borderValue=0)
    out[inside == 0] = IGNORE
    return out, m


def convert(rgb, min_component=20):
    labels = colour_labels(rgb)
    rect = field_rectangle(labels, min_component)
    field, m = rotate_to_axis(labels, rect)
    return labels, field, rect, m


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--input", required=True, help="WeedMap ground-truth PNG (RGB colours)")
    ap.add_argument("--out", required=True, help="field directory to write")
    ap.add_argument("--name", default="weedmap-rededge-000")
    ap.add_argument("--gsd-cm", type=float, default=1.0)
    ap.add_argument("--min-component", type=int, default=20,
                    help="vegetation components smaller than this [px] do not shape the boundary")
    ap.add_argument("--preview", help="write a downscaled PNG of the input with the boundary drawn")
    a = ap.parse_args()
    bgr = cv2.imread(a.input, cv2.IMREAD_COLOR)
    if bgr is None:
        sys.exit(f"convert_weedmap: cannot read {a.input}")
    src, field, rect, _ = convert(bgr[:, :, ::-1].copy(), a.min_component)
    write_field(a.out, a.name, a.gsd_cm, field, CLASSES, ["crop", "weed"])
    before = np.bincount(src.ravel(), minlength=3)[:3]
    after = np.bincount(field.ravel(), minlength=256)
    (cx, cy), (w, h), angle = rect
    print(f"boundary: centre ({cx:.1f}, {cy:.1f}) px, size {w:.1f} x {h:.1f} px, angle {angle:.3f} deg")
    print(f"field: {field.shape[1]} x {field.shape[0]} px; ignore {after[IGNORE]} px")
    for i, (n, _) in enumerate(CLASSES):
        print(f"  {n}: source {before[i]} px, field {after[i]} px")
    if a.preview:
        box = cv2.boxPoints(rect).astype(np.int32)
        prev = bgr.copy()
        cv2.polylines(prev, [box], True, (255, 0, 255), 25)
        s = 1000.0 / max(prev.shape[:2])
        cv2.imwrite(a.preview, cv2.resize(prev, None, fx=s, fy=s, interpolation=cv2.INTER_AREA))


if __name__ == "__main__":
    main()
