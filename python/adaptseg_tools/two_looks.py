"""What a closer look adds to the top-level map of a field, class by class: two whole-field lawnmowers fused.

A descent puts a finer look over part of a field the top level has seen. This tool measures the
same over the whole field, where nothing else decides: the top-level lawnmower and a finer one,
each image segmented on the C++ backend's path (eval_ensemble.member_probabilities: model.pt in
PyTorch or model.onnx through OpenCV's DNN module), painted into the field's frame as log-
probabilities, then per class of interest L (IoU of L against the field's labels):

  - `top`, `fine`: each lawnmower's map alone (a point of the lawnmower curve);
  - `pooled`: the two fused as MapFusion::pooled fuses them (argmax_c of the images'
    log(max(p_c, 1/256)) / GSD summed), the map a descent everywhere would leave;
  - `union`: L wherever either lawnmower's map says L, the rest as `pooled` (the class of
    interest kept where any look saw it);
  - `trim`: L where the pooled map says L and the top level did too (the closer look may
    remove the class but not add it);
  - `bonus`: pooled (or union, or trim) minus the better of the two lawnmowers alone: what fusing two
    looks maps beyond either, before any time is counted (a descent must add this and more
    than the lawnmower curve rises over its seconds);
  - the closer look's additions (pixels it calls L where the top level did not) and removals
    (L at the top level, not in the closer look): each as a share of the labelled ground and
    how often it is right (additions: truly L; removals: truly not L). An addition of precision
    p raises IoU only where p > IoU / (1 + IoU) of the map it joins (`break-even`).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.two_looks \\
      --loto examples/models/mobilenetv2-dubai-loto [--tiles 1,2,3,4,5,6] \\
      [--top 3] [--bands 2,1] [--classes building,road,vegetation,water]
  (each tile-K network on examples/data/dubai-tile-K, the tile it never saw), or
  ... two_looks NETWORK FIELD [NETWORK FIELD ...] with the same options.
--top and --bands are GSD factors of the field's own GSD (3 and 2 on the Dubai tiles: 15 and
10 cm/px). Prints Markdown: one row per class, field and finer band, then per class and band
the mean bonus and in how many fields it is above +0.001. Needs torch, as eval_ensemble does.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from . import REPO
from .eval_ensemble import load_member, member_probabilities
from .fieldio import IGNORE
from .training.fields import capture, lawnmower_rects, load_field

LOG_FLOOR = 1.0 / 256.0  # SemanticMap's floor under a pooled probability
FUSIONS = ("pooled", "union", "trim")  # the two looks fused, each with its bonus (module docstring)


def painted_log_probabilities(model, spec, meta, field, gsd_cm: float) -> np.ndarray:
    """C x H x W in the field's frame: per pixel the sum over the lawnmower's images at `gsd_cm`
    covering it of log(max(p_c, 1/256)) (0 where none fell; its footprints tile the field)."""
    h, w = field.labels.shape
    out = np.zeros((len(field.classes), h, w), np.float32)
    for (c0, r0, fw, fh) in lawnmower_rects(field, gsd_cm, tuple(spec.camera_wh)):
        bgr, _, _ = capture(field, c0, r0, fw, fh, tuple(spec.camera_wh))
        lp = np.log(np.maximum(member_probabilities(model, spec, meta, bgr), LOG_FLOOR)).astype(np.float32)
        ra, ca, rb, cb = max(r0, 0), max(c0, 0), min(r0 + fh, h), min(c0 + fw, w)
        for c in range(out.shape[0]):
            plane = cv2.resize(lp[c], (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
            out[c, ra:rb, ca:cb] += plane[ra - r0:rb - r0, ca - c0:cb - c0]
    return out


def iou(predicted: np.ndarray, truth: np.ndarray) -> float:
    """IoU of two boolean masks (nan where both are empty)."""
    union = int((predicted | truth).sum())
    return int((predicted & truth).sum()) / union if union else float("nan")


def compare(top_lp: np.ndarray, fine_lp: np.ndarray, top_gsd: float, fine_gsd: float, truth: np.ndarray,
            cls: int) -> dict:
    """The measures of the module docstring for class `cls`, over the labelled pixels."""
    valid = truth != IGNORE
    t = (truth == cls) & valid
    top = (top_lp.argmax(0) == cls) & valid
    fine = (fine_lp.argmax(0) == cls) & valid
    pooled = ((top_lp / top_gsd + fine_lp / fine_gsd).argmax(0) == cls) & valid
    fused = {"pooled": pooled, "union": pooled | top | fine, "trim": pooled & top}
    n = max(1, int(valid.sum()))
    added, removed = fine & ~top, top & ~fine
    r = {"top": iou(top, t), "fine": iou(fine, t), **{f: iou(fused[f], t) for f in FUSIONS},
         "added": int(added.sum()) / n, "removed": int(removed.sum()) / n,
         "added_right": float(t[added].mean()) if added.any() else float("nan"),
         "removed_right": float((~t[removed]).mean()) if removed.any() else float("nan")}
    best = max(r["top"], r["fine"])
    r.update({f"{f}_bonus": r[f] - best for f in FUSIONS})
    r["break_even"] = r["top"] / (1.0 + r["top"])
    return r


def pairs_of(args) -> list[tuple[str, Path, Path]]:
    """(label, network folder, field folder) to measure."""
    if args.loto:
        tiles = [int(k) for k in args.tiles.split(",")]
        return [(f"tile {k}", Path(args.loto) / f"tile-{k}", REPO / "examples" / "data" / f"dubai-tile-{k}")
                for k in tiles]
    if not args.pairs or len(args.pairs) % 2:
        raise SystemExit("give --loto DIR or NETWORK FIELD pairs")
    return [(Path(f).name, Path(n), Path(f)) for n, f in zip(args.pairs[::2], args.pairs[1::2])]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("pairs", nargs="*", help="NETWORK FIELD ...")
    parser.add_argument("--loto", help="a leave-one-tile-out set: tile-K flies examples/data/dubai-tile-K")
    parser.add_argument("--tiles", default="1,2,3,4,5,6")
    parser.add_argument("--top", type=float, default=3.0, help="the top level's GSD factor (default 3)")
    parser.add_argument("--bands", default="2", help="the finer lawnmowers' GSD factors (default 2)")
    parser.add_argument("--classes", default="building,road,vegetation,water")
    args = parser.parse_args(argv)
    bands = [float(b) for b in args.bands.split(",")]
    if args.top <= 0 or any(b <= 0 or b >= args.top for b in bands):
        raise SystemExit(f"--bands {args.bands}: each must be above 0 and below --top {args.top}")
    wanted = args.classes.split(",")
    summary: dict[tuple[str, float], list[tuple[float, float, float]]] = {}
    rows = []
    for label, net, fdir in pairs_of(args):
        field = load_field(fdir)
        unknown = [c for c in wanted if c not in field.classes]
        if unknown:
            raise SystemExit(f"{fdir}: no class {', '.join(unknown)} (it has {', '.join(field.classes)})")
        model, spec, meta = load_member(net)
        top_gsd = args.top * field.gsd_cm
        top_lp = painted_log_probabilities(model, spec, meta, field, top_gsd)
        for b in bands:
            fine_gsd = b * field.gsd_cm
            fine_lp = painted_log_probabilities(model, spec, meta, field, fine_gsd)
            for name in wanted:
                r = compare(top_lp, fine_lp, top_gsd, fine_gsd, field.labels, field.classes.index(name))
                rows.append((name, label, top_gsd, fine_gsd, r))
                summary.setdefault((name, fine_gsd), []).append([r[f"{f}_bonus"] for f in FUSIONS])
    print("| class | field | GSD top → fine [cm/px] | IoU top | fine | " + " | ".join(FUSIONS) + " | bonus "
          + " | ".join(FUSIONS) + " | added [% of ground] | right | break-even | removed [%] | right |")
    print("| --- | --- | --- |" + " ---: |" * (7 + 2 * len(FUSIONS)))
    for name, label, top_gsd, fine_gsd, r in sorted(rows, key=lambda x: (wanted.index(x[0]), x[3], x[1])):
        print(f"| {name} | {label} | {top_gsd:g} → {fine_gsd:g} | {r['top']:.3f} | {r['fine']:.3f} | "
              + "".join(f"{r[f]:.3f} | " for f in FUSIONS) + "".join(f"{r[f + '_bonus']:+.3f} | " for f in FUSIONS) +
              f"{100 * r['added']:.2f} | {r['added_right']:.2f} | {r['break_even']:.2f} | "
              f"{100 * r['removed']:.2f} | {r['removed_right']:.2f} |")
    print()
    print("| class | fine GSD [cm/px] | fields |" + "".join(f" mean bonus, {f} | above +0.001 |" for f in FUSIONS))
    print("| --- | ---: | ---: |" + " ---: | ---: |" * len(FUSIONS))
    for (name, fine_gsd), v in sorted(summary.items(), key=lambda x: (wanted.index(x[0][0]), x[0][1])):
        a = np.array(v)
        print(f"| {name} | {fine_gsd:g} | {len(v)} |"
              + "".join(f" {a[:, k].mean():+.4f} | {int((a[:, k] > 0.001).sum())} |" for k in range(len(FUSIONS))))


if __name__ == "__main__":
    main()
