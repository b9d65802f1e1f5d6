"""The field curve's prediction of flying lower, against the training fields' real curves.

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.curve_check_table LABEL=RUN_DIR[,RUN_DIR...] [...]

With `--curve field` the front-aware rule weighs a descent against the rise of this field's
lawnmower curve as the cell gain model predicts it: from the top-level GSD t to a lawnmower
GSD g, the field mIoU rises by beta(t, g) * X / sigma (FrontAwarePolicy::field_curve, with the
field factor s = 1; X the field's mean decision input, sigma its share of L). Each run's
model.yaml holds the slopes beta and, for every training field, X (`top_input` per top-level GSD,
or `field_input`, the nominal top's, in models before it), sigma
(`field_sigma`) and its real lawnmower curve (`miou` per `gsd_cm`). For every (top, g) pair of
the slopes this prints the mean predicted and real rise over the training fields of all runs of
a label, and their ratio: above 1 the model predicts too little for flying lower (a descent
then looks better against the curve than it is), below 1 too much. The training fields are the
ones each model was fitted on: an in-sample check of the curve, not of a test field.
"""
import sys

import yaml


def rises(run_dirs):
    """{(top, g): [(predicted, real), ...]} over every training field of every run."""
    out = {}
    for d in run_dirs:
        with open(f"{d}/model.yaml") as f:
            model = yaml.safe_load(f)
        cells = model.get("gain_model", {}).get("cells")
        if not cells:
            raise SystemExit(f"{d}/model.yaml: no gain_model.cells (not a --coverage ranked model)")
        beta = {(t, g): b for t, g, b in zip(cells["top_gsd_cm"], cells["sub_gsd_cm"], cells["gain_slope"])}
        for ref in model["rule"]["reference"]:
            curve = dict(zip(ref["gsd_cm"], ref["miou"]))
            sigma = ref["field_sigma"]
            if not sigma > 0:
                continue
            # X at each top level (models before top_input: field_input, the nominal top's, at every top)
            x_at = dict(zip(ref.get("top_input_gsd_cm", []), ref.get("top_input", [])))
            for (t, g), b in beta.items():
                if t in curve and g in curve:
                    x = x_at.get(t, ref["field_input"])
                    out.setdefault((t, g), []).append((b * x / sigma, curve[g] - curve[t]))
    return out


def main(args):
    print("| runs | top -> lawnmower GSD [cm/px] | training fields | predicted rise (mean) | real rise (mean) | real / predicted |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for arg in args:
        label, _, dirs = arg.partition("=")
        if not dirs:
            raise SystemExit(f"expected LABEL=RUN_DIR[,RUN_DIR...], got {arg!r}")
        for (t, g), v in sorted(rises(dirs.split(",")).items(), key=lambda kv: (-kv[0][0], -kv[0][1])):
            p = sum(a for a, _ in v) / len(v)
            r = sum(b for _, b in v) / len(v)
            ratio = f"{r / p:.2f}" if p > 0 else "nan"
            print(f"| {label} | {t:g} -> {g:g} | {len(v)} | {p:+.4f} | {r:+.4f} | {ratio} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
