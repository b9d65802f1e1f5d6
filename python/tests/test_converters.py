#!/usr/bin/env python3
"""Self-test of the data converters on synthetic inputs (run by CTest; exit code != 0 on failure).

- WeedMap, --method rows (default): a field of crop rows with a weed patch and an unsurveyed
  notch, rotated by a known angle inside a black image, must come back with the row angle
  recovered within 1 degree, rows vertical, crop and weed counts exactly preserved, the notch
  ignore (--boundary region) or soil (--boundary rect); the three-shear rotation must be a
  bijection.
- WeedMap, --method hull-rect (the first bundled field's method): the angle recovered within
  1 degree, vegetation preserved up to the nearest-neighbour resampling of the rotation, and
  ignore outside the source image.
- Dubai: a 3x3 tile with parts differing by 1 px between rows/columns, a palette PNG mask and
  an unknown colour must reassemble to the right size with the right classes and ignore.
"""
import os
import tempfile

import cv2
import numpy as np

from adaptseg_tools import convert_dubai, convert_weedmap
from adaptseg_tools.fieldio import IGNORE, check_field, write_field


def synthetic_weedmap(angle_deg, notch=True):
    """RGB image: a 300 x 700 px field of vertical crop rows (pitch 12 px), a weed patch and,
    if notch, an unsurveyed bottom-right quarter (black: no rows), rotated by angle_deg
    (counter-clockwise on screen) inside a 1200 x 1200 black image."""
    w, h = 300, 700
    field = np.zeros((h, w, 3), np.uint8)
    for x in range(10, w - 10, 12):
        field[10:h - 10, x:x + 3] = (0, 255, 0)
    field[200:230, 100:140] = (255, 0, 0)
    if notch:
        field[h // 2:, w // 2:] = 0
    big = np.zeros((1200, 1200, 3), np.uint8)
    big[250:250 + h, 450:450 + w] = field
    m = cv2.getRotationMatrix2D((600, 600), angle_deg, 1.0)
    return cv2.warpAffine(big, m, (1200, 1200), flags=cv2.INTER_NEAREST, borderValue=(0, 0, 0))


def test_rotate_exact():
    rng = np.random.default_rng(1)
    img = rng.integers(0, 200, size=(37, 53)).astype(np.uint8)
    for phi in (-90.0, -44.14, -7.3, 0.0, 12.5, 60.0, 90.0):
        out = convert_weedmap.rotate_exact(img, phi, fill=250)
        assert np.array_equal(np.bincount(out[out != 250], minlength=256)[:200],
                              np.bincount(img.ravel(), minlength=256)[:200]), phi
        ys, xs = np.nonzero(np.ones(img.shape, bool))
        xr, yr = convert_weedmap.rotate_points_exact(xs, ys, img.shape, phi)
        assert np.array_equal(out[yr, xr], img[ys, xs]), phi
        # close to a true rotation: a displacement of (10, 0) turns by phi within ~1 px
        a, b = convert_weedmap.rotate_points_exact(np.array([5, 45]), np.array([18, 18]), img.shape, phi)
        t = np.radians(phi)
        assert abs((a[1] - a[0]) - 40 * np.cos(t)) <= 1.5 and abs((b[1] - b[0]) - 40 * np.sin(t)) <= 1.5, phi
    print("exact rotation: ok")


def test_weedmap_rows(angle_deg=33.0):
    rgb = synthetic_weedmap(angle_deg)
    src = convert_weedmap.colour_labels(rgb)
    n_src = np.bincount(src.ravel(), minlength=3)[:3]
    res = convert_weedmap.convert_rows(src, log=lambda *_: None)
    # rows were vertical (90 deg); a counter-clockwise turn by angle_deg gives 90 - angle_deg
    err = abs((res["angle_deg"] - (90.0 - angle_deg) + 90.0) % 180.0 - 90.0)
    assert err < 1.0, (res["angle_deg"], angle_deg)
    assert abs(res["spacing_px"] - 12.0) < 1.0, res["spacing_px"]
    out = res["field"]
    n_out = np.bincount(out.ravel(), minlength=256)
    assert n_out[1] == n_src[1] and n_out[2] == n_src[2], (n_src, n_out[:3])
    assert set(np.unique(out)) <= {0, 1, 2, IGNORE}
    hh, ww = out.shape
    assert abs(hh - 680) <= 6 and abs(ww - 281) <= 6, out.shape
    profile = (out == 1).mean(axis=0)  # rows vertical: columns on a row are mostly crop
    assert (profile > 0.3).sum() >= 15, "crop rows are not vertical"
    # orientation is kept (no flip): the unsurveyed notch is the bottom-right quarter
    notch = out[hh // 2 + 15:, ww // 2 + 15:]
    body = out[15:hh // 2 - 15, 15:ww - 15]
    assert (notch == IGNORE).mean() > 0.95, (notch == IGNORE).mean()
    assert (body == IGNORE).mean() < 0.01, (body == IGNORE).mean()
    rect = convert_weedmap.convert_rows(src, boundary="rect", log=lambda *_: None)["field"]
    n_rect = np.bincount(rect.ravel(), minlength=256)
    assert n_rect[1] == n_src[1] and n_rect[2] == n_src[2]
    assert (rect[hh // 2 + 15:, ww // 2 + 15:] == 0).mean() > 0.95, "rect: the notch is soil"
    print("weedmap converter (rows): ok (angle %.2f deg, field %dx%d, ignore %.3f)"
          % (res["angle_deg"], ww, hh, n_out[IGNORE] / out.size))


def test_weedmap(angle_deg=33.0):
    w, h = 300, 700
    field = np.zeros((h, w, 3), np.uint8)
    for x in range(10, w - 10, 12):  # crop rows along the field's long axis
        field[10:h - 10, x:x + 3] = (0, 255, 0)
    field[200:230, 100:140] = (255, 0, 0)  # a weed patch
    big = np.zeros((1200, 1200, 3), np.uint8)
    big[250:250 + h, 450:450 + w] = field
    m = cv2.getRotationMatrix2D((600, 600), angle_deg, 1.0)
    rgb = cv2.warpAffine(big, m, (1200, 1200), flags=cv2.INTER_NEAREST, borderValue=(0, 0, 0))
    src, out, rect, _ = convert_weedmap.convert(rgb, min_component=5)
    angle = rect[2]
    # minAreaRect reports the orientation modulo 90 degrees and in image coordinates (y down),
    # where the rotation by +angle_deg appears as -angle_deg.
    err = abs(((angle + angle_deg) + 45) % 90 - 45)
    assert err < 1.0, f"angle {angle} vs {angle_deg}"
    n_src = np.bincount(src.ravel(), minlength=3)[1:3]
    n_out = np.bincount(out.ravel(), minlength=256)[1:3]
    assert np.all(np.abs(n_out.astype(int) - n_src) <= 0.02 * n_src), (n_src, n_out)
    hh, ww = out.shape
    veg_w = max(range(10, w - 10, 12)) + 3 - 10  # extent of the rows across the field
    assert abs(max(hh, ww) - (h - 20)) <= 4 and abs(min(hh, ww) - veg_w) <= 4, out.shape
    assert set(np.unique(out)) <= {0, 1, 2, IGNORE}
    # The crop rows run along one image axis: every row (or column) crossing them sees them.
    long_axis = 0 if hh > ww else 1
    profile = (out == 1).mean(axis=long_axis)
    assert (profile > 0.5).sum() >= 15, "crop rows are not axis-aligned"
    print("weedmap converter: ok (angle %.2f deg, field %dx%d)" % (angle, ww, hh))


def test_dubai():
    with tempfile.TemporaryDirectory() as tmp:
        tile = os.path.join(tmp, "Tile_9")
        os.makedirs(os.path.join(tile, "images"))
        os.makedirs(os.path.join(tile, "masks"))
        heights, widths = [20, 21, 20], [30, 30, 31]
        colours = [c for _, c in convert_dubai.CLASSES]
        for r in range(3):
            for c in range(3):
                k = 3 * r + c + 1
                img = np.full((heights[r], widths[c], 3), 10 * k, np.uint8)
                cv2.imwrite(os.path.join(tile, "images", f"image_part_{k:03d}.jpg"), img)
                mask = np.zeros((heights[r], widths[c], 3), np.uint8)
                mask[:] = colours[(k - 1) % 5][::-1]
                mask[0, 0] = convert_dubai.UNLABELED[::-1]
                mask[0, 1] = (1, 2, 3)  # unknown colour
                path = os.path.join(tile, "masks", f"image_part_{k:03d}.png")
                cv2.imwrite(path, mask)
        # Make part 1's mask a palette PNG, as in the real tiles 2 and 4.
        from PIL import Image
        p1 = os.path.join(tile, "masks", "image_part_001.png")
        Image.open(p1).convert("P", palette=Image.ADAPTIVE, colors=8).save(p1)
        assert Image.open(p1).mode == "P"
        image, labels, ignored = convert_dubai.convert_tile(tile)
        assert image.shape[:2] == (61, 91) and labels.shape == (61, 91), labels.shape
        assert labels[5, 5] == 0 and labels[5, 35] == 1 and labels[25, 5] == 3, labels[::20, ::30]
        assert labels[0, 0] == IGNORE and labels[0, 1] == IGNORE
        assert ignored["#9B9B9B"] == 9 and ignored["#030201"] == 9, ignored
        out = os.path.join(tmp, "out")
        write_field(out, "t", 5.0, labels, convert_dubai.CLASSES, ["water"], image)
        summary = check_field(out)
        assert summary["width"] == 91 and summary["ignore"] == 18, summary
        # A missing part is reported by name.
        os.remove(os.path.join(tile, "masks", "image_part_005.png"))
        try:
            convert_dubai.convert_tile(tile)
        except ValueError as e:
            assert "image_part_005.png" in str(e)
        else:
            raise AssertionError("missing part not reported")
    # Parts differing by a pixel anywhere are placed by cumulative sizes; gaps are counted.
    parts = [np.full((20 + (k == 1), 30 + (k == 4), 3), k, np.uint8) for k in range(9)]
    mosaic, geo = convert_dubai.assemble(parts, "irregular", fill=255)
    assert mosaic.shape[:2] == (61, 91), mosaic.shape
    assert mosaic[20, 30, 0] == 1 and mosaic[21, 0, 0] == 3 and mosaic[21, 61, 0] == 5, mosaic[::10, ::10, 0]
    # 61 x 91 mosaic - 9 x 600 - 30 - 20 extra part pixels + 1 overlap
    assert geo["gap"] == 61 * 91 - 9 * 600 - 30 - 20 + 1 and geo["overlap"] == 1, geo
    try:
        convert_dubai.assemble([np.zeros((20, 30 + 3 * (k == 8)), np.uint8) for k in range(9)], "bad")
    except ValueError as e:
        assert "not a 3x3 grid" in str(e)
    else:
        raise AssertionError("inconsistent part sizes not reported")
    print("dubai converter: ok")


if __name__ == "__main__":
    tests = [test_rotate_exact, test_weedmap_rows, lambda: test_weedmap_rows(-20.0),
             lambda: test_weedmap_rows(-45.9), test_weedmap, lambda: test_weedmap(-20.0), test_dubai]
    for t in tests:
        t()
    print(f"converters: {len(tests)} passed, 0 failed")
