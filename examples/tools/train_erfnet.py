#!/usr/bin/python3
"""Train ERFNet (Romera et al. 2017) for adaptseg's ERFNet backend and export it to ONNX.

The network sees exactly what adaptseg's simulated camera produces (SimulatedSensor,
include/adaptseg/simulated_sensor.hpp): the footprint of a camera (default 480x360 px) at a
GSD drawn uniformly from [gsd_min_factor, gsd_max_factor] x the field's gsd_cm is cut from the
orthomosaic, edges snapped to whole orthomosaic pixels, parts outside the orthomosaic filled
black / ignore, and the RGB resampled with cv::INTER_AREA to the camera size. The training
target is the oracle's label map (include/adaptseg/oracle_segmenter.hpp): per camera pixel the
area-weighted majority of the orthomosaic labels it covers, ignore pixels not voting, ties to
the lower class index, 255 where no valid pixel is covered. Random 256x256 crops of that
camera image with flips, 90-degree rotations and a mild photometric jitter form the batches;
CrossEntropy ignores label 255.

Validation runs on a held-out field at several GSD bands: the field is covered by a
lawnmower (as adaptseg::LawnmowerPlanner does) at each band and the mIoU over all classes is
computed (a) against the oracle at camera resolution (the training target) and (b) against
the orthomosaic labels at orthomosaic resolution (as adaptseg::image_confusion does).

Outputs (in --work-dir): checkpoint.pt (latest, for --resume), train_log.csv,
val_log.csv; at the end (or with --export-only) in --model-dir: model.onnx (fp32, opset 11,
input 1x3xHxW "input", output 1xCxHxW "logits"), model.yaml (metadata), model.pt (final
weights, state_dict), train_log.csv, val_log.csv.

The defaults are the first cycle of the committed model (examples/models/erfnet-dubai/
README.md, which gives both commands): train on dubai-tile-1,2,3,5, validate on dubai-tile-4,
never read dubai-tile-6 (the test field); half width, 1600 steps of 8 crops, one thread
(~55-60 min on an idle core); then --resume --extend 2400 --lr 1e-3 --warmup 20 --threads 2.

Usage:
  /usr/bin/python3 examples/tools/train_erfnet.py [--work-dir /tmp/erfnet-run] \\
      [--model-dir examples/models/erfnet-dubai]
  ... --resume             continue from WORK_DIR/checkpoint.pt after an interruption
  ... --resume --extend N --lr LR
                           train a finished run N steps more under a new learning-rate
                           cycle (peak LR); an interrupted extension resumes with --resume
  ... --export-only        re-export model.onnx/model.yaml/model.pt from the checkpoint
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F
import yaml

IGNORE = 255


# ---------------------------------------------------------------------------------------------
# ERFNet (Romera, Alvarez, Bergasa, Arroyo: "ERFNet: Efficient Residual Factorized ConvNet for
# Real-time Semantic Segmentation", T-ITS 2017), Table I, with a width multiplier on the
# channel counts 16/64/128.
# ---------------------------------------------------------------------------------------------
class DownsamplerBlock(nn.Module):
    """3x3 stride-2 conv (cout - cin channels) concatenated with 2x2 max-pooling, BN, ReLU."""

    def __init__(self, cin: int, cout: int):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout - cin, 3, stride=2, padding=1, bias=True)
        self.pool = nn.MaxPool2d(2, stride=2)
        self.bn = nn.BatchNorm2d(cout, eps=1e-3)

    def forward(self, x):
        return F.relu(self.bn(torch.cat([self.conv(x), self.pool(x)], 1)))


class NonBottleneck1D(nn.Module):
    """Residual block of factorised convolutions: 3x1, ReLU, 1x3, BN, ReLU, 3x1 and 1x3 with
    dilation d, BN, dropout, then ReLU(x + block(x))."""

    def __init__(self, ch: int, dropout: float, dilation: int):
        super().__init__()
        d = dilation
        self.conv3x1_1 = nn.Conv2d(ch, ch, (3, 1), padding=(1, 0), bias=True)
        self.conv1x3_1 = nn.Conv2d(ch, ch, (1, 3), padding=(0, 1), bias=True)
        self.bn1 = nn.BatchNorm2d(ch, eps=1e-3)
        self.conv3x1_2 = nn.Conv2d(ch, ch, (3, 1), padding=(d, 0), dilation=(d, 1), bias=True)
        self.conv1x3_2 = nn.Conv2d(ch, ch, (1, 3), padding=(0, d), dilation=(1, d), bias=True)
        self.bn2 = nn.BatchNorm2d(ch, eps=1e-3)
        self.dropout = nn.Dropout2d(dropout) if dropout > 0 else nn.Identity()

    def forward(self, x):
        y = F.relu(self.conv3x1_1(x))
        y = F.relu(self.bn1(self.conv1x3_1(y)))
        y = F.relu(self.conv3x1_2(y))
        y = self.dropout(self.bn2(self.conv1x3_2(y)))
        return F.relu(y + x)


class UpsamplerBlock(nn.Module):
    """3x3 transposed conv, stride 2, BN, ReLU."""

    def __init__(self, cin: int, cout: int):
        super().__init__()
        self.conv = nn.ConvTranspose2d(cin, cout, 3, stride=2, padding=1, output_padding=1, bias=True)
        self.bn = nn.BatchNorm2d(cout, eps=1e-3)

    def forward(self, x):
        return F.relu(self.bn(self.conv(x)))


def erfnet_channels(width: float) -> tuple[int, int, int]:
    return tuple(max(4, int(round(c * width))) for c in (16, 64, 128))  # type: ignore[return-value]


class ERFNet(nn.Module):
    """Encoder: downsampler 3->c1, downsampler c1->c2, 5 x NB1D(c2), downsampler c2->c3,
    2 x [NB1D(c3) with dilations 2, 4, 8, 16]. Decoder: upsampler c3->c2, 2 x NB1D(c2),
    upsampler c2->c1, 2 x NB1D(c1), 2x2 stride-2 transposed conv c1->classes.
    (c1, c2, c3) = (16, 64, 128) x width. Input H and W must be multiples of 8."""

    def __init__(self, num_classes: int, width: float = 1.0, drop_enc1: float = 0.03,
                 drop_enc2: float = 0.3):
        super().__init__()
        c1, c2, c3 = erfnet_channels(width)
        enc = [DownsamplerBlock(3, c1), DownsamplerBlock(c1, c2)]
        enc += [NonBottleneck1D(c2, drop_enc1, 1) for _ in range(5)]
        enc += [DownsamplerBlock(c2, c3)]
        for _ in range(2):
            enc += [NonBottleneck1D(c3, drop_enc2, d) for d in (2, 4, 8, 16)]
        dec = [UpsamplerBlock(c3, c2), NonBottleneck1D(c2, 0, 1), NonBottleneck1D(c2, 0, 1),
               UpsamplerBlock(c2, c1), NonBottleneck1D(c1, 0, 1), NonBottleneck1D(c1, 0, 1)]
        self.encoder = nn.Sequential(*enc)
        self.decoder = nn.Sequential(*dec)
        self.output_conv = nn.ConvTranspose2d(c1, num_classes, 2, stride=2, bias=True)

    def forward(self, x):
        return self.output_conv(self.decoder(self.encoder(x)))


# ---------------------------------------------------------------------------------------------
# Fields and the simulated camera (mirrors adaptseg's Field, SimulatedSensor, OracleSegmenter)
# ---------------------------------------------------------------------------------------------
@dataclass
class FieldData:
    name: str
    gsd_cm: float
    labels: np.ndarray  # HxW uint8
    image: np.ndarray   # HxWx3 uint8 BGR
    classes: list[str]
    ignore: int


def load_field(directory: Path) -> FieldData:
    meta = yaml.safe_load((directory / "field.yaml").read_text())
    labels = cv2.imread(str(directory / meta["labels"]), cv2.IMREAD_UNCHANGED)
    if labels is None or labels.ndim != 2 or labels.dtype != np.uint8:
        raise SystemExit(f"{directory}: cannot read an 8-bit label map {meta['labels']}")
    if "image" not in meta:
        raise SystemExit(f"{directory}: the field has no RGB image; it cannot train ERFNet")
    image = cv2.imread(str(directory / meta["image"]), cv2.IMREAD_COLOR)
    if image is None or image.shape[:2] != labels.shape:
        raise SystemExit(f"{directory}: cannot read {meta['image']} or its size differs from the labels")
    ignore = int(meta.get("ignore_label", 255))
    if ignore != IGNORE:
        labels = labels.copy()
        valid = labels != ignore
        labels[~valid] = IGNORE  # one ignore value in training: 255
    classes = [c["name"] for c in meta["classes"]]
    return FieldData(meta["name"], float(meta["gsd_cm"]), labels, image, classes, ignore)


def lround(v: float) -> int:
    """std::lround: half away from zero (Python's round() is half-to-even)."""
    return int(math.copysign(math.floor(abs(v) + 0.5), v))


def crop_fill(src: np.ndarray, c0: int, r0: int, w: int, h: int, fill) -> np.ndarray:
    """src[r0:r0+h, c0:c0+w] with `fill` outside src (SimulatedSensor::crop)."""
    out = np.empty((h, w) + src.shape[2:], src.dtype)
    out[...] = fill
    H, W = src.shape[:2]
    a0, a1 = max(c0, 0), min(c0 + w, W)
    b0, b1 = max(r0, 0), min(r0 + h, H)
    if a1 > a0 and b1 > b0:
        out[b0 - r0:b1 - r0, a0 - c0:a1 - c0] = src[b0:b1, a0:a1]
    return out


def oracle_labels(gt: np.ndarray, size_wh: tuple[int, int], num_classes: int) -> np.ndarray:
    """OracleSegmenter::segment: area-weighted majority per camera pixel, ignore not voting,
    ties to the lower index, 255 where no valid pixel."""
    w, h = size_wh
    if gt.shape[1] == w and gt.shape[0] == h:
        return gt.copy()
    best = np.zeros((h, w), np.float32)
    out = np.full((h, w), IGNORE, np.uint8)
    for c in range(num_classes):
        ind = gt == c
        if not ind.any():
            continue
        votes = cv2.resize(ind.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
        better = votes > best
        best[better] = votes[better]
        out[better] = c
    return out


def capture(field: FieldData, c0: int, r0: int, fw: int, fh: int, cam_wh: tuple[int, int]):
    """Camera image (BGR, cam size) and oracle target of the footprint rect (c0, r0, fw, fh)."""
    rgb = crop_fill(field.image, c0, r0, fw, fh, 0)
    rgb = cv2.resize(rgb, cam_wh, interpolation=cv2.INTER_AREA)
    gt = crop_fill(field.labels, c0, r0, fw, fh, IGNORE)
    return rgb, oracle_labels(gt, cam_wh, len(field.classes)), gt


def lawnmower_rects(field: FieldData, gsd_cm: float, cam_wh: tuple[int, int]):
    """Footprint pixel rects of LawnmowerPlanner::plan(field.area(), gsd) snapped by
    Field::pixel_rect (order does not matter for metrics)."""
    H, W = field.labels.shape
    g0 = field.gsd_cm
    fw_m, fh_m = cam_wh[0] * gsd_cm / 100.0, cam_wh[1] * gsd_cm / 100.0
    area_w, area_h = W * g0 / 100.0, H * g0 / 100.0
    nx = max(1, math.ceil(area_w / fw_m - 1e-9))
    ny = max(1, math.ceil(area_h / fh_m - 1e-9))
    s = 100.0 / g0
    rects = []
    for row in range(ny):
        y0 = row * fh_m
        for col in range(nx):
            x0 = col * fw_m
            c0, c1 = lround(x0 * s), lround((x0 + fw_m) * s)
            r0, r1 = lround(H - (y0 + fh_m) * s), lround(H - y0 * s)
            rects.append((c0, r0, c1 - c0, r1 - r0))
    return rects


# ---------------------------------------------------------------------------------------------
# Normalisation (shared with the C++ backend through model.yaml)
# ---------------------------------------------------------------------------------------------
def to_tensor(bgr: np.ndarray, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    """BGR uint8 HxWx3 -> normalised RGB float32 3xHxW: (v / 255 - mean) / std."""
    rgb = bgr[:, :, ::-1].astype(np.float32) / np.float32(255.0)
    return ((rgb - mean.astype(np.float32)) / std.astype(np.float32)).transpose(2, 0, 1).copy()


def channel_stats(fields: list[FieldData]) -> tuple[np.ndarray, np.ndarray]:
    s = np.zeros(3)
    s2 = np.zeros(3)
    n = 0
    for f in fields:
        px = f.image[f.labels != IGNORE][:, ::-1].astype(np.float64) / 255.0  # RGB
        s += px.sum(0)
        s2 += (px ** 2).sum(0)
        n += len(px)
    mean = s / n
    std = np.sqrt(s2 / n - mean ** 2)
    return mean, std


# ---------------------------------------------------------------------------------------------
# Training samples
# ---------------------------------------------------------------------------------------------
class Sampler:
    def __init__(self, fields, cam_wh, crop, fmin, fmax, mean, std, num_classes):
        self.fields = fields
        self.cam_wh = cam_wh
        self.crop = crop
        self.fmin, self.fmax = fmin, fmax
        self.mean, self.std = mean, std
        self.nc = num_classes
        area = np.array([float((f.labels != IGNORE).sum()) for f in fields])
        self.p = area / area.sum()

    def sample(self, rng: np.random.Generator):
        while True:
            f = self.fields[rng.choice(len(self.fields), p=self.p)]
            factor = rng.uniform(self.fmin, self.fmax)
            scale = factor  # footprint px per camera px
            fw = lround(self.cam_wh[0] * scale)
            fh = lround(self.cam_wh[1] * scale)
            H, W = f.labels.shape
            # Allow up to 25 % of the footprint outside the orthomosaic, as the last row /
            # column of a lawnmower does.
            c0 = int(rng.integers(-fw // 4, max(-fw // 4 + 1, W - 3 * fw // 4)))
            r0 = int(rng.integers(-fh // 4, max(-fh // 4 + 1, H - 3 * fh // 4)))
            rgb, target, _ = capture(f, c0, r0, fw, fh, self.cam_wh)
            cw, ch = self.cam_wh
            x = int(rng.integers(0, cw - self.crop + 1))
            y = int(rng.integers(0, ch - self.crop + 1))
            rgb = rgb[y:y + self.crop, x:x + self.crop]
            target = target[y:y + self.crop, x:x + self.crop]
            if (target != IGNORE).mean() < 0.05:
                continue
            if rng.random() < 0.5:
                rgb, target = rgb[:, ::-1], target[:, ::-1]
            if rng.random() < 0.5:
                rgb, target = rgb[::-1], target[::-1]
            k = int(rng.integers(0, 4))
            rgb, target = np.rot90(rgb, k), np.rot90(target, k)
            x = to_tensor(np.ascontiguousarray(rgb), self.mean, self.std)
            # Mild photometric jitter in normalised space: contrast and per-channel offset.
            x = x * np.float32(rng.uniform(0.9, 1.1)) + rng.uniform(-0.1, 0.1, (3, 1, 1)).astype(np.float32)
            return x, np.ascontiguousarray(target).astype(np.int64), factor

    def batch(self, rng, n):
        xs, ys = zip(*[self.sample(rng)[:2] for _ in range(n)])
        return torch.from_numpy(np.stack(xs)), torch.from_numpy(np.stack(ys))


# ---------------------------------------------------------------------------------------------
# Validation
# ---------------------------------------------------------------------------------------------
def confusion(truth: np.ndarray, pred: np.ndarray, nc: int) -> np.ndarray:
    """(nc) x (nc+1) counts over truth != ignore; prediction outside 0..nc-1 -> column nc."""
    m = truth != IGNORE
    t = truth[m].astype(np.int64)
    p = pred[m].astype(np.int64)
    p[p >= nc] = nc
    return np.bincount(t * (nc + 1) + p, minlength=nc * (nc + 1)).reshape(nc, nc + 1)


def miou(cm: np.ndarray) -> tuple[float, list]:
    """adaptseg ConfusionMatrix::miou_all: classes present in truth or prediction."""
    nc = cm.shape[0]
    ious = []
    for c in range(nc):
        tp = cm[c, c]
        fn = cm[c].sum() - tp
        fp = cm[:, c].sum() - tp
        u = tp + fn + fp
        ious.append(float(tp / u) if u > 0 else None)
    vals = [v for v in ious if v is not None]
    return (float(np.mean(vals)) if vals else float("nan")), ious


@torch.no_grad()
def evaluate(model, field: FieldData, factors, cam_wh, mean, std, nc, max_images=None):
    """Per band: mIoU vs the oracle at camera resolution, and vs the orthomosaic labels at
    orthomosaic resolution (adaptseg::image_confusion). Returns {factor: {...}}."""
    model.eval()
    out = {}
    for fac in factors:
        gsd = field.gsd_cm * fac
        cm_cam = np.zeros((nc, nc + 1), np.int64)
        cm_ortho = np.zeros((nc, nc + 1), np.int64)
        rects = [r for r in lawnmower_rects(field, gsd, cam_wh)]
        n_img = 0
        for (c0, r0, fw, fh) in rects:
            rgb, target, gt = capture(field, c0, r0, fw, fh, cam_wh)
            if (gt != IGNORE).sum() == 0:
                continue
            if max_images is not None and n_img >= max_images:
                break
            x = torch.from_numpy(to_tensor(rgb, mean, std))[None]
            pred = model(x)[0].argmax(0).numpy().astype(np.uint8)
            cm_cam += confusion(target, pred, nc)
            up = cv2.resize(pred, (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
            cm_ortho += confusion(gt, up, nc)
            n_img += 1
        m_cam, iou_cam = miou(cm_cam)
        m_ortho, iou_ortho = miou(cm_ortho)
        out[fac] = {"gsd_cm": gsd, "images": n_img, "miou_camera": m_cam, "miou_ortho": m_ortho,
                    "iou_ortho": iou_ortho, "iou_camera": iou_cam}
    model.train()
    return out


# ---------------------------------------------------------------------------------------------
# Inference graph for export: the same function, arranged for OpenCV DNN
# ---------------------------------------------------------------------------------------------
def _fold_bn(weight, bias, bn: nn.BatchNorm2d, reps: int):
    """Conv weight/bias followed by eval-mode `bn`, each BN channel covering `reps` conv
    output channels."""
    scale = bn.weight.detach() / torch.sqrt(bn.running_var + bn.eps)
    shift = bn.bias.detach() - bn.running_mean * scale
    s = scale.repeat_interleave(reps)
    return weight * s[:, None, None, None], bias * s + shift.repeat_interleave(reps)


def _pixel_shuffle_4d(y):
    """F.pixel_shuffle(y, 2) for batch 1 with 4-D reshapes/transposes only: OpenCV 4.6 runs
    ONNX DepthToSpace as a slow 6-D permute."""
    _, c4, h, w = y.shape
    c = c4 // 4
    y = y.reshape(c * 2, 2, h, w).permute(0, 2, 3, 1).reshape(c, 2, h, 2 * w)
    return y.permute(0, 2, 1, 3).reshape(1, c, 2 * h, 2 * w)


class SubPixelUpsampler(nn.Module):
    """A stride-2 ConvTranspose2d (kernel 3, padding 1, output_padding 1, or kernel 2,
    padding 0), optionally followed by BN and ReLU, rewritten exactly as an ordinary
    convolution producing the four output phases as channels, followed by a pixel shuffle.

    Kernel 3: output row 2m takes input row m with kernel row 1; output row 2m+1 takes input
    rows m (kernel row 2) and m+1 (kernel row 0); the same along columns. A 2x2 convolution
    with padding 1 whose output is cropped by one row/column at the top/left sees exactly the
    input window {m, m+1} (zero beyond the last row, as output_padding implies)."""

    def __init__(self, deconv: nn.ConvTranspose2d, bn: nn.BatchNorm2d | None, relu: bool):
        super().__init__()
        w = deconv.weight.detach()  # (cin, cout, kh, kw)
        cin, cout, kh, kw = w.shape
        if (kh, kw) == (3, 3) and deconv.stride == (2, 2) and deconv.padding == (1, 1) \
                and deconv.output_padding == (1, 1):
            k = torch.zeros(cout, 2, 2, cin, 2, 2)  # (o, phase y, phase x, c, window y, window x)
            taps = {(0, 0): 1, (1, 0): 2, (1, 1): 0}  # (phase, window offset) -> kernel index
            for (a, dy), ky in taps.items():
                for (b, dx), kx in taps.items():
                    k[:, a, b, :, dy, dx] = w[:, :, ky, kx].t()
            k = k.reshape(cout * 4, cin, 2, 2)
            self.crop = True
        elif (kh, kw) == (2, 2) and deconv.stride == (2, 2) and deconv.padding == (0, 0):
            k = w.permute(1, 2, 3, 0).reshape(cout * 4, cin, 1, 1)
            self.crop = False
        else:
            raise ValueError(f"unsupported ConvTranspose2d {deconv}")
        bias = deconv.bias.detach().repeat_interleave(4)
        if bn is not None:
            k, bias = _fold_bn(k, bias, bn, 4)
        self.conv = nn.Conv2d(cin, cout * 4, k.shape[-1], padding=1 if self.crop else 0)
        self.conv.weight.data.copy_(k)
        self.conv.bias.data.copy_(bias)
        self.relu = relu

    def forward(self, x):
        y = self.conv(x)
        if self.crop:
            y = y[:, :, 1:, 1:]
        if self.relu:
            y = F.relu(y)
        return _pixel_shuffle_4d(y)


class ERFNetInference(nn.Module):
    """`model` (in eval mode) with its transposed convolutions as SubPixelUpsampler: the same
    function up to float rounding (~1e-6). Tried as a way to avoid OpenCV DNN's Deconvolution
    layer; on the 2-core benchmark machine it was not measurably faster (docs/benchmarks.md),
    so the default export keeps ConvTranspose (--export-graph deconv). Batch 1 only."""

    def __init__(self, model: ERFNet):
        super().__init__()
        self.encoder = model.encoder
        self.decoder = nn.Sequential(*[SubPixelUpsampler(b.conv, b.bn, True) if isinstance(b, UpsamplerBlock)
                                       else b for b in model.decoder])
        self.output_conv = SubPixelUpsampler(model.output_conv, None, False)

    def forward(self, x):
        return self.output_conv(self.decoder(self.encoder(x)))


# ---------------------------------------------------------------------------------------------
# Export
# ---------------------------------------------------------------------------------------------
def export(model, ckpt, args, model_dir: Path, val_result):
    model_dir.mkdir(parents=True, exist_ok=True)
    model.eval()
    cw, ch = ckpt["camera_wh"]
    dummy = torch.zeros(1, 3, ch, cw)
    onnx_path = model_dir / "model.onnx"
    graph = ERFNetInference(model).eval() if args.export_graph == "subpixel" else model
    with warnings.catch_warnings():  # torch 1.13 warns about not folding the crop's Slice
        warnings.simplefilter("ignore", UserWarning)
        torch.onnx.export(graph, dummy, str(onnx_path), opset_version=11, input_names=["input"],
                          output_names=["logits"], do_constant_folding=True)
    torch.save(model.state_dict(), model_dir / "model.pt")
    # Check: OpenCV DNN loads the file and agrees with the trained PyTorch model.
    net = cv2.dnn.readNetFromONNX(str(onnx_path))
    rng = np.random.default_rng(1)
    x = rng.standard_normal((1, 3, ch, cw)).astype(np.float32)
    net.setInput(x)
    y_cv = net.forward()
    with torch.no_grad():
        y_pt = model(torch.from_numpy(x)).numpy()
    diff = float(np.abs(y_cv - y_pt).max())
    print(f"export ({args.export_graph}): OpenCV DNN vs PyTorch max |diff| = {diff:.3g}", flush=True)
    if diff > 1e-3:
        raise SystemExit("export check failed: OpenCV DNN output differs from PyTorch")
    meta = {
        "format": "adaptseg-erfnet-1",
        "architecture": "ERFNet (Romera et al. 2017), width multiplier applied to 16/64/128 channels",
        "width": float(ckpt["width"]),
        "channels": list(erfnet_channels(ckpt["width"])),
        "parameters": int(sum(p.numel() for p in model.parameters())),
        "classes": list(ckpt["classes"]),
        "ignore_label": IGNORE,
        "input": {"name": "input", "width": int(cw), "height": int(ch), "channel_order": "RGB",
                  "layout": "NCHW", "dtype": "float32",
                  "normalization": "(value / 255 - mean) / std, per channel, RGB order",
                  "mean": [float(v) for v in ckpt["mean"]], "std": [float(v) for v in ckpt["std"]]},
        "output": {"name": "logits", "layout": "NCHW", "activation": "none (apply softmax)"},
        "onnx_opset": 11,
        "onnx_graph": ("subpixel: transposed convolutions exported as convolution + 4-D pixel shuffle "
                       "(the same function)") if args.export_graph == "subpixel"
                      else "deconv: transposed convolutions exported as ConvTranspose",
        "training": {
            "fields": list(ckpt["train_fields"]),
            "validation_field": ckpt["val_field"],
            "held_out_test_field": args.test_field,
            "gsd_factor_range": [float(args.gsd_min_factor), float(args.gsd_max_factor)],
            "gsd_cm_range": [float(ckpt["gsd_cm_range"][0]), float(ckpt["gsd_cm_range"][1])],
            "steps": int(ckpt["step"]),
            "batch": int(args.batch),
            "crop": int(args.crop),
            "camera": list(ckpt["camera_wh"]),
            "samples_seen": int(ckpt["step"]) * int(args.batch),
            "train_minutes": round(float(ckpt["train_seconds"]) / 60.0, 1),
            "threads": int(args.threads),
            "seed": int(args.seed),
            "optimizer": f"Adam wd {args.weight_decay}; per learning-rate cycle linear warm-up to the "
                         "peak, then poly(0.9) decay to 0",
            "lr_cycles": [{k: (float(v) if k == "lr" else int(v)) for k, v in c.items()}
                          for c in ckpt.get("stages", [])],
            "dropout": [round(0.03 * ckpt["dropout_scale"], 4), round(0.3 * ckpt["dropout_scale"], 4)],
            "augmentation": "random 256x256 crops of camera images, flips, 90-degree rotations, "
                            "contrast x U(0.9, 1.1) and per-channel offset U(-0.1, 0.1) after normalisation",
            "class_weights": [float(v) for v in ckpt["class_weights"]],
            "torch_version": str(torch.__version__),
            "opencv_version": str(cv2.__version__),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        },
        "validation": {
            "field": ckpt["val_field"],
            "metric": "mIoU over all classes (present in truth or prediction), whole field by lawnmower per band",
            "bands": [{"gsd_factor": float(k), "gsd_cm": round(float(v["gsd_cm"]), 3),
                       "images": int(v["images"]),
                       "miou_camera": round(float(v["miou_camera"]), 4),
                       "miou_ortho": round(float(v["miou_ortho"]), 4)}
                      for k, v in sorted(val_result.items())],
        },
        "check": {"opencv_vs_pytorch_max_abs_diff": diff},
    }
    (model_dir / "model.yaml").write_text(
        "# ERFNet model metadata for adaptseg::ErfnetSegmenter (written by examples/tools/train_erfnet.py)\n"
        + yaml.safe_dump(meta, sort_keys=False, default_flow_style=None, width=100))
    for name in ("train_log.csv", "val_log.csv"):
        src = Path(args.work_dir) / name
        if src.exists():
            (model_dir / name).write_text(src.read_text())
    print(f"exported {onnx_path} and {model_dir / 'model.yaml'}", flush=True)


# ---------------------------------------------------------------------------------------------
def main(argv=None):
    here = Path(__file__).resolve().parent
    repo = here.parent.parent
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", default=str(repo / "examples" / "data"))
    ap.add_argument("--train-fields", default="dubai-tile-1,dubai-tile-2,dubai-tile-3,dubai-tile-5")
    ap.add_argument("--val-field", default="dubai-tile-4")
    ap.add_argument("--test-field", default="dubai-tile-6",
                    help="recorded in the metadata only; never read by this script")
    ap.add_argument("--work-dir", default="/tmp/erfnet-run")
    ap.add_argument("--model-dir", default=str(repo / "examples" / "models" / "erfnet-dubai"))
    ap.add_argument("--width", type=float, default=0.5)
    ap.add_argument("--steps", type=int, default=1600)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--crop", type=int, default=256)
    ap.add_argument("--camera", default="480x360", help="camera (= network input) WxH")
    ap.add_argument("--gsd-min-factor", type=float, default=1.0)
    ap.add_argument("--gsd-max-factor", type=float, default=3.0)
    ap.add_argument("--val-factors", default="1,1.5,2,2.5,3")
    ap.add_argument("--val-every", type=int, default=400)
    ap.add_argument("--val-max-images", type=int, default=0, help="0 = all images of a band")
    ap.add_argument("--ckpt-every", type=int, default=50)
    ap.add_argument("--log-every", type=int, default=10)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--dropout-scale", type=float, default=0.33,
                    help="multiplies the paper's dropout rates (0.03 in the first, 0.3 in the dilated blocks)")
    ap.add_argument("--weight-decay", type=float, default=1e-4)
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--resume", action="store_true", help="continue from WORK_DIR/checkpoint.pt")
    ap.add_argument("--extend", type=int, default=0, metavar="STEPS",
                    help="with --resume of a finished run: train STEPS more steps under a new "
                         "learning-rate cycle (warm-up to --lr, then poly decay; a warm restart)")
    ap.add_argument("--export-only", action="store_true", help="export WORK_DIR/checkpoint.pt and exit")
    ap.add_argument("--no-export", action="store_true")
    ap.add_argument("--export-graph", choices=("subpixel", "deconv"), default="deconv",
                    help="how transposed convolutions are written to ONNX (same function)")
    args = ap.parse_args(argv)

    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    work = Path(args.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    ckpt_path = work / "checkpoint.pt"
    cam_wh = tuple(int(v) for v in args.camera.lower().split("x"))
    if cam_wh[0] % 8 or cam_wh[1] % 8:
        raise SystemExit("--camera: ERFNet needs width and height that are multiples of 8")
    val_factors = [float(v) for v in args.val_factors.split(",")]

    data = Path(args.data_dir)
    train_names = [s for s in args.train_fields.split(",") if s]
    if args.test_field in train_names or args.test_field == args.val_field:
        raise SystemExit("the test field must not be used for training or validation")
    t0 = time.time()
    train_fields = [load_field(data / n) for n in train_names]
    val_field = load_field(data / args.val_field)
    classes = train_fields[0].classes
    for f in train_fields + [val_field]:
        if f.classes != classes:
            raise SystemExit(f"field {f.name}: classes {f.classes} differ from {classes}")
    nc = len(classes)
    print(f"loaded {len(train_fields)} training fields + {val_field.name} in {time.time() - t0:.1f} s; "
          f"classes {classes}", flush=True)

    if args.extend < 0 or (args.extend and not args.resume):
        raise SystemExit("--extend needs --resume and a step count >= 0")
    resume = (args.resume or args.export_only) and ckpt_path.exists()
    if (args.resume or args.export_only) and not resume:
        if args.export_only:
            raise SystemExit(f"--export-only: no checkpoint at {ckpt_path}")
        print(f"--resume: no checkpoint at {ckpt_path}, starting from scratch", flush=True)

    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    if resume:
        ckpt = torch.load(ckpt_path, map_location="cpu")
        width = ckpt["width"]
        if ckpt["classes"] != classes:
            raise SystemExit("checkpoint classes differ from the fields' classes")
    else:
        width = args.width
        mean, std = channel_stats(train_fields)
        counts = np.zeros(nc)
        for f in train_fields:
            counts += np.bincount(f.labels.ravel(), minlength=256)[:nc]
        freq = counts / counts.sum()
        # ENet-style weights 1 / ln(c + p), softened (c = 1.10) to keep the rare classes
        # from dominating a short training run.
        class_weights = 1.0 / np.log(1.10 + freq)
        class_weights = class_weights / class_weights.mean()
        ckpt = {"step": 0, "width": width, "classes": classes, "mean": mean.tolist(),
                "std": std.tolist(), "class_weights": class_weights.tolist(),
                "train_fields": train_names, "val_field": args.val_field, "camera_wh": list(cam_wh),
                "gsd_cm_range": [train_fields[0].gsd_cm * args.gsd_min_factor,
                                 train_fields[0].gsd_cm * args.gsd_max_factor],
                "train_seconds": 0.0, "last_val": None}
    mean = np.array(ckpt["mean"])
    std = np.array(ckpt["std"])
    dscale = ckpt.setdefault("dropout_scale", args.dropout_scale)
    model = ERFNet(nc, width, 0.03 * dscale, 0.3 * dscale)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr, weight_decay=args.weight_decay)
    if resume:
        model.load_state_dict(ckpt["model"])
        opt.load_state_dict(ckpt["optimizer"])
        torch.set_rng_state(ckpt["torch_rng"])
        rng.bit_generator.state = ckpt["numpy_rng"]
        print(f"resumed from {ckpt_path} at step {ckpt['step']}", flush=True)
    # Learning-rate cycles: the first from step 0 to --steps (--lr, --warmup); each --extend
    # appends one. The checkpoint keeps them, so --resume continues the schedule it was in.
    stages = ckpt.setdefault("stages", [{"start": 0, "end": args.steps, "lr": args.lr,
                                         "warmup": args.warmup}])
    if args.extend:
        if ckpt["step"] != stages[-1]["end"]:
            raise SystemExit(f"--extend: the checkpoint is at step {ckpt['step']}, inside its last "
                             f"learning-rate cycle (ends at {stages[-1]['end']}); finish it with --resume first")
        stages.append({"start": ckpt["step"], "end": ckpt["step"] + args.extend, "lr": args.lr,
                       "warmup": args.warmup})
        print(f"extending by {args.extend} steps: new learning-rate cycle, peak {args.lr:g}", flush=True)
    total_steps = stages[-1]["end"]
    print(f"ERFNet width {width}: channels {erfnet_channels(width)}, "
          f"{sum(p.numel() for p in model.parameters())} parameters; mean {np.round(mean, 4).tolist()} "
          f"std {np.round(std, 4).tolist()}; class weights {np.round(ckpt['class_weights'], 3).tolist()}",
          flush=True)

    if args.export_only:
        val = ckpt.get("last_val") or evaluate(model, val_field, val_factors, cam_wh, mean, std, nc)
        export(model, ckpt, args, Path(args.model_dir), {float(k): v for k, v in val.items()})
        return 0

    sampler = Sampler(train_fields, cam_wh, args.crop, args.gsd_min_factor, args.gsd_max_factor,
                      mean, std, nc)
    criterion = nn.CrossEntropyLoss(weight=torch.tensor(ckpt["class_weights"], dtype=torch.float32),
                                    ignore_index=IGNORE)
    train_log = work / "train_log.csv"
    val_log = work / "val_log.csv"
    if not resume:
        train_log.write_text("step,elapsed_s,loss,lr,img_per_s\n")
        val_log.write_text("step,elapsed_s,gsd_factor,gsd_cm,images,miou_camera,miou_ortho\n")
    else:  # drop log rows written after the checkpoint: they will be redone
        for log in (train_log, val_log):
            if log.exists():
                lines = log.read_text().splitlines(keepends=True)
                log.write_text("".join(lines[:1] + [ln for ln in lines[1:] if int(ln.split(",")[0]) <= ckpt["step"]]))

    def lr_at(step):
        st = next(c for c in stages if c["start"] <= step < c["end"])
        i, n, w = step - st["start"], st["end"] - st["start"], st["warmup"]
        if i < w:
            return st["lr"] * (i + 1) / w
        return st["lr"] * (1.0 - (i - w) / max(1, n - w)) ** 0.9

    def save_checkpoint():
        ckpt.update({"model": model.state_dict(), "optimizer": opt.state_dict(),
                     "torch_rng": torch.get_rng_state(), "numpy_rng": rng.bit_generator.state})
        tmp = ckpt_path.with_suffix(".tmp")
        torch.save(ckpt, tmp)
        os.replace(tmp, ckpt_path)

    def validate(step):
        tv = time.time()
        res = evaluate(model, val_field, val_factors, cam_wh, mean, std, nc,
                       args.val_max_images or None)
        with val_log.open("a") as fh:
            for fac, r in res.items():
                fh.write(f"{step},{ckpt['train_seconds']:.1f},{fac},{r['gsd_cm']:.3f},{r['images']},"
                         f"{r['miou_camera']:.4f},{r['miou_ortho']:.4f}\n")
        summary = " ".join(f"x{fac:g}:{r['miou_camera']:.3f}/{r['miou_ortho']:.3f}" for fac, r in res.items())
        print(f"[val step {step}] mIoU camera/ortho per GSD factor: {summary} ({time.time() - tv:.0f} s)",
              flush=True)
        ckpt["last_val"] = {str(k): v for k, v in res.items()}
        return res

    model.train()
    step = ckpt["step"]
    run_loss, run_n, t_log = 0.0, 0, time.time()
    while step < total_steps:
        ts = time.time()
        lr = lr_at(step)
        for g in opt.param_groups:
            g["lr"] = lr
        x, y = sampler.batch(rng, args.batch)
        loss = criterion(model(x), y)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        step += 1
        ckpt["step"] = step
        ckpt["train_seconds"] += time.time() - ts
        run_loss += float(loss)
        run_n += 1
        if step % args.log_every == 0 or step == total_steps:
            ips = run_n * args.batch / (time.time() - t_log)
            with train_log.open("a") as fh:
                fh.write(f"{step},{ckpt['train_seconds']:.1f},{run_loss / run_n:.5f},{lr:.3e},{ips:.2f}\n")
            eta = (total_steps - step) * (time.time() - t_log) / run_n / 60
            print(f"step {step}/{total_steps} loss {run_loss / run_n:.4f} lr {lr:.2e} {ips:.2f} img/s "
                  f"elapsed {ckpt['train_seconds'] / 60:.1f} min, eta {eta:.1f} min", flush=True)
            run_loss, run_n, t_log = 0.0, 0, time.time()
        if step % args.val_every == 0 and step < total_steps:
            validate(step)
            t_log = time.time()
        if step % args.ckpt_every == 0:
            save_checkpoint()
    val = validate(step)
    save_checkpoint()
    print(f"training done: {step} steps, {ckpt['train_seconds'] / 60:.1f} min of training", flush=True)
    if not args.no_export:
        export(model, ckpt, args, Path(args.model_dir), val)
    return 0


if __name__ == "__main__":
    sys.exit(main())
