#!/usr/bin/python3
"""train_segnet --slim-checkpoint (what scripts/loto.sh train brings back from a device call): a
one-step ERFNet run on the CPU (quarter width, from scratch, a few seconds), its checkpoint
slimmed; --export-only of the slim file writes the same weights (model.pt) as of the full one,
--resume refuses it, and it holds no optimiser state. Skipped (exit 77) without torch (Debian
python3-torch). About 20 s on the 2-core VM.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

if importlib.util.find_spec("torch") is None:
    print("torch is not installed (Debian python3-torch): skipped")
    sys.exit(77)

import torch  # noqa: E402

from adaptseg_tools import REPO  # noqa: E402


def segnet(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "adaptseg_tools.train_segnet", *args], capture_output=True,
                          text=True)


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        fields = ["--data-dir", str(REPO / "examples" / "data"), "--train-fields", "dubai-tile-1",
                  "--val-field", "dubai-tile-2", "--test-field", "none"]
        run = segnet("--arch", "erfnet", "--width", "0.25", "--device", "cpu", "--steps", "1", "--warmup", "1",
                     "--batch", "1", "--crop", "160", "--ema", "0.99", "--val-every", "0", "--val-max-images", "1",
                     "--val-factors", "3", "--no-export", "--work-dir", str(t / "work"), "--model-dir", str(t / "m"),
                     *fields)
        assert run.returncode == 0, run.stdout + run.stderr
        slim = t / "slim" / "checkpoint.pt"
        run = segnet("--work-dir", str(t / "work"), "--model-dir", str(t / "unused"), "--slim-checkpoint", str(slim))
        assert run.returncode == 0, run.stdout + run.stderr
        full, small = (torch.load(p, map_location="cpu", weights_only=False) for p in (t / "work" / "checkpoint.pt", slim))
        assert full["optimizer_state"] is not None and small["optimizer_state"] is None
        assert small["step"] == full["step"] == 1 and small["arch"] == "erfnet"
        for k, v in full["ema_model"].items():  # the exported weights, as the network and as the average
            assert torch.equal(small["model"][k], v) and torch.equal(small["ema_model"][k], v), k
        assert slim.stat().st_size < 0.6 * (t / "work" / "checkpoint.pt").stat().st_size
        exported = {}
        for name, work in (("full", t / "work"), ("slim", slim.parent)):
            run = segnet("--arch", "erfnet", "--export-only", "--work-dir", str(work), "--model-dir", str(t / name),
                         *fields)
            assert run.returncode == 0, run.stdout + run.stderr
            exported[name] = torch.load(t / name / "model.pt", map_location="cpu")
            assert (t / name / "model.onnx").stat().st_size > 0
        assert exported["full"].keys() == exported["slim"].keys()
        for k, v in exported["full"].items():
            assert torch.equal(v, exported["slim"][k]), f"model.pt differs at {k}"
        run = segnet("--arch", "erfnet", "--resume", "--steps", "2", "--work-dir", str(slim.parent), "--model-dir",
                     str(t / "m2"), *fields)
        assert run.returncode != 0 and "not resumed" in run.stdout + run.stderr, run.stdout + run.stderr
    print("ok: the slim checkpoint exports the same weights and is refused for --resume")
    return 0


if __name__ == "__main__":
    sys.exit(main())
