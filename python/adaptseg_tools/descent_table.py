"""Every descent of the adaptive strategy in adaptseg_evaluate runs, its forecast against what it
did to the field's map: why a region's gain and the field's disagree.

Per descent (decisions.csv of each run directory): the GSD and images, the forecast field gain,
the realised field gain and the region's gain (realised_region_delta_miou, sign turned: > 0
helped), and what the descent changed in the field's map over L in pixels: true positives
gained (ΔTP: misses corrected, net), false positives added (ΔFP; < 0: removed). A class's field
IoU moves by about (ΔTP − IoU·ΔFP) / (TP + FP + FN): a false positive removed is worth IoU times
a miss corrected, one added costs as much. And Δσ, what the UAV saw: the region's σ after the
descent minus its top-level σ (observed_sigma_sub − sigma; a descent that writes the class where
it is absent raises it far beyond the others). Then, over all descents: how often the region's
gain and the field's disagree in sign, and for those, whether the descent added false positives.
Where decisions.csv has it (adaptseg_evaluate since 2026-12-06), also the realised field gain of
the descent's pixels inside its region alone (realised_field_gain_region: what the forecast
models, calibration re-mapping a region's cells within the region) and, over all descents, the
forecast's correlation with it and how much of the realised gain came from where the images
overhang the region. Then the same sums per descent GSD and number of images.

With --curve, per descent also the lawnmower curve it had to beat: the rise the rule predicted
over the descent's extra time (forecast_curve_rise) against the rise of the field's real curve
(results.csv's lawnmowers, upper envelope, linear between points, flat beyond the last, as the
front margin reads it) over the same seconds, ending at the forecast end (forecast_end_s), and
each descent's margin, forecast (forecast gain − predicted rise) and realised (realised gain −
real rise). Where the rule predicts the rise too steep it keeps descents that would have paid;
too flat, it takes descents that the curve outruns. Below the table, the sums of both rises and of
both margins and their correlations over the descents: the rule decides on the forecast margin,
so whether it ranks the descents as the realised margins do is what its decisions rest on.

With --hindsight, per run: what the mission would have ended at had it flown only its best
descents, known in hindsight. Its descents sorted by realised gain per second, the prefix whose
top-level lawnmower (results.csv: the lawnmower at the mission's top GSD) plus their realised
gains and extra times ends highest above the real curve: whether the descents a rule took hold
any that pay (selection) or none (the candidates themselves). Gains taken as additive. With
--gsd G also the margin of its descents to G cm/px alone, in the order flown: what the mission
would have ended at had it descended to G only where it did; with --max-extra S, of its descents
of at most S seconds of extra time alone (both: those that are both). Gains taken as additive:
what a cap on a descent's seconds could earn on the descents a rule chose, not what a rule with
the cap would choose.

With --images, per image of a descent (per_image.csv): its σ (the share of L in its labels)
against its region's top-level σ (the level-0 image before it), the jump between the two, and
the ground truth's shares of the same two images (truth_sigma): what the UAV could see of a
network that writes the class where it is absent at a finer GSD (a large jump the ground truth
does not share), image by image, before the descent ends. Sorted by the jump, largest first.

With --relabelled, per run its descents' relabelled share against its forecast (observed /
forecast_relabelled_interest) beside their realised field gain against its forecast; then the
variance of the logarithm of the first ratio within the runs (about each run's mean, n − 1 per
run) and over all: how far one descent's relabelled share says what its field's does
(docs/method.md, "The field factor from what a descent relabelled").

Usage: descent_table.py [--strategy adaptive] [--curve | --hindsight [--gsd G] [--max-extra S] | --images | --relabelled] RUN_DIR [RUN_DIR ...]
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

from .lawnmower_envelope import envelope_at, upper_envelope


def number(text: str) -> float:
    return float(text) if text not in ("", None) else math.nan


def correlation(x: list[float], y: list[float]) -> float:
    n = len(x)
    if n < 3:
        return math.nan
    mx, my = sum(x) / n, sum(y) / n
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sx = math.sqrt(sum((a - mx) ** 2 for a in x))
    sy = math.sqrt(sum((b - my) ** 2 for b in y))
    return sxy / (sx * sy) if sx > 0 and sy > 0 else math.nan


def real_curves(run: Path) -> dict[str, list[tuple[float, float]]]:
    """Per field, the upper envelope of the run's lawnmowers (results.csv)."""
    points: dict[str, list[tuple[float, float]]] = {}
    with open(run / "results.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["strategy"] == "lawnmower":
                points.setdefault(r["field"], []).append((float(r["time_total"]), float(r["miou_interest"])))
    return {field: upper_envelope(p) for field, p in points.items()}


def curve_table(rows: list[tuple[str, dict]], curves: dict[tuple[str, str], list]) -> None:
    print("| run | decision | GSD [cm/px] | extra time [s] | forecast end [s] | forecast gain | predicted rise | "
          "real rise | forecast margin | realised margin |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    predicted, real, forecast_margin, realised_margin, paid, without = [], [], [], [], 0, 0
    for run, d in rows:
        if d.get("forecast_curve_rise", "") in ("", None) or d.get("forecast_end_s", "") in ("", None):
            without += 1  # the utility rule, or a file written before 2026-11-30
            continue
        env = curves[(run, d["field"])]
        end, extra = number(d["forecast_end_s"]), number(d["extra_time_s"])
        rise, real_rise = number(d["forecast_curve_rise"]), envelope_at(env, end) - envelope_at(env, end - extra)
        fg, rg = number(d["forecast_field_gain"]), number(d["realised_field_gain"])
        print(f"| {run} | {d['decision']} | {number(d['gsd_cm']):g} | {extra:.1f} | {end:.1f} | {fg:+.4f} | "
              f"{rise:+.4f} | {real_rise:+.4f} | {fg - rise:+.4f} | {rg - real_rise:+.4f} |")
        predicted.append(rise)
        real.append(real_rise)
        forecast_margin.append(fg - rise)
        realised_margin.append(rg - real_rise)
        paid += rg > real_rise
    print()
    if without:
        print(f"{without} descents left out: no forecast_curve_rise / forecast_end_s (the utility rule predicts "
              "no curve; adaptseg_evaluate writes them since 2026-11-30)")
    if predicted:
        print(f"{len(predicted)} descents: predicted rise {sum(predicted):+.4f} in all against the real curve's "
              f"{sum(real):+.4f} (correlation {correlation(predicted, real):+.2f}); {paid} of {len(predicted)} "
              f"gained more than the real curve rose in their seconds")
        # What the rule decides on: the margin, gain less rise, both halves' errors together.
        print(f"margins: forecast {sum(forecast_margin):+.4f} in all against realised {sum(realised_margin):+.4f} "
              f"(correlation {correlation(forecast_margin, realised_margin):+.2f})")


def hindsight_table(runs: list[str], rows: list[tuple[str, dict]], strategy: str, gsd: float | None,
                    max_extra: float | None = None) -> None:
    words = ([f"to {gsd:g} cm/px"] if gsd is not None else []) + \
        ([f"of at most {max_extra:g} s"] if max_extra is not None else [])
    alone_words = "descents " + " and ".join(words) if words else ""

    def kept_alone(d: dict) -> bool:
        return ((gsd is None or abs(number(d["gsd_cm"]) - gsd) < 1e-6)
                and (max_extra is None or number(d["extra_time_s"]) <= max_extra))

    only = f" | {alone_words} alone: margin" if words else ""
    print("| run | descents | margin flown | best prefix: descents | its margin" + only + " |")
    print("| --- | ---: | ---: | ---: | ---: |" + (" ---: |" if words else ""))
    flown_above = best_above = only_above = 0
    for run in runs:
        path = Path(run)
        with open(path / "results.csv", newline="") as f:
            results = list(csv.DictReader(f))
        for field, env in real_curves(path).items():
            mission = next(r for r in results if r["field"] == field and r["strategy"] == strategy)
            top = next(r for r in results if r["field"] == field and r["strategy"] == "lawnmower"
                       and abs(float(r["gsd_cm"]) - float(mission["gsd_cm"])) < 1e-6)
            t, m = float(top["time_total"]), float(top["miou_interest"])
            flown_descents = [d for name, d in rows if name == path.name and d["field"] == field]
            descents = sorted(((number(d["realised_field_gain"]), number(d["extra_time_s"])) for d in flown_descents),
                              key=lambda gt: -gt[0] / max(gt[1], 1e-9))
            cell = ""
            if words:
                kept = [d for d in flown_descents if kept_alone(d)]
                t_only = t + sum(number(d["extra_time_s"]) for d in kept)
                m_only = m + sum(number(d["realised_field_gain"]) for d in kept) - envelope_at(env, t_only)
                only_above += m_only > 0.001
                cell = f" {m_only:+.4f} |"
            best, best_k = m - envelope_at(env, t), 0
            for k, (g, dt) in enumerate(descents, start=1):
                t, m = t + dt, m + g
                if m - envelope_at(env, t) > best:
                    best, best_k = m - envelope_at(env, t), k
            flown = float(mission["front_margin"])
            flown_above += flown > 0.001
            best_above += best > 0.001
            print(f"| {path.name} | {len(descents)} | {flown:+.4f} | {best_k} | {best:+.4f} |{cell}")
    print()
    alone = f", {only_above} with their {alone_words} alone" if words else ""
    print(f"{len(runs)} runs: {flown_above} above +0.001 as flown, {best_above} with their best descents only{alone}")


def images_table(runs: list[str], strategy: str) -> None:
    """Each descent image's σ against its region's top-level σ, and the ground truth's of both."""
    rows = []
    for run in runs:
        with open(Path(run) / "per_image.csv", newline="") as f:
            top: dict[tuple[str, str], dict] = {}
            for r in csv.DictReader(f):
                if r["strategy"] != strategy:
                    continue
                key = (r["field"], r["gsd_cm"])
                if r["level"] == "0":
                    top[key] = r
                elif key in top:
                    t = top[key]
                    rows.append((number(r["sigma"]) - number(t["sigma"]), Path(run).name, r, t))
    rows.sort(key=lambda x: -x[0] if math.isfinite(x[0]) else math.inf)
    print("| run | image | GSD [cm/px] | σ | region's top-level σ | jump | truth σ | top-level truth σ |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for jump, run, r, t in rows:
        print(f"| {run} | {r['image']} | {number(r['image_gsd_cm']):g} | {number(r['sigma']):.3f} | "
              f"{number(t['sigma']):.3f} | {jump:+.3f} | {number(r['truth_sigma']):.3f} | "
              f"{number(t['truth_sigma']):.3f} |")
    print()
    for bound in (0.1, 0.2, 0.3):
        above = [(j, r, t) for j, _, r, t in rows if j > bound]
        unshared = sum(number(r["truth_sigma"]) - number(t["truth_sigma"]) < j / 2 for j, r, t in above)
        print(f"jump above {bound:.1f}: {len(above)} of {len(rows)} descent images, of which {unshared} with a "
              f"ground-truth rise below half the jump")


def relabelled_table(rows: list[tuple[str, dict]]) -> None:
    """Per run, each descent's relabelled share and field gain against their forecasts; the
    spread of the first's logarithm within the runs and over all."""
    by_run: dict[str, list[tuple[float, float]]] = {}
    for run, d in rows:
        fc, ob = number(d["forecast_relabelled_interest"]), number(d["observed_relabelled_interest"])
        fg, rg = number(d["forecast_field_gain"]), number(d["realised_field_gain"])
        by_run.setdefault(run, []).append((ob / fc if fc > 0 else math.nan, rg / fg if fg > 0 else math.nan))
    print("| run | relabelled / forecast, realised / forecast gain, per descent |")
    print("| --- | --- |")
    logs: list[tuple[str, float]] = []
    for run, pairs in sorted(by_run.items()):
        print(f"| {run} | {', '.join(f'{a:.2f} / {b:.2f}' for a, b in pairs)} |")
        logs += [(run, math.log(a)) for a, _ in pairs if a > 0]
    if len(logs) < 2:
        return
    mean = sum(x for _, x in logs) / len(logs)
    total = sum((x - mean) ** 2 for _, x in logs) / (len(logs) - 1)
    within = dof = 0.0
    for run in by_run:
        xs = [x for r, x in logs if r == run]
        if len(xs) >= 2:
            m = sum(xs) / len(xs)
            within += sum((x - m) ** 2 for x in xs)
            dof += len(xs) - 1
    print()
    print(f"{len(logs)} descents: variance of log(relabelled / forecast) {total:.3f} over all, "
          f"{within / dof if dof else math.nan:.3f} within the runs ({dof:g} degrees of freedom)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strategy", default="adaptive")
    ap.add_argument("--curve", action="store_true",
                    help="each descent against the lawnmower curve: the predicted rise and the real one")
    ap.add_argument("--hindsight", action="store_true",
                    help="per run, the margin of its best descents only, chosen in hindsight")
    ap.add_argument("--gsd", type=float, help="with --hindsight: the margin of the descents to this GSD alone")
    ap.add_argument("--max-extra", type=float, metavar="S",
                    help="with --hindsight: the margin of the descents of at most S seconds of extra time alone")
    ap.add_argument("--images", action="store_true",
                    help="each descent image's σ against its region's top-level σ, and the ground truth's")
    ap.add_argument("--relabelled", action="store_true",
                    help="each descent's relabelled share against its forecast, and its spread within the runs")
    ap.add_argument("runs", nargs="+")
    args = ap.parse_args(argv)
    if (args.gsd is not None or args.max_extra is not None) and not args.hindsight:
        ap.error("--gsd and --max-extra belong to --hindsight")
    if args.max_extra is not None and not args.max_extra >= 0:
        ap.error(f"--max-extra must be seconds >= 0; got {args.max_extra:g}")
    if args.images:
        images_table(args.runs, args.strategy)
        return 0
    rows = []
    for run in args.runs:
        path = Path(run) / "decisions.csv"
        with open(path, newline="") as f:
            for d in csv.DictReader(f):
                if d["strategy"] != args.strategy or d["action"] != "descend":
                    continue
                if "realised_delta_tp" not in d:
                    raise SystemExit(f"{path}: no realised_delta_tp column (written by adaptseg_evaluate since 2026-11-29)")
                rows.append((Path(run).name, d))
    if args.relabelled:
        relabelled_table(rows)
        return 0
    if args.hindsight:
        hindsight_table(args.runs, rows, args.strategy, args.gsd, args.max_extra)
        return 0
    if args.curve:
        curves = {(Path(run).name, field): env for run in args.runs for field, env in real_curves(Path(run)).items()}
        curve_table(rows, curves)
        return 0
    inside = all(d.get("realised_field_gain_region", "") not in ("", None) for _, d in rows) and bool(rows)
    print("| run | decision | GSD [cm/px] | images | forecast field gain | realised field gain | "
          + ("of which inside the region | " if inside else "") + "region gain | ΔTP [px] | ΔFP [px] | Δσ |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | " + ("---: | " if inside else "") + "---: | ---: | ---: | ---: |")
    forecast, realised, realised_inside = [], [], []
    disagree = disagree_fp = 0
    for run, d in rows:
        fg, rg = number(d["forecast_field_gain"]), number(d["realised_field_gain"])
        rgi = number(d["realised_field_gain_region"]) if inside else math.nan
        region = -number(d["realised_region_delta_miou"])
        tp, fp = int(d["realised_delta_tp"]), int(d["realised_delta_fp"])
        d_sigma = number(d.get("observed_sigma_sub", "")) - number(d.get("sigma", ""))
        print(f"| {run} | {d['decision']} | {number(d['gsd_cm']):g} | {d['images']} | {fg:+.4f} | {rg:+.4f} | "
              + (f"{rgi:+.4f} | " if inside else "") + f"{region:+.4f} | {tp:+d} | {fp:+d} | {d_sigma:+.3f} |")
        if math.isfinite(fg) and math.isfinite(rg):
            forecast.append(fg)
            realised.append(rg)
            realised_inside.append(rgi)
        if math.isfinite(region) and math.isfinite(rg) and (region > 0) != (rg > 0):
            disagree += 1
            disagree_fp += fp > 0
    print()
    print(f"{len(rows)} descents; forecast and realised field gain correlate at {correlation(forecast, realised):+.2f}; "
          f"the region's gain and the field's disagree in sign in {disagree}, of which {disagree_fp} added false "
          f"positives; false positives added in {sum(int(d['realised_delta_fp']) > 0 for _, d in rows)} descents, "
          f"misses corrected (ΔTP > 0) in {sum(int(d['realised_delta_tp']) > 0 for _, d in rows)}")
    if inside and forecast:
        print(f"inside the regions alone: forecast and realised correlate at "
              f"{correlation(forecast, realised_inside):+.2f}; realised {sum(realised_inside):+.4f} of "
              f"{sum(realised):+.4f} in all (where the images overhang: {sum(realised) - sum(realised_inside):+.4f})")
    group_sums(rows, inside)
    return 0


def group_sums(rows, inside: bool) -> None:
    """The descents' forecast and realised field gains summed per descent GSD and number of images
    (and the realised gain inside the regions, where decisions.csv has it): where the forecast's
    level is right, and whether it depends on how far a descent's images reach beyond its region."""
    groups: dict[tuple[float, int], list[list[float]]] = {}
    for _, d in rows:
        fg, rg = number(d["forecast_field_gain"]), number(d["realised_field_gain"])
        if not (math.isfinite(fg) and math.isfinite(rg)):
            continue
        rgi = number(d["realised_field_gain_region"]) if inside else math.nan
        groups.setdefault((number(d["gsd_cm"]), int(d["images"])), []).append([fg, rg, rgi])
    print()
    print("| GSD [cm/px] | images | descents | Σ forecast | Σ realised |" + (" Σ inside the regions |" if inside else ""))
    print("| ---: | ---: | ---: | ---: | ---: |" + (" ---: |" if inside else ""))
    for (gsd, images), g in sorted(groups.items()):
        sums = [sum(column) for column in zip(*g)]
        print(f"| {gsd:g} | {images} | {len(g)} | {sums[0]:+.4f} | {sums[1]:+.4f} |"
              + (f" {sums[2]:+.4f} |" if inside else ""))


if __name__ == "__main__":
    raise SystemExit(main())
