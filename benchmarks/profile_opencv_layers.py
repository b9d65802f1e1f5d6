#!/usr/bin/python3
"""Where OpenCV DNN spends an ONNX network's forward pass, and how its convolutions compare with
PyTorch's on the shapes that dominate.

1. The model's forward through OpenCV DNN (DNN_BACKEND_OPENCV, CPU), per layer type and for the
   slowest convolution layers, from cv::dnn::Net::getPerfProfile (mean over --iters passes).
2. Single convolutions of the model's most expensive shapes (kernel 3x1, 1x3, 3x3, dilated 3x1,
   1x1; channels and map size given), each exported to ONNX and run by OpenCV DNN and by
   PyTorch side by side (interleaved, medians), at the given thread count.

Usage:
  /usr/bin/python3 benchmarks/profile_opencv_layers.py --model-dir examples/models/erfnet-dubai \\
      [--threads 1] [--iters 5] [--channels 128 --height 45 --width 60]
"""

from __future__ import annotations

import argparse
import collections
import io
import time
from pathlib import Path

import cv2
import numpy as np
import torch
import yaml


def profile_model(model_dir: Path, iters: int) -> None:
    meta = yaml.safe_load((model_dir / "model.yaml").read_text())
    h, w = meta["input"]["height"], meta["input"]["width"]
    net = cv2.dnn.readNetFromONNX(str(model_dir / "model.onnx"))
    net.setPreferableBackend(cv2.dnn.DNN_BACKEND_OPENCV)
    net.setPreferableTarget(cv2.dnn.DNN_TARGET_CPU)
    x = np.random.default_rng(0).standard_normal((1, 3, h, w)).astype(np.float32)
    net.setInput(x)
    net.forward()
    per_layer = collections.defaultdict(float)
    totals = []
    for _ in range(iters):
        net.setInput(x)
        t0 = time.perf_counter()
        net.forward()
        totals.append((time.perf_counter() - t0) * 1000)
        _, per = net.getPerfProfile()
        for i, ticks in enumerate(per.ravel()):
            per_layer[i + 1] += ticks / cv2.getTickFrequency() * 1000 / iters
    by_type = collections.Counter()
    count = collections.Counter()
    convs = []
    for lid, ms in per_layer.items():
        layer = net.getLayer(lid)
        by_type[layer.type] += ms
        count[layer.type] += 1
        if layer.type == "Convolution" and layer.blobs:
            convs.append((ms, layer.name, tuple(layer.blobs[0].shape)))
    print(f"## {model_dir.name}: OpenCV DNN forward, input 1x3x{h}x{w}, {cv2.getNumThreads()} thread(s)\n")
    print(f"median forward {np.median(totals):.1f} ms (wall clock; the per-layer sum below excludes "
          "the framework's overhead)\n")
    print("| layer type | layers | ms | share |")
    print("| --- | ---: | ---: | ---: |")
    total = sum(by_type.values())
    for typ, ms in by_type.most_common():
        print(f"| {typ} | {count[typ]} | {ms:.1f} | {100 * ms / total:.0f} % |")
    convs.sort(reverse=True)
    shapes = collections.Counter()
    for ms, _, shape in convs:
        shapes[shape] += ms
    print("\n| convolution weight shape (out, in, kh, kw) | ms, all layers of that shape |")
    print("| --- | ---: |")
    for shape, ms in shapes.most_common(8):
        print(f"| {shape} | {ms:.1f} |")


def conv_table(c: int, h: int, w: int, iters: int, rounds: int) -> None:
    cases = [("3x1", (3, 1), (1, 0), 1), ("1x3", (1, 3), (0, 1), 1), ("3x1, dilation 4", (3, 1), (4, 0), (4, 1)),
             ("3x3", (3, 3), (1, 1), 1), ("1x1", (1, 1), 0, 1)]
    print(f"\n## One convolution, {c} -> {c} channels on a {h}x{w} map, batch 1, "
          f"{torch.get_num_threads()} thread(s); medians of {rounds} rounds x {iters} passes\n")
    print("| kernel | MFLOP | OpenCV DNN [ms] | PyTorch [ms] | PyTorch / OpenCV |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, k, pad, dil in cases:
        torch.manual_seed(0)
        m = torch.nn.Conv2d(c, c, k, padding=pad, dilation=dil).eval()
        x = torch.randn(1, c, h, w)
        buf = io.BytesIO()
        torch.onnx.export(m, x, buf, opset_version=11)
        net = cv2.dnn.readNetFromONNX(np.frombuffer(buf.getvalue(), np.uint8))
        xn = x.numpy()
        cv_ms, pt_ms = [], []
        with torch.inference_mode():
            for _ in range(3):
                net.setInput(xn)
                net.forward()
                m(x)
            for _ in range(rounds):
                for _ in range(iters):
                    t0 = time.perf_counter()
                    m(x)
                    pt_ms.append((time.perf_counter() - t0) * 1000)
                for _ in range(iters):
                    net.setInput(xn)
                    t0 = time.perf_counter()
                    net.forward()
                    cv_ms.append((time.perf_counter() - t0) * 1000)
        mflop = 2 * c * c * k[0] * k[1] * h * w / 1e6
        cv_med, pt_med = float(np.median(cv_ms)), float(np.median(pt_ms))
        print(f"| {name} | {mflop:.0f} | {cv_med:.2f} | {pt_med:.2f} | {pt_med / cv_med:.2f}x |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model-dir", required=True)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--iters", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--channels", type=int, default=128)
    ap.add_argument("--height", type=int, default=45)
    ap.add_argument("--width", type=int, default=60)
    args = ap.parse_args()
    cv2.setNumThreads(args.threads)
    torch.set_num_threads(args.threads)
    print(f"OpenCV {cv2.__version__}, PyTorch {torch.__version__}")
    profile_model(Path(args.model_dir), args.iters)
    conv_table(args.channels, args.height, args.width, args.iters, args.rounds)


if __name__ == "__main__":
    main()
