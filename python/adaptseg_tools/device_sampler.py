"""Training batches made on the training device (train_segnet.py --sampler device).

The CPU sampler (training.samples.Sampler, augmentation `altitude`) spends about 20 ms of one
core per crop cutting the camera footprint out of the orthomosaic and resampling it as adaptseg's
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
  8 bits as the camera delivers it. The yaw and mirror move no pixels: they reverse columns of
  the weight matrices and transpose the result; only the rows and columns of the crop are
  computed, and only the part of the footprint inside the orthomosaic (what lies outside is
  black and does not vote);
- the CPU sampler's photometric augmentation (saturation, contrast, brightness, white balance,
  gamma, hue, blur, noise, JPEG) with the same draws of its parameters; hue is rotated in a
  float HSV (OpenCV rounds H to 2 degrees and S, V to 8 bits in between), the noise is drawn on
  the device from a seed the sample's generator draws (so the draws after it differ from the CPU
  sampler's), JPEG round trips through OpenCV on the CPU for the 30 % of images it hits.

A whole batch is made at once, so that the GPU, not the launching of small kernels and the
waits for their results, sets the pace: the footprints are cut into one zero-padded buffer and
resampled by two batched matrix products; every photometric step runs on the whole batch (or on
the samples that drew it), with per-sample parameters; the labelled-share check costs one
synchronisation per batch (and one more per round of redraws), JPEG one copy to the host and
back; Prefetcher makes them ahead of the training step on a stream of their own. The first
version (until 2026-11-28) made the samples one by one: on an H200, 146 ms per batch of 32 ERFNet
crops against 55 ms now, and a training alone 185 crops/s against 480 with the prefetching thread,
the step then taking 93 % of the wall clock (docs/benchmarks.md, "Training batches on the GPU").

So a batch is a function of (seed, step) as with the CPU sampler, but not the same batch: the
arithmetic differs in rounding (tests: python/tests/test_device_sampler.py compares the two).
"""

from __future__ import annotations

import contextlib
import queue
import threading
from typing import NamedTuple

import cv2
import numpy as np
import torch
import torch.nn.functional as F

from .fieldio import IGNORE


def area_weights(axes: torch.Tensor, n: int, tmax: int) -> torch.Tensor:
    """B x n x tmax INTER_AREA weights, one matrix per row of `axes` (B x 7, float64): (n_out,
    n_in, offset, count, reversed, a0, a1). Shrinking n_in pixels to n_out, camera pixel j
    averages the source interval [j s, (j + 1) s), s = n_in / n_out, each pixel by its overlap;
    row o of the result is camera pixel offset + o (rows from `count` on are 0), column w is
    source pixel a0 + w (from a1 on 0), counted from the far end where `reversed` > 0."""
    n_out, n_in, off, cnt, rev, a0, a1 = (axes[:, i].view(-1, 1, 1) for i in range(7))
    o = torch.arange(n, dtype=torch.float64, device=axes.device).view(1, -1, 1)
    w = torch.arange(tmax, dtype=torch.float64, device=axes.device).view(1, 1, -1)
    s = n_in / n_out
    j = off + o                                   # camera pixel
    a = a0 + w                                    # footprint pixel, before the reversal
    i = torch.where(rev > 0, n_in - 1 - a, a)     # index of the resampled image's axis
    lo, hi = j * s, (j + 1) * s
    wts = (torch.minimum(hi, i + 1) - torch.maximum(lo, i)).clamp_min(0.0) / s
    return torch.where((o < cnt) & (a < a1), wts, torch.zeros_like(wts)).float()


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


def gaussian_blur_batch(x: torch.Tensor, sigmas) -> torch.Tensor:
    """cv2.GaussianBlur(x[b], (0, 0), sigmas[b]) for 8-bit images, each with its own sigma (kernel
    size 2 round(3 sigma) + 1, reflected borders, BORDER_REFLECT_101), in one depthwise
    convolution: every kernel zero-padded to the longest and the borders reflected by its half-width
    (reflecting further repeats what a shorter reflection gives, so each image's result is
    its own kernel's). x: B x C x H x W float."""
    ks = [int(round(s * 3 * 2 + 1)) | 1 for s in sigmas]
    r = max(ks) // 2
    t = torch.arange(2 * r + 1, device=x.device, dtype=torch.float32) - r
    g = []
    for s, k in zip(sigmas, ks):
        w = torch.exp(-0.5 * (t / s) ** 2) * (t.abs() <= k // 2)
        g.append(w / w.sum())
    g = torch.stack(g)                                          # B x (2r + 1)
    B, C, H, W = x.shape
    kern = g.repeat_interleave(C, 0)                            # (B C) x (2r + 1)
    y = F.pad(x.reshape(1, B * C, H, W), (r, r, r, r), mode="reflect")
    y = F.conv2d(y, kern.view(B * C, 1, 1, -1), groups=B * C)
    y = F.conv2d(y, kern.view(B * C, 1, -1, 1), groups=B * C)
    return y.view(B, C, H, W)


class Geometry(NamedTuple):
    """The geometric draws of one sample: field index, footprint rect (c0, r0, fw, fh) in
    orthomosaic pixels, quarter turns k, mirror, crop position (x, y) in camera pixels."""
    field: int
    c0: int
    r0: int
    fw: int
    fh: int
    k: int
    mirror: bool
    x: int
    y: int


class Photometric(NamedTuple):
    """The photometric draws of one sample (None: that augmentation not drawn)."""
    sat: float
    con: float
    bri: float
    wb: np.ndarray
    gamma: float
    hue: float | None        # hue shift in degrees
    blur: float | None       # sigma
    noise: tuple | None      # (standard deviation, generator seed)
    jpeg: int | None         # quality


class DeviceSampler:
    """Batches of augmentation `altitude` made on `device` (see the module's docstring).
    `cpu_sampler`: the training.samples.Sampler whose fields, network spec, crop, GSD range and
    seed this one shares (and whose footprint() draws the geometry)."""

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
        self.classes = torch.arange(self.nc, device=self.device, dtype=torch.uint8)

    def _dev(self, values, dtype=torch.float32) -> torch.Tensor:
        """Host values on the device without waiting for it: from pinned memory, asynchronously
        (a plain copy from pageable memory would wait for the work queued before it)."""
        t = torch.as_tensor(np.asarray(values), dtype=dtype)
        return t.pin_memory().to(self.device, non_blocking=True) if self.device.type == "cuda" else t.to(self.device)

    def crop_size(self):
        """(width, height) of a training crop in camera pixels."""
        cw, ch = self.spec.camera_wh
        return min(self.cpu.crop, cw), min(self.cpu.crop, ch)

    # -- the draws of one sample (its generator, in training.samples.Sampler's order) -------
    def draw_geometry(self, rng) -> Geometry:
        """The geometric draws of training.samples.Sampler.altitude_camera: quarter-turn yaw,
        footprint (field, GSD factor, position), mirror, crop position."""
        cw, ch = self.spec.camera_wh
        k = int(rng.integers(0, 4))
        f, c0, r0, fw, fh = self.cpu.footprint(rng, k % 2 == 1)
        mirror = bool(rng.random() < 0.5)
        ccw, cch = self.crop_size()
        x = int(rng.integers(0, cw - ccw + 1))
        y = int(rng.integers(0, ch - cch + 1))
        return Geometry(self.index[id(f)], c0, r0, fw, fh, k, mirror, x, y)

    @staticmethod
    def draw_photometric(rng) -> Photometric:
        """The draws of training.samples.photometric, in its order."""
        sat, con, bri = float(rng.uniform(0.7, 1.3)), float(rng.uniform(0.75, 1.25)), float(rng.uniform(-20, 20))
        wb = rng.uniform(0.92, 1.08, 3)
        gamma = float(rng.uniform(0.8, 1.25))
        hue = 2.0 * int(rng.integers(-5, 6)) if rng.random() < 0.5 else None
        blur = float(rng.uniform(0.3, 1.2)) if rng.random() < 0.3 else None
        noise = (float(rng.uniform(1.0, 6.0)), int(rng.integers(0, 2**62))) if rng.random() < 0.3 else None
        jpeg = int(rng.integers(40, 91)) if rng.random() < 0.3 else None
        return Photometric(sat, con, bri, wb, gamma, hue, blur, noise, jpeg)

    # -- whole batches -----------------------------------------------------------------------
    def _axis_weights(self, axes) -> torch.Tensor:
        """B x n x T weights of one contraction, each sample's INTER_AREA matrix cut to its crop
        (camera side) and to the part of its footprint inside the orthomosaic (source side),
        reversed where the yaw and mirror reverse that source axis, zero-padded to the batch's
        longest window. axes: per sample (n_out, n_in, offset, count, reversed, a0, a1): camera
        pixels offset..offset+count of n_out, footprint pixels a0..a1 of n_in (the window)."""
        return area_weights(self._dev(axes, torch.float64), max(a[3] for a in axes), max(a[6] - a[5] for a in axes))

    def cameras(self, geos, chunk: int = 8):
        """Camera crops (B x 3 x h x w float BGR, rounded to 8 bits) and oracle targets (B x h x w
        long) of the geometries `geos`: in groups of `chunk` footprints of similar size (each
        group's buffer is padded to its largest; footprints differ up to 9x in area)."""
        order = sorted(range(len(geos)), key=lambda b: geos[b].fw * geos[b].fh)
        if len(order) <= chunk:
            return self._cameras(geos)
        cam = target = None
        for i in range(0, len(order), chunk):
            idx = order[i:i + chunk]
            c, t = self._cameras([geos[b] for b in idx])
            if cam is None:
                cam = c.new_empty((len(geos),) + tuple(c.shape[1:]))
                target = t.new_empty((len(geos),) + tuple(t.shape[1:]))
            at = self._dev(idx, torch.long)
            cam[at], target[at] = c, t
        return cam, target

    def _cameras(self, geos):
        """cameras() of one group, all at once: the footprint windows cut into one padded
        buffer, then two batched matrix products (rows, then columns) of the image and of the
        per-class indicators of its labels. The yaw and mirror are not applied to the pixels:
        a quarter turn transposes the result and reverses one source axis, a mirror reverses
        the other (np.rot90(S, k), then [:, ::-1])."""
        cw, ch = self.spec.camera_wh
        ccw, cch = self.crop_size()
        rows, cols, wins = [], [], []
        for g in geos:
            H, W = self.labels[g.field].shape
            a0, a1 = max(0, -g.r0), min(g.fh, H - g.r0)    # footprint rows inside the orthomosaic
            b0, b1 = max(0, -g.c0), min(g.fw, W - g.c0)
            a1, b1 = max(a1, a0), max(b1, b0)
            # The camera axis (pixels, crop offset, crop length) that the footprint's rows (P)
            # and columns (Q) become, and whether reversed, from np.rot90(S, k) then the mirror:
            cam_rows, cam_cols = (ch, g.y, cch), (cw, g.x, ccw)
            if g.k % 2 == 0:
                p_cam, q_cam = cam_rows, cam_cols
                p_rev, q_rev = g.k == 2, g.mirror != (g.k == 2)
            else:  # a quarter turn: the footprint's rows become camera columns
                p_cam, q_cam = cam_cols, cam_rows
                p_rev, q_rev = g.mirror != (g.k == 3), g.k == 1
            rows.append((p_cam[0], g.fh, p_cam[1], p_cam[2], float(p_rev), a0, a1))
            cols.append((q_cam[0], g.fw, q_cam[1], q_cam[2], float(q_rev), b0, b1))
            wins.append((g.field, g.r0 + a0, g.r0 + a1, g.c0 + b0, g.c0 + b1))
        B = len(geos)
        P, Q = self._axis_weights(rows), self._axis_weights(cols)   # B x n x Hwin, B x n x Wwin
        hmax, wmax = P.shape[2], Q.shape[2]
        img = torch.zeros((B, hmax, wmax, 3), dtype=torch.uint8, device=self.device)
        lab = torch.full((B, hmax, wmax), IGNORE, dtype=torch.uint8, device=self.device)
        for b, (fi, ra, rb, ca, cb) in enumerate(wins):
            if rb > ra and cb > ca:
                img[b, :rb - ra, :cb - ca] = self.images[fi][ra:rb, ca:cb]
                lab[b, :rb - ra, :cb - ca] = self.labels[fi][ra:rb, ca:cb]
        # Channels: B, G, R, then one indicator per class (ignore matches none: it does not vote).
        x = torch.empty((B, 3 + self.nc, hmax, wmax), dtype=torch.float32, device=self.device)
        x[:, :3] = img.permute(0, 3, 1, 2)
        x[:, 3:] = lab[:, None] == self.classes.view(1, -1, 1, 1)
        c = x.shape[1]
        t = torch.bmm(x.view(B, c * hmax, wmax), Q.transpose(1, 2)).view(B, c, hmax, Q.shape[1])  # columns
        u = torch.matmul(P[:, None], t)                                                          # rows: B x C x n x n
        odd = self._dev([g.k % 2 == 1 for g in geos], torch.bool).view(B, 1, 1, 1)
        if u.shape[2] != u.shape[3]:
            n = max(u.shape[2], u.shape[3])
            u = F.pad(u, (0, n - u.shape[3], 0, n - u.shape[2]))
        u = torch.where(odd, u.transpose(2, 3), u)[:, :, :cch, :ccw]
        cam = torch.round(u[:, :3]).clamp(0, 255)
        best, cls = u[:, 3:].max(1)  # ties: the first maximum, the lower class index
        target = torch.where(best > 0, cls, torch.full_like(cls, IGNORE))
        return cam, target

    def photometric_batch(self, cam, draws):
        """training.samples.photometric on a B x 3 x H x W float BGR batch in 0..255, sample b with
        the parameters draws[b]."""
        B, dev = cam.shape[0], cam.device

        def col(values):
            return self._dev(values).view(B, 1, 1, 1)

        img = cam
        gray = img.mean(1, keepdim=True)
        img = gray + (img - gray) * col([d.sat for d in draws])
        img = (img - 128.0) * col([d.con for d in draws]) + 128.0 + col([d.bri for d in draws])
        img = img * self._dev(np.stack([d.wb for d in draws])).view(B, 3, 1, 1)
        img = 255.0 * (img.clamp(0, 255) / 255.0) ** col([d.gamma for d in draws])
        out = torch.floor((img + 0.5).clamp(0, 255))
        # The samples that drew an augmentation, as device indices (a Python list would be
        # copied to the device synchronously).
        hue = [b for b, d in enumerate(draws) if d.hue is not None]
        if hue:
            at = self._dev(hue, torch.long)
            h, s, v = bgr_to_hsv(out[at].transpose(0, 1) / 255.0)           # 3 x n x H x W -> n x H x W each
            shift = self._dev([draws[b].hue for b in hue]).view(-1, 1, 1)
            out[at] = torch.round(hsv_to_bgr(h + shift, s, v).transpose(0, 1) * 255.0).clamp(0, 255)
        blur = [b for b, d in enumerate(draws) if d.blur is not None]
        if blur:
            at = self._dev(blur, torch.long)
            out[at] = torch.round(gaussian_blur_batch(out[at], [draws[b].blur for b in blur])).clamp(0, 255)
        noisy = [b for b, d in enumerate(draws) if d.noise is not None]
        if noisy:
            at = self._dev(noisy, torch.long)
            noise = torch.empty((len(noisy),) + tuple(out.shape[1:]), dtype=torch.float32, device=dev)
            for i, b in enumerate(noisy):
                sd, seed = draws[b].noise
                gen = torch.Generator(device=dev)
                gen.manual_seed(seed)
                noise[i] = torch.randn(tuple(out.shape[1:]), generator=gen, device=dev) * sd
            out[at] = torch.floor((out[at] + noise + 0.5).clamp(0, 255))
        jpeg = [b for b, d in enumerate(draws) if d.jpeg is not None]
        if jpeg:  # OpenCV's codec on the CPU: one copy there and back for the whole batch
            at = self._dev(jpeg, torch.long)
            host = out[at].permute(0, 2, 3, 1).to("cpu", torch.uint8).numpy()
            done = []
            for i, b in enumerate(jpeg):
                ok, enc = cv2.imencode(".jpg", host[i], [cv2.IMWRITE_JPEG_QUALITY, draws[b].jpeg])
                done.append(cv2.imdecode(enc, cv2.IMREAD_COLOR))
            out[at] = self._dev(np.stack(done), torch.uint8).permute(0, 3, 1, 2).float()
        return out

    def samples(self, step: int, indices):
        """Samples `indices` of `step`, made together: (n x 3 x h x w normalised RGB, n x h x w
        long). Each is a function of (seed, step, index) alone, so the same sample in a batch or
        alone differs at most by the rounding of the batch's padded matrix products."""
        rngs = [np.random.default_rng((self.cpu.seed, step, j)) for j in indices]
        geos = [self.draw_geometry(r) for r in rngs]
        cam, target = self.cameras(geos)
        while True:  # a crop less than 5 % labelled is drawn again from its own generator
            short = torch.nonzero((target != IGNORE).float().mean((1, 2)) < 0.05).view(-1).tolist()
            if not short:
                break
            at = self._dev(short, torch.long)
            cam[at], target[at] = self.cameras([self.draw_geometry(rngs[b]) for b in short])
        black = (cam == 0).all(1, keepdim=True)  # no-data pixels stay exactly black (the backend masks them)
        cam = self.photometric_batch(cam, [self.draw_photometric(r) for r in rngs])
        cam = torch.where(black, torch.zeros_like(cam), cam)
        nw, nh = self.cpu.network_size(cam.shape[3], cam.shape[2])
        if (nw, nh) != (cam.shape[3], cam.shape[2]):  # training.network_path.to_network_size
            mode = "area" if nw < cam.shape[3] else "bilinear"
            cam = F.interpolate(cam, size=(nh, nw), mode=mode, **({} if mode == "area" else {"align_corners": False}))
            cam = torch.round(cam).clamp(0, 255)
        rgb = cam.flip(1) / 255.0
        return (rgb - self.mean) / self.std, target

    def batch(self, step: int, size: int):
        """Samples 0..size-1 of `step`."""
        return self.samples(step, range(size))

    # -- one sample (the checks of test_device_sampler.py) ---------------------------------------
    def camera(self, rng):
        """training.samples.Sampler.altitude_camera on the device: camera crop (3 x h x w float,
        rounded to 8 bits, BGR) and oracle target (h x w long) of one sample."""
        cam, target = self.cameras([self.draw_geometry(rng)])
        return cam[0], target[0]

    def photometric(self, cam, rng):
        """training.samples.photometric's augmentation on a 3 x H x W float BGR image in 0..255."""
        return self.photometric_batch(cam[None], [self.draw_photometric(rng)])[0]

    def sample(self, step: int, index: int):
        """Sample `index` of `step` alone."""
        x, y = self.samples(step, [index])
        return x[0], y[0]


class Prefetcher:
    """The batches of steps first..last-1 from `sampler` (a DeviceSampler), made up to `depth`
    steps ahead by a background thread (by default on a CUDA device only; elsewhere the batches
    are made when asked for). On CUDA the thread makes them on a stream of its own, so that the
    sampler's waits (its labelled-share check, the JPEG round trip) wait for its own work only and
    its kernels run while the training step's do; the consumer's stream waits for each batch's
    event before using it. Iterate; close() (or leaving a `with` block) stops the thread."""

    def __init__(self, sampler: DeviceSampler, first: int, last: int, batch: int, depth: int = 2,
                 thread: bool | None = None):
        self.sampler, self.first, self.last, self.batch = sampler, first, last, batch
        self.cuda = sampler.device.type == "cuda"
        self.threaded = (self.cuda if thread is None else thread) and depth > 0
        self._stop = threading.Event()
        if self.threaded:
            self._queue = queue.Queue(maxsize=depth)
            self._thread = threading.Thread(target=self._run, name="device-sampler", daemon=True)
            self._thread.start()

    def _put(self, item) -> bool:
        """Hands `item` to the consumer; False once close() was called."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _run(self):
        stream = torch.cuda.Stream(device=self.sampler.device) if self.cuda else None
        try:
            with torch.cuda.stream(stream) if self.cuda else contextlib.nullcontext():
                for step in range(self.first, self.last):
                    x, y = self.sampler.batch(step, self.batch)
                    done = None
                    if self.cuda:
                        done = torch.cuda.Event()
                        done.record(stream)
                    if not self._put((x, y, done)):
                        return
        except BaseException as e:  # noqa: BLE001 - handed to the consumer, which raises it
            self._put(e)
            return
        self._put(None)

    def __iter__(self):
        if not self.threaded:
            for step in range(self.first, self.last):
                if self._stop.is_set():
                    return
                yield self.sampler.batch(step, self.batch)
            return
        current = torch.cuda.current_stream(self.sampler.device) if self.cuda else None
        while True:
            item = self._queue.get()
            if item is None:
                return
            if isinstance(item, BaseException):
                raise RuntimeError("the device sampler's thread failed") from item
            x, y, done = item
            if self.cuda:
                current.wait_event(done)
                x.record_stream(current)  # their memory is not reused before this stream is done with them
                y.record_stream(current)
            yield x, y

    def close(self):
        self._stop.set()
        if self.threaded:
            self._thread.join()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
