#!/usr/bin/env python3
"""Self-test of the experiments' driver (adaptseg_tools.experiments) and scripts/results.toml
(run by CTest; exit code != 0 on failure), without the programs or any download: the list
parses and every part expands, in a scratch folder with the folders each part needs faked; the
runs of loto, oracle-default, z-choice and others are the ones results.sh has always flown;
the knobs change what they change; a missing prerequisite, an unknown part or name, a typo in a
key are refused saying so; and the runner, on a stand-in program, runs the jobs, reports the
run that wrote nothing, expands the tables' globs and prints the dry run.
"""
import contextlib
import io
import os
import shlex
import sys
import tempfile
import tomllib

from adaptseg_tools.experiments import __main__ as cli
from adaptseg_tools.experiments.plan import CatalogError, expand
from adaptseg_tools.experiments.runner import run_plan

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
CLASSES = ["building", "road", "vegetation", "water"]
SWEEP = ["weedmap-train-left", "weedmap-train-right"] + [f"dubai-{c}-tile-{t}" for c in CLASSES for t in range(1, 7)]


def fake_tree(root):
    """The folders the parts read from earlier parts, and examples/ (the bundled networks)."""
    os.symlink(os.path.join(REPO, "examples"), os.path.join(root, "examples"))
    runs = {f"oracle-{c}/{n}" for c in ("default", "previous") for n in SWEEP}
    runs |= {f"network/{net}-{c}-fly{t}" for net in ("erfnet-dubai", "mobilenetv2-dubai", "ensemble-dubai")
             for c in CLASSES for t in (4, 6)}
    runs |= {f"{cfg}/mobilenetv2-loto-{c}-tile-{t}" for cfg in ("loto-pooled-z0", "loto-insample-pooled")
             for c in CLASSES for t in range(1, 7)}
    runs |= {f"loto-proxy/{c}-tile-{t}" for c in CLASSES for t in (1, 2, 3, 4, 6)}
    for run in runs:
        os.makedirs(os.path.join(root, "out", "results", run))
    for k in (1, 2, 3, 5):
        os.makedirs(os.path.join(root, "out", "loto-cpu", f"model-{k}"))
        with open(os.path.join(root, "out", "loto-cpu", f"model-{k}", "model.onnx"), "w") as f:
            f.write("stand-in")


def runs(plan):
    """Every command of the plan's jobs, as argument lists."""
    return [c.argv for stage in plan.stages for job in stage.jobs for c in job]


def flag_values(argv, flag):
    return [argv[i + 1] for i, a in enumerate(argv[:-1]) if a == flag]


def check_parts(catalog):
    for part in catalog["parts"]:
        plan = expand(catalog, part, {}, 2)
        assert not plan.missing, (part, plan.missing)
        assert plan.stages and (runs(plan) or any(s.tables for s in plan.stages)), part
        assert catalog["parts"][part].get("description", "").strip(), f"{part} has no description"

    # loto: 24 runs, each tile flown by the network that never saw it, calibrated on the other
    # five tiles, each segmented by the network that never saw it.
    loto = runs(expand(catalog, "loto", {}, 2))
    assert len(loto) == 24
    names = set()
    for argv in loto:
        tile = flag_values(argv, "--test")[0].rsplit("-", 1)[1]
        assert flag_values(argv, "--network") == [f"examples/models/mobilenetv2-dubai-loto/tile-{tile}"], argv
        assert flag_values(argv, "--calibration-network") == [f"examples/models/mobilenetv2-dubai-loto/tile-{k}" for k in range(1, 7)]
        assert flag_values(argv, "--train") == [f"examples/data/dubai-tile-{k}" for k in range(1, 7) if str(k) != tile], argv
        assert argv[argv.index("--seg-time-s"):][:4] == ["--seg-time-s", "0.1", "--plan-time-s", "0"]
        names.add(flag_values(argv, "--out")[0])
    assert names == {f"out/results/loto/mobilenetv2-loto-{c}-tile-{t}" for c in CLASSES for t in range(1, 7)}
    # Its knobs: another folder, more flags, measured times.
    for argv in runs(expand(catalog, "loto", {"CONFIG": "x", "EXTRA": "--map-fusion pooled --jump-guard",
                                              "LOTO_TIMES": "measured"}, 2)):
        assert flag_values(argv, "--out")[0].startswith("out/results/x/") and "--seg-time-s" not in argv
        assert argv[-5:-2] == ["--map-fusion", "pooled", "--jump-guard"], argv
    # loto-insample: the same runs, each calibrated on its own tile.
    for argv in runs(expand(catalog, "loto-insample", {}, 2)):
        assert flag_values(argv, "--train") == flag_values(argv, "--test"), argv

    # oracle-default: 2 WeedMap runs and 24 Dubai runs, then its two tables.
    plan = expand(catalog, "oracle-default", {}, 2)
    oracle = runs(plan)
    assert len(oracle) == 26
    assert sum("examples/data/weedmap-000:0,0,0.5,1" in a for a in oracle) == 2
    assert sum(len(flag_values(a, "--train")) == 5 for a in oracle) == 24
    assert plan.stages[0].remove == ["out/results/oracle-default"]
    assert [t.words[2] for t in plan.stages[0].tables] == ["adaptseg_tools.sweep_table", "adaptseg_tools.per_image_table"]
    hull = runs(expand(catalog, "oracle-default", {"CONFIG": "oracle-hull", "EXTRA": "--top-level hull"}, 2))
    assert all(a[-4:] == ["--top-level", "hull", "--out", a[-1]] and "/oracle-hull/" in a[-1] for a in hull)

    # network: NETS flies a subset; z-choice: the calibrations, then each run at every z with its
    # model's z set by compose_model (no sed); sigma-prior: σ̂'s prior weight so.
    assert len(runs(expand(catalog, "network", {}, 2))) == 24
    assert len(runs(expand(catalog, "network", {"NETS": "mobilenetv2-dubai"}, 2))) == 8
    z = expand(catalog, "z-choice", {}, 2).stages[0].jobs
    assert len(z) == 26 + 26 * 5 and all(len(job) == 2 for job in z[26:])
    assert sorted({flag_values(job[0].argv, "--confidence")[0] for job in z[26:]}) == ["0", "0.5", "1", "1.5", "2"]
    for job in expand(catalog, "sigma-prior", {}, 2).stages[0].jobs:
        assert job[0].argv[2] == "adaptseg_tools.compose_model" and flag_values(job[0].argv, "--sigma-prior-weight")
        assert flag_values(job[1].argv, "--decision-model") == flag_values(job[0].argv, "--out")
    # cross-fit with all four tiles the network trained on: the cross-fitted runs alone.
    assert len(runs(expand(catalog, "cross-fit", {}, 2))) == 16
    assert len(runs(expand(catalog, "cross-fit", {"CROSS_TILES": "1 2 3 5"}, 2))) == 8
    # cells: one stage per network, one study at a time.
    cells = expand(catalog, "cells", {"NETS": "erfnet-dubai mobilenetv2-dubai"}, 2).stages
    assert len(cells) == 2 and not cells[0].parallel and len(cells[0].jobs) == 8


def check_refusals(catalog):
    os.rmdir(os.path.join("out", "results", "oracle-previous", "weedmap-train-left"))
    os.rename(os.path.join("out", "results", "oracle-default"), "moved")
    assert expand(catalog, "z-choice", {}, 2).missing == [
        "z-choice needs out/results/oracle-default: run 'bash scripts/results.sh oracle-default' first"]
    os.rename("moved", os.path.join("out", "results", "oracle-default"))
    assert len(expand(catalog, "sigma-prior", {}, 2).stages[0].jobs) == 2 * 25  # only the runs that are there
    assert "cross-fit needs out/loto-cpu/model-4/model.onnx: bash scripts/loto.sh cpu 4" in \
        expand(catalog, "cross-fit", {"CROSS_TILES": "1 4"}, 2).missing
    for change, message in [
        (lambda c: c["parts"]["oracle"]["runs"][0].update(agrs="x"), "parts.oracle.runs[0]: unknown key agrs"),
        (lambda c: c["parts"]["oracle"]["runs"][0].update(args="{trian}"), "parts.oracle.runs[0]: unknown name {trian}"),
        (lambda c: c["parts"]["oracle"]["runs"][0].update(config="x{classes}"), "{classes} is 4 words"),
        (lambda c: c["parts"]["oracle"].update(remove=["/tmp"]), "/tmp is not under out/results/"),
    ]:
        broken = {**catalog, "parts": {k: {**v, "runs": [dict(r) for r in v.get("runs", [])]} for k, v in catalog["parts"].items()}}
        change(broken)
        try:
            expand(broken, "oracle", {}, 2)
            raise AssertionError(f"not refused: {message}")
        except CatalogError as e:
            assert message in str(e), (message, str(e))
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert cli.main(["--runs", os.path.join(REPO, "scripts", "results.toml"), "no-such-part"]) == 2
    assert "unknown part 'no-such-part'; the parts: all, oracle," in err.getvalue()


# A stand-in for adaptseg_evaluate: writes OUT/results.csv unless the run is named `bad`.
FAKE_EVALUATE = """import os, sys
out = sys.argv[sys.argv.index("--out") + 1]
print("flying", " ".join(sys.argv[1:]))
if not out.endswith("/bad"):
    os.makedirs(out)
    open(os.path.join(out, "results.csv"), "w").write("strategy,miou\\n")
"""
CATALOG = """
[values]
root = "out/results"
evaluate = "{python} fake_evaluate.py"
[parts.demo]
knobs = { NAMES = ["a", "b"] }
remove = ["{root}/demo"]
tables = [{ command = "{python} -c 'import sys; print(sys.argv[1:])' runs={root}/demo/*/ none={root}/none/*/" }]
[[parts.demo.runs]]
for = { name = "{NAMES}" }
config = "demo"
args = "--field {name}"
"""


def check_runner():
    with open("fake_evaluate.py", "w") as f:
        f.write(FAKE_EVALUATE)
    catalog = tomllib.loads(CATALOG)
    catalog["values"]["python"] = sys.executable
    dry = io.StringIO()
    assert run_plan(expand(catalog, "demo", {}, 2), 2, dry_run=True, out=dry) == 0
    lines = dry.getvalue().splitlines()
    assert lines[0] == "rm -rf out/results/demo" and lines[3] == "wait", lines
    assert shlex.split(lines[1])[-5:] == ["--out", "out/results/demo/a", ">", "out/results/demo/a.log", "2>&1"]
    assert shlex.split(lines[4])[-1] == "runs=out/results/demo/a,out/results/demo/b", lines[4]
    assert not os.path.exists("out/results/demo")
    with tempfile.TemporaryFile("w+") as printed:
        os.makedirs("out/results/demo/stale")
        saved = os.dup(1)
        os.dup2(printed.fileno(), 1)
        try:
            assert run_plan(expand(catalog, "demo", {}, 2), 2) == 0
        finally:
            os.dup2(saved, 1)
        printed.seek(0)
        assert printed.read().strip() == "['runs=out/results/demo/a,out/results/demo/b']"
    with open("out/results/demo/b.log") as f:
        assert f.read().startswith("flying --field b --out out/results/demo/b")
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert run_plan(expand(catalog, "demo", {"NAMES": "a bad"}, 1), 1) == 1
    assert err.getvalue() == "FAILED: demo/bad (see out/results/demo/bad.log)\n", err.getvalue()


def main():
    with open(os.path.join(REPO, "scripts", "results.toml"), "rb") as f:
        catalog = tomllib.load(f)
    start = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            fake_tree(tmp)
            check_parts(catalog)
            check_refusals(catalog)
            os.makedirs("runner")
            os.chdir("runner")
            check_runner()
        finally:
            os.chdir(start)
    print(f"PASS: adaptseg_tools.experiments ({len(catalog['parts'])} parts)")


if __name__ == "__main__":
    main()
