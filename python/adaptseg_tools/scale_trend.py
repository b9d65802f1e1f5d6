"""Whether a look coarser than the top level tells where, and on which fields, a closer look pays.

The top level's own inputs tell where a closer look changes labels, not whether the changes are
right (docs/journal/2026-12-guard.md). A look coarser than the top level costs no flight: the
top-level images shrunk (here a lawnmower at that GSD stands for it). This tool asks whether the
way the labels move from that coarser look to the top level (the scale trend, label-free before
any descent) tells what the next step, from the top level to a closer look, is worth. Per field
and class of interest L, each map painted over the whole field as two_looks paints it (each
image's log(max(p_c, 1/256)) summed per pixel, the map its argmax):

  - cells: the finer lawnmower's footprints (what a descent's images cover); a cell's `gain` is
    the field's IoU of L when that cell alone takes the pooled map of the top level and the finer
    look (MapFusion::pooled, weights 1 / GSD), less the top level's IoU (labels used);
  - per cell, four rankings: `ambiguity`, the share of the cell where the top level's pooled
    probability of L lies in (0.2, 0.8) (the deployment's decision input, DecisionInput::ambiguity,
    read off the pooled map rather than image by image); `unsure`, the mean of 1 − the top level's
    pooled probability of its class (the guard's reading of how sure it is); `scale`, the share of
    the cell whose label moves from the coarser look to the top level with L one of the two labels
    (label-free, before any descent); and `relabelled`, the share whose label moves from the top level to the finer
    look with L one of the two (what a descent would show; not known before it);
  - per field, each ranking's rank correlation with the cells' gains (`rho`), and with the
    relabelled share (`rho rel`): how well it tells where labels change;
  - per field, label-free: the share of the coarse → top changes that the coarser look was sure
    of (its pooled probability above 0.75: `scale sure`), beside the same share of the top →
    finer changes (`sure changes`, the sign two_looks prints after a descent), and the whole
    field's pooled gain over the top level (`field gain`, labels used).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.scale_trend \\
      --loto examples/models/mobilenetv2-dubai-loto [--tiles 1,2,3,4,5,6] \\
      [--top 2.5,3] [--fine 1,1.5,2] [--coarse 2] [--classes building,road,vegetation,water] \\
      [--cells-csv PREFIX]
  (each tile-K network on examples/data/dubai-tile-K, the tile it never saw; --top and --fine GSD
  factors of the field's own GSD, 15 and 5 cm/px by default on the Dubai tiles; the coarser look
  at --coarse times each top level's GSD, a lawnmower flown that high). Prints Markdown: a row per
  class, field, top level and closer look, then per class each ranking's mean rank correlation
  over them. --cells-csv writes PREFIX-CLASS.csv, the cells with their gains and rankings as
  cell_ceiling reads them (top_ambiguity, top_unsure, top_scale, relabelled), to set beside a
  calibration's model (its fields' lawnmower curves): what fixed plans ranked so would earn.
  Needs torch, as eval_ensemble does.
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np

from . import REPO
from .eval_ensemble import load_member
from .fieldio import IGNORE
from .proxy_table import spearman
from .training.fields import lawnmower_rects, load_field
from .two_looks import GUARD, confidence, factors, iou, painted_log_probabilities

RANKINGS = ("ambiguity", "unsure", "scale", "relabelled")


def iou_of(tp: float, fp: float, fn: float) -> float:
    return tp / (tp + fp + fn) if tp + fp + fn > 0 else math.nan


def touching(a: np.ndarray, b: np.ndarray, cls: int) -> np.ndarray:
    """Pixels whose label moves from map a to map b with class `cls` one of the two labels."""
    return (a != b) & ((a == cls) | (b == cls))


def region_of(rect, top_rects) -> int:
    """The index of the top-level footprint holding the cell's centre (the nearest centre where none does)."""
    cx, cy = rect[0] + rect[2] / 2.0, rect[1] + rect[3] / 2.0
    inside = [i for i, (c0, r0, w, h) in enumerate(top_rects) if c0 <= cx < c0 + w and r0 <= cy < r0 + h]
    if inside:
        return inside[0]
    return min(range(len(top_rects)), key=lambda i: (top_rects[i][0] + top_rects[i][2] / 2.0 - cx) ** 2
               + (top_rects[i][1] + top_rects[i][3] / 2.0 - cy) ** 2)


def field_measures(coarse_lp, top_lp, fine_lp, top_gsd: float, fine_gsd: float, truth: np.ndarray, cls: int,
                   rects, top_rects=()) -> dict:
    """The measures of the module docstring for class `cls` on one field; `rects` the cells as
    (c0, r0, w, h) in field pixels (clipped to the field; overlaps are counted in each cell); with
    `top_rects` (the top level's footprints) each cell also names its region."""
    valid = truth != IGNORE
    t = (truth == cls) & valid
    coarse_lab, top_lab, fine_lab = coarse_lp.argmax(0), top_lp.argmax(0), fine_lp.argmax(0)
    pooled_lab = (top_lp / top_gsd + fine_lp / fine_gsd).argmax(0)
    top, pooled = (top_lab == cls) & valid, (pooled_lab == cls) & valid
    counts = np.array([(top & t).sum(), (top & ~t & valid).sum(), (~top & t).sum()], float)
    base = iou_of(*counts)
    scale_moved, fine_moved = touching(coarse_lab, top_lab, cls) & valid, touching(top_lab, fine_lab, cls) & valid
    unsure = 1.0 - confidence(top_lp)
    p_cls = 1.0 / np.exp(top_lp - top_lp[cls][None]).sum(0)  # the top level's pooled probability of cls
    ambiguous = (p_cls > 0.2) & (p_cls < 0.8) & valid
    h, w = truth.shape
    cells = []
    for (c0, r0, fw, fh) in rects:
        sl = (slice(max(r0, 0), min(r0 + fh, h)), slice(max(c0, 0), min(c0 + fw, w)))
        v = valid[sl]
        if not v.any():
            continue
        tt, a, b = t[sl], top[sl], pooled[sl]
        delta = np.array([(b & tt).sum() - (a & tt).sum(), (b & ~tt & v).sum() - (a & ~tt & v).sum(),
                          (~b & tt).sum() - (~a & tt).sum()], float)
        n = float(v.sum())
        cells.append({"gain": iou_of(*(counts + delta)) - base, "unsure": float(unsure[sl][v].mean()),
                      "ambiguity": ambiguous[sl].sum() / n,
                      "scale": scale_moved[sl].sum() / n, "relabelled": fine_moved[sl].sum() / n,
                      "region": region_of((c0, r0, fw, fh), top_rects) if top_rects else -1})
    coarse_sure = confidence(coarse_lp) > GUARD
    top_sure = confidence(top_lp) > GUARD
    gains = [c["gain"] for c in cells]
    return {
        "field_gain": iou(pooled, t) - base,
        "scale_share": float(scale_moved.sum() / max(1, valid.sum())),
        "scale_sure": float(coarse_sure[scale_moved].mean()) if scale_moved.any() else math.nan,
        "sure_changes": float(top_sure[fine_moved].mean()) if fine_moved.any() else math.nan,
        "cells": len(cells), "cell_rows": cells,
        "rho": {k: spearman([c[k] for c in cells], gains) for k in RANKINGS},
        "rho_rel": {k: spearman([c[k] for c in cells], [c["relabelled"] for c in cells]) for k in RANKINGS[:-1]},
    }


def write_cells(prefix: str, rows, wanted) -> None:
    """PREFIX-CLASS.csv per class: cell_ceiling's columns (field, region, top_gsd_cm, sub_gsd_cm,
    field_gain) and the rankings as top_ambiguity, top_unsure, top_scale and relabelled."""
    for name in wanted:
        with open(f"{prefix}-{name}.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["field", "region", "top_gsd_cm", "sub_gsd_cm", "field_gain", "top_ambiguity", "top_unsure",
                        "top_scale", "relabelled"])
            for n, _, r in rows:
                if n == name:
                    for c in r["cell_rows"]:
                        w.writerow([r["field"], c["region"], f"{r['top_gsd']:g}", f"{r['fine_gsd']:g}",
                                    *(f"{c[k]:.6g}" for k in ("gain", "ambiguity", "unsure", "scale", "relabelled"))])


def mean(values) -> float:
    """The mean of the values that are not NaN (NaN where none is)."""
    v = [x for x in values if not math.isnan(x)]
    return sum(v) / len(v) if v else math.nan


def fmt(x: float) -> str:
    return "nan" if math.isnan(x) else f"{x:+.2f}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--loto", required=True, help="a leave-one-tile-out set: tile-K flies examples/data/dubai-tile-K")
    parser.add_argument("--tiles", default="1,2,3,4,5,6")
    parser.add_argument("--coarse", default="2", help="the coarser look's GSD over the top level's (default 2)")
    parser.add_argument("--top", default="3", help="the top levels' GSD factors (default 3)")
    parser.add_argument("--fine", default="1", help="the closer looks' GSD factors (default 1)")
    parser.add_argument("--classes", default="building,road,vegetation,water")
    parser.add_argument("--cells-csv", help="also write the cells as cell_ceiling reads them: PREFIX-CLASS.csv")
    args = parser.parse_args(argv)
    ratio, tops, fines = (factors(args.coarse, "--coarse")[0], factors(args.top, "--top"), factors(args.fine, "--fine"))
    if not ratio > 1 or any(f >= t for t in tops for f in fines):
        raise SystemExit(f"--coarse {args.coarse} must be above 1 and each --fine ({args.fine}) below each --top "
                         f"({args.top})")
    wanted = args.classes.split(",")
    rows = []
    for k in args.tiles.split(","):
        net, fdir = Path(args.loto) / f"tile-{k}", REPO / "examples" / "data" / f"dubai-tile-{k}"
        if not (net / "model.yaml").is_file():
            raise SystemExit(f"{net}: no model.yaml (tile {k} of --loto {args.loto})")
        field = load_field(fdir)
        unknown = [c for c in wanted if c not in field.classes]
        if unknown:
            raise SystemExit(f"{fdir}: no class {', '.join(unknown)} (it has {', '.join(field.classes)})")
        model, spec, meta = load_member(net)
        cam = tuple(spec.camera_wh)
        lps = {f: painted_log_probabilities(model, spec, meta, field, f * field.gsd_cm)
               for f in sorted({*tops, *(t * ratio for t in tops), *fines})}
        for top in tops:
            top_rects = lawnmower_rects(field, top * field.gsd_cm, cam)
            for fine in fines:
                rects = lawnmower_rects(field, fine * field.gsd_cm, cam)
                for name in wanted:
                    r = field_measures(lps[top * ratio], lps[top], lps[fine], top * field.gsd_cm, fine * field.gsd_cm,
                                       field.labels, field.classes.index(name), rects, top_rects)
                    r["field"], r["top_gsd"], r["fine_gsd"] = fdir.name, top * field.gsd_cm, fine * field.gsd_cm
                    rows.append((name, f"tile {k}", r))
    if args.cells_csv:
        write_cells(args.cells_csv, rows, wanted)
    print(f"The coarser look at {ratio:g} times the top level's GSD")
    print("| class | field | GSD top → fine [cm/px] | cells | field gain | scale share | scale sure | sure changes | "
          + " | ".join(f"rho {k}" for k in RANKINGS) + " | " + " | ".join(f"rho rel {k}" for k in RANKINGS[:-1]) + " |")
    print("| --- | --- | --- |" + " ---: |" * (5 + 2 * len(RANKINGS) - 1))
    for name, label, r in sorted(rows, key=lambda x: (wanted.index(x[0]), x[1], -x[2]["top_gsd"], -x[2]["fine_gsd"])):
        print(f"| {name} | {label} | {r['top_gsd']:g} → {r['fine_gsd']:g} | {r['cells']} | {r['field_gain']:+.4f} | "
              f"{r['scale_share']:.4f} | "
              f"{r['scale_sure']:.2f} | {r['sure_changes']:.2f} | "
              + " | ".join(fmt(r["rho"][k]) for k in RANKINGS) + " | "
              + " | ".join(fmt(r["rho_rel"][k]) for k in RANKINGS[:-1]) + " |")
    print()
    print("| class | fields × plans | " + " | ".join(f"mean rho {k}" for k in RANKINGS) + " | "
          + " | ".join(f"mean rho rel {k}" for k in RANKINGS[:-1]) + " |")
    print("| --- | ---: |" + " ---: |" * (2 * len(RANKINGS) - 1))
    for name in wanted:
        rs = [r for n, _, r in rows if n == name]
        print(f"| {name} | {len(rs)} | " + " | ".join(fmt(mean([r["rho"][k] for r in rs])) for k in RANKINGS) + " | "
              + " | ".join(fmt(mean([r["rho_rel"][k] for r in rs])) for k in RANKINGS[:-1]) + " |")


if __name__ == "__main__":
    main()
