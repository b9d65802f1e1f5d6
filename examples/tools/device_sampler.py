"""Training batches made on the training device (train_segnet.py --sampler device).

The CPU sampler (train_segnet.Sampler, augmentation `altitude`) spends about 20 ms of one core
per crop cutting the camera footprint out of the orthomosaic and resampling it as adaptseg's
SimulatedSensor does; on a GPU that, not the network, sets the pace (examples/models/erfnet-dubai
README: 133-220 crops/s with 7-14 workers). This sampler does the same on the device, for whole
batches:

- the same geometric draws as the CPU sampler, from np.random.default_rng((seed, step, index)):
  field, GSD factor, footprint position, quarter-turn yaw, mirror, crop position; the same
  redraw when less than 5 % of a crop is labelled;
- INTER_AREA as what it is for shrinking, the area-weighted mean of the source pixels each camera
  pixel covers: two dense 1-D weight matrices per sample (camera x source), applied to the
  image and to the per-class indicators of the labels (the oracle's votes: ignore pixels do not
  vote, ties go to the lower class index, 255 where nothing votes); the camera image rounded to
  8 bits as the camera delivers it;
- the CPU sampler's photometric augmentation (saturation, contrast, brightness, white balance,
  gamma, hue, blur, noise, JPEG) with the same draws of its parameters; hue is rotated in a
  float HSV (OpenCV rounds H to 2 degrees and S, V to 8 bits in between), the noise is drawn on
  the device from a seed the sample's generator draws (so the draws after it differ from the CPU
  sampler's), JPEG round trips through OpenCV on the CPU for the 30 % of images it hits.

So a batch is a function of (seed, step) as with the CPU sampler, but not the same batch: the
arithmetic differs in rounding (tests: examples/tools/test_device_sampler.py compares the two).
"""

from __future__ import annotations

import cv2
import numpy as np
import torch
import torch.nn.functional as F

IGNORE = 255


def area_weights(n_out: int, n_in: int, device) -> torch.Tensor:
    """n_out x n_in matrix of INTER_AREA's weights for shrinking n_in pixels to n_out: row j
    averages the source interval [j s, (j + 1) s), s = n_in / n_out, each pixel by its overlap."""
    s = n_in / n_out
    j = torch.arange(n_out, device=device, dtype=torch.float64)[:, None]
    i = torch.arange(n_in, device=device, dtype=torch.float64)[None, :]
    lo, hi = j * s, (j + 1) * s
    w = (torch.minimum(hi, i + 1) - torch.maximum(lo, i)).clamp_min(0.0) / s
    return w.float()


def crop_fill(src: torch.Tensor, c0: int, r0: int, w: int, h: int, fill: int) -> torch.Tensor:
    """src[r0:r0+h, c0:c0+w] (H x W [x C]) with `fill` outside src (SimulatedSensor::crop)."""
    H, W = src.shape[:2]
    if 0 <= c0 and 0 <= r0 and c0 + w <= W and r0 + h <= H:
        return src[r0:r0 + h, c0:c0 + w]
    out = torch.full((h, w) + tuple(src.shape[2:]), fill, dtype=src.dtype, device=src.device)
    a0, a1 = max(c0, 0), min(c0 + w, W)
    b0, b1 = max(r0, 0), min(r0 + h, H)
    if a1 > a0 and b1 > b0:
        out[b0 - r0:b1 - r0, a0 - c0:a1 - c0] = src[b0:b1, a0:a1]
    return out


def bgr_to_hsv(x: torch.Tensor):
    """x: 3 x H x W BGR in [0, 1] -> hue [0, 360), saturation, value (float)."""
    b, g, r = x[0], x[1], x[2]
    v, _ = x.max(0)
    mn, _ = x.min(0)
    d = v - mn
    s = torch.where(v > 0, d / v.clamp_min(1e-12), torch.zeros_like(v))
    dd = d.clamp_min(1e-12)
    h = torch.where(v == r, (g - b) / dd, torch.where(v == g, 2.0 + (b - r) / dd, 4.0 + (r - g) / dd))
    h = torch.where(d > 0, (60.0 * h) % 360.0, torch.zeros_like(h))
    return h, s, v


def hsv_to_bgr(h: torch.Tensor, s: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    c = v * s
    hp = (h % 360.0) / 60.0
    xx = c * (1.0 - torch.abs(hp % 2.0 - 1.0))
    zero = torch.zeros_like(h)
    sector = hp.floor().long().clamp(0, 5)
    r = torch.stack([c, xx, zero, zero, xx, c])
    g = torch.stack([xx, c, c, xx, zero, zero])
    b = torch.stack([zero, zero, xx, c, c, xx])
    idx = sector[None]
    m = v - c
    return torch.stack([b.gather(0, idx)[0] + m, g.gather(0, idx)[0] + m, r.gather(0, idx)[0] + m])


def gaussian_blur(x: torch.Tensor, sigma: float) -> torch.Tensor:
    """cv2.GaussianBlur(x, (0, 0), sigma) for an 8-bit image: kernel size 2 round(3 sigma) + 1,
    reflected borders (BORDER_REFLECT_101). x: C x H x W float."""
    k = int(round(sigma * 3 * 2 + 1)) | 1
    r = k // 2
    t = torch.arange(k, device=x.device, dtype=torch.float32) - r
    g = torch.exp(-0.5 * (t / sigma) ** 2)
    g = g / g.sum()
    y = F.pad(x[None], (r, r, r, r), mode="reflect")
    c = x.shape[0]
    y = F.conv2d(y, g.view(1, 1, 1, k).repeat(c, 1, 1, 1), groups=c)
    y = F.conv2d(y, g.view(1, 1, k, 1).repeat(c, 1, 1, 1), groups=c)
    return y[0]


class DeviceSampler:
    """Batches of augmentation `altitude` made on `device` (see the module's docstring).
    `cpu_sampler`: the train_segnet.Sampler whose fields, network spec, crop, GSD range and seed
    this one shares (and whose footprint() draws the geometry)."""

    def __init__(self, cpu_sampler, device):
        self.cpu = cpu_sampler
        self.spec = cpu_sampler.spec
        self.device = torch.device(device)
        self.nc = cpu_sampler.nc
        self.images = [torch.from_numpy(np.ascontiguousarray(f.image)).to(self.device) for f in cpu_sampler.fields]
        self.labels = [torch.from_numpy(np.ascontiguousarray(f.labels)).to(self.device) for f in cpu_sampler.fields]
        self.index = {id(f): i for i, f in enumerate(cpu_sampler.fields)}
        self.mean = torch.tensor(self.spec.mean, dtype=torch.float32, device=self.device).view(3, 1, 1)
        self.std = torch.tensor(self.spec.std, dtype=torch.float32, device=self.device).view(3, 1, 1)
        self._weights = {}

    def weights(self, n_out, n_in):
        key = (n_out, n_in)
        if key not in self._weights:
            self._weights[key] = area_weights(n_out, n_in, self.device)
        return self._weights[key]

    # -- one sample ----------------------------------------------------------------------------
    def camera(self, rng):
        """train_segnet.Sampler.altitude_camera on the device: camera image (3 x ch x cw float,
        rounded to 8 bits, BGR) and oracle target (ch x cw long) of one crop."""
        cw, ch = self.spec.camera_wh
        k = int(rng.integers(0, 4))
        f, c0, r0, fw, fh = self.cpu.footprint(rng, k % 2 == 1)
        fi = self.index[id(f)]
        img = crop_fill(self.images[fi], c0, r0, fw, fh, 0)       # fh x fw x 3 uint8
        lab = crop_fill(self.labels[fi], c0, r0, fw, fh, IGNORE)  # fh x fw uint8
        img = torch.rot90(img, k, dims=(0, 1))
        lab = torch.rot90(lab, k, dims=(0, 1))
        if rng.random() < 0.5:
            img, lab = torch.flip(img, dims=(1,)), torch.flip(lab, dims=(1,))
        sh, sw = lab.shape
        wy, wx = self.weights(ch, sh), self.weights(cw, sw)
        cam = torch.einsum("oh,hwc,pw->cop", wy, img.float(), wx)
        cam = torch.round(cam).clamp(0, 255)
        onehot = (lab.long()[None] == torch.arange(self.nc, device=self.device)[:, None, None]).float()
        votes = torch.einsum("oh,khw,pw->kop", wy, onehot, wx)
        best, cls = votes.max(0)  # ties: the first maximum, the lower class index
        target = torch.where(best > 0, cls, torch.full_like(cls, IGNORE))
        ccw, cch = min(self.cpu.crop, cw), min(self.cpu.crop, ch)
        x = int(rng.integers(0, cw - ccw + 1))
        y = int(rng.integers(0, ch - cch + 1))
        return cam[:, y:y + cch, x:x + ccw], target[y:y + cch, x:x + ccw]

    def photometric(self, cam, rng):
        """train_segnet.photometric's augmentation on a 3 x H x W float BGR image in 0..255."""
        img = cam
        gray = img.mean(0, keepdim=True)
        img = gray + (img - gray) * float(rng.uniform(0.7, 1.3))
        img = (img - 128.0) * float(rng.uniform(0.75, 1.25)) + 128.0 + float(rng.uniform(-20, 20))
        img = img * torch.tensor(rng.uniform(0.92, 1.08, 3), dtype=torch.float32, device=img.device).view(3, 1, 1)
        img = 255.0 * (img.clamp(0, 255) / 255.0) ** float(rng.uniform(0.8, 1.25))
        out = torch.floor((img + 0.5).clamp(0, 255))
        if rng.random() < 0.5:
            h, s, v = bgr_to_hsv(out / 255.0)
            out = torch.round(hsv_to_bgr(h + 2.0 * int(rng.integers(-5, 6)), s, v) * 255.0).clamp(0, 255)
        if rng.random() < 0.3:
            out = torch.round(gaussian_blur(out, float(rng.uniform(0.3, 1.2)))).clamp(0, 255)
        if rng.random() < 0.3:
            sd = float(rng.uniform(1.0, 6.0))
            gen = torch.Generator(device=out.device)
            gen.manual_seed(int(rng.integers(0, 2**62)))
            noise = torch.randn(out.shape, generator=gen, device=out.device) * sd
            out = torch.floor((out + noise + 0.5).clamp(0, 255))
        if rng.random() < 0.3:
            q = int(rng.integers(40, 91))
            host = out.permute(1, 2, 0).to("cpu", torch.uint8).numpy()
            ok, enc = cv2.imencode(".jpg", host, [cv2.IMWRITE_JPEG_QUALITY, q])
            out = torch.from_numpy(cv2.imdecode(enc, cv2.IMREAD_COLOR)).to(out.device).permute(2, 0, 1).float()
        return out

    def sample(self, step: int, index: int):
        rng = np.random.default_rng((self.cpu.seed, step, index))
        while True:
            cam, target = self.camera(rng)
            if (target != IGNORE).float().mean().item() >= 0.05:
                break
        black = (cam == 0).all(0)
        cam = self.photometric(cam, rng)
        cam = torch.where(black[None], torch.zeros_like(cam), cam)
        nw, nh = self.cpu.network_size(cam.shape[2], cam.shape[1])
        if (nw, nh) != (cam.shape[2], cam.shape[1]):  # train_segnet.to_network_size
            mode = "area" if nw < cam.shape[2] else "bilinear"
            cam = F.interpolate(cam[None], size=(nh, nw), mode=mode,
                                **({} if mode == "area" else {"align_corners": False}))[0]
            cam = torch.round(cam).clamp(0, 255)
        rgb = cam.flip(0) / 255.0
        return (rgb - self.mean) / self.std, target

    def batch(self, step: int, size: int):
        xs, ys = zip(*[self.sample(step, j) for j in range(size)])
        return torch.stack(xs), torch.stack(ys)
