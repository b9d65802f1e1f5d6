"""A diagnostic decision model put together from two calibrations of the front-aware rule: the
gain model (and everything else) of one, the reference of another (`rule.reference`: the
training fields' lawnmower curves, with their σ and input, the priors of σ̂ and X̂), optionally
at another confidence level z or another weight of σ̂'s prior. Which half of a calibration
transfers badly to new ground: fly a field with its leave-one-tile-out model's gain model and
the curves of a calibration on the field itself, and the other way round (scripts/results.sh
loto-swap). Without --reference, the model keeps its own reference: one setting of its rule
changed, as scripts/results.sh z-choice (z) and sigma-prior (σ̂'s prior) fly them.

Not a way to calibrate: a model whose reference is the test field's own was fitted on its
labels.

Usage: compose_model.py --gain A.yaml [--reference B.yaml] [--confidence Z]
                        [--sigma-prior-weight K] --out OUT.yaml
"""

from __future__ import annotations

import argparse
import sys

import yaml

# The settings of the front-aware rule that a composed model may change, each with the check
# its value must pass (the bound FrontAwarePolicy::Params enforces) and how to say it.
RULE_SETTINGS = {
    "confidence": (lambda v: v >= 0.0, ">= 0"),
    "sigma_prior_weight": (lambda v: v > 0.0, "> 0"),
}


def require_front_aware(model: dict, name: str) -> None:
    """Raises ValueError unless `model` is a front-aware decision model with reference curves."""
    rule = model.get("rule") if isinstance(model, dict) else None
    if not isinstance(rule, dict) or rule.get("kind") != "front-aware" or "reference" not in rule:
        raise ValueError(f"{name}: not a front-aware decision model with reference curves")


def with_rule_setting(model: dict, setting: str, value: float) -> dict:
    """A copy of the front-aware `model` with one setting of its rule (RULE_SETTINGS) at `value`;
    `model` itself is left as it was."""
    require_front_aware(model, "the model")
    if setting not in RULE_SETTINGS:
        raise ValueError(f"the rule's {setting} is not one a composed model may change (those: {', '.join(RULE_SETTINGS)})")
    valid, bound = RULE_SETTINGS[setting]
    flag = "--" + setting.replace("_", "-")
    if not valid(value):
        raise ValueError(f"{flag} must be {bound}, got {value}")
    if setting not in model["rule"]:
        raise ValueError(f"the model's rule has no {setting} to change (a model written by another version?)")
    out = dict(model)
    out["rule"] = dict(model["rule"])
    out["rule"][setting] = value
    return out


def compose(gain: dict, reference: dict | None, confidence: float | None,
            sigma_prior_weight: float | None = None) -> dict:
    """`gain` with `reference`'s rule.reference (its own where `reference` is None), z =
    `confidence` and σ̂'s prior weight `sigma_prior_weight` where given."""
    require_front_aware(gain, "--gain")
    out = dict(gain)
    out["rule"] = dict(gain["rule"])
    if reference is not None:
        require_front_aware(reference, "--reference")
        if gain.get("interest") != reference.get("interest") or gain.get("classes") != reference.get("classes"):
            raise ValueError("the two models are for different classes or labels of interest")
        out["rule"]["reference"] = reference["rule"]["reference"]
    for setting, value in (("confidence", confidence), ("sigma_prior_weight", sigma_prior_weight)):
        if value is not None:
            out = with_rule_setting(out, setting, value)
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--gain", required=True, help="model whose gain model (and all but the reference) is kept")
    ap.add_argument("--reference", help="model whose rule.reference is taken (default: the --gain model's own)")
    ap.add_argument("--confidence", type=float, help="the rule's z in the composed model")
    ap.add_argument("--sigma-prior-weight", type=float, help="the rule's weight k of σ̂'s prior in the composed model")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    try:
        with open(args.gain) as f:
            gain = yaml.safe_load(f)
        reference = None
        if args.reference is not None:
            with open(args.reference) as f:
                reference = yaml.safe_load(f)
        composed = compose(gain, reference, args.confidence, args.sigma_prior_weight)
    except (OSError, ValueError, yaml.YAMLError) as e:
        print(f"compose_model.py: {e}", file=sys.stderr)
        return 2
    with open(args.out, "w") as f:
        yaml.safe_dump(composed, f, sort_keys=False, default_flow_style=None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
