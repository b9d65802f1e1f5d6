"""A diagnostic decision model put together from two calibrations of the front-aware rule: the
gain model (and everything else) of one, the reference of another (`rule.reference`: the
training fields' lawnmower curves, with their σ and input, the priors of σ̂ and X̂), optionally
at another confidence level z. Which half of a calibration transfers badly to new ground: fly
a field with its leave-one-tile-out model's gain model and the curves of a calibration on the
field itself, and the other way round (scripts/results.sh loto-swap).

Not a way to calibrate: a model whose reference is the test field's own was fitted on its
labels.

Usage: compose_model.py --gain A.yaml --reference B.yaml [--confidence Z] --out OUT.yaml
"""

from __future__ import annotations

import argparse
import sys

import yaml


def compose(gain: dict, reference: dict, confidence: float | None) -> dict:
    """`gain` with `reference`'s rule.reference (and z = `confidence` where given)."""
    for name, model in (("--gain", gain), ("--reference", reference)):
        rule = model.get("rule") if isinstance(model, dict) else None
        if not isinstance(rule, dict) or rule.get("kind") != "front-aware" or "reference" not in rule:
            raise ValueError(f"{name}: not a front-aware decision model with reference curves")
    if gain.get("interest") != reference.get("interest") or gain.get("classes") != reference.get("classes"):
        raise ValueError("the two models are for different classes or labels of interest")
    out = dict(gain)
    out["rule"] = dict(gain["rule"])
    out["rule"]["reference"] = reference["rule"]["reference"]
    if confidence is not None:
        if not confidence >= 0.0:
            raise ValueError(f"--confidence must be >= 0, got {confidence}")
        out["rule"]["confidence"] = confidence
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--gain", required=True, help="model whose gain model (and all but the reference) is kept")
    ap.add_argument("--reference", required=True, help="model whose rule.reference is taken")
    ap.add_argument("--confidence", type=float, help="the rule's z in the composed model")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    try:
        with open(args.gain) as f:
            gain = yaml.safe_load(f)
        with open(args.reference) as f:
            reference = yaml.safe_load(f)
        composed = compose(gain, reference, args.confidence)
    except (OSError, ValueError, yaml.YAMLError) as e:
        print(f"compose_model.py: {e}", file=sys.stderr)
        return 2
    with open(args.out, "w") as f:
        yaml.safe_dump(composed, f, sort_keys=False, default_flow_style=None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
