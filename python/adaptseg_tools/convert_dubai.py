"""Converts the Dubai aerial-imagery tiles into adaptseg field directories.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.convert_dubai --input ../shared/data/dubai-aerial \
      --out examples/data [--tiles 1 2 ...] [--gsd-cm 5.0] [--interest vegetation]

Every Tile_N folder present (or those named) holds images/image_part_00K.jpg and
masks/image_part_00K.png, K = 1..9, a 3x3 grid in row-major order. Part sizes may differ by
a pixel (in tiles 1-6 parts of a grid row share a height and parts of a grid column share a
width); each part is placed by the cumulative widths of the parts before it in its grid row
and the cumulative heights of the parts above it in its grid column (see assemble()). A
missing or unreadable part, an image part and mask part of different sizes, or parts whose
sizes differ by more than 2 px are errors naming the part or tile. Mask colours are mapped to
class indices [building, land, road, vegetation, water] with the colours the masks actually
use (see the dataset's PROVENANCE.txt: classes.json is wrong); "unlabeled" (#9B9B9B), black
and any other colour become ignore (255), and the counts of such pixels are printed.
Writes OUT/dubai-tile-N/{field.yaml, labels.png, image.jpg}.
"""
import argparse
import glob
import os
import re
import sys

import cv2
import numpy as np

from .fieldio import IGNORE, write_field

CLASSES = [
    ("building", (0x3C, 0x10, 0x98)),
    ("land", (0x84, 0x29, 0xF6)),
    ("road", (0x6E, 0xC1, 0xE4)),
    ("vegetation", (0xFE, 0xDD, 0x3A)),
    ("water", (0xE2, 0xA9, 0x29)),
]
UNLABELED = (0x9B, 0x9B, 0x9B)


def read_part(path, flags):
    img = cv2.imread(path, flags)
    if img is None:
        raise ValueError(f"missing or unreadable part: {path}")
    return img


def assemble(parts, what, fill=0, max_spread=2):
    """3x3 list of arrays (row-major) -> (mosaic, {"gap": px, "overlap": px}).

    Part (r, c) is placed at x = sum of the widths of parts (r, 0..c-1) and y = sum of the
    heights of parts (0..r-1, c), i.e. by the cumulative widths along its grid row and the
    cumulative heights down its grid column, so parts may differ by a pixel anywhere. The
    mosaic is as wide as the widest row and as tall as the tallest column. If the parts do
    not tile exactly, pixels no part covers get `fill` and, where two parts overlap (at most
    a pixel or so), the later part wins; both are counted. Parts whose sizes differ by more
    than max_spread px are not one tile's 3x3 grid: an error.
    """
    hs = np.array([[parts[3 * r + c].shape[0] for c in range(3)] for r in range(3)])
    ws = np.array([[parts[3 * r + c].shape[1] for c in range(3)] for r in range(3)])
    for name, v in (("heights", hs), ("widths", ws)):
        if v.max() - v.min() > max_spread:
            raise ValueError(f"{what}: part {name} range from {v.min()} to {v.max()} px "
                             f"(more than {max_spread} px apart): not a 3x3 grid of one tile")
    xs = np.concatenate([np.zeros((3, 1), int), np.cumsum(ws, axis=1)[:, :2]], axis=1)
    ys = np.concatenate([np.zeros((1, 3), int), np.cumsum(hs, axis=0)[:2, :]], axis=0)
    width, height = int(ws.sum(axis=1).max()), int(hs.sum(axis=0).max())
    first = parts[0]
    out = np.full((height, width) + first.shape[2:], fill, first.dtype)
    cover = np.zeros((height, width), np.uint8)
    for r in range(3):
        for c in range(3):
            y, x, p = ys[r, c], xs[r, c], parts[3 * r + c]
            out[y:y + p.shape[0], x:x + p.shape[1]] = p
            cover[y:y + p.shape[0], x:x + p.shape[1]] += 1
    return out, {"gap": int((cover == 0).sum()), "overlap": int((cover > 1).sum())}


def mask_to_labels(mask_rgb):
    """RGB mask -> class indices; returns (labels, {colour: count} of colours mapped to ignore)."""
    labels = np.full(mask_rgb.shape[:2], IGNORE, np.uint8)
    for index, (_, colour) in enumerate(CLASSES):
        labels[np.all(mask_rgb == np.array(colour, np.uint8), axis=2)] = index
    rest = mask_rgb[labels == IGNORE]
    colours, counts = np.unique(rest.reshape(-1, 3), axis=0, return_counts=True)
    return labels, {"#%02X%02X%02X" % tuple(int(v) for v in c): int(n) for c, n in zip(colours, counts)}


def convert_tile(tile_dir):
    """Returns (image BGR, labels, ignored colours) of one Tile_N folder."""
    images, masks = [], []
    for k in range(1, 10):
        img = read_part(os.path.join(tile_dir, "images", f"image_part_{k:03d}.jpg"), cv2.IMREAD_COLOR)
        msk = read_part(os.path.join(tile_dir, "masks", f"image_part_{k:03d}.png"), cv2.IMREAD_COLOR)
        if img.shape[:2] != msk.shape[:2]:
            raise ValueError(f"{tile_dir}: part {k}: image {img.shape[1]}x{img.shape[0]} and mask "
                             f"{msk.shape[1]}x{msk.shape[0]} differ in size")
        images.append(img)
        masks.append(msk)
    image, geo = assemble(images, f"{tile_dir}/images", fill=0)
    mask, _ = assemble(masks, f"{tile_dir}/masks", fill=0)  # black -> ignore
    if image.shape[:2] != mask.shape[:2]:
        raise ValueError(f"{tile_dir}: image mosaic {image.shape[1]}x{image.shape[0]} and mask mosaic "
                         f"{mask.shape[1]}x{mask.shape[0]} differ in size")
    labels, ignored = mask_to_labels(mask[:, :, ::-1])
    if geo["gap"] or geo["overlap"]:
        print(f"convert_dubai: {tile_dir}: parts do not tile exactly: {geo['gap']} px uncovered "
              f"(ignore), {geo['overlap']} px covered twice (later part kept)", file=sys.stderr)
    return image, labels, ignored


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--input", required=True, help="folder with Tile_N subfolders")
    ap.add_argument("--out", required=True, help="parent folder of the field directories")
    ap.add_argument("--tiles", type=int, nargs="*", help="tile numbers (default: every Tile_N present)")
    ap.add_argument("--gsd-cm", type=float, default=5.0, help="nominal orthomosaic GSD [cm/px]")
    ap.add_argument("--interest", default="water", help="default labels of interest, comma-separated")
    a = ap.parse_args()
    found = {}
    for d in glob.glob(os.path.join(a.input, "Tile_*")):
        m = re.fullmatch(r"Tile_(\d+)", os.path.basename(d))
        if m and os.path.isdir(d):
            found[int(m.group(1))] = d
    tiles = sorted(found) if not a.tiles else a.tiles
    if not tiles:
        sys.exit(f"convert_dubai: no Tile_N folders in {a.input}")
    interest = [s for s in a.interest.split(",") if s]
    for n in interest:
        if n not in [c for c, _ in CLASSES]:
            sys.exit(f"convert_dubai: unknown class of interest '{n}'")
    for t in tiles:
        if t not in found:
            sys.exit(f"convert_dubai: Tile_{t} not found in {a.input}")
        try:
            image, labels, ignored = convert_tile(found[t])
        except ValueError as e:
            sys.exit(f"convert_dubai: {e}")
        out = os.path.join(a.out, f"dubai-tile-{t}")
        write_field(out, f"dubai-tile-{t}", a.gsd_cm, labels, CLASSES, interest, image)
        counts = np.bincount(labels.ravel(), minlength=256)
        valid = counts[: len(CLASSES)].sum()
        fr = ", ".join(f"{c} {counts[i] / max(valid, 1):.3f}" for i, (c, _) in enumerate(CLASSES))
        print(f"dubai-tile-{t}: {labels.shape[1]}x{labels.shape[0]} px; {fr}; ignore {counts[IGNORE]} px "
              f"(colours: {ignored})")
        unknown = {c: n for c, n in ignored.items() if c not in ("#9B9B9B", "#000000")}
        if unknown:
            print(f"convert_dubai: Tile_{t}: unknown mask colours mapped to ignore: {unknown}", file=sys.stderr)


if __name__ == "__main__":
    main()
