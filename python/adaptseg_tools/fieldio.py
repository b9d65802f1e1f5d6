"""Shared helpers of the data tools: writing and checking adaptseg field directories.

Field format (docs/data_format.md): DIR/field.yaml, DIR/labels.png (8-bit class indices,
255 = ignore), optional DIR/image.jpg|png.
"""
import math
import os

import cv2
import numpy as np
import yaml

IGNORE = 255


def write_field(out_dir, name, gsd_cm, labels, classes, interest, image=None, image_name="image.jpg",
                jpeg_quality=92):
    """Writes a field directory. `classes`: list of (name, (r, g, b)); `image`: BGR uint8 or None."""
    assert labels.dtype == np.uint8 and labels.ndim == 2
    os.makedirs(out_dir, exist_ok=True)
    if not cv2.imwrite(os.path.join(out_dir, "labels.png"), labels, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise RuntimeError(f"cannot write {out_dir}/labels.png")
    lines = [f"name: {name}", f"gsd_cm: {gsd_cm}", "labels: labels.png"]
    if image is not None:
        assert image.shape[:2] == labels.shape
        params = [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality] if image_name.endswith(".jpg") else []
        if not cv2.imwrite(os.path.join(out_dir, image_name), image, params):
            raise RuntimeError(f"cannot write {out_dir}/{image_name}")
        lines.append(f"image: {image_name}")
    lines.append(f"ignore_label: {IGNORE}")
    lines.append("classes:                    # label-index order")
    for cname, (r, g, b) in classes:
        lines.append(f"  - {{name: {cname}, color: [{r}, {g}, {b}]}}")
    lines.append(f"interest: [{', '.join(interest)}]")
    with open(os.path.join(out_dir, "field.yaml"), "w") as f:
        f.write("\n".join(lines) + "\n")


def check_field(field_dir):
    """Validates a field directory; returns a summary dict or raises ValueError naming the problem."""
    path = os.path.join(field_dir, "field.yaml")
    if not os.path.isfile(path):
        raise ValueError(f"missing {path}")
    with open(path) as f:
        try:
            meta = yaml.safe_load(f)
        except yaml.YAMLError as e:
            raise ValueError(f"{path}: YAML error: {e}") from e
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: the document must be a mapping")
    known = {"name", "gsd_cm", "labels", "image", "ignore_label", "classes", "interest", "geo"}
    for key in meta:
        if key not in known:
            raise ValueError(f"{path}: unknown key '{key}'")
    if "gsd_cm" not in meta:
        raise ValueError(f"{path}: missing key 'gsd_cm' (a GeoTIFF field, whose rasters give the GSD, "
                         "is checked by the C++ loader: adaptseg_mission --field DIR)")
    if "geo" in meta:
        geo = meta["geo"]
        keys = {"latitude_deg", "longitude_deg", "altitude_m", "heading_deg"}
        if not isinstance(geo, dict) or set(geo) != keys or not all(
                isinstance(v, (int, float)) and math.isfinite(v) for v in geo.values()):
            raise ValueError(f"{path}: 'geo' must map exactly {sorted(keys)} to finite numbers")
    for key in ("name", "gsd_cm", "labels", "classes"):
        if key not in meta:
            raise ValueError(f"{path}: missing key '{key}'")
    gsd = meta["gsd_cm"]
    if not isinstance(gsd, (int, float)) or not gsd > 0:
        raise ValueError(f"{path}: 'gsd_cm' must be a number > 0")
    classes = meta["classes"]
    if not isinstance(classes, list) or not classes:
        raise ValueError(f"{path}: 'classes' must be a non-empty list")
    names = []
    for i, c in enumerate(classes):
        if not isinstance(c, dict) or set(c) != {"name", "color"}:
            raise ValueError(f"{path}: classes[{i}] must be {{name, color}}")
        col = c["color"]
        if not (isinstance(col, list) and len(col) == 3 and all(isinstance(v, int) and 0 <= v <= 255 for v in col)):
            raise ValueError(f"{path}: classes[{i}].color must be 3 integers 0..255")
        if c["name"] in names:
            raise ValueError(f"{path}: class '{c['name']}' listed twice")
        names.append(str(c["name"]))
    ignore = meta.get("ignore_label", IGNORE)
    if not isinstance(ignore, int) or not len(names) <= ignore <= 255:
        raise ValueError(f"{path}: 'ignore_label' must be in {len(names)}..255")
    for n in meta.get("interest", []) or []:
        if n not in names:
            raise ValueError(f"{path}: 'interest' names unknown class '{n}'")
    labels = cv2.imread(os.path.join(field_dir, meta["labels"]), cv2.IMREAD_UNCHANGED)
    if labels is None:
        raise ValueError(f"{path}: cannot read {meta['labels']}")
    if labels.dtype != np.uint8 or labels.ndim != 2:
        raise ValueError(f"{path}: {meta['labels']} must be 8-bit single channel")
    counts = np.bincount(labels.ravel(), minlength=256)
    bad = [v for v in np.nonzero(counts)[0] if v >= len(names) and v != ignore]
    if bad:
        raise ValueError(f"{path}: label values {bad} are neither class indices nor the ignore label")
    if "image" in meta:
        image = cv2.imread(os.path.join(field_dir, meta["image"]), cv2.IMREAD_COLOR)
        if image is None:
            raise ValueError(f"{path}: cannot read {meta['image']}")
        if image.shape[:2] != labels.shape:
            raise ValueError(f"{path}: image {image.shape[1]}x{image.shape[0]} and labels "
                             f"{labels.shape[1]}x{labels.shape[0]} differ in size")
    valid = counts[: len(names)].sum()
    return {
        "name": meta["name"], "width": labels.shape[1], "height": labels.shape[0], "gsd_cm": gsd,
        "classes": names, "valid": int(valid), "ignore": int(counts[ignore]),
        "fractions": {n: (float(counts[i]) / valid if valid else 0.0) for i, n in enumerate(names)},
    }
