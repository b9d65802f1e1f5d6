#!/usr/bin/env python3
"""Self-test of compose_model.py on the bundled deployment network's decision models (run by
CTest; exit code != 0 on failure): the reference of one model in the other's place, z where
asked, everything else the gain model's; without a reference, one setting of the model's own
rule changed; models of different labels of interest, or of another rule, and values out of
bounds refused with exit code 2 and one line.
"""
import contextlib
import io
import os
import tempfile

import yaml

from adaptseg_tools import compose_model

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MODELS = os.path.join(REPO, "examples", "models", "mobilenetv2-dubai-all")


def load(path):
    with open(path) as f:
        return yaml.safe_load(f)


def main():
    road = os.path.join(MODELS, "decision-road.yaml")
    building = os.path.join(MODELS, "decision-building.yaml")
    with tempfile.TemporaryDirectory() as tmp:
        # A reference of its own: road's with its first field's curve dropped.
        other = load(road)
        other["rule"]["reference"] = other["rule"]["reference"][1:]
        other_path = os.path.join(tmp, "other.yaml")
        with open(other_path, "w") as f:
            yaml.safe_dump(other, f)
        out = os.path.join(tmp, "composed.yaml")
        assert compose_model.main(["--gain", road, "--reference", other_path, "--confidence", "0.5", "--out", out]) == 0
        composed, gain = load(out), load(road)
        assert composed["rule"]["reference"] == other["rule"]["reference"]
        assert len(composed["rule"]["reference"]) == len(gain["rule"]["reference"]) - 1
        assert composed["rule"]["confidence"] == 0.5 and gain["rule"]["confidence"] != 0.5
        for key in gain:
            if key != "rule":
                assert composed[key] == gain[key], key
        for key in gain["rule"]:
            if key not in ("reference", "confidence"):
                assert composed["rule"][key] == gain["rule"][key], key
        # Without --confidence the gain model's z stays.
        assert compose_model.main(["--gain", road, "--reference", other_path, "--out", out]) == 0
        assert load(out)["rule"]["confidence"] == gain["rule"]["confidence"]

        # Without --reference the model keeps its own: one setting of its rule changed (z, or the
        # weight of σ̂'s prior), everything else as it was.
        for flag, setting, value in (("--confidence", "confidence", 1.5), ("--sigma-prior-weight", "sigma_prior_weight", 0.01)):
            assert compose_model.main(["--gain", road, flag, str(value), "--out", out]) == 0
            edited = load(out)
            assert edited["rule"][setting] == value and gain["rule"][setting] != value
            edited["rule"][setting] = gain["rule"][setting]
            assert edited == gain, setting

        # Refused: another label of interest, another rule, a negative z, a weight of 0.
        utility = load(road)
        utility["rule"] = {"kind": "utility"}
        utility_path = os.path.join(tmp, "utility.yaml")
        with open(utility_path, "w") as f:
            yaml.safe_dump(utility, f)
        for args, message in [
            (["--gain", road, "--reference", building], "different classes or labels of interest"),
            (["--gain", utility_path, "--reference", road], "--gain: not a front-aware decision model"),
            (["--gain", road, "--reference", road, "--confidence", "-1"], "--confidence must be >= 0"),
            (["--gain", road, "--sigma-prior-weight", "0"], "--sigma-prior-weight must be > 0"),
            (["--gain", utility_path, "--confidence", "1"], "--gain: not a front-aware decision model"),
        ]:
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                code = compose_model.main(args + ["--out", os.path.join(tmp, "refused.yaml")])
            assert code == 2 and message in err.getvalue() and err.getvalue().count("\n") == 1, (args, err.getvalue())
            assert not os.path.exists(os.path.join(tmp, "refused.yaml")), args
    print("PASS: compose_model.py")


if __name__ == "__main__":
    main()
