"""Training samples: footprints drawn over the training fields, the camera image and oracle target
of each, and their augmentation (train_segnet.py's --augment mild and altitude); a sample is a
function of (seed, step, index in batch) only.
"""

from __future__ import annotations

import cv2
import numpy as np
import torch

from ..fieldio import IGNORE
from .fields import capture, crop_fill, lround, oracle_labels
from .network_path import NetSpec, to_network_size, to_tensor


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
