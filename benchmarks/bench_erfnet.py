#!/usr/bin/python3
"""Network inference: PyTorch vs OpenCV DNN (adaptseg::OnnxSegmenter, the ONNX backend) side
by side, for any bundled model (ERFNet, MobileNetV2).

Runs PyTorch on the checkpoint the ONNX model was exported from (model.pt next to
model.onnx) and the C++ timing binary bench_erfnet (benchmarks/bench_erfnet.cpp) on the ONNX
model, on the same input size (the network's: 480x360 for ERFNet, 512x384 for MobileNetV2) and
the same thread counts. OpenCV's segment() takes a camera image of the size the model was
trained for (480x360), resampled to the input size where that differs. To be fair on
a shared machine the two are interleaved: --rounds rounds, each timing --iters forward passes
of PyTorch, then of OpenCV; the median is over all rounds. Also reports the FLOPs per image
(convolutions and transposed convolutions counted per layer with forward hooks; 1 MAC = 2
FLOPs; BN, ReLU, pooling and additions are not counted, they are < 1 % of the total) and the
achieved GFLOP/s.

Usage:
  PYTHONPATH=python /usr/bin/python3 benchmarks/bench_erfnet.py --bench-bin BUILD/benchmarks/bench_erfnet \\
      [--model-dir examples/models/erfnet-dubai] [--threads 1,2] [--rounds 3] [--iters 10]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np
import torch

from adaptseg_tools.training.models import load_exported
from bench_common import cpu_model

REPO = Path(__file__).resolve().parents[1]


def conv_flops(model: torch.nn.Module, x: torch.Tensor) -> tuple[int, list]:
    """Multiply-adds of every Conv2d / ConvTranspose2d for input x, as FLOPs (2 per MAC)."""
    rows = []

    def hook(mod, inp, out):
        cin = inp[0].shape[1]
        kh, kw = mod.kernel_size
        if isinstance(mod, torch.nn.ConvTranspose2d):
            # every input pixel scatters a kh x kw x cout patch
            macs = inp[0].shape[2] * inp[0].shape[3] * cin * mod.out_channels * kh * kw // mod.groups
        else:
            macs = out.shape[2] * out.shape[3] * out.shape[1] * (cin // mod.groups) * kh * kw
        rows.append((type(mod).__name__, tuple(out.shape[1:]), 2 * macs))

    hs = [m.register_forward_hook(hook) for m in model.modules()
          if isinstance(m, (torch.nn.Conv2d, torch.nn.ConvTranspose2d))]
    with torch.no_grad():
        model(x)
    for h in hs:
        h.remove()
    return sum(r[2] for r in rows), rows


def time_torch(model, x, iters: int, warmup: int) -> list[float]:
    out = []
    with torch.inference_mode():
        for _ in range(warmup):
            model(x)
        for _ in range(iters):
            t0 = time.perf_counter()
            model(x)
            out.append(1e3 * (time.perf_counter() - t0))
    return out


def time_opencv(binary: str, model_dir: Path, threads: int, iters: int, warmup: int, camera, extra) -> dict:
    cmd = [binary, str(model_dir), "--threads", str(threads), "--iters", str(iters), "--warmup", str(warmup),
           "--camera", f"{camera[0]}x{camera[1]}"] + extra
    res = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if res.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{res.stderr}")
    return json.loads(res.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model-dir", default=str(REPO / "examples" / "models" / "erfnet-dubai"))
    ap.add_argument("--bench-bin", default=str(REPO / "build" / "benchmarks" / "bench_erfnet"))
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--iters", type=int, default=10)
    ap.add_argument("--warmup", type=int, default=3)
    ap.add_argument("--opencv-args", default="", help="extra arguments for bench_erfnet, e.g. --no-fusion")
    ap.add_argument("--json", help="also write the results here")
    args = ap.parse_args()

    model_dir = Path(args.model_dir)
    model, _, meta = load_exported(model_dir)
    h, w = meta["input"]["height"], meta["input"]["width"]
    camera = meta["training"]["camera"]
    x = torch.from_numpy(np.random.default_rng(0).standard_normal((1, 3, h, w)).astype(np.float32))
    flops, _ = conv_flops(model, x)
    params = sum(p.numel() for p in model.parameters())
    extra = args.opencv_args.split() if args.opencv_args else []

    load_before = os.getloadavg()
    results = []
    for n in [int(v) for v in args.threads.split(",")]:
        torch.set_num_threads(n)
        pt, cv_fwd, cv_seg = [], [], []
        for _ in range(args.rounds):
            pt += time_torch(model, x, args.iters, args.warmup)
            r = time_opencv(args.bench_bin, model_dir, n, args.iters, args.warmup, camera, extra)
            cv_fwd.append(r["forward_ms"]["median"])
            cv_seg.append(r["segment_ms"]["median"])
        row = {"threads": n, "pytorch_ms": statistics.median(pt),
               "opencv_forward_ms": statistics.median(cv_fwd),
               "opencv_segment_ms": statistics.median(cv_seg)}
        row["speedup_forward"] = row["pytorch_ms"] / row["opencv_forward_ms"]
        row["gflops_pytorch"] = flops / row["pytorch_ms"] / 1e6
        row["gflops_opencv"] = flops / row["opencv_forward_ms"] / 1e6
        results.append(row)
    load_after = os.getloadavg()

    arch = meta.get("arch", "erfnet")
    name = f"ERFNet width {meta['width']}" if arch == "erfnet" else "MobileNetV2 + decoder"
    print(f"{model_dir.name}: {name} ({params} parameters), input 1x3x{h}x{w}, camera {camera[0]}x{camera[1]}, "
          f"{flops / 1e9:.2f} GFLOP per image (conv + transposed conv, 2 FLOP per MAC)")
    print(f"CPU: {cpu_model()}, {os.cpu_count()} logical CPUs; torch {torch.__version__}, "
          f"OpenCV {r['opencv']}; load average before {load_before[0]:.2f}, after {load_after[0]:.2f}")
    print(f"median over {args.rounds} interleaved rounds x {args.iters} forward passes"
          + (f"; bench_erfnet {' '.join(extra)}" if extra else ""))
    print()
    print("| threads | PyTorch forward [ms] | OpenCV DNN forward [ms] | OpenCV segment() [ms] | "
          "speed-up (PyTorch / OpenCV forward) | GFLOP/s PyTorch | GFLOP/s OpenCV |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for row in results:
        print(f"| {row['threads']} | {row['pytorch_ms']:.1f} | {row['opencv_forward_ms']:.1f} | "
              f"{row['opencv_segment_ms']:.1f} | {row['speedup_forward']:.2f}x | "
              f"{row['gflops_pytorch']:.1f} | {row['gflops_opencv']:.1f} |")
    if args.json:
        Path(args.json).write_text(json.dumps({"flops": flops, "params": params, "results": results,
                                               "load_before": load_before, "load_after": load_after},
                                              indent=2))


if __name__ == "__main__":
    main()
