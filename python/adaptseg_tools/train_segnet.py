"""Train a segmentation network for adaptseg's ONNX backend (adaptseg::ErfnetSegmenter) and
export it: ERFNet from scratch (--arch erfnet) or MobileNetV2 with ImageNet weights and a
light decoder (--arch mobilenetv2, adaptseg_tools.mobilenet_v2).

The network sees exactly what adaptseg's simulated camera produces (SimulatedSensor,
include/adaptseg/vision/simulated_sensor.hpp): the footprint of a camera (default 480x360 px) at a
GSD drawn uniformly from [gsd_min_factor, gsd_max_factor] x the field's gsd_cm is cut from the
orthomosaic, edges snapped to whole orthomosaic pixels, parts outside the orthomosaic filled
black / ignore, and the RGB resampled with cv::INTER_AREA to the camera size. The training
target is the oracle's label map (include/adaptseg/vision/oracle_segmenter.hpp): per camera pixel the
area-weighted majority of the orthomosaic labels it covers, ignore pixels not voting, ties to
the lower class index, 255 where no valid pixel is covered. CrossEntropy ignores label 255.

Then the backend's own path: the camera image is resampled to the network input size when the
two differ (INTER_AREA shrinking, INTER_LINEAR enlarging) and the logits, which a network may
give at a fraction of its input size (its output stride), are resampled bilinearly back to
the camera size, where the loss is taken. Validation and export checks run that path too.

Augmentations (--augment):
  mild      ERFNet's original recipe: random 256x256 crops of the camera image, flips,
            90-degree rotations, contrast / offset jitter after normalisation.
  altitude  what changes with altitude and scene: the camera yawed by a quarter turn (a
            transposed footprint, rotated) and mirrored; colour (brightness, contrast,
            saturation, hue, white balance, gamma), blur, sensor noise and JPEG compression,
            each drawn per image; crops of --crop camera pixels, scaled like the whole image.

Samples are a function of (seed, step, index in batch) only, so a run resumed from a checkpoint
sees the same batches, however many data workers (--workers) produce them. --sampler device
makes the `altitude` batches on the training device instead of in CPU workers (device_sampler.py:
the same draws and resampling, different rounding; for a GPU, whose pace the CPU workers set),
a whole batch at a time, --prefetch steps ahead by a thread on a CUDA stream of its own.

Devices: --device cuda runs the network in bfloat16 autocast with channels-last tensors and
data workers; --device cpu in float32. A checkpoint written on one continues on the other.
--max-minutes stops a run with a checkpoint before a wall-clock limit (for sessions of
limited length); --resume continues it. --minutes M instead fits the learning-rate cycle into M
minutes: at the end of the warm-up the cycle's length (at most --steps) is set from the
measured time per step and of one validation, so that the whole schedule, annealing
included, ends in time (for a lease of an accelerator of unknown speed).

Weight averaging (--ema DECAY): the run also keeps an exponential moving average of the weights
(and batch-norm statistics), validates it next to the trained weights (val_ema_log.csv) and
exports the average instead of the last step's weights; averaged weights tend to sit in flatter
minima that transfer better to unseen scenes (Izmailov et al., UAI 2018; Cha et al., SWAD,
NeurIPS 2021).

Outputs (in --work-dir): checkpoint.pt (latest, for --resume), train_log.csv, val_log.csv
(val_ema_log.csv with --ema); at the end (or with --export-only) in --model-dir: model.onnx
(fp32, input 1x3xHxW "input", output 1xCx(H/s)x(W/s) "logits"), model.yaml (metadata),
model.pt (final weights, state_dict), train_log.csv, val_log.csv (val_ema_log.csv).

Split: train on dubai-tile-1,2,3,5, validate on dubai-tile-4; dubai-tile-6 (the test field)
is never read by this script. The commands of the bundled models are in their READMEs
(examples/models/*/README.md).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.train_segnet --arch mobilenetv2 --work-dir W --model-dir M ...
  ... --resume             continue from WORK_DIR/checkpoint.pt after an interruption
  ... --resume --extend N --lr LR
                           train a finished run N steps more under a new learning-rate
                           cycle (peak LR); an interrupted extension resumes with --resume
  ... --export-only        re-export model.onnx/model.yaml/model.pt from the checkpoint
  ... --init-weights DIR   a new run from the weights of an exported model (DIR/model.pt), e.g. a
                           bundled model trained further in a later session
"""

from __future__ import annotations

import argparse
import copy
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

from . import REPO, device_sampler, mobilenet_v2
from .erfnet import ERFNet, ERFNetInference, erfnet_channels

IGNORE = 255
ARCHS = ("erfnet", "mobilenetv2")


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
        raise SystemExit(f"{directory}: the field has no RGB image; it cannot train a network")
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
# The backend's path: camera image -> network input -> logits at camera size
# (mirrors ErfnetSegmenter::logits in include/adaptseg/erfnet/erfnet_segmenter.hpp)
# ---------------------------------------------------------------------------------------------
@dataclass
class NetSpec:
    arch: str
    camera_wh: tuple[int, int]
    input_wh: tuple[int, int]  # network input for a whole camera image
    stride: int                # logits are input / stride
    mean: np.ndarray           # RGB, on v / 255
    std: np.ndarray


def to_network_size(bgr: np.ndarray, wh: tuple[int, int]) -> np.ndarray:
    if (bgr.shape[1], bgr.shape[0]) == tuple(wh):
        return bgr
    shrink = bgr.shape[1] > wh[0]
    return cv2.resize(bgr, tuple(wh), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)


def to_tensor(bgr: np.ndarray, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    """BGR uint8 HxWx3 -> normalised RGB float32 3xHxW: (v / 255 - mean) / std."""
    rgb = bgr[:, :, ::-1].astype(np.float32) / np.float32(255.0)
    return ((rgb - mean.astype(np.float32)) / std.astype(np.float32)).transpose(2, 0, 1).copy()


def logits_to(logits: torch.Tensor, hw: tuple[int, int]) -> torch.Tensor:
    """Bilinear resampling of N x C x h x w logits to hw (= cv::resize INTER_LINEAR)."""
    if tuple(logits.shape[-2:]) == tuple(hw):
        return logits
    return F.interpolate(logits, size=tuple(hw), mode="bilinear", align_corners=False)


def predict_labels(model, bgr: np.ndarray, spec: NetSpec, device) -> np.ndarray:
    """Labels of a camera image as ErfnetSegmenter::segment gives them (argmax, no masking)."""
    x = torch.from_numpy(to_tensor(to_network_size(bgr, spec.input_wh), spec.mean, spec.std))[None]
    logits = model(x.to(device)).float()
    return logits_to(logits, bgr.shape[:2])[0].argmax(0).cpu().numpy().astype(np.uint8)


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
def photometric(bgr: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """What differs between flights and scenes, on the 8-bit camera image: brightness, contrast,
    saturation, hue, white balance and gamma; then, each with probability 0.3, Gaussian blur
    (defocus, motion), sensor noise and JPEG compression."""
    img = bgr.astype(np.float32)
    gray = img.mean(axis=2, keepdims=True)
    img = gray + (img - gray) * rng.uniform(0.7, 1.3)                       # saturation
    img = (img - 128.0) * rng.uniform(0.75, 1.25) + 128.0 + rng.uniform(-20, 20)  # contrast, brightness
    img = img * rng.uniform(0.92, 1.08, 3).astype(np.float32)                # white balance
    img = 255.0 * (np.clip(img, 0, 255) / 255.0) ** rng.uniform(0.8, 1.25)   # gamma
    out = np.clip(img + 0.5, 0, 255).astype(np.uint8)
    if rng.random() < 0.5:                                                   # hue
        hsv = cv2.cvtColor(out, cv2.COLOR_BGR2HSV)
        hsv[:, :, 0] = ((hsv[:, :, 0].astype(np.int16) + int(rng.integers(-5, 6))) % 180).astype(np.uint8)
        out = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)
    if rng.random() < 0.3:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.3, 1.2))
    if rng.random() < 0.3:
        noise = rng.normal(0.0, rng.uniform(1.0, 6.0), out.shape)
        out = np.clip(out.astype(np.float32) + noise + 0.5, 0, 255).astype(np.uint8)
    if rng.random() < 0.3:
        ok, enc = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(40, 91))])
        out = cv2.imdecode(enc, cv2.IMREAD_COLOR)
    return out


class Sampler:
    """Sample `index` of step `step` is drawn from np.random.default_rng((seed, step, index))."""

    def __init__(self, fields, spec: NetSpec, crop, fmin, fmax, augment, seed):
        self.fields = fields
        self.spec = spec
        self.crop = crop
        self.fmin, self.fmax = fmin, fmax
        self.augment = augment
        self.seed = seed
        self.nc = len(fields[0].classes)
        area = np.array([float((f.labels != IGNORE).sum()) for f in fields])
        self.p = area / area.sum()

    def footprint(self, rng, transpose):
        f = self.fields[rng.choice(len(self.fields), p=self.p)]
        factor = rng.uniform(self.fmin, self.fmax)
        cw, ch = self.spec.camera_wh
        fw, fh = lround(cw * factor), lround(ch * factor)
        if transpose:
            fw, fh = fh, fw
        H, W = f.labels.shape
        # Allow up to 25 % of the footprint outside the orthomosaic, as the last row /
        # column of a lawnmower does.
        c0 = int(rng.integers(-fw // 4, max(-fw // 4 + 1, W - 3 * fw // 4)))
        r0 = int(rng.integers(-fh // 4, max(-fh // 4 + 1, H - 3 * fh // 4)))
        return f, c0, r0, fw, fh

    def sample_mild(self, rng):
        spec = self.spec
        f, c0, r0, fw, fh = self.footprint(rng, False)
        rgb, target, _ = capture(f, c0, r0, fw, fh, spec.camera_wh)
        cw, ch = spec.camera_wh
        x = int(rng.integers(0, cw - self.crop + 1))
        y = int(rng.integers(0, ch - self.crop + 1))
        rgb = rgb[y:y + self.crop, x:x + self.crop]
        target = target[y:y + self.crop, x:x + self.crop]
        if (target != IGNORE).mean() < 0.05:
            return None
        if rng.random() < 0.5:
            rgb, target = rgb[:, ::-1], target[:, ::-1]
        if rng.random() < 0.5:
            rgb, target = rgb[::-1], target[::-1]
        k = int(rng.integers(0, 4))
        rgb, target = np.rot90(rgb, k), np.rot90(target, k)
        x = to_tensor(np.ascontiguousarray(rgb), spec.mean, spec.std)
        # Mild photometric jitter in normalised space: contrast and per-channel offset.
        x = x * np.float32(rng.uniform(0.9, 1.1)) + rng.uniform(-0.1, 0.1, (3, 1, 1)).astype(np.float32)
        return x, np.ascontiguousarray(target).astype(np.int64)

    def altitude_camera(self, rng):
        """The geometric part of sample_altitude: the camera image (BGR uint8) and oracle target
        of one crop, before the labelled-share check and the photometric augmentation."""
        spec = self.spec
        k = int(rng.integers(0, 4))  # camera yaw in quarter turns
        f, c0, r0, fw, fh = self.footprint(rng, k % 2 == 1)
        rgb = np.rot90(crop_fill(f.image, c0, r0, fw, fh, 0), k)
        gt = np.rot90(crop_fill(f.labels, c0, r0, fw, fh, IGNORE), k)
        if rng.random() < 0.5:
            rgb, gt = rgb[:, ::-1], gt[:, ::-1]
        cam = cv2.resize(np.ascontiguousarray(rgb), spec.camera_wh, interpolation=cv2.INTER_AREA)
        target = oracle_labels(np.ascontiguousarray(gt), spec.camera_wh, self.nc)
        # A crop of the camera image, fed at the scale the whole image has in the network.
        cw, ch = spec.camera_wh
        ccw, cch = min(self.crop, cw), min(self.crop, ch)
        x = int(rng.integers(0, cw - ccw + 1))
        y = int(rng.integers(0, ch - cch + 1))
        return cam[y:y + cch, x:x + ccw], target[y:y + cch, x:x + ccw]

    def sample_altitude(self, rng):
        spec = self.spec
        cam, target = self.altitude_camera(rng)
        if (target != IGNORE).mean() < 0.05:
            return None
        black = (cam == 0).all(axis=2)  # no-data pixels stay exactly black (the backend masks them)
        cam = photometric(cam, rng)
        cam[black] = 0
        net = to_network_size(cam, self.network_size(cam.shape[1], cam.shape[0]))
        return to_tensor(net, spec.mean, spec.std), target.astype(np.int64)

    def network_size(self, w: int, h: int) -> tuple[int, int]:
        """Network pixels (w, h) of a crop of w x h camera pixels: the scale the whole camera
        image has in the network."""
        (cw, ch), (iw, ih) = self.spec.camera_wh, self.spec.input_wh
        return lround(w * iw / cw), lround(h * ih / ch)

    def sample(self, step: int, index: int):
        rng = np.random.default_rng((self.seed, step, index))
        draw = self.sample_mild if self.augment == "mild" else self.sample_altitude
        while True:
            s = draw(rng)
            if s is not None:
                return s


class StepBatches(torch.utils.data.Dataset):
    """Item i = the batch of step first_step + i (a DataLoader with batch_size=None)."""

    def __init__(self, sampler: Sampler, first_step: int, last_step: int, batch: int):
        self.sampler, self.first, self.n, self.batch = sampler, first_step, last_step - first_step, batch

    def __len__(self):
        return self.n

    def __getitem__(self, i):
        step = self.first + i
        xs, ys = zip(*[self.sampler.sample(step, j) for j in range(self.batch)])
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
def evaluate(model, field: FieldData, factors, spec: NetSpec, max_images=None, device="cpu", on_image=None):
    """Per band: mIoU vs the oracle at camera resolution, and vs the orthomosaic labels at
    orthomosaic resolution (adaptseg::image_confusion). Returns {factor: {...}}. With
    `on_image`, also calls on_image(factor, gt, confusion) for every image scored: its
    orthomosaic labels and its confusion matrix against them."""
    was_training = model.training
    model.eval()
    nc = len(field.classes)
    out = {}
    for fac in factors:
        gsd = field.gsd_cm * fac
        cm_cam = np.zeros((nc, nc + 1), np.int64)
        cm_ortho = np.zeros((nc, nc + 1), np.int64)
        n_img = 0
        for (c0, r0, fw, fh) in lawnmower_rects(field, gsd, spec.camera_wh):
            rgb, target, gt = capture(field, c0, r0, fw, fh, spec.camera_wh)
            if (gt != IGNORE).sum() == 0:
                continue
            if max_images is not None and n_img >= max_images:
                break
            pred = predict_labels(model, rgb, spec, device)
            cm_cam += confusion(target, pred, nc)
            up = cv2.resize(pred, (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
            image_cm = confusion(gt, up, nc)
            cm_ortho += image_cm
            if on_image is not None:
                on_image(fac, gt, image_cm)
            n_img += 1
        m_cam, iou_cam = miou(cm_cam)
        m_ortho, iou_ortho = miou(cm_ortho)
        out[fac] = {"gsd_cm": gsd, "images": n_img, "miou_camera": m_cam, "miou_ortho": m_ortho,
                    "iou_ortho": iou_ortho, "iou_camera": iou_cam}
    model.train(was_training)
    return out


# ---------------------------------------------------------------------------------------------
# Networks
# ---------------------------------------------------------------------------------------------
def build_model(ckpt: dict, nc: int) -> nn.Module:
    if ckpt["arch"] == "erfnet":
        d = ckpt["dropout_scale"]
        return ERFNet(nc, ckpt["width"], 0.03 * d, 0.3 * d)
    return mobilenet_v2.MobileNetV2Seg(nc, ckpt["dropout"], image_pooling=ckpt.get("image_pooling", False))


def frozen_encoder_modules(model, frozen_blocks: int):
    """The MobileNetV2 stem and its first frozen_blocks - 1 blocks (frozen_blocks counts the stem)."""
    if frozen_blocks <= 0:
        return []
    return [model.encoder.stem] + list(model.encoder.blocks[:frozen_blocks - 1])


def set_train_mode(model, ckpt):
    """train() with the MobileNetV2 encoder's batch norms kept on their ImageNet statistics
    (batches of a few images cannot estimate them better)."""
    model.train()
    if ckpt["arch"] == "mobilenetv2":
        for m in model.encoder.modules():
            if isinstance(m, nn.BatchNorm2d):
                m.eval()


# ---------------------------------------------------------------------------------------------
# Export
# ---------------------------------------------------------------------------------------------
def export(model, ckpt, args, model_dir: Path, val_result):
    model_dir.mkdir(parents=True, exist_ok=True)
    model = model.to("cpu", memory_format=torch.contiguous_format).float().eval()
    spec = net_spec(ckpt)
    iw, ih = spec.input_wh
    dummy = torch.zeros(1, 3, ih, iw)
    onnx_path = model_dir / "model.onnx"
    if ckpt["arch"] == "erfnet":
        graph = ERFNetInference(model).eval() if args.export_graph == "subpixel" else model
        opset = 11
    else:
        graph = model
        opset = 10  # OpenCV 4.6 reads ReLU6 as opset-10 Clip (attributes), not opset-11 Clip (inputs)
    with warnings.catch_warnings():  # torch 1.13 warns about not folding the crop's Slice
        warnings.simplefilter("ignore", UserWarning)
        torch.onnx.export(graph, dummy, str(onnx_path), opset_version=opset, input_names=["input"],
                          output_names=["logits"], do_constant_folding=True)
    torch.save(model.state_dict(), model_dir / "model.pt")
    # Check: OpenCV DNN loads the file and agrees with the trained PyTorch model.
    net = cv2.dnn.readNetFromONNX(str(onnx_path))
    rng = np.random.default_rng(1)
    x = rng.standard_normal((1, 3, ih, iw)).astype(np.float32)
    net.setInput(x)
    y_cv = net.forward()
    with torch.no_grad():
        y_pt = model(torch.from_numpy(x)).numpy()
    if y_cv.shape != y_pt.shape:
        raise SystemExit(f"export check failed: OpenCV DNN output {y_cv.shape} vs PyTorch {y_pt.shape}")
    diff = float(np.abs(y_cv - y_pt).max())
    print(f"export: OpenCV DNN vs PyTorch max |diff| = {diff:.3g}", flush=True)
    if diff > 1e-3:
        raise SystemExit("export check failed: OpenCV DNN output differs from PyTorch")
    if ckpt["arch"] == "erfnet":
        arch = {"architecture": "ERFNet (Romera et al. 2017), width multiplier applied to 16/64/128 channels",
                "width": float(ckpt["width"]), "channels": list(erfnet_channels(ckpt["width"])),
                "onnx_graph": ("subpixel: transposed convolutions exported as convolution + 4-D pixel "
                               "shuffle (the same function)") if args.export_graph == "subpixel"
                else "deconv: transposed convolutions exported as ConvTranspose"}
        dropout = [round(0.03 * ckpt["dropout_scale"], 4), round(0.3 * ckpt["dropout_scale"], 4)]
    else:
        arch = {"architecture": "MobileNetV2 encoder (Sandler et al. 2018, width 1.0, stem .. block_10, "
                                "ImageNet weights from npm nsfwjs 4.3.0) + DeepLabv3+-style separable "
                                "decoder (examples/tools/mobilenet_v2.py)",
                "encoder_frozen_blocks": int(ckpt["frozen_blocks"]),
                "image_pooling": bool(ckpt.get("image_pooling", False)),
                "encoder_lr_scale": float(ckpt["encoder_lr_scale"])}
        dropout = [float(ckpt["dropout"])]
    meta = {
        "format": "adaptseg-segnet-1",
        "arch": ckpt["arch"],
        **arch,
        "parameters": int(sum(p.numel() for p in model.parameters())),
        "classes": list(ckpt["classes"]),
        "ignore_label": IGNORE,
        "input": {"name": "input", "width": int(iw), "height": int(ih), "channel_order": "RGB",
                  "layout": "NCHW", "dtype": "float32",
                  "normalization": "(value / 255 - mean) / std, per channel, RGB order",
                  "mean": [float(v) for v in ckpt["mean"]], "std": [float(v) for v in ckpt["std"]]},
        "output": {"name": "logits", "layout": "NCHW", "stride": int(spec.stride),
                   "activation": "none (apply softmax)"},
        "onnx_opset": opset,
        "training": {
            "fields": list(ckpt["train_fields"]),
            "validation_field": ckpt["val_field"],
            "held_out_test_field": args.test_field,
            "gsd_factor_range": [float(v) for v in ckpt["gsd_factor_range"]],
            "gsd_cm_range": [float(ckpt["gsd_cm_range"][0]), float(ckpt["gsd_cm_range"][1])],
            "steps": int(ckpt["step"]),
            "batch": int(ckpt["batch"]),
            "crop": int(ckpt["crop"]),
            "camera": list(ckpt["camera_wh"]),
            "samples_seen": int(ckpt["step"]) * int(ckpt["batch"]),
            "train_minutes": round(float(ckpt["train_seconds"]) / 60.0, 1),
            "devices": sorted(set(ckpt.get("devices", []))),
            "seed": int(ckpt["seed"]),
            "weights": (f"exponential moving average of the trained weights, decay {ckpt['ema_decay']:g}"
                        if ckpt.get("ema_decay") else "the trained weights at the last step"),
            "initialised_from": ckpt.get("init_weights", "ImageNet encoder" if ckpt["arch"] == "mobilenetv2"
                                         else "random"),
            "optimizer": f"{ckpt['optimizer']} wd {ckpt['weight_decay']}; per learning-rate cycle linear "
                         "warm-up to the peak, then poly(0.9) decay to 0",
            "lr_cycles": [{k: (int(v) if k in ("start", "end", "warmup", "fitted_steps") else float(v))
                           for k, v in c.items()} for c in ckpt.get("stages", [])],
            "dropout": dropout,
            "augmentation": ckpt["augment"],
            "sampler": ckpt.get("sampler", "cpu"),
            "class_weights": [float(v) for v in ckpt["class_weights"]],
            "torch_version": str(torch.__version__),  # of the export
            **({"train_torch_versions": sorted(ckpt["torch_versions"])} if ckpt.get("torch_versions") else {}),
            "opencv_version": str(cv2.__version__),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        },
        "validation": {
            "field": ckpt["val_field"],
            "metric": "mIoU over all classes (present in truth or prediction), whole field by lawnmower per band",
            "bands": [{"gsd_factor": float(k), "gsd_cm": round(float(v["gsd_cm"]), 3),
                       "images": int(v["images"]),
                       "miou_camera": round(float(v["miou_camera"]), 4),
                       "miou_ortho": round(float(v["miou_ortho"]), 4),
                       "iou_ortho": [None if u is None else round(float(u), 4) for u in v["iou_ortho"]]}
                      for k, v in sorted(val_result.items())],
        },
        "check": {"opencv_vs_pytorch_max_abs_diff": diff},
    }
    (model_dir / "model.yaml").write_text(
        "# Segmentation model metadata for adaptseg::ErfnetSegmenter (written by examples/tools/train_segnet.py)\n"
        + yaml.safe_dump(meta, sort_keys=False, default_flow_style=None, width=100))
    for name in ("train_log.csv", "val_log.csv", "val_ema_log.csv"):
        src = Path(args.work_dir) / name
        if src.exists():
            (model_dir / name).write_text(src.read_text())
    print(f"exported {onnx_path} and {model_dir / 'model.yaml'}", flush=True)


def load_exported(model_dir: Path):
    """The network of an exported model directory (model.yaml + model.pt), in eval mode, with its
    NetSpec and metadata. Reads the metadata of this script and of train_erfnet.py before it."""
    meta = yaml.safe_load((Path(model_dir) / "model.yaml").read_text())
    arch = meta.get("arch", "erfnet")
    ckpt = {"arch": arch, "camera_wh": list(meta["training"]["camera"]),
            "input_wh": [meta["input"]["width"], meta["input"]["height"]],
            "mean": meta["input"]["mean"], "std": meta["input"]["std"]}
    if arch == "erfnet":
        ckpt.update(width=meta["width"], dropout_scale=1.0)
    else:
        ckpt.update(dropout=0.0, image_pooling=bool(meta.get("image_pooling", False)))
    model = build_model(ckpt, len(meta["classes"]))
    model.load_state_dict(torch.load(Path(model_dir) / "model.pt", map_location="cpu"))
    model.eval()
    return model, net_spec(ckpt), meta


def net_spec(ckpt) -> NetSpec:
    stride = 1 if ckpt["arch"] == "erfnet" else mobilenet_v2.MobileNetV2Seg.stride
    return NetSpec(ckpt["arch"], tuple(ckpt["camera_wh"]), tuple(ckpt["input_wh"]), stride,
                   np.array(ckpt["mean"]), np.array(ckpt["std"]))


# ---------------------------------------------------------------------------------------------
def parse_wh(text: str, what: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise SystemExit(f"{what}: expected WxH, got '{text}'")
    return w, h


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--arch", choices=ARCHS, default="mobilenetv2")
    ap.add_argument("--data-dir", default=str(REPO / "examples" / "data"))
    ap.add_argument("--train-fields", default="dubai-tile-1,dubai-tile-2,dubai-tile-3,dubai-tile-5")
    ap.add_argument("--val-field", default="dubai-tile-4")
    ap.add_argument("--test-field", default="dubai-tile-6",
                    help="recorded in the metadata only; never read by this script")
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("--model-dir", required=True)
    ap.add_argument("--device", choices=("auto", "cpu", "cuda"), default="auto")
    ap.add_argument("--workers", type=int, default=-1,
                    help="data worker processes (-1: none on CPU, up to 12 on CUDA)")
    ap.add_argument("--sampler", choices=("cpu", "device"), default="cpu",
                    help="new runs: make the batches in CPU workers (cpu) or on the training device "
                         "(device; augmentation altitude only; adaptseg_tools.device_sampler)")
    ap.add_argument("--prefetch", type=int, default=2,
                    help="--sampler device on CUDA: batches made ahead by a thread on a stream of its own (0: each "
                         "made when the step asks for it)")
    ap.add_argument("--width", type=float, default=0.5, help="ERFNet width multiplier")
    ap.add_argument("--encoder-weights", default="",
                    help="MobileNetV2 encoder state_dict from mobilenet_v2.py (default: import with npm)")
    ap.add_argument("--init-weights", default="", metavar="MODEL_DIR",
                    help="start a new run from an exported model's weights (MODEL_DIR/model.pt, same "
                         "architecture and options), e.g. to train a bundled model further once its "
                         "checkpoint is gone; the optimizer and the learning-rate cycle start afresh")
    ap.add_argument("--frozen-blocks", type=int, default=4,
                    help="MobileNetV2: stem + first blocks kept at ImageNet weights (4: up to block_2)")
    ap.add_argument("--no-image-pooling", action="store_true",
                    help="MobileNetV2: leave out the decoder's image-level branch")
    ap.add_argument("--encoder-lr-scale", type=float, default=0.25,
                    help="MobileNetV2: encoder learning rate / decoder learning rate")
    ap.add_argument("--steps", type=int, default=1600)
    ap.add_argument("--batch", type=int, default=0, help="0: 8 on CPU, 32 on CUDA")
    ap.add_argument("--crop", type=int, default=0,
                    help="camera pixels per side of a training crop (0: 256 where the network input "
                         "is the camera size, else 300)")
    ap.add_argument("--camera", default="480x360", help="camera image WxH")
    ap.add_argument("--input", default="",
                    help="network input WxH for a whole camera image (default: camera size for "
                         "ERFNet, 512x384 for MobileNetV2)")
    ap.add_argument("--augment", choices=("mild", "altitude"), default="",
                    help="default: mild for ERFNet, altitude for MobileNetV2")
    ap.add_argument("--gsd-min-factor", type=float, default=1.0)
    ap.add_argument("--gsd-max-factor", type=float, default=3.0)
    ap.add_argument("--val-factors", default="1,1.5,2,2.5,3")
    ap.add_argument("--val-every", type=int, default=400, help="validate every N steps (0: at the end only)")
    ap.add_argument("--val-max-images", type=int, default=0, help="0 = all images of a band")
    ap.add_argument("--ckpt-every", type=int, default=50)
    ap.add_argument("--log-every", type=int, default=10)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--dropout-scale", type=float, default=0.33,
                    help="ERFNet: multiplies the paper's dropout rates (0.03 in the first, 0.3 in the dilated blocks)")
    ap.add_argument("--dropout", type=float, default=0.1, help="MobileNetV2: dropout before the classifier")
    ap.add_argument("--weight-decay", type=float, default=1e-4)
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--ema", type=float, default=0.0, metavar="DECAY",
                    help="new runs: also keep an exponential moving average of the weights (decay in "
                         "(0, 1), e.g. 0.998), validate it next to the trained weights and export it")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--max-minutes", type=float, default=0.0,
                    help="> 0: checkpoint and stop after this much wall-clock time (continue with --resume)")
    ap.add_argument("--minutes", type=float, default=0.0,
                    help="> 0: fit the new learning-rate cycle (of a new run or of --extend) into this much "
                         "wall-clock time from the start of this invocation, export excluded: its length, "
                         "at most --steps (--extend), is set at the end of the warm-up from the measured "
                         "time per step and per validation")
    ap.add_argument("--resume", action="store_true", help="continue from WORK_DIR/checkpoint.pt")
    ap.add_argument("--extend", type=int, default=0, metavar="STEPS",
                    help="with --resume of a finished run: train STEPS more steps under a new "
                         "learning-rate cycle (warm-up to --lr, then poly decay; a warm restart)")
    ap.add_argument("--export-only", action="store_true", help="export WORK_DIR/checkpoint.pt and exit")
    ap.add_argument("--no-export", action="store_true")
    ap.add_argument("--export-graph", choices=("subpixel", "deconv"), default="deconv",
                    help="ERFNet: how transposed convolutions are written to ONNX (same function)")
    args = ap.parse_args(argv)
    t_start = time.time()

    if args.device == "auto":
        args.device = "cuda" if torch.cuda.is_available() else "cpu"
    if args.device == "cuda" and not torch.cuda.is_available():
        raise SystemExit("--device cuda: no CUDA device is available to PyTorch")
    device = torch.device(args.device)
    cuda = device.type == "cuda"
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    work = Path(args.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    ckpt_path = work / "checkpoint.pt"
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
          f"classes {classes}; device {device}", flush=True)

    if args.extend < 0 or (args.extend and not args.resume):
        raise SystemExit("--extend needs --resume and a step count >= 0")
    resume = (args.resume or args.export_only) and ckpt_path.exists()
    if (args.resume or args.export_only) and not resume:
        if args.export_only:
            raise SystemExit(f"--export-only: no checkpoint at {ckpt_path}")
        print(f"--resume: no checkpoint at {ckpt_path}, starting from scratch", flush=True)

    torch.manual_seed(args.seed)
    if resume:
        ckpt = torch.load(ckpt_path, map_location="cpu", weights_only=False)  # our own file
        if ckpt["classes"] != classes:
            raise SystemExit("checkpoint classes differ from the fields' classes")
        if "arch" not in ckpt:
            raise SystemExit(f"{ckpt_path}: a checkpoint of the former train_erfnet.py (its data sampling "
                             "differs); start a new run")
        if isinstance(ckpt["optimizer"], dict):  # checkpoints before 2026-11-23 kept the state under this key
            ckpt["optimizer_state"] = ckpt["optimizer"]
            ckpt["optimizer"] = "Adam" if ckpt["arch"] == "erfnet" else "AdamW"
    else:
        camera_wh = parse_wh(args.camera, "--camera")
        erf = args.arch == "erfnet"
        input_wh = parse_wh(args.input, "--input") if args.input else (camera_wh if erf else (512, 384))
        multiple = 8 if erf else 16
        if input_wh[0] % multiple or input_wh[1] % multiple:
            raise SystemExit(f"--input: {args.arch} needs a width and height that are multiples of {multiple}")
        if abs((input_wh[0] / input_wh[1]) / (camera_wh[0] / camera_wh[1]) - 1.0) > 0.01:
            raise SystemExit("--input: the aspect ratio must be the camera's (within 1 %, as the backend checks)")
        augment = args.augment or ("mild" if erf else "altitude")
        crop = args.crop or (256 if input_wh == camera_wh else 300)
        net_crop = (crop * input_wh[0] / camera_wh[0], crop * input_wh[1] / camera_wh[1])
        if any(v != int(v) or int(v) % multiple for v in net_crop):
            raise SystemExit(f"--crop {crop}: the crop must map to whole network pixels, a multiple of {multiple}")
        if augment == "mild" and input_wh != camera_wh:
            raise SystemExit("--augment mild crops the network input from the camera image: --input must be the camera size")
        if args.sampler == "device" and augment != "altitude":
            raise SystemExit("--sampler device makes the batches of --augment altitude only")
        if erf:
            mean, std = channel_stats(train_fields)
        else:  # Keras MobileNetV2 preprocessing: x / 127.5 - 1
            mean, std = np.full(3, 0.5), np.full(3, 0.5)
        counts = np.zeros(nc)
        for f in train_fields:
            counts += np.bincount(f.labels.ravel(), minlength=256)[:nc]
        freq = counts / counts.sum()
        # ENet-style weights 1 / ln(c + p), softened (c = 1.10) to keep the rare classes
        # from dominating a short training run.
        class_weights = 1.0 / np.log(1.10 + freq)
        class_weights = class_weights / class_weights.mean()
        if not 0.0 <= args.ema < 1.0:
            raise SystemExit(f"--ema {args.ema}: the decay must lie in [0, 1) (0: no average)")
        ckpt = {"step": 0, "arch": args.arch, "ema_decay": args.ema, "classes": classes, "mean": mean.tolist(),
                "std": std.tolist(), "class_weights": class_weights.tolist(),
                "train_fields": train_names, "val_field": args.val_field, "camera_wh": list(camera_wh),
                "input_wh": list(input_wh), "augment": augment, "crop": crop,
                "batch": args.batch or (32 if cuda else 8), "seed": args.seed,
                "gsd_factor_range": [args.gsd_min_factor, args.gsd_max_factor],
                "gsd_cm_range": [train_fields[0].gsd_cm * args.gsd_min_factor,
                                 train_fields[0].gsd_cm * args.gsd_max_factor],
                "weight_decay": args.weight_decay, "optimizer": "Adam" if erf else "AdamW", "sampler": args.sampler,
                "train_seconds": 0.0, "last_val": None, "devices": []}
        if erf:
            ckpt.update(width=args.width, dropout_scale=args.dropout_scale)
        else:
            ckpt.update(dropout=args.dropout, frozen_blocks=args.frozen_blocks,
                        encoder_lr_scale=args.encoder_lr_scale, image_pooling=not args.no_image_pooling)
    spec = net_spec(ckpt)
    model = build_model(ckpt, nc)
    if not resume and args.init_weights:
        src = Path(args.init_weights) / "model.pt"
        try:
            model.load_state_dict(torch.load(src, map_location="cpu"))
        except (OSError, RuntimeError) as e:
            raise SystemExit(f"--init-weights: cannot load {src} into this network ({args.arch} with these "
                             f"options): {e}")
        ckpt["init_weights"] = str(args.init_weights)
        print(f"initialised from {src}", flush=True)
    elif not resume and ckpt["arch"] == "mobilenetv2":
        enc = (torch.load(args.encoder_weights, map_location="cpu") if args.encoder_weights
               else mobilenet_v2.import_weights(None))
        model.encoder.load_state_dict(enc)
    for m in frozen_encoder_modules(model, ckpt.get("frozen_blocks", 0)):
        for p in m.parameters():
            p.requires_grad = False
    model.to(device)
    if cuda:
        model = model.to(memory_format=torch.channels_last)
    trainable = [p for p in model.parameters() if p.requires_grad]
    if ckpt["optimizer"] == "Adam":
        opt = torch.optim.Adam(trainable, lr=args.lr, weight_decay=ckpt["weight_decay"])
        lr_scales = [1.0]
    else:
        enc_ids = {id(p) for p in model.encoder.parameters()}
        groups = [[p for p in trainable if id(p) not in enc_ids], [p for p in trainable if id(p) in enc_ids]]
        opt = torch.optim.AdamW([{"params": g} for g in groups], lr=args.lr, weight_decay=ckpt["weight_decay"])
        lr_scales = [1.0, float(ckpt["encoder_lr_scale"])]
    if resume:
        model.load_state_dict(ckpt["model"])
        opt.load_state_dict(ckpt["optimizer_state"])
        torch.set_rng_state(ckpt["torch_rng"])
        if cuda and ckpt.get("cuda_rng") is not None:
            torch.cuda.set_rng_state(ckpt["cuda_rng"])
        print(f"resumed from {ckpt_path} at step {ckpt['step']}", flush=True)
    # Weight averaging (--ema): a copy of the network whose weights and buffers follow the trained
    # ones as an exponential moving average, debiased over the first steps; what --ema exports.
    ema_decay = float(ckpt.get("ema_decay", 0.0))
    ema_model = None
    if ema_decay > 0.0:
        ema_model = copy.deepcopy(model).eval()
        for p in ema_model.parameters():
            p.requires_grad = False
        if resume:
            ema_model.load_state_dict(ckpt["ema_model"])
    exported_model = model if ema_model is None else ema_model  # what validation reports and export writes
    # Learning-rate cycles: the first from step 0 to --steps (--lr, --warmup); each --extend
    # appends one. The checkpoint keeps them, so --resume continues the schedule it was in.
    if args.minutes < 0 or (args.minutes > 0 and args.resume and not args.extend):
        raise SystemExit("--minutes fits a new learning-rate cycle: give it to a new run or with --extend")
    if args.minutes > 0 and args.warmup < 40:
        raise SystemExit("--minutes measures the time per step over the second half of the warm-up: "
                         "--warmup must be at least 40 steps")
    fit = {"minutes": args.minutes} if args.minutes > 0 else {}
    stages = ckpt.setdefault("stages", [{"start": 0, "end": args.steps, "lr": args.lr,
                                         "warmup": args.warmup, **fit}])
    if args.extend:
        if ckpt["step"] != stages[-1]["end"]:
            raise SystemExit(f"--extend: the checkpoint is at step {ckpt['step']}, inside its last "
                             f"learning-rate cycle (ends at {stages[-1]['end']}); finish it with --resume first")
        stages.append({"start": ckpt["step"], "end": ckpt["step"] + args.extend, "lr": args.lr,
                       "warmup": args.warmup, **fit})
        print(f"extending by {args.extend} steps: new learning-rate cycle, peak {args.lr:g}", flush=True)
    total_steps = stages[-1]["end"]
    print(f"{ckpt['arch']}: {sum(p.numel() for p in model.parameters())} parameters "
          f"({sum(p.numel() for p in trainable)} trained); input {spec.input_wh} for camera {spec.camera_wh}, "
          f"logits at stride {spec.stride}; augment {ckpt['augment']}, crop {ckpt['crop']}, batch {ckpt['batch']}; "
          f"mean {np.round(spec.mean, 4).tolist()} std {np.round(spec.std, 4).tolist()}; "
          f"class weights {np.round(ckpt['class_weights'], 3).tolist()}", flush=True)

    if args.export_only:
        val = ckpt.get("last_val") or evaluate(exported_model, val_field, val_factors, spec, device=device)
        export(exported_model, ckpt, args, Path(args.model_dir), {float(k): v for k, v in val.items()})
        return 0

    sampler = Sampler(train_fields, spec, ckpt["crop"], *ckpt["gsd_factor_range"], ckpt["augment"], ckpt["seed"])
    criterion = nn.CrossEntropyLoss(weight=torch.tensor(ckpt["class_weights"], dtype=torch.float32),
                                    ignore_index=IGNORE).to(device)
    train_log = work / "train_log.csv"
    val_log = work / "val_log.csv"
    val_ema_log = work / "val_ema_log.csv"
    iou_cols = ",".join(f"iou_{c}" for c in classes)
    if not resume:
        train_log.write_text("step,elapsed_s,loss,lr,img_per_s\n")
        for log in (val_log, val_ema_log) if ema_model is not None else (val_log,):
            log.write_text(f"step,elapsed_s,gsd_factor,gsd_cm,images,miou_camera,miou_ortho,{iou_cols}\n")
    else:  # drop log rows written after the checkpoint: they will be redone
        for log in (train_log, val_log, val_ema_log):
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
        if ema_model is not None:
            ckpt["ema_model"] = {k: v.detach().cpu() for k, v in ema_model.state_dict().items()}
        ckpt.update({"model": {k: v.detach().cpu() for k, v in model.state_dict().items()},
                     "optimizer_state": opt.state_dict(), "torch_rng": torch.get_rng_state(),
                     "cuda_rng": torch.cuda.get_rng_state() if cuda else None})
        tmp = ckpt_path.with_suffix(".tmp")
        torch.save(ckpt, tmp)
        os.replace(tmp, ckpt_path)

    def validate(step):
        """Validates the trained weights (val_log.csv) and, with --ema, their average
        (val_ema_log.csv); returns the result of the weights that are exported."""
        for net, log, name in ((model, val_log, "val"), (ema_model, val_ema_log, "val ema")):
            if net is None:
                continue
            tv = time.time()
            res = evaluate(net, val_field, val_factors, spec, args.val_max_images or None, device)
            with log.open("a") as fh:
                for fac, r in res.items():
                    ious = ",".join("" if u is None else f"{u:.4f}" for u in r["iou_ortho"])
                    fh.write(f"{step},{ckpt['train_seconds']:.1f},{fac},{r['gsd_cm']:.3f},{r['images']},"
                             f"{r['miou_camera']:.4f},{r['miou_ortho']:.4f},{ious}\n")
            summary = " ".join(f"x{fac:g}:{r['miou_camera']:.3f}/{r['miou_ortho']:.3f}" for fac, r in res.items())
            print(f"[{name} step {step}] mIoU camera/ortho per GSD factor: {summary} ({time.time() - tv:.0f} s)",
                  flush=True)
        ckpt["last_val"] = {str(k): v for k, v in res.items()}
        return res

    # --minutes: the last cycle's length is fitted at the end of its warm-up (the learning rate of
    # the warm-up does not depend on it), from the time per step over its second half (or from the
    # step a resumed run starts at). A run resumed before that point fits it on resuming.
    fit_stage = stages[-1] if stages[-1].get("minutes") and "fitted_steps" not in stages[-1] else None
    fit_step = fit_stage["start"] + fit_stage["warmup"] if fit_stage else -1
    fit_from = max(fit_step - fit_stage["warmup"] // 2, ckpt["step"]) if fit_stage else -1
    if fit_stage and fit_step - fit_from < 10:
        raise SystemExit(f"--minutes: the checkpoint (step {ckpt['step']}) leaves fewer than 10 warm-up steps "
                         f"(to step {fit_step}) to measure the time per step; the cycle cannot be fitted")
    fit_t0 = None

    def fit_cycle(step):
        """Sets the cycle's end so that the steps left, their validations and the final one end
        within the budget (validating once here to measure a validation's time)."""
        nonlocal total_steps
        t_step = (time.time() - fit_t0) / (fit_step - fit_from)
        tv = time.time()
        validate(step)
        t_val = time.time() - tv
        left = 60.0 * fit_stage["minutes"] - (time.time() - t_start) - t_val - 15.0  # final validation, checkpoint
        per_step = t_step + (t_val / args.val_every if args.val_every > 0 else 0.0)
        n = max(1, int(0.97 * left / per_step))
        fit_stage["end"] = min(fit_stage["end"], step + n)
        fit_stage["fitted_steps"] = fit_stage["end"] - fit_stage["start"]
        fit_stage["measured_s_per_step"] = round(t_step, 5)
        fit_stage["measured_s_per_validation"] = round(t_val, 2)
        total_steps = stages[-1]["end"]
        print(f"--minutes {fit_stage['minutes']:g}: {t_step * 1000:.1f} ms per step, {t_val:.1f} s per "
              f"validation -> the cycle ends at step {total_steps}", flush=True)

    if ckpt.get("sampler", "cpu") == "device":  # resumed runs keep the sampler they started with
        loader = device_sampler.Prefetcher(device_sampler.DeviceSampler(sampler, device), ckpt["step"], total_steps,
                                           ckpt["batch"], depth=args.prefetch)
    else:
        workers = args.workers if args.workers >= 0 else (min(12, max(0, (os.cpu_count() or 1) - 2)) if cuda else 0)
        loader = torch.utils.data.DataLoader(
            StepBatches(sampler, ckpt["step"], total_steps, ckpt["batch"]), batch_size=None, shuffle=False,
            num_workers=workers, pin_memory=cuda, persistent_workers=False,
            **({"prefetch_factor": 4} if workers > 0 else {}))
    ckpt["devices"] = sorted(set(ckpt.get("devices", [])) | {args.device})
    ckpt["torch_versions"] = sorted(set(ckpt.get("torch_versions", [])) | {str(torch.__version__)})
    set_train_mode(model, ckpt)
    step = ckpt["step"]
    run_loss, run_n, t_log = 0.0, 0, time.time()
    if fit_stage and fit_from == step:  # resumed inside the measurement: it starts now (data start-up included)
        fit_t0 = time.time()
    paused = False
    for x, y in loader:
        if step >= total_steps:
            break
        ts = time.time()
        lr = lr_at(step)
        for g, s in zip(opt.param_groups, lr_scales):
            g["lr"] = lr * s
        x = x.to(device, non_blocking=True)
        y = y.to(device, non_blocking=True)
        if cuda:
            x = x.contiguous(memory_format=torch.channels_last)
        with torch.autocast(device_type=device.type, dtype=torch.bfloat16, enabled=cuda):
            logits = logits_to(model(x), y.shape[-2:])
        loss = criterion(logits.float(), y)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if ema_model is not None:
            with torch.no_grad():
                d = min(ema_decay, (1.0 + step) / (10.0 + step))
                for e, w in zip(ema_model.state_dict().values(), model.state_dict().values()):
                    if e.dtype.is_floating_point:
                        e.mul_(d).add_(w.detach(), alpha=1.0 - d)
                    else:
                        e.copy_(w)
        step += 1
        ckpt["step"] = step
        ckpt["train_seconds"] += time.time() - ts
        run_loss += float(loss)
        run_n += 1
        if step % args.log_every == 0 or step == total_steps:
            ips = run_n * ckpt["batch"] / (time.time() - t_log)
            with train_log.open("a") as fh:
                fh.write(f"{step},{ckpt['train_seconds']:.1f},{run_loss / run_n:.5f},{lr:.3e},{ips:.2f}\n")
            eta = (total_steps - step) * (time.time() - t_log) / run_n / 60
            print(f"step {step}/{total_steps} loss {run_loss / run_n:.4f} lr {lr:.2e} {ips:.2f} img/s "
                  f"elapsed {ckpt['train_seconds'] / 60:.1f} min, eta {eta:.1f} min", flush=True)
            run_loss, run_n, t_log = 0.0, 0, time.time()
        if fit_stage and step == fit_from:
            fit_t0 = time.time()
        if fit_stage and step == fit_step:
            fit_cycle(step)  # validates too
            fit_stage = None
            set_train_mode(model, ckpt)
            t_log = time.time()
        elif args.val_every > 0 and step % args.val_every == 0 and step < total_steps:
            validate(step)
            set_train_mode(model, ckpt)
            t_log = time.time()
        if step % args.ckpt_every == 0:
            save_checkpoint()
        if args.max_minutes > 0 and time.time() - t_start > 60.0 * args.max_minutes and step < total_steps:
            paused = True
            break
    if isinstance(loader, device_sampler.Prefetcher):
        loader.close()  # its thread may be making batches past the end
    if paused:
        save_checkpoint()
        print(f"stopped at step {step}/{total_steps} after {args.max_minutes:g} min (--max-minutes); "
              "continue with --resume", flush=True)
        return 0
    val = validate(step)
    save_checkpoint()
    print(f"training done: {step} steps, {ckpt['train_seconds'] / 60:.1f} min of training", flush=True)
    if not args.no_export:
        export(exported_model, ckpt, args, Path(args.model_dir), val)
    return 0


if __name__ == "__main__":
    sys.exit(main())
