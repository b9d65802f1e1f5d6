#!/usr/bin/python3
"""Checks device_sampler.DeviceSampler (train_segnet.py --sampler device) against the CPU
sampler it replaces, on the bundled training tiles, with PyTorch on the CPU (or --device cuda):

1. INTER_AREA by weight matrices equals cv2.resize(INTER_AREA) to one 8-bit level;
2. the same draws give the same crop: camera images within one level (mean |diff| < 0.1) and
   oracle targets agreeing on >= 99.5 % of the pixels;
3. the photometric augmentation with the same parameters agrees with the CPU one (mean |diff|
   under 1.5 levels where neither adds noise or JPEG);
4. whole samples: shapes, types, normalisation and label frequencies as the CPU sampler's.

Needs torch (Debian python3-torch): CTest's tools:device_sampler is skipped (exit 77) where it
is missing, as on CI, which trains nothing. Usage:
  /usr/bin/python3 examples/tools/test_device_sampler.py [--device cpu|cuda] [--n 40]
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

if importlib.util.find_spec("torch") is None:
    print("torch is not installed (Debian python3-torch): skipped")
    sys.exit(77)

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import device_sampler as ds  # noqa: E402
import train_segnet as ts  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--n", type=int, default=40, help="samples per check")
    args = ap.parse_args(argv)
    torch.set_num_threads(2)
    cv2.setNumThreads(1)
    data = HERE.parent / "data"
    fields = [ts.load_field(data / f"dubai-tile-{k}") for k in (1, 2, 3, 5)]
    spec = ts.NetSpec("erfnet", (480, 360), (480, 360), 1, np.array([0.47, 0.47, 0.47]), np.array([0.34, 0.33, 0.35]))
    cpu = ts.Sampler(fields, spec, 352, 1.0, 3.0, "altitude", seed=7)
    dev = ds.DeviceSampler(cpu, args.device)
    failures = []

    def check(ok, what):
        print(("ok  " if ok else "FAIL") + "  " + what)
        if not ok:
            failures.append(what)

    # 1. INTER_AREA by matrices.
    rng = np.random.default_rng(1)
    worst = 0.0
    for (w, h) in ((1440, 1080), (1000, 751), (481, 361), (960, 720), (613, 1187)):
        img = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        ref = cv2.resize(img, (480, 360) if w > h else (360, 480), interpolation=cv2.INTER_AREA).astype(np.float32)
        oh, ow = ref.shape[:2]
        t = torch.from_numpy(img).to(dev.device).float()
        out = torch.einsum("oh,hwc,pw->opc", dev.weights(oh, h), t, dev.weights(ow, w))
        out = torch.round(out).clamp(0, 255).cpu().numpy()
        worst = max(worst, float(np.abs(out - ref).max()))
    check(worst <= 1.0, f"INTER_AREA by weight matrices = cv2.resize to one level (max |diff| {worst:g})")

    # 2. Same draws, same crop.
    cam_diff, cam_max, agree = [], 0.0, []
    for i in range(args.n):
        a_img, a_t = cpu.altitude_camera(np.random.default_rng((7, 0, i)))
        b_img, b_t = dev.camera(np.random.default_rng((7, 0, i)))
        b_img = b_img.permute(1, 2, 0).cpu().numpy()
        d = np.abs(b_img - a_img.astype(np.float32))
        cam_diff.append(float(d.mean()))
        cam_max = max(cam_max, float(d.max()))
        agree.append(float((b_t.cpu().numpy() == a_t).mean()))
    check(cam_max <= 1.0 and np.mean(cam_diff) < 0.1,
          f"camera images: max |diff| {cam_max:g}, mean |diff| {np.mean(cam_diff):.4f} over {args.n} crops")
    check(min(agree) >= 0.995, f"oracle targets agree on {100 * np.mean(agree):.3f} % (worst crop {100 * min(agree):.3f} %)")

    # 3. Photometric augmentation, same parameters.
    diffs = []
    for i in range(args.n):
        a_img, _ = cpu.altitude_camera(np.random.default_rng((7, 1, i)))
        probe = np.random.default_rng((9, i))
        draws = [probe.uniform(0.7, 1.3), probe.uniform(0.75, 1.25), probe.uniform(-20, 20), probe.uniform(0.92, 1.08, 3),
                 probe.uniform(0.8, 1.25), probe.random()]
        hue = draws[-1] < 0.5
        if hue:
            probe.integers(-5, 6)
        blur = probe.random() < 0.3
        if blur:
            probe.uniform(0.3, 1.2)
        if probe.random() < 0.3:  # noise: the two samplers draw it differently
            continue
        a = ts.photometric(a_img.copy(), np.random.default_rng((9, i))).astype(np.float32)
        b = dev.photometric(torch.from_numpy(a_img.astype(np.float32)).permute(2, 0, 1).to(dev.device),
                            np.random.default_rng((9, i)))
        b = b.permute(1, 2, 0).cpu().numpy()
        if b.shape != a.shape:
            failures.append("photometric changed the shape")
            continue
        diffs.append(float(np.abs(a - b).mean()))
    check(len(diffs) >= args.n // 3 and np.mean(diffs) < 1.5 and max(diffs) < 4.0,
          f"photometric: mean |diff| {np.mean(diffs):.3f} levels (worst image {max(diffs):.3f}) over {len(diffs)} images "
          "without noise")

    # 4. Whole samples.
    xs, ys = dev.batch(3, 16)
    cx, cy = zip(*[cpu.sample(3, j) for j in range(16)])
    cx, cy = np.stack(cx), np.stack(cy)
    check(tuple(xs.shape) == cx.shape and xs.dtype == torch.float32 and tuple(ys.shape) == cy.shape
          and ys.dtype == torch.int64, f"batch shapes {tuple(xs.shape)} / {tuple(ys.shape)} as the CPU sampler's")
    m_dev, m_cpu = float(xs.mean()), float(cx.mean())
    check(abs(m_dev - m_cpu) < 0.15, f"normalised input mean {m_dev:.3f} vs CPU {m_cpu:.3f}")
    f_dev = np.bincount(ys.cpu().numpy().ravel(), minlength=256)[:5] / ys.numel()
    f_cpu = np.bincount(cy.ravel(), minlength=256)[:5] / cy.size
    check(np.abs(f_dev - f_cpu).max() < 0.01, f"label frequencies {np.round(f_dev, 3).tolist()} vs CPU "
          f"{np.round(f_cpu, 3).tolist()}")
    print("device sampler:", "FAILED " + "; ".join(failures) if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
