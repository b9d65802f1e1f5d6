#!/usr/bin/python3
"""Training-batch throughput: the device sampler (adaptseg_tools.device_sampler, what
`adaptseg_tools.train_segnet --sampler device` uses) side by side with another implementation of the same
class (--baseline FILE, e.g. an earlier device_sampler.py taken from git) and with the CPU
sampler (one process), on the same batches of the bundled training tiles.

Each round makes --batches batches (steps 0, 1, ...) with every implementation in turn, the
device synchronised before and after; the median over rounds of the time per batch is
reported, with crops per second. Batches of the ERFNet recipe (480x360 camera, 352x352 crops)
and of the MobileNetV2 recipe (300x300 crops fed at 320x320) by default.

Usage:
  PYTHONPATH=python /usr/bin/python3 benchmarks/bench_sampler.py [--device cuda] [--batch 32] [--batches 5]
      [--rounds 3] [--baseline OLD_device_sampler.py] [--no-cpu] [--json FILE]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import time
from pathlib import Path

import numpy as np
import torch

from adaptseg_tools import device_sampler
from adaptseg_tools.training.fields import load_field
from adaptseg_tools.training.network_path import NetSpec
from adaptseg_tools.training.samples import Sampler

REPO = Path(__file__).resolve().parents[1]


def load_module(path: Path):
    spec = importlib.util.spec_from_file_location("baseline_sampler", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--batches", type=int, default=5, help="batches per implementation per round")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--baseline", type=Path, help="another device_sampler.py to time beside this one")
    ap.add_argument("--no-cpu", action="store_true", help="leave out the CPU sampler")
    ap.add_argument("--threads", type=int, default=1, help="PyTorch threads (the trainings use 1)")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    fields = [load_field(REPO / "examples" / "data" / f"dubai-tile-{k}") for k in (1, 2, 3, 5)]
    mean, std = np.array([0.47, 0.47, 0.47]), np.array([0.34, 0.33, 0.35])
    recipes = {"erfnet (352 crops)": (NetSpec("erfnet", (480, 360), (480, 360), 1, mean, std), 352),
               "mobilenetv2 (300 crops)": (NetSpec("mobilenetv2", (480, 360), (512, 384), 4, mean, std), 300)}
    sync = torch.cuda.synchronize if device.type == "cuda" else (lambda: None)
    rows = []
    for recipe, (spec, crop) in recipes.items():
        cpu = Sampler(fields, spec, crop, 1.0, 3.0, "altitude", seed=0)
        impls = {"device sampler": device_sampler.DeviceSampler(cpu, device).batch}
        if args.baseline:
            impls["baseline " + args.baseline.name] = load_module(args.baseline).DeviceSampler(cpu, device).batch
        if not args.no_cpu:
            impls["CPU sampler, 1 process"] = lambda step, n, cpu=cpu: [cpu.sample(step, j) for j in range(n)]
        times = {name: [] for name in impls}
        for name, make in impls.items():  # warm-up: caches, kernels, allocator
            make(0, args.batch)
        for r in range(args.rounds):
            for name, make in impls.items():
                sync()
                t0 = time.perf_counter()
                for s in range(args.batches):
                    make(r * args.batches + s, args.batch)
                sync()
                times[name].append((time.perf_counter() - t0) / args.batches)
        for name, ts_ in times.items():
            med = statistics.median(ts_)
            rows.append({"recipe": recipe, "sampler": name, "ms_per_batch": round(1000 * med, 1),
                         "crops_per_s": round(args.batch / med, 1)})
    dev_name = torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu"
    print(f"device {dev_name}, PyTorch {torch.__version__}, batch {args.batch}, {args.rounds} rounds of "
          f"{args.batches} batches, {args.threads} thread(s)")
    print("| recipe | sampler | ms per batch | crops/s |\n| --- | --- | ---: | ---: |")
    for r in rows:
        print(f"| {r['recipe']} | {r['sampler']} | {r['ms_per_batch']} | {r['crops_per_s']} |")
    if args.json:
        args.json.write_text(json.dumps({"device": dev_name, "torch": torch.__version__, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
