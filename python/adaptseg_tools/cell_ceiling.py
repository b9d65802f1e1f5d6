"""What descents could earn on a field if it were known where they pay, and how well a ranking of its cells must work.

Reads calibrations' cell samples (`adaptseg_calibrate --cell-samples-csv`: per training field, per top-level and
finer GSD, one row per finer image's footprint, a cell, with the field gain that re-mapping it realised over the
pooled top-level map) and their decision models (each field's lawnmower mIoU per GSD, `rule.reference`), with each
field's lawnmower times (flown here by adaptseg_mission with the oracle segmenter and the segmentation time the
calibration declared, or given by --times CSV: field,gsd_cm,time_s,images).

A plan is a top-level GSD, a finer GSD and the first n of the field's cells in some order, flown after the whole
top level. Its time: the top-level lawnmower's, plus per cell the finer lawnmower's seconds per image, plus
--overhead-s per top-level region it enters (the climbs down and back), or per finer GSD the median that flown
descents took beyond their images at the lawnmower's rate, or where none was flown the candidates the rule weighed
(--overhead-from RUN ...: adaptseg_evaluate run folders). Its mIoU: the top level's plus the cells' field gains,
taken as additive. Its margin: that mIoU less the field's lawnmower curve's upper envelope at its time
(lawnmower_envelope, as the library's front_margin reads it: the running maximum, flat after a lawnmower a slower
one does not beat and back on the curve where it climbs through that level, linear between its points, flat beyond
its ends). An approximation of the planner: no cell is flown in flight order, and neighbouring cells' gains
interact.

Prints, per field and summed over the fields (runs above +0.001, median, mean, below -0.002):
  0. with --overhead-from, the overheads measured per finer GSD;
  1. clairvoyant: the plan of largest margin with the cells in order of realised gain (none: 0);
  2. the same with the cells in random order: how much of 1 the stop earns, not the order;
  3. fixed plans, each field's chosen on the other fields of its calibration: the (top GSD, finer GSD, share of
     the cells) of largest mean margin there, or a top level alone, the cells ranked by each --rank column
     (`field_gain`: perfectly; `random`; a top-level input such as `top_ambiguity`; or `learnt`: a ridge
     regression of the gain on every top-level input, `top_*` and `field_sigma`, fitted on the other fields'
     cells; a column NaN throughout left out); on a field where a finer top level is no slower to fly (its
     geometry alone), that one is flown instead; and per class each ranking's rank correlation with the realised gains within a field (the mean
     over the fields and their plans), and with --against COLUMN,... with those columns of the cells too (e.g.
     `relabelled`, the share of a cell the closer look relabelled: whether an input sees where labels change
     rather than where a change is right);
  4. with --noise R,...: the same, ranked by the realised gain plus Gaussian noise scaled for a correlation R with
     it within each field (the rank correlation it realised is printed beside);
  5. first, with --sums: per field and plan the sum of its cells' gains (to set beside a whole-field measure).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.cell_ceiling MODEL CELLS [MODEL CELLS ...] \\
      [--rank field_gain,random,top_ambiguity] [--noise 1,0.9,0.7,0.5] [--overhead-s 20] [--times CSV] \\
      [--against relabelled]
(MODEL and CELLS from one adaptseg_calibrate run, e.g. out/agree/model2-road.yaml out/agree/cells-road.csv.)
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import yaml

from . import REPO
from .lawnmower_envelope import envelope_at, upper_envelope
from .proxy_table import spearman

SHARES = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0)  # the shares of a field's cells a fixed plan may descend into


class Field:
    """One field of one calibration: its lawnmower curve and its cells per (top GSD, finer GSD)."""

    def __init__(self, name: str, miou: dict[float, float], times: dict[float, tuple[float, int]]):
        self.name, self.miou, self.times = name, miou, times
        self.envelope = upper_envelope([(times[g][0], m) for g, m in miou.items()])  # as front_margin reads it
        self.cells: dict[tuple[float, float], list[dict]] = {}

    def plans(self) -> list[tuple[float, float]]:
        return sorted(self.cells)

    def top_for(self, top: float) -> float:
        """`top`, or the finest top-level GSD of this field that is no slower to fly (the field's geometry alone:
        flying a coarser lawnmower that takes longer is never chosen, as the planner's `undominated` top level)."""
        tops = {t for t, _ in self.cells}
        return min(t for t in tops if t <= top and self.times[t][0] <= self.times[top][0]) if top in tops else top

    def top_margin(self, top: float) -> float:
        """The top level alone against the curve (below 0 where a faster lawnmower maps better)."""
        return self.miou[top] - envelope_at(self.envelope, self.times[top][0])

    def margins(self, top: float, sub: float, order: list[dict], overhead: dict[float, float]) -> np.ndarray:
        """The margin after each of the first n cells of `order`, n = 1, 2, ... (`overhead`: seconds per region
        entered, per finer GSD)."""
        per_image = self.times[sub][0] / self.times[sub][1]
        overhead_s = overhead[sub]
        regions, gain, out = set(), 0.0, []
        for n, cell in enumerate(order, 1):
            regions.add(cell["region"])
            gain += cell["field_gain"]
            t = self.times[top][0] + len(regions) * overhead_s + n * per_image
            out.append(self.miou[top] + gain - envelope_at(self.envelope, t))
        return np.array(out)


def read(model_path: Path, cells_path: Path, times) -> tuple[str, list[Field]]:
    """The calibration's class of interest and its fields, each with its cells."""
    model = yaml.safe_load(Path(model_path).read_text())
    interest = ",".join(model["interest"])
    fields = {}
    for ref in model["rule"]["reference"]:
        miou = {float(g): float(m) for g, m in zip(ref["gsd_cm"], ref["miou"])}
        fields[ref["field"]] = Field(ref["field"], miou, times(ref["field"], sorted(miou), model))
    with open(cells_path, newline="") as f:
        for row in csv.DictReader(f):
            if row["field"] not in fields:
                raise SystemExit(f"{cells_path}: field {row['field']} is not among {model_path}'s reference fields")
            cell = {k: (float(v) if k not in ("field", "region") else v) for k, v in row.items()}
            key = (cell["top_gsd_cm"], cell["sub_gsd_cm"])
            fields[row["field"]].cells.setdefault(key, []).append(cell)
    missing = [n for n, f in fields.items() if not f.cells]
    if missing:
        raise SystemExit(f"{cells_path}: no cells of {', '.join(missing)}")
    return interest, list(fields.values())


class Times:
    """Each field's lawnmower time and images per GSD: from a CSV, or flown by adaptseg_mission (oracle)."""

    def __init__(self, csv_path: str | None, mission: Path, fields_root: Path):
        self.mission, self.root, self.known = mission, fields_root, {}
        if csv_path:
            with open(csv_path, newline="") as f:
                for row in csv.DictReader(f):
                    self.known[(row["field"], float(row["gsd_cm"]))] = (float(row["time_s"]), int(row["images"]))

    def __call__(self, field: str, gsds: list[float], model: dict) -> dict[float, tuple[float, int]]:
        return {g: self.one(field, g, model) for g in gsds}

    def one(self, field: str, gsd: float, model: dict) -> tuple[float, int]:
        """The lawnmower at `gsd` flown with the model's camera, speed and declared segmentation time."""
        if (field, gsd) not in self.known:
            if not self.mission.is_file():
                raise SystemExit(f"no time for {field} at {gsd:g} cm/px: give --times or build {self.mission}")
            with tempfile.TemporaryDirectory() as tmp:
                cam, timing = model["camera"], model["timing"]
                subprocess.run([str(self.mission), "--field", str(self.root / field), "--strategy", "lawnmower",
                                "--gsd", f"{gsd:g}", "--segmenter", "oracle", "--plan-time-s", "0", "--out", tmp,
                                "--seg-time-s", f"{model['calibration'].get('segmentation_time_s') or 0.1:g}",
                                "--image-width", str(cam["image_width_px"]), "--image-height", str(cam["image_height_px"]),
                                "--sensor-width-mm", f"{cam['sensor_width_mm']:g}", "--focal-mm", f"{cam['focal_length_mm']:g}",
                                "--speed", f"{timing['max_speed_mps']:g}", "--accel", f"{timing['max_accel_mps2']:g}"],
                               check=True, capture_output=True)
                r = json.loads((Path(tmp) / "result.json").read_text())
            self.known[(field, gsd)] = (float(r["time_s"]["total"]), int(r["images"]))
        return self.known[(field, gsd)]


def ordered(cells: list[dict], key: str, rng) -> list[dict]:
    """The cells best first by `key` (NaN last), or shuffled for `random`."""
    if key == "random":
        out = list(cells)
        rng.shuffle(out)
        return out
    return sorted(cells, key=lambda c: -c[key] if not math.isnan(c[key]) else math.inf)


def best_plan(field: Field, key: str, overhead: dict[float, float], rng) -> float:
    """The largest margin over every plan with the cells in `key`'s order (0: the top level alone, where that is
    not below the curve)."""
    best = max(0.0, max(field.top_margin(top) for top, _ in field.plans()))
    for top, sub in field.plans():
        m = field.margins(top, sub, ordered(field.cells[(top, sub)], key, rng), overhead)
        best = max(best, float(m.max()))
    return best


def fixed_plans(fields: list[Field], key: str, overhead: dict[float, float], rng) -> list[tuple[str, str, float]]:
    """Per field: the plan of largest mean margin on the other fields, and its margin on this one."""
    margin: dict[tuple, dict[str, float]] = {}
    for f in fields:
        for top, sub in f.plans():
            flown = f.top_for(top)
            if (flown, sub) not in f.cells:
                continue
            m = f.margins(flown, sub, ordered(f.cells[(flown, sub)], key, rng), overhead)
            for share in SHARES:
                margin.setdefault((top, sub, share), {})[f.name] = float(m[max(1, round(share * len(m))) - 1])
        for top in {t for t, _ in f.plans()}:
            margin.setdefault((top, None, 0.0), {})[f.name] = f.top_margin(f.top_for(top))
    out = []
    for f in fields:
        others = [g.name for g in fields if g is not f]
        means = {p: np.mean([v[o] for o in others]) for p, v in margin.items()
                 if f.name in v and all(o in v for o in others)}
        plan = max(means, key=lambda p: (means[p], p[1] is None))
        label = f"top {plan[0]:g} alone" if plan[1] is None else f"{plan[0]:g} → {plan[1]:g}, {plan[2]:.0%} of cells"
        out.append((f.name, label, margin[plan][f.name]))
    return out


def with_noise(fields: list[Field], r: float, rng) -> list[float]:
    """Puts into each cell a `noisy` ranking: its gain standardised within its field's plan plus noise of spread
    sqrt(1/r^2 - 1) (correlation r with the gain for Gaussian gains); returns the rank correlations realised."""
    spread = math.sqrt(max(0.0, 1.0 / (r * r) - 1.0)) if r > 0 else math.inf
    realised = []
    for f in fields:
        for cells in f.cells.values():
            g = np.array([c["field_gain"] for c in cells])
            z = (g - g.mean()) / (g.std() or 1.0)
            noisy = rng.standard_normal(len(g)) if math.isinf(spread) else z + spread * rng.standard_normal(len(g))
            for c, v in zip(cells, noisy):
                c["noisy"] = float(v)
            rho = spearman(list(noisy), list(g))
            if not math.isnan(rho):
                realised.append(rho)
    return realised


def measured_overheads(run_dirs: list[Path]) -> dict[float, dict[str, list[float]]]:
    """Per descent GSD, what each descent of the adaptive strategy took beyond its images at the lawnmower's rate:
    decisions.csv's extra_time_s less images times the seconds per image of the same run's lawnmower at that GSD
    (results.csv); `flown` for the descents flown, `candidates` for those the rule weighed and did not take (their
    extra time as the planner computed it)."""
    out: dict[float, dict[str, list[float]]] = {}
    for d in run_dirs:
        with open(Path(d) / "results.csv", newline="") as f:
            rate = {float(r["gsd_cm"]): float(r["time_total"]) / int(r["images"]) for r in csv.DictReader(f)
                    if r["strategy"] == "lawnmower" and int(r["images"]) > 0}
        with open(Path(d) / "decisions.csv", newline="") as f:
            for r in csv.DictReader(f):
                if r["strategy"] != "adaptive" or r["action"] not in ("descend", "continue") or not r["images"]:
                    continue
                g = float(r["gsd_cm"])
                if g not in rate:
                    raise SystemExit(f"{d}: a descent to {g:g} cm/px and no lawnmower at it in results.csv")
                kind = "flown" if r["action"] == "descend" else "candidates"
                out.setdefault(g, {"flown": [], "candidates": []})[kind].append(
                    float(r["extra_time_s"]) - int(r["images"]) * rate[g])
    return out


def rank_correlation(fields: list[Field], key: str, target: str = "field_gain") -> float:
    """The mean over the fields' plans of the rank correlation of `key` with the cells' `target`
    (their realised gains, or e.g. `relabelled`: how much of them the closer look relabelled)."""
    out = []
    for f in fields:
        for cells in f.cells.values():
            pairs = [(c[key], c[target]) for c in cells if math.isfinite(c[key]) and math.isfinite(c[target])]
            rho = spearman([p[0] for p in pairs], [p[1] for p in pairs])
            if not math.isnan(rho):
                out.append(rho)
    return float(np.mean(out)) if out else math.nan


def learn(fields: list[Field], ridge: float = 1.0) -> None:
    """Puts into each cell `learnt`: its gain as a ridge regression on the top-level inputs (`top_*` columns and
    `field_sigma`, standardised, NaN as the mean) predicts it, fitted on the other fields' cells."""
    every = [c for f in fields for cs in f.cells.values() for c in cs]
    names = sorted(k for k in every[0] if (k.startswith("top_") and k != "top_gsd_cm") or k == "field_sigma")
    names = [n for n in names if any(math.isfinite(c[n]) for c in every)]  # not a column that is NaN throughout

    def matrix(cells):
        return np.array([[c[n] for n in names] + [c["top_gsd_cm"], c["sub_gsd_cm"]] for c in cells], float)

    for f in fields:
        train = [c for g in fields if g is not f for cs in g.cells.values() for c in cs]
        X, y = matrix(train), np.array([c["field_gain"] for c in train])
        mean = np.nanmean(X, axis=0)
        sd = np.nanstd(X, axis=0)
        sd[~(sd > 0)] = 1.0
        mean[~np.isfinite(mean)] = 0.0

        def z(a):
            a = (a - mean) / sd
            return np.where(np.isfinite(a), a, 0.0)

        Z = z(X)
        beta = np.linalg.solve(Z.T @ Z + ridge * np.eye(Z.shape[1]), Z.T @ (y - y.mean()))
        for cs in f.cells.values():
            for c, v in zip(cs, z(matrix(cs)) @ beta):
                c["learnt"] = float(v)


def summary(margins: list[float]) -> str:
    m = np.array(margins)
    return (f"{int((m > 0.001).sum())} of {len(m)} above +0.001, median {np.median(m):+.4f}, mean {m.mean():+.4f}, "
            f"{int((m < -0.002).sum())} below -0.002")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("pairs", nargs="+", help="MODEL CELLS [MODEL CELLS ...]: one calibration's model and cells")
    parser.add_argument("--rank", default="field_gain,random,top_ambiguity",
                        help="the cells' orders of the fixed plans: columns of CELLS, or random")
    parser.add_argument("--noise", default="", help="correlations R of noisy perfect rankings, comma-separated")
    parser.add_argument("--reps", type=int, default=3, help="draws per noisy ranking (default 3)")
    parser.add_argument("--overhead-s", type=float, default=20.0, help="seconds per region descended into")
    parser.add_argument("--overhead-from", nargs="+", metavar="RUN",
                        help="adaptseg_evaluate run folders: per finer GSD the median overhead of their flown descents, "
                             "or where none was flown of the candidates the rule weighed (--overhead-s where neither)")
    parser.add_argument("--times", help="CSV field,gsd_cm,time_s,images instead of flying adaptseg_mission")
    parser.add_argument("--mission", default=str(REPO / "build" / "release" / "examples" / "adaptseg_mission"),
                        help="the adaptseg_mission program that flies the lawnmowers (default: the release build's)")
    parser.add_argument("--fields-root", default=str(REPO / "examples" / "data"),
                        help="the folder holding the fields the models name (default: examples/data)")
    parser.add_argument("--seed", type=int, default=0, help="of the random orders and the noise (default 0)")
    parser.add_argument("--against", default="",
                        help="cell columns to rank-correlate the rankings with besides the gains, e.g. relabelled")
    parser.add_argument("--sums", action="store_true",
                        help="also print per field and plan the sum of its cells' gains (all descended)")
    args = parser.parse_args(argv)
    if len(args.pairs) % 2:
        raise SystemExit("give MODEL CELLS pairs")
    if args.overhead_s < 0 or args.reps < 1:
        raise SystemExit("--overhead-s must not be negative and --reps at least 1")
    try:
        noise = [float(r) for r in args.noise.split(",")] if args.noise else []
    except ValueError:
        raise SystemExit(f"--noise {args.noise}: comma-separated numbers") from None
    if any(not 0 < r <= 1 for r in noise):
        raise SystemExit(f"--noise {args.noise}: each in (0, 1]")
    times = Times(args.times, Path(args.mission), Path(args.fields_root))
    sets = [read(Path(m), Path(c), times) for m, c in zip(args.pairs[::2], args.pairs[1::2])]
    keys = args.rank.split(",")
    against = [a for a in args.against.split(",") if a]
    for interest, fields in sets:
        columns = set(next(iter(fields[0].cells.values()))[0])
        unknown = [k for k in keys if k not in ("random", "learnt") and k not in columns]
        if unknown:
            raise SystemExit(f"--rank: no column {', '.join(unknown)} in the cells of {interest}")
        unknown = [a for a in against if a not in columns]
        if unknown:
            raise SystemExit(f"--against: no column {', '.join(unknown)} in the cells of {interest}")
    gsds = {sub for _, fields in sets for f in fields for _, sub in f.plans()}
    overhead = {g: args.overhead_s for g in gsds}
    if args.overhead_from:
        for g, kinds in sorted(measured_overheads([Path(d) for d in args.overhead_from]).items()):
            kind = "flown" if kinds["flown"] else "candidates"
            v = kinds[kind]
            overhead[g] = float(np.median(v))
            print(f"overhead at {g:g} cm/px: median {overhead[g]:+.1f} s over {len(v)} "
                  f"{'flown descents' if kind == 'flown' else 'candidates not taken (none flown)'} "
                  f"(from {min(v):+.1f} to {max(v):+.1f})")
        print()
    rng = np.random.default_rng(args.seed)
    if "learnt" in keys:
        for _, fields in sets:
            learn(fields)

    if args.sums:
        print("| class | field | top → finer GSD [cm/px] | cells | sum of their gains |")
        print("| --- | --- | --- | ---: | ---: |")
        for interest, fields in sets:
            for f in fields:
                for top, sub in f.plans():
                    cells = f.cells[(top, sub)]
                    print(f"| {interest} | {f.name} | {top:g} → {sub:g} | {len(cells)} | "
                          f"{sum(c['field_gain'] for c in cells):+.4f} |")
        print()
    print("| class | field | clairvoyant | random order, best stop | "
          + " | ".join(f"fixed plan, {k}" for k in keys) + " |")
    print("| --- | --- | ---: | ---: |" + " --- |" * len(keys))
    totals: dict[str, list[float]] = {}
    for interest, fields in sets:
        rows = {f.name: [best_plan(f, "field_gain", overhead, rng), best_plan(f, "random", overhead, rng)]
                for f in fields}
        labels = {f.name: [] for f in fields}
        for k in keys:
            for name, label, m in fixed_plans(fields, k, overhead, rng):
                rows[name].append(m)
                labels[name].append(label)
        for f in fields:
            r = rows[f.name]
            print(f"| {interest} | {f.name} | {r[0]:+.4f} | {r[1]:+.4f} | "
                  + " | ".join(f"{m:+.4f} ({lab})" for m, lab in zip(r[2:], labels[f.name])) + " |")
            for name, m in zip(["clairvoyant", "random order, best stop"] + [f"fixed plan, {k}" for k in keys], r):
                totals.setdefault(name, []).append(m)
    print()
    for name, m in totals.items():
        print(f"- {name}: {summary(m)}")
    for r in noise:
        counts, medians, realised = [], [], []
        for _ in range(args.reps):
            margins = []
            for _, fields in sets:
                realised += with_noise(fields, r, rng)
                margins += [m for _, _, m in fixed_plans(fields, "noisy", overhead, rng)]
            counts.append(int((np.array(margins) > 0.001).sum()))
            medians.append(float(np.median(margins)))
        print(f"- fixed plan, the realised gain with noise (correlation {r:g}, rank correlation within a field "
              f"{np.mean(realised):.2f}): above +0.001 in {np.mean(counts):.1f} of {len(margins)} "
              f"(draws {', '.join(map(str, counts))}), median {np.mean(medians):+.4f}")
    shown = [k for k in keys if k not in ("random", "field_gain")]
    for target in ["field_gain"] + against if shown else []:
        print()
        what = "realised gains" if target == "field_gain" else target
        print(f"Rank correlation with the cells' {what} within a field (mean over the fields and their plans):")
        print("| class | " + " | ".join(shown) + " |")
        print("| --- |" + " ---: |" * len(shown))
        for interest, fields in sets:
            print(f"| {interest} | " + " | ".join(f"{rank_correlation(fields, k, target):+.2f}" for k in shown) + " |")


if __name__ == "__main__":
    main()
