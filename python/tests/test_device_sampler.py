#!/usr/bin/python3
"""Checks device_sampler.DeviceSampler (train_segnet.py --sampler device) against the CPU
sampler it replaces, on the bundled training tiles, with PyTorch on the CPU (or --device cuda):

1. INTER_AREA by weight matrices equals cv2.resize(INTER_AREA) to one 8-bit level;
2. the same draws give the same crop: camera images within one level (mean |diff| < 0.1) and
   oracle targets agreeing on >= 99.5 % of the pixels, over crops covering every quarter turn
   with and without the mirror and footprints partly outside the orthomosaic, and crops wider
   than the camera is high in one batch;
3. the photometric augmentation with the same parameters agrees with the CPU one (mean |diff|
   under 1.5 levels where neither adds noise or JPEG), and the batched blur with cv2's (two
   levels, OpenCV's fixed point);
4. whole samples: shapes, types, normalisation and label frequencies as the CPU sampler's;
5. a sample made in a batch equals the same sample made alone (to one level);
6. crops less than 5 % labelled are drawn again from the sample's own generator, as the CPU
   sampler draws them (a field labelled only in one corner: most first draws are redrawn);
7. the prefetching thread (train_segnet.py's loader on CUDA; here forced on) yields the same
   batches in step order, stops when closed early, and hands its failures to the consumer.

Needs torch (Debian python3-torch): CTest's tools:device_sampler is skipped (exit 77) where it
is missing. On the CPU the full size is slow (more than 28 minutes on the 2-core VM): CTest runs it
with --quick (half the side, about 80 s of CPU there). Usage:
  PYTHONPATH=python /usr/bin/python3 python/tests/test_device_sampler.py [--device cpu|cuda] [--n 40] [--quick]
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

from adaptseg_tools import device_sampler as ds  # noqa: E402
from adaptseg_tools.fieldio import IGNORE  # noqa: E402
from adaptseg_tools.training.fields import FieldData, load_field  # noqa: E402
from adaptseg_tools.training.network_path import NetSpec  # noqa: E402
from adaptseg_tools.training.samples import Sampler, photometric  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent.parent / "examples"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--n", type=int, default=40, help="samples per check")
    ap.add_argument("--quick", action="store_true",
                    help="a camera of 240 x 180 and crops of 176 (and 210) instead of 480 x 360 and 352 (420): "
                         "footprints a quarter the area, the same checks (CTest's tools:device_sampler)")
    args = ap.parse_args(argv)
    torch.set_num_threads(2)
    cv2.setNumThreads(1)
    data = EXAMPLES / "data"
    fields = [load_field(data / f"dubai-tile-{k}") for k in (1, 2, 3, 5)]
    # The camera and the crops; --quick halves each side (on the CPU the device sampler's matrix
    # products over the footprints took most of the half hour the full size took here).
    half = 2 if args.quick else 1
    cam_wh, crop, wide_crop = (480 // half, 360 // half), 352 // half, 420 // half
    spec = NetSpec("erfnet", cam_wh, cam_wh, 1, np.array([0.47, 0.47, 0.47]), np.array([0.34, 0.33, 0.35]))
    cpu = Sampler(fields, spec, crop, 1.0, 3.0, "altitude", seed=7)
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
        wy, wx = (ds.area_weights(torch.tensor([[no, ni, 0, no, 0, 0, ni]], dtype=torch.float64, device=dev.device),
                                  no, ni)[0] for no, ni in ((oh, h), (ow, w)))
        out = torch.einsum("oh,hwc,pw->opc", wy, t, wx)
        out = torch.round(out).clamp(0, 255).cpu().numpy()
        worst = max(worst, float(np.abs(out - ref).max()))
    check(worst <= 1.0, f"INTER_AREA by weight matrices = cv2.resize to one level (max |diff| {worst:g})")

    # 2. Same draws, same crop: until every quarter turn with and without the mirror was seen
    # twice and three footprints lay partly outside the orthomosaic (at least --n crops).
    cam_diff, cam_max, agree = [], 0.0, []
    seen, outside, i = {}, 0, 0
    while i < args.n or (len(seen) < 8 or min(seen.values()) < 2 or outside < 3) and i < 400:
        g = dev.draw_geometry(np.random.default_rng((7, 0, i)))
        H, W = dev.labels[g.field].shape
        seen[(g.k, g.mirror)] = seen.get((g.k, g.mirror), 0) + 1
        outside += g.c0 < 0 or g.r0 < 0 or g.c0 + g.fw > W or g.r0 + g.fh > H
        a_img, a_t = cpu.altitude_camera(np.random.default_rng((7, 0, i)))
        b_img, b_t = dev.camera(np.random.default_rng((7, 0, i)))
        b_img = b_img.permute(1, 2, 0).cpu().numpy()
        d = np.abs(b_img - a_img.astype(np.float32))
        cam_diff.append(float(d.mean()))
        cam_max = max(cam_max, float(d.max()))
        agree.append(float((b_t.cpu().numpy() == a_t).mean()))
        i += 1
    check(len(seen) == 8 and min(seen.values()) >= 2 and outside >= 3,
          f"crops cover every yaw and mirror ({min(seen.values())}+ each) and {outside} footprints partly outside")
    check(cam_max <= 1.0 and np.mean(cam_diff) < 0.1,
          f"camera images: max |diff| {cam_max:g}, mean |diff| {np.mean(cam_diff):.4f} over {i} crops")
    check(min(agree) >= 0.995, f"oracle targets agree on {100 * np.mean(agree):.3f} % (worst crop {100 * min(agree):.3f} %)")

    # Crops wider than the camera is high (420 x 360; --quick 210 x 180) come out of a batch transposed and padded
    # where the yaw turned them: the same crops as the CPU sampler's, in one batch of 12.
    wide = ds.DeviceSampler(Sampler(fields, spec, wide_crop, 1.0, 3.0, "altitude", seed=7), args.device)
    cams, targets = wide.cameras([wide.draw_geometry(np.random.default_rng((7, 2, i))) for i in range(12)])
    wmax, wagree = 0.0, []
    for i in range(12):
        a_img, a_t = wide.cpu.altitude_camera(np.random.default_rng((7, 2, i)))
        wmax = max(wmax, float(np.abs(cams[i].permute(1, 2, 0).cpu().numpy() - a_img).max()))
        wagree.append(float((targets[i].cpu().numpy() == a_t).mean()))
    check(tuple(cams.shape[2:]) == (cam_wh[1], wide_crop) and wmax <= 1.0 and min(wagree) >= 0.995,
          f"{wide_crop} x {cam_wh[1]} crops, one batch: camera images within {wmax:g} level, targets agree on >= "
          f"{100 * min(wagree):.2f} %")

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
        a = photometric(a_img.copy(), np.random.default_rng((9, i))).astype(np.float32)
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
    sigmas = [0.3, 0.55, 0.8, 1.2]
    imgs = np.random.default_rng(3).integers(0, 256, (len(sigmas), 60, 70, 3), dtype=np.uint8)
    out = ds.gaussian_blur_batch(torch.from_numpy(imgs).permute(0, 3, 1, 2).float().to(dev.device), sigmas)
    out = torch.round(out).clamp(0, 255).permute(0, 2, 3, 1).cpu().numpy()
    d = np.stack([np.abs(out[b] - cv2.GaussianBlur(imgs[b], (0, 0), s).astype(np.float32)) for b, s in enumerate(sigmas)])
    # OpenCV blurs 8-bit images in fixed point: on white noise a fifth of a level apart on average,
    # two at most (a wrong sigma is tens of levels off).
    check(d.max() <= 2.0 and d.mean() < 0.25, f"batched blur, sigmas {sigmas}: cv2.GaussianBlur's within "
          f"{d.max():g} levels, mean |diff| {d.mean():.3f}")

    # 5. In a batch or alone.
    alone = [dev.sample(3, j) for j in range(16)]
    dx = max(float((xs[j] - a[0]).abs().max() * dev.std.min()) * 255 for j, a in enumerate(alone))
    same_t = min(float((ys[j] == a[1]).float().mean()) for j, a in enumerate(alone))
    check(dx <= 1.0 + 1e-3 and same_t >= 0.999, f"batch vs alone: max |diff| {dx:.3f} levels, targets agree on "
          f">= {100 * same_t:.2f} %")

    # 6. Redraws: a field labelled only in its top-left 1200 x 900 pixels (of 2391 x 1931): about
    # three draws in four are redrawn (22 redraws over these 8 samples). A corner of 400 x 300 drew
    # 228, which the device sampler on the CPU took most of half an hour to redraw here and in 7.
    f0 = fields[0]
    labels = np.full_like(f0.labels, IGNORE)
    labels[:900, :1200] = f0.labels[:900, :1200]
    sparse = FieldData("sparse", f0.gsd_cm, labels, f0.image, f0.classes, f0.ignore)
    cpu6 = Sampler([sparse], spec, crop, 1.0, 3.0, "altitude", seed=11)
    dev6 = ds.DeviceSampler(cpu6, args.device)
    redrawn = 0
    for j in range(8):
        rng = np.random.default_rng((11, 0, j))
        while (cpu6.altitude_camera(rng)[1] != IGNORE).mean() < 0.05:
            redrawn += 1
    _, y6 = dev6.batch(0, 8)
    c6 = np.stack([cpu6.sample(0, j)[1] for j in range(8)])
    agree6 = float((y6.cpu().numpy() == c6).mean())
    labelled6 = float((y6 != IGNORE).float().mean((1, 2)).min())
    check(redrawn >= 8 and agree6 >= 0.995 and labelled6 >= 0.05,
          f"redraws: {redrawn} over 8 samples; targets agree with the CPU sampler's on {100 * agree6:.2f} %, "
          f"every crop >= 5 % labelled ({100 * labelled6:.1f} % the least)")

    # 7. The prefetcher: the same batches, in order; closed early; a failure reaches the consumer.
    direct = [dev6.batch(s, 4) for s in (5, 6, 7)]
    with ds.Prefetcher(dev6, 5, 8, 4, depth=2, thread=True) as pf:
        got = list(pf)
    same = len(got) == 3 and all(torch.equal(a[0], b[0]) and torch.equal(a[1], b[1]) for a, b in zip(direct, got))
    pf = ds.Prefetcher(dev6, 0, 1000, 2, depth=1, thread=True)
    next(iter(pf))
    pf.close()
    stopped = not pf._thread.is_alive()
    failed = False
    try:
        list(ds.Prefetcher(dev6, 0, 3, -1, depth=1, thread=True))  # a negative batch size cannot be made
    except RuntimeError as e:
        failed = e.__cause__ is not None
    check(same and stopped and failed, f"prefetcher: same batches in order {same}, stops when closed {stopped}, "
          f"failure raised in the consumer {failed}")
    print("device sampler:", "FAILED " + "; ".join(failures) if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
