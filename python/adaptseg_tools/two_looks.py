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
  - `guarded`: the pooled map, but where the top level's own pooled probability of its class
    (softmax of its images' summed log(max(p_c, 1/256))) is above `--guard` (default 0.75, the
    library's SemanticMap::kGuardConfidence) the top level's label: MapFusion::pooled_guarded,
    a closer look changing only what the top level was unsure of;
  - `bonus`: pooled (or union, or trim) minus the better of the two lawnmowers alone: what fusing two
    looks maps beyond either, before any time is counted (a descent must add this and more
    than the lawnmower curve rises over its seconds);
  - the closer look's additions (pixels it calls L where the top level did not) and removals
    (L at the top level, not in the closer look): each as a share of the labelled ground and
    how often it is right (additions: truly L; removals: truly not L). An addition of precision
    p raises IoU only where p > IoU / (1 + IoU) of the map it joins (`break-even`); and of the
    closer look's changes of label with L among the two labels, the share the top level was sure
    of (its probability above the guard: `sure changes`, label-free, what the guard undoes);
  - with `--check DIR` (a second leave-one-tile-out set, e.g. the other seed's), `agreed`: the
    pooled map, but a pixel takes a label other than the top level's only where the check
    network's lawnmower at the finer GSD gives that label too (a second network as a gate on
    what a closer look changes, every class at once);
  - with `--curve FACTORS` (the lawnmower curve's GSD factors, e.g. 1,1.5,2,2.5,3), each fusion's
    margin over the best of those lawnmowers (`over curve`): what two whole passes, the top level
    and then the finer one everywhere, score against the lawnmower curve's upper envelope. Exact
    where the two passes end after every lawnmower of the curve (the finer pass at the curve's
    finest GSD: the envelope is flat beyond it), a lower bound otherwise. The summary then gives
    per class the finer GSD the other fields choose (the largest mean pooled margin over the
    curve, none where it is not positive) and what it scores on each field;
  - with `--guards T1,T2,...` the guard chosen on other fields: per threshold T the mean over
    classes, bands and fields of the guarded map's IoU less the top level's, and per field the
    T whose mean over the other fields is largest (how MapFusion::pooled_guarded's threshold
    was chosen, docs/journal/2026-12-guard.md);
  - with `--flips`, per field and finer band the closer look's changes of label (the top level's
    class a, the finer lawnmower's b, a class of interest among them, at least 0.2 % of the
    labelled ground): their share of the ground, how often the truth is b (the change right) or
    a, and the median probability each look gives its own class there (`confidence`: the
    softmax of its images' summed log-probabilities, the guard's reading).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.two_looks \\
      --loto examples/models/mobilenetv2-dubai-loto [--tiles 1,2,3,4,5,6] \\
      [--top 3] [--bands 2,1] [--classes building,road,vegetation,water] \\
      [--check examples/models/mobilenetv2-dubai-loto-seed1] [--curve 1,1.5,2,2.5,3] \\
      [--guard 0.75] [--guards 0.95,0.9,0.85,0.8,0.75,0.7,0.65,0.6] [--flips]
  (each tile-K network on examples/data/dubai-tile-K, the tile it never saw), or
  ... two_looks NETWORK FIELD [NETWORK FIELD ...] with the same options.
--top and --bands are GSD factors of the field's own GSD (3 and 2 on the Dubai tiles: 15 and
10 cm/px). Prints Markdown: one row per class, field and finer band, then per class and band
the mean bonus and in how many fields it is above +0.001. --check needs --loto. Needs torch, as
eval_ensemble does.
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
FUSIONS = ("pooled", "union", "trim", "guarded")  # the two looks fused, each with its bonus (module docstring)
GUARD = 0.75  # SemanticMap::kGuardConfidence: MapFusion::pooled_guarded's threshold


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


def fusions_of(checked: bool) -> tuple[str, ...]:
    """The fusions measured: FUSIONS, and `agreed` where a check network gates the changes."""
    return FUSIONS + (("agreed",) if checked else ())


def confidence(lp: np.ndarray) -> np.ndarray:
    """Per pixel a lawnmower's pooled probability of its most likely class: the softmax of its
    images' summed log-probabilities (1 / the sum of exp(s_c - max s)), as SemanticMap's guard
    reads the top level's."""
    return 1.0 / np.exp(lp - lp.max(0, keepdims=True)).sum(0)


def compare(top_lp: np.ndarray, fine_lp: np.ndarray, top_gsd: float, fine_gsd: float, truth: np.ndarray,
            cls: int, check_labels: np.ndarray | None = None, curve_best: float | None = None,
            guard: float = GUARD, guards: tuple[float, ...] = ()) -> dict:
    """The measures of the module docstring for class `cls`, over the labelled pixels: with
    `check_labels` (the check network's labels at the finer GSD) also `agreed`; with `curve_best`
    (the best IoU of `cls` among the curve's lawnmowers) each fusion's `<fusion>_over_curve`; with
    `guards`, `guard_gains`: per threshold the guarded map's IoU less the top level's."""
    valid = truth != IGNORE
    t = (truth == cls) & valid
    top_labels, pooled_labels = top_lp.argmax(0), (top_lp / top_gsd + fine_lp / fine_gsd).argmax(0)
    top = (top_labels == cls) & valid
    fine = (fine_lp.argmax(0) == cls) & valid
    pooled = (pooled_labels == cls) & valid
    sure = confidence(top_lp)
    fused = {"pooled": pooled, "union": pooled | top | fine, "trim": pooled & top,
             "guarded": np.where(sure > guard, top, pooled)}
    if check_labels is not None:
        fused["agreed"] = (np.where(check_labels == pooled_labels, pooled_labels, top_labels) == cls) & valid
    fusions = fusions_of(check_labels is not None)
    n = max(1, int(valid.sum()))
    added, removed = fine & ~top, top & ~fine
    r = {"top": iou(top, t), "fine": iou(fine, t), **{f: iou(fused[f], t) for f in fusions},
         "added": int(added.sum()) / n, "removed": int(removed.sum()) / n,
         "added_right": float(t[added].mean()) if added.any() else float("nan"),
         "removed_right": float((~t[removed]).mean()) if removed.any() else float("nan")}
    best = max(r["top"], r["fine"])
    r.update({f"{f}_bonus": r[f] - best for f in fusions})
    if curve_best is not None:
        r.update({f"{f}_over_curve": r[f] - max(best, curve_best) for f in fusions})
    r["break_even"] = r["top"] / (1.0 + r["top"])
    changed = added | removed  # the closer look's changes of label with `cls` one of the two
    r["sure_changes"] = float((sure[changed] > guard).mean()) if changed.any() else float("nan")
    if guards:
        r["guard_gains"] = [iou(np.where(sure > g, top, pooled), t) - r["top"] for g in guards]
    return r


def flips(top_lp: np.ndarray, fine_lp: np.ndarray, truth: np.ndarray, classes, wanted) -> list[tuple]:
    """The closer look's changes of label (module docstring, `--flips`): (a, b, share of the
    labelled ground, share truly b, share truly a, median top confidence, median fine confidence),
    largest first, for the changes touching a class of `wanted` over at least 0.2 % of the ground."""
    valid = truth != IGNORE
    a_lab, b_lab = top_lp.argmax(0), fine_lp.argmax(0)
    top_sure, fine_sure = confidence(top_lp), confidence(fine_lp)
    interest = {classes.index(n) for n in wanted}
    n = max(1, int(valid.sum()))
    out = []
    for a in range(len(classes)):
        for b in range(len(classes)):
            if a == b or not {a, b} & interest:
                continue
            m = valid & (a_lab == a) & (b_lab == b)
            if m.sum() < 0.002 * n:
                continue
            t = truth[m]
            out.append((classes[a], classes[b], m.sum() / n, float((t == b).mean()), float((t == a).mean()),
                        float(np.median(top_sure[m])), float(np.median(fine_sure[m]))))
    return sorted(out, key=lambda x: -x[2])


def pairs_of(args) -> list[tuple[str, Path, Path, Path | None]]:
    """(label, network folder, field folder, check network folder or None) to measure."""
    if args.loto:
        tiles = [int(k) for k in args.tiles.split(",")]
        return [(f"tile {k}", Path(args.loto) / f"tile-{k}", REPO / "examples" / "data" / f"dubai-tile-{k}",
                 Path(args.check) / f"tile-{k}" if args.check else None) for k in tiles]
    if args.check:
        raise SystemExit("--check needs --loto (each tile's check network is the check set's tile-K)")
    if not args.pairs or len(args.pairs) % 2:
        raise SystemExit("give --loto DIR or NETWORK FIELD pairs")
    return [(Path(f).name, Path(n), Path(f), None) for n, f in zip(args.pairs[::2], args.pairs[1::2])]


def factors(text: str, option: str) -> list[float]:
    """Comma-separated positive GSD factors."""
    try:
        values = [float(b) for b in text.split(",")]
    except ValueError:
        raise SystemExit(f"{option} {text}: comma-separated numbers") from None
    if not values or min(values) <= 0:
        raise SystemExit(f"{option} {text}: each must be above 0")
    return values


def labels_at(model, spec, meta, field, gsd_cm: float) -> np.ndarray:
    """The lawnmower's labels at `gsd_cm` in the field's frame."""
    return painted_log_probabilities(model, spec, meta, field, gsd_cm).argmax(0).astype(np.uint8)


def chosen_on_others(rows, wanted) -> list[tuple[str, str, str, float]]:
    """Per class and field: the finer GSD whose mean pooled margin over the curve on the other
    fields is largest, none (margin 0: the top level alone, a point of the curve) where that mean
    is not positive, and the margin it scores on the field."""
    margins: dict[tuple[str, str], dict[float, float]] = {}
    for name, label, _, fine_gsd, r in rows:
        margins.setdefault((name, label), {})[fine_gsd] = r["pooled_over_curve"]
    out = []
    for (name, label), own in sorted(margins.items(), key=lambda x: (wanted.index(x[0][0]), x[0][1])):
        others = [m for (n, lab), m in margins.items() if n == name and lab != label]
        if not others:
            continue
        mean = {g: float(np.mean([m[g] for m in others])) for g in own}
        g = max(mean, key=mean.get)
        out.append((name, label, f"{g:g}", own[g]) if mean[g] > 0 else (name, label, "none", 0.0))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("pairs", nargs="*", help="NETWORK FIELD ...")
    parser.add_argument("--loto", help="a leave-one-tile-out set: tile-K flies examples/data/dubai-tile-K")
    parser.add_argument("--tiles", default="1,2,3,4,5,6")
    parser.add_argument("--top", type=float, default=3.0, help="the top level's GSD factor (default 3)")
    parser.add_argument("--bands", default="2", help="the finer lawnmowers' GSD factors (default 2)")
    parser.add_argument("--classes", default="building,road,vegetation,water")
    parser.add_argument("--check", help="with --loto: a second set whose tile-K gates what the closer look changes")
    parser.add_argument("--curve", help="the lawnmower curve's GSD factors: each fusion's margin over its best")
    parser.add_argument("--guard", type=float, default=GUARD, help=f"the guarded map's threshold (default {GUARD})")
    parser.add_argument("--guards", help="thresholds to choose the guard from on the other fields, e.g. 0.9,0.8,0.7")
    parser.add_argument("--flips", action="store_true", help="per field and band the closer look's changes of label")
    args = parser.parse_args(argv)
    bands = factors(args.bands, "--bands")
    curve = factors(args.curve, "--curve") if args.curve else []
    guards = tuple(factors(args.guards, "--guards")) if args.guards else ()
    if not 0 < args.guard <= 1 or any(g > 1 for g in guards):
        raise SystemExit(f"--guard {args.guard} / --guards {args.guards}: each must be in (0, 1]")
    if args.top <= 0 or any(b >= args.top for b in bands):
        raise SystemExit(f"--bands {args.bands}: each must be above 0 and below --top {args.top}")
    wanted = args.classes.split(",")
    fusions = fusions_of(bool(args.check))
    summary: dict[tuple[str, float], list[list[float]]] = {}
    rows, flip_rows = [], []
    for label, net, fdir, check_net in pairs_of(args):
        field = load_field(fdir)
        unknown = [c for c in wanted if c not in field.classes]
        if unknown:
            raise SystemExit(f"{fdir}: no class {', '.join(unknown)} (it has {', '.join(field.classes)})")
        model, spec, meta = load_member(net)
        checker = load_member(check_net) if check_net else None
        if checker and checker[2]["classes"] != meta["classes"]:
            raise SystemExit(f"{check_net}: classes {checker[2]['classes']} differ from {net}'s {meta['classes']}")
        top_gsd = args.top * field.gsd_cm
        lps = {f: painted_log_probabilities(model, spec, meta, field, f * field.gsd_cm) for f in [args.top, *bands]}
        top_lp = lps[args.top]
        # The curve's lawnmowers: those already painted (the top level, the bands) read off their maps.
        curve_labels = [lps[f].argmax(0).astype(np.uint8) if f in lps else labels_at(model, spec, meta, field,
                                                                                     f * field.gsd_cm) for f in curve]
        for b in bands:
            fine_gsd = b * field.gsd_cm
            fine_lp = lps[b]
            check_labels = labels_at(*checker, field, fine_gsd) if checker else None
            if args.flips:
                flip_rows += [(label, top_gsd, fine_gsd, *f) for f in flips(top_lp, fine_lp, field.labels,
                                                                           field.classes, wanted)]
            for name in wanted:
                cls = field.classes.index(name)
                best = None
                if curve_labels:
                    valid = field.labels != IGNORE
                    truth = (field.labels == cls) & valid
                    best = max(iou((m == cls) & valid, truth) for m in curve_labels)
                r = compare(top_lp, fine_lp, top_gsd, fine_gsd, field.labels, cls, check_labels, best,
                            args.guard, guards)
                rows.append((name, label, top_gsd, fine_gsd, r))
                summary.setdefault((name, fine_gsd), []).append(
                    [r[f"{f}_bonus"] for f in fusions] + ([r[f"{f}_over_curve"] for f in fusions] if curve else []))
    over = [f"over curve {f}" for f in fusions] if curve else []
    print("| class | field | GSD top → fine [cm/px] | IoU top | fine | " + " | ".join(fusions) + " | bonus "
          + " | ".join(fusions) + "".join(f" | {o}" for o in over)
          + " | added [% of ground] | right | break-even | removed [%] | right | sure changes |")
    print("| --- | --- | --- |" + " ---: |" * (8 + 2 * len(fusions) + len(over)))
    for name, label, top_gsd, fine_gsd, r in sorted(rows, key=lambda x: (wanted.index(x[0]), x[3], x[1])):
        print(f"| {name} | {label} | {top_gsd:g} → {fine_gsd:g} | {r['top']:.3f} | {r['fine']:.3f} | "
              + "".join(f"{r[f]:.3f} | " for f in fusions) + "".join(f"{r[f + '_bonus']:+.3f} | " for f in fusions)
              + "".join(f"{r[f + '_over_curve']:+.4f} | " for f in fusions if curve) +
              f"{100 * r['added']:.2f} | {r['added_right']:.2f} | {r['break_even']:.2f} | "
              f"{100 * r['removed']:.2f} | {r['removed_right']:.2f} | {r['sure_changes']:.2f} |")
    print()
    heads = [f"bonus, {f}" for f in fusions] + over
    print("| class | fine GSD [cm/px] | fields |" + "".join(f" mean {h} | above +0.001 |" for h in heads))
    print("| --- | ---: | ---: |" + " ---: | ---: |" * len(heads))
    for (name, fine_gsd), v in sorted(summary.items(), key=lambda x: (wanted.index(x[0][0]), x[0][1])):
        a = np.array(v)
        print(f"| {name} | {fine_gsd:g} | {len(v)} |"
              + "".join(f" {a[:, k].mean():+.4f} | {int((a[:, k] > 0.001).sum())} |" for k in range(len(heads))))
    if curve:
        chosen = chosen_on_others(rows, wanted)
        print()
        print("Two passes, the finer GSD chosen on the other fields (pooled, margin over the curve's best):")
        print("| class | field | finer GSD [cm/px] | margin |")
        print("| --- | --- | --- | ---: |")
        for name, label, g, m in chosen:
            print(f"| {name} | {label} | {g} | {m:+.4f} |")
        m = np.array([c[3] for c in chosen])
        if len(m):
            print(f"\n{int((m > 0.001).sum())} of {len(m)} above +0.001, median {np.median(m):+.4f}, "
                  f"mean {m.mean():+.4f}, {int((m < -0.002).sum())} below −0.002")
    if guards:
        print_guard_choice(rows, guards)
    if args.flips:
        print("\nThe closer look's changes of label (top level a → finer lawnmower b):")
        print("| field | GSD top → fine [cm/px] | a → b | share of ground [%] | truly b | truly a |"
              " median p, top | median p, fine |")
        print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |")
        for label, top_gsd, fine_gsd, a, b, share, right, wrong, p_top, p_fine in flip_rows:
            print(f"| {label} | {top_gsd:g} → {fine_gsd:g} | {a} → {b} | {100 * share:.2f} | {right:.2f} | "
                  f"{wrong:.2f} | {p_top:.2f} | {p_fine:.2f} |")


def print_guard_choice(rows, guards) -> None:
    """The guard chosen on other fields (module docstring): per threshold the mean gain of the
    guarded map over the top level's, over every class, band and field, then per field the
    threshold of the largest mean over the other fields."""
    gains: dict[str, list[list[float]]] = {}
    for _, label, _, _, r in rows:
        gains.setdefault(label, []).append(r["guard_gains"])
    every = np.array([g for v in gains.values() for g in v])
    print("\nThe guard: the guarded map's IoU less the top level's, mean over classes, bands and fields:")
    print("| threshold |" + "".join(f" {g:g} |" for g in guards) + " chosen |")
    print("| --- |" + " ---: |" * len(guards) + " ---: |")
    print("| all fields |" + "".join(f" {x:+.4f} |" for x in every.mean(0)) + " |")
    for label in gains:
        others = np.array([g for lab, v in gains.items() if lab != label for g in v])
        if len(others):
            mean = others.mean(0)
            print(f"| without {label} |" + "".join(f" {x:+.4f} |" for x in mean)
                  + f" {guards[int(np.argmax(mean))]:g} |")


if __name__ == "__main__":
    main()
