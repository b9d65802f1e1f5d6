"""Converts a WeedMap orthomosaic ground-truth PNG into an adaptseg field directory.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.convert_weedmap \
      --input ../shared/data/weedmap-rededge-000/first000_gt.png --out examples/data/weedmap-000 \
      [--name weedmap-rededge-000] [--gsd-cm 1.0] [--method rows|hull-rect] \
      [--boundary region|rect] [--preview DIR]

The WeedMap label PNGs colour soil black, crop green and weed red, and the area outside the
field is black as well: there is no validity mask, and the field lies rotated in the image.

--method rows (default)
  1. The crop-row direction is estimated from the crop pixels by projection-profile
     sharpness: for candidate angles the crop pixels are projected across the candidate row
     direction and the angle whose histogram is most peaked (largest sum of squared bin
     counts) wins; 0.5 degree coarse search over 180 degrees, then 0.02 degree refinement.
     The row spacing is the dominant period of that profile.
  2. The label map is rotated so the rows run vertically (image columns), by an exact
     three-shear rotation with integer shifts (Paeth): each shear moves whole rows or
     columns by whole pixels, so every source pixel lands on exactly one target pixel.
     Labels are never interpolated, duplicated or dropped, and the crop and weed pixel
     counts are preserved exactly.
  3. The field boundary:
     --boundary region (default): the morphological closing of all vegetation (crop or
       weed) pixels with a square of --kernel-rows row spacings, interior holes filled.
       Outside it is ignore (255): there is no ground truth there, the source's black is
       unsurveyed ground as much as soil.
     --boundary rect: the axis-aligned bounding box of the vegetation components of at
       least --min-component px; everything inside is soil/crop/weed.
     In both cases the output is cropped to the boundary's bounding box, and pixels that no
     source pixel maps to are ignore.
--method hull-rect (how the bundled field was first made)
  The field is the minimum-area rectangle (cv2.minAreaRect) around every vegetation pixel of
  components of at least --min-component px; the image is rotated by the rectangle's angle
  with nearest-neighbour warpAffine and cropped to it; inside it black is soil and what lies
  beyond the source image is ignore. The rectangle follows the outline of the vegetation,
  not the rows (3.8 degrees apart on field 000), and nearest-neighbour warping drops and
  duplicates a few pixels, so crop/weed counts change slightly.
"""
import argparse
import json
import math
import os
import sys

import cv2
import numpy as np

from .fieldio import IGNORE, write_field

CLASSES = [("soil", (0, 0, 0)), ("crop", (0, 255, 0)), ("weed", (255, 0, 0))]
OUTSIDE_SRC = 254  # internal marker during rotation: no source pixel maps here


def colour_labels(rgb):
    """RGB label image -> class indices; colours other than the three are an error."""
    labels = np.full(rgb.shape[:2], IGNORE, np.uint8)
    for index, (_, colour) in enumerate(CLASSES):
        labels[np.all(rgb == np.array(colour, np.uint8), axis=2)] = index
    unknown = int((labels == IGNORE).sum())
    if unknown:
        raise ValueError(f"{unknown} pixels have colours other than black, green and red")
    return labels


def _large_components(mask, min_component):
    n, comp, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    keep = np.zeros(n, bool)
    keep[1:] = stats[1:, cv2.CC_STAT_AREA] >= min_component
    return keep[comp]


# ---------------------------------------------------------------------------------------------
# --method hull-rect (kept so that the first bundled field stays reproducible)
# ---------------------------------------------------------------------------------------------
def field_rectangle(labels, min_component):
    """minAreaRect around the vegetation pixels of components of at least min_component px."""
    pts = np.column_stack(np.nonzero(_large_components(labels > 0, min_component)))[:, ::-1]
    pts = pts.astype(np.float32)  # (x, y)
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
    """--method hull-rect on an RGB array: returns (source labels, field, rect, matrix)."""
    labels = colour_labels(rgb)
    rect = field_rectangle(labels, min_component)
    field, m = rotate_to_axis(labels, rect)
    return labels, field, rect, m


# ---------------------------------------------------------------------------------------------
# --method rows
# ---------------------------------------------------------------------------------------------
def _profile(xs, ys, theta_deg, bin_px):
    """Histogram of the points projected across direction theta (image coords, y down)."""
    t = math.radians(theta_deg)
    r = ys * math.cos(t) - xs * math.sin(t)
    return np.bincount(((r - r.min()) / bin_px).astype(np.int64)).astype(np.float64)


def estimate_row_angle(mask, max_points=200_000, seed=0):
    """Direction of the rows formed by the mask pixels, in degrees in [-90, 90), in image
    coordinates (x right, y down): rows run along (cos a, sin a), so a < 0 means rising to
    the right on screen."""
    ys, xs = np.nonzero(mask)
    if len(xs) < 10:
        raise ValueError("too few crop pixels to estimate the row direction")
    xs, ys = xs.astype(np.float64), ys.astype(np.float64)
    if len(xs) > max_points:
        idx = np.random.default_rng(seed).choice(len(xs), max_points, replace=False)
        xs, ys = xs[idx], ys[idx]

    def score(a, b):
        h = _profile(xs, ys, a, b)
        return float((h * h).sum())

    coarse = np.arange(-90.0, 90.0, 0.5)
    best = float(coarse[int(np.argmax([score(a, 2.0) for a in coarse]))])
    fine = np.arange(best - 1.0, best + 1.0 + 1e-9, 0.02)
    a = float(fine[int(np.argmax([score(a, 1.0) for a in fine]))])
    return (a + 90.0) % 180.0 - 90.0


def row_spacing(mask, angle_deg):
    """Dominant distance [px] between rows of direction angle_deg (period of the profile)."""
    ys, xs = np.nonzero(mask)
    h = _profile(xs.astype(np.float64), ys.astype(np.float64), angle_deg, 1.0)
    if len(h) < 16:
        return float(len(h))
    f = np.abs(np.fft.rfft(h - h.mean()))
    k = int(np.argmax(f[4:])) + 4  # skip the lowest frequencies (the field's extent)
    return float(len(h) / k)


def hull_rect(mask):
    """Cross-check: cv2.minAreaRect of the convex hull of the mask pixels; returns
    (long-side direction in degrees in [-90, 90), long side, short side, centre)."""
    ys, xs = np.nonzero(mask)
    (cx, cy), (w, h), a = cv2.minAreaRect(cv2.convexHull(np.column_stack([xs, ys]).astype(np.int32)))
    if w < h:
        a, w, h = a + 90.0, h, w
    return (a + 90.0) % 180.0 - 90.0, w, h, (cx, cy)


def _shear_amounts(n, a):
    s = np.rint(a * np.arange(n)).astype(np.int64)
    return s - s.min()


def _shear_rows(img, a, fill):
    """Row y moves right by round(a*y) (minus the minimum): a permutation of the pixels."""
    h, w = img.shape
    s = _shear_amounts(h, a)
    out = np.full((h, w + int(s.max())), fill, img.dtype)
    for y in range(h):
        out[y, s[y]:s[y] + w] = img[y]
    return out


def _shear_params(phi_deg):
    if abs(phi_deg) > 90.0:
        raise ValueError("rotation angle must be within [-90, 90] degrees")
    phi = math.radians(phi_deg)
    return -math.tan(phi / 2.0), math.sin(phi)


def rotate_exact(labels, phi_deg, fill=OUTSIDE_SRC):
    """Rotates by phi_deg in image coordinates (a direction of angle a gets angle a + phi;
    on screen, with y down, positive phi turns clockwise) as R = Sx(alpha) Sy(beta) Sx(alpha),
    alpha = -tan(phi/2), beta = sin(phi), with integer shifts. Every source pixel appears
    exactly once in the result; the rest is `fill`."""
    alpha, beta = _shear_params(phi_deg)
    r = _shear_rows(labels, alpha, fill)
    r = np.ascontiguousarray(_shear_rows(np.ascontiguousarray(r.T), beta, fill).T)
    return _shear_rows(r, alpha, fill)


def rotate_points_exact(xs, ys, shape, phi_deg):
    """Where rotate_exact puts source pixels (xs, ys) of an image of `shape` (h, w)."""
    h, w = shape
    alpha, beta = _shear_params(phi_deg)
    s1 = _shear_amounts(h, alpha)
    x = xs + s1[ys]
    w1 = w + int(s1.max())
    s2 = _shear_amounts(w1, beta)
    y = ys + s2[x]
    s3 = _shear_amounts(h + int(s2.max()), alpha)
    return x + s3[y], y


def _fill_holes(mask):
    h, w = mask.shape
    pad = np.zeros((h + 2, w + 2), np.uint8)
    pad[1:-1, 1:-1] = mask
    flood = pad.copy()
    cv2.floodFill(flood, np.zeros((h + 4, w + 4), np.uint8), (0, 0), 1)
    return (pad.astype(bool) | (flood == 0))[1:-1, 1:-1]


def field_region(veg, kernel_px):
    """Closing of the vegetation mask with a kernel_px square, interior holes filled."""
    k = max(3, int(kernel_px) | 1)
    m = cv2.copyMakeBorder(veg.astype(np.uint8), k, k, k, k, cv2.BORDER_CONSTANT, value=0)
    m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_RECT, (k, k)))
    return _fill_holes(m[k:-k, k:-k])


def convert_rows(labels, boundary="region", kernel_rows=1.5, min_component=20, angle_deg=None,
                 log=print):
    """--method rows on class indices. Returns a dict: field (labels), angle_deg (row
    direction in the source), rotation_deg, spacing_px, kernel_px, bbox (x0, y0, x1, y1 in
    the rotated image), rotated_shape, region (bool, in the field), hull (cross-check)."""
    crop, veg = labels == 1, labels >= 1
    rows_from = crop if crop.sum() >= 10 else veg
    if angle_deg is None:
        angle_deg = estimate_row_angle(rows_from)
    spacing = row_spacing(rows_from, angle_deg)
    hull = hull_rect(veg)
    log(f"row direction {angle_deg:.2f} deg (image coordinates, y down), row spacing {spacing:.1f} px; "
        f"cross-check minAreaRect of the vegetation's convex hull: {hull[0]:.2f} deg, "
        f"{hull[1]:.0f} x {hull[2]:.0f} px")
    phi = (-90.0 if angle_deg < 0 else 90.0) - angle_deg  # rows -> vertical, |phi| <= 90
    rot = rotate_exact(labels, phi)
    rveg = (rot == 1) | (rot == 2)
    kernel = int(round(kernel_rows * spacing))
    if boundary == "region":
        region = field_region(rveg, kernel)
    elif boundary == "rect":
        big = _large_components(rveg, min_component)
        if not big.any():
            raise ValueError("no vegetation found: cannot locate the field")
        ys, xs = np.nonzero(big)
        region = np.zeros(rot.shape, bool)
        region[ys.min():ys.max() + 1, xs.min():xs.max() + 1] = True
    else:
        raise ValueError(f"unknown boundary '{boundary}'")
    ys, xs = np.nonzero(region)
    x0, y0, x1, y1 = int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1
    field = rot[y0:y1, x0:x1].copy()
    region = region[y0:y1, x0:x1]
    field[~region | (field == OUTSIDE_SRC)] = IGNORE
    return dict(field=field, angle_deg=angle_deg, rotation_deg=phi, spacing_px=spacing, kernel_px=kernel,
                bbox=(x0, y0, x1, y1), rotated_shape=rot.shape, region=region, hull=hull)


# ---------------------------------------------------------------------------------------------
# previews
# ---------------------------------------------------------------------------------------------
def _colour(labels, soil=(70, 70, 70), ignore=(110, 0, 110)):
    lut = np.zeros((256, 3), np.uint8)
    lut[0], lut[1], lut[2], lut[IGNORE] = soil, (0, 255, 0), (0, 0, 255), ignore
    return lut[labels]


def _small(img, target=1000):
    s = target / max(img.shape[:2])
    return cv2.resize(img, None, fx=s, fy=s, interpolation=cv2.INTER_AREA) if s < 1 else img


def write_previews(prev_dir, src, res):
    """raw image with the detected boundary (cyan) and the crop rectangle (yellow) drawn,
    and the resulting field (ignore magenta), both downscaled to 1000 px."""
    os.makedirs(prev_dir, exist_ok=True)
    field = res["field"]
    cv2.imwrite(os.path.join(prev_dir, "weedmap_field.png"), _small(_colour(field)))
    ys, xs = np.nonzero(np.ones(src.shape, bool))
    xr, yr = rotate_points_exact(xs, ys, src.shape, res["rotation_deg"])
    x0, y0, x1, y1 = res["bbox"]
    inb = (xr >= x0) & (xr < x1) & (yr >= y0) & (yr < y1)
    inside = np.zeros(src.size, bool)
    inside[inb] = field[yr[inb] - y0, xr[inb] - x0] != IGNORE
    inside = inside.reshape(src.shape)
    vis = _colour(src, soil=(0, 0, 0))
    vis[inside & (src == 0)] = (60, 45, 45)
    cnts, _ = cv2.findContours(inside.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(vis, cnts, -1, (255, 255, 0), 14)
    # the crop rectangle: source pixels mapped to its border
    border = inb & ((xr == x0) | (xr == x1 - 1) | (yr == y0) | (yr == y1 - 1))
    bys, bxs = ys[border], xs[border]
    for x, y in zip(bxs[::50], bys[::50]):
        cv2.circle(vis, (int(x), int(y)), 9, (0, 255, 255), -1)
    cv2.imwrite(os.path.join(prev_dir, "weedmap_raw_boundary.png"), _small(vis))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--input", required=True, help="WeedMap ground-truth PNG (RGB colours)")
    ap.add_argument("--out", required=True, help="field directory to write")
    ap.add_argument("--name", default="weedmap-rededge-000")
    ap.add_argument("--gsd-cm", type=float, default=1.0)
    ap.add_argument("--method", choices=["rows", "hull-rect"], default="rows")
    ap.add_argument("--boundary", choices=["region", "rect"], default="region",
                    help="--method rows: field = closed vegetation region, or its bounding box")
    ap.add_argument("--kernel-rows", type=float, default=1.5,
                    help="--boundary region: closing kernel in row spacings (default 1.5)")
    ap.add_argument("--angle", type=float, help="--method rows: row direction [deg] instead of estimating it")
    ap.add_argument("--min-component", type=int, default=20,
                    help="vegetation components smaller than this [px] do not shape a rectangle")
    ap.add_argument("--preview", help="--method rows: directory for preview PNGs; "
                    "--method hull-rect: PNG file of the input with the rectangle drawn")
    ap.add_argument("--stats-json", help="also write the printed numbers as JSON")
    a = ap.parse_args()
    bgr = cv2.imread(a.input, cv2.IMREAD_COLOR)
    if bgr is None:
        sys.exit(f"convert_weedmap: cannot read {a.input}")
    rgb = np.ascontiguousarray(bgr[:, :, ::-1])
    stats = {"method": a.method}
    try:
        if a.method == "hull-rect":
            src, field, rect, _ = convert(rgb, a.min_component)
            (cx, cy), (w, h), angle = rect
            print(f"boundary: centre ({cx:.1f}, {cy:.1f}) px, size {w:.1f} x {h:.1f} px, angle {angle:.3f} deg")
            stats["rect"] = [cx, cy, w, h, angle]
        else:
            src = colour_labels(rgb)
            res = convert_rows(src, a.boundary, a.kernel_rows, a.min_component, a.angle)
            field = res["field"]
            x0, y0, x1, y1 = res["bbox"]
            print(f"rotated by {res['rotation_deg']:.2f} deg (exact three-shear; rows now vertical) -> "
                  f"{res['rotated_shape'][1]} x {res['rotated_shape'][0]} px; boundary '{a.boundary}' "
                  f"(closing kernel {res['kernel_px']} px); crop x [{x0}, {x1}) y [{y0}, {y1})")
            stats.update(angle_deg=res["angle_deg"], rotation_deg=res["rotation_deg"],
                         spacing_px=res["spacing_px"], kernel_px=res["kernel_px"], bbox=list(res["bbox"]),
                         rotated_shape=list(res["rotated_shape"]), hull=[res["hull"][0], res["hull"][1],
                                                                        res["hull"][2]])
    except ValueError as e:
        sys.exit(f"convert_weedmap: {e}")
    write_field(a.out, a.name, a.gsd_cm, field, CLASSES, ["crop", "weed"])
    before = np.bincount(src.ravel(), minlength=256)
    after = np.bincount(field.ravel(), minlength=256)
    valid = int(after[:3].sum())
    print(f"field: {field.shape[1]} x {field.shape[0]} px; {valid} valid px, ignore {after[IGNORE]} px")
    for i, (n, _) in enumerate(CLASSES):
        print(f"  {n}: source {before[i]} px, field {after[i]} px ({after[i] / max(valid, 1):.4f} of valid)"
              + (f", excluded {before[i] - after[i]}" if i else ""))
    stats.update(size=[field.shape[1], field.shape[0]], before=before[:3].tolist(),
                 after=after[:3].tolist(), ignore=int(after[IGNORE]))
    if a.stats_json:
        with open(a.stats_json, "w") as f:
            json.dump(stats, f, indent=1)
    if a.preview:
        if a.method == "rows":
            write_previews(a.preview, src, res)
        else:
            prev = bgr.copy()
            cv2.polylines(prev, [cv2.boxPoints(rect).astype(np.int32)], True, (255, 0, 255), 25)
            cv2.imwrite(a.preview, _small(prev))


if __name__ == "__main__":
    main()
