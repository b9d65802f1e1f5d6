"""MobileNetV2 (Sandler et al., CVPR 2018) as a segmentation encoder, with its ImageNet weights
imported from the npm package nsfwjs 4.3.0.

The package (MIT, Infinite Red) ships a Keras MobileNetV2 (width 1.0, Keras 2.2.4) converted to
TF.js under dist/models/mobilenet_v2/: model.min.js (the Keras topology and the weights
manifest) and group1-shard1of1.min.js (the weights, 8-bit quantised, base64). Its layers up to
block_10 are marked `trainable: false` in that topology: they are the original Keras
ImageNet weights, frozen while the later blocks were retrained for nsfwjs's own task. Only
those frozen layers are used here (stem, expanded_conv, block_1 .. block_10).

The PyTorch module reproduces Keras's arithmetic: kernels transposed from HWIO, batch-norm
eps 1e-3, ReLU6, and TF's asymmetric zero padding on stride-2 convolutions (one row/column at
the bottom/right, the ZeroPadding2D layers of the topology, then a 'valid' convolution);
inputs are RGB scaled to x / 127.5 - 1.

Usage:
  # fetch the package with npm and write the encoder weights (a torch state_dict)
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.mobilenet_v2 --out /tmp/mobilenet_v2_block10.pt
  # or from an unpacked package (npm pack nsfwjs@4.3.0 && tar xzf nsfwjs-4.3.0.tgz)
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.mobilenet_v2 --package /tmp/package --out ...

Decoding the JavaScript needs `node` (Debian nodejs); the rest is numpy and torch.
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

NPM_PACKAGE = "nsfwjs@4.3.0"
# sha512 integrity of nsfwjs-4.3.0.tgz as published on the npm registry (npm view nsfwjs@4.3.0 dist).
NPM_INTEGRITY = "sha512-WTKDte0vp1X97N1h34P79G/hG+sVT3+TnDz9di1WseIJR93v11E4viNX7Vg9WsO6HYoR772Nzq2iM8jo3XBZ+g=="
MODEL_DIR = "dist/models/mobilenet_v2"
LAST_FROZEN_BLOCK = 10
BN_EPS = 1e-3  # Keras BatchNormalization default, as in the topology

# (expansion t, output channels c, stride s) of expanded_conv and block_1 .. block_10
# (Sandler et al., Table 2: rows t,c,n,s = 1,16,1,1 / 6,24,2,2 / 6,32,3,2 / 6,64,4,2 / 6,96,3,1,
# the last row cut after its first block).
BLOCKS = [(1, 16, 1), (6, 24, 2), (6, 24, 1), (6, 32, 2), (6, 32, 1), (6, 32, 1),
          (6, 64, 2), (6, 64, 1), (6, 64, 1), (6, 64, 1), (6, 96, 1)]
# The rest of Table 2 (block_11 .. block_16): 96 x 2 more, 160 x 3 (stride 2), 320 x 1.
BLOCKS_FULL = BLOCKS + [(6, 96, 1), (6, 96, 1), (6, 160, 2), (6, 160, 1), (6, 160, 1), (6, 320, 1)]
# Encoder outputs used as decoder skips: block index -> stride (the last block is stride 16's).
TAPS = {2: 4, 5: 8}
# The encoders train_segnet builds (--encoder): width multiplier, last block, and the weights
# that initialise it (the module that imports them).
ENCODERS = {
    # Keras Applications MobileNetV2 1.0 from nsfwjs's mobilenet_v2 (this module): stem .. block_10.
    "mnv2-100-b10": (1.0, 10),
    # TF-Hub's MobileNetV2 1.4 (imagenet/mobilenet_v2_140_224) from nsfwjs's mobilenet_v2_mid
    # (adaptseg_tools.mobilenet_v2_140): every block at output stride 16 (encoder_layout).
    "mnv2-140-b16": (1.4, 16),
}
# The bundled networks' encoder, and that of a checkpoint or model.yaml that names none (all
# before 2026-12-04).
DEFAULT_ENCODER = "mnv2-100-b10"


def make_divisible(v: float, divisor: int = 8) -> int:
    """Channels of width multiplier * nominal channels, as TF's MobileNetV2 rounds them (to a
    multiple of 8, never below 90 % of the product)."""
    n = max(divisor, int(v + divisor / 2) // divisor * divisor)
    return n + divisor if n < 0.9 * v else n


def encoder_layout(width: float, last_block: int) -> tuple[int, list[tuple[int, int, int, int]]]:
    """Stem channels and (expansion, channels, stride, dilation) of blocks 0 .. last_block. Width
    1.0 keeps the nominal channels (16 for expanded_conv where TF would round too). Output stride
    16 as DeepLab's MobileNetV2 keeps it (TF-slim's output_stride): the block that would reach
    stride 32 keeps stride 16, and the blocks after it dilate their depthwise convolutions by 2."""
    if not 10 <= last_block < len(BLOCKS_FULL):
        raise ValueError(f"last block {last_block}: 10 .. {len(BLOCKS_FULL) - 1}")
    blocks, stride, rate = [], 2, 1
    for t, c, s in BLOCKS_FULL[:last_block + 1]:
        dilation = rate
        if stride * s > 16:
            s, rate = 1, rate * s
        stride *= s
        blocks.append((t, c if width == 1.0 else make_divisible(c * width), s, dilation))
    return (32 if width == 1.0 else make_divisible(32 * width)), blocks


def keras_pad(x: torch.Tensor) -> torch.Tensor:
    """Keras's ZeroPadding2D(((0, 1), (0, 1))) before a stride-2 'valid' convolution."""
    return F.pad(x, (0, 1, 0, 1))


class ConvBN(nn.Sequential):
    """Convolution without bias, batch norm (eps 1e-3), optional ReLU6; stride 2 pads as TF."""

    def __init__(self, cin, cout, k, stride=1, groups=1, relu6=True, dilation=1):
        pad = 0 if stride == 2 else dilation * (k // 2)
        layers = [nn.Conv2d(cin, cout, k, stride, pad, dilation=dilation, groups=groups, bias=False),
                  nn.BatchNorm2d(cout, eps=BN_EPS)]
        if relu6:
            layers.append(nn.ReLU6())
        super().__init__(*layers)
        self.tf_pad = stride == 2

    def forward(self, x):
        return super().forward(keras_pad(x) if self.tf_pad else x)


class InvertedResidual(nn.Module):
    """1x1 expansion (t > 1), 3x3 depthwise (stride s), linear 1x1 projection; identity shortcut
    when the shape is kept (Sandler et al., Fig. 4, Table 1)."""

    def __init__(self, cin, t, cout, stride, dilation=1):
        super().__init__()
        hidden = cin * t
        self.expand = ConvBN(cin, hidden, 1) if t != 1 else None
        self.depthwise = ConvBN(hidden, hidden, 3, stride, groups=hidden, dilation=dilation)
        self.project = ConvBN(hidden, cout, 1, relu6=False)
        self.residual = stride == 1 and cin == cout

    def forward(self, x):
        y = self.expand(x) if self.expand is not None else x
        y = self.project(self.depthwise(y))
        return x + y if self.residual else y


class MobileNetV2Encoder(nn.Module):
    """Stem (3x3 stride-2 conv) and blocks expanded_conv, block_1 .. block_<last_block> of
    MobileNetV2 at a width multiplier; the default, width 1.0 to block_10, is the bundled networks'.
    forward() returns the features at strides 4, 8 and 16 (the outputs of block_2, block_5 and the
    last block: 24, 32 and 96 channels by default; `channels`)."""

    def __init__(self, width: float = 1.0, last_block: int = 10):
        super().__init__()
        stem, layout = encoder_layout(width, last_block)
        self.stem = ConvBN(3, stem, 3, 2)
        blocks, cin = [], stem
        for t, c, s, d in layout:
            blocks.append(InvertedResidual(cin, t, c, s, d))
            cin = c
        self.blocks = nn.ModuleList(blocks)
        self.channels = {4: layout[2][1], 8: layout[5][1], 16: layout[-1][1]}

    def forward(self, x):
        x = self.stem(x)
        feats = {}
        for i, b in enumerate(self.blocks):
            x = b(x)
            if i in TAPS:
                feats[TAPS[i]] = x
        return feats[4], feats[8], x


class SepConv(nn.Sequential):
    """Depthwise 3x3 (dilation d), BN, ReLU, pointwise 1x1, BN, ReLU (the decoder's unit)."""

    def __init__(self, cin, cout, dilation=1):
        super().__init__(
            nn.Conv2d(cin, cin, 3, padding=dilation, dilation=dilation, groups=cin, bias=False),
            nn.BatchNorm2d(cin), nn.ReLU(),
            nn.Conv2d(cin, cout, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU())


def conv1x1(cin, cout):
    return nn.Sequential(nn.Conv2d(cin, cout, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU())


def up2(x):
    """Nearest-neighbour 2x upsampling: exported as an ONNX Resize that OpenCV 4.6 reads exactly."""
    return F.interpolate(x, scale_factor=2.0, mode="nearest")


class ImagePooling(nn.Module):
    """DeepLabv3's image-level branch: global average, 1x1 convolution, spread back over the map
    (nearest, to the map's fixed size: the export knows the input size)."""

    def __init__(self, cin, cout):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout, 1)  # no BN: one value per channel and image
        self.relu = nn.ReLU()

    def forward(self, x):
        y = self.relu(self.conv(F.adaptive_avg_pool2d(x, 1)))
        return F.interpolate(y, size=tuple(x.shape[-2:]), mode="nearest")


class MobileNetV2Seg(nn.Module):
    """Semantic segmentation on the MobileNetV2 encoder above, DeepLabv3+-style (Chen et al.,
    ECCV 2018) with depthwise-separable units throughout: at stride 16 a 1x1 branch, three
    dilated branches (2, 4, 8) and an image-level branch fused by a 1x1 convolution; upsampled
    to stride 8 and fused with block_5's features, then to stride 4 and fused with block_2's; a
    1x1 classifier. The logits come out at stride 4 (H/4 x W/4): the backend resamples them
    bilinearly to the image size. H and W must be multiples of 16."""

    stride = 4

    def __init__(self, num_classes: int, dropout: float = 0.1, aspp=128, mid=96, low=64, image_pooling=True,
                 encoder: str = DEFAULT_ENCODER):
        super().__init__()
        self.encoder = MobileNetV2Encoder(*ENCODERS[encoder])
        c = self.encoder.channels
        branches = [conv1x1(c[16], aspp)] + [SepConv(c[16], aspp, d) for d in (2, 4, 8)]
        if image_pooling:
            branches.append(ImagePooling(c[16], aspp))
        self.aspp = nn.ModuleList(branches)
        self.aspp_fuse = conv1x1(len(branches) * aspp, aspp)
        self.skip8 = conv1x1(c[8], 32)
        self.fuse8 = SepConv(aspp + 32, mid)
        self.skip4 = conv1x1(c[4], 24)
        self.fuse4 = SepConv(mid + 24, low)
        self.dropout = nn.Dropout2d(dropout) if dropout > 0 else nn.Identity()
        self.classifier = nn.Conv2d(low, num_classes, 1)

    def forward(self, x):
        f4, f8, f16 = self.encoder(x)
        y = self.aspp_fuse(torch.cat([b(f16) for b in self.aspp], 1))
        y = self.fuse8(torch.cat([up2(y), self.skip8(f8)], 1))
        y = self.fuse4(torch.cat([up2(y), self.skip4(f4)], 1))
        return self.classifier(self.dropout(y))

    def encoder_parameters(self):
        return self.encoder.parameters()

    def decoder_parameters(self):
        enc = {id(p) for p in self.encoder.parameters()}
        return [p for p in self.parameters() if id(p) not in enc]


def _keras_names(i: int) -> dict[str, str]:
    """Keras layer name of each ConvBN of block i (0 = expanded_conv)."""
    if i == 0:
        return {"depthwise": "expanded_conv_depthwise", "project": "expanded_conv_project"}
    return {p: f"block_{i}_{p}" for p in ("expand", "depthwise", "project")}


def keras_to_torch_names() -> list[tuple[str, str, str]]:
    """(torch parameter or buffer, Keras weight, kind) for every tensor of MobileNetV2Encoder."""
    out = []

    def conv_bn(prefix, conv_name, bn_name, depthwise):
        out.append((f"{prefix}.0.weight", f"{conv_name}/{'depthwise_kernel' if depthwise else 'kernel'}",
                    "depthwise" if depthwise else "conv"))
        for t, k in (("weight", "gamma"), ("bias", "beta"), ("running_mean", "moving_mean"),
                     ("running_var", "moving_variance")):
            out.append((f"{prefix}.1.{t}", f"{bn_name}/{k}", "bn"))

    conv_bn("stem", "Conv1", "bn_Conv1", False)
    for i in range(len(BLOCKS)):
        for part, name in _keras_names(i).items():
            conv_bn(f"blocks.{i}.{part}", name, f"{name}_BN", part == "depthwise")
    return out


def run_node(script: str, *args: str) -> bytes:
    try:
        return subprocess.run(["node", "-e", script, *args], check=True, capture_output=True).stdout
    except FileNotFoundError:
        raise SystemExit("node not found: decoding the TF.js files needs Node.js (Debian nodejs)")
    except subprocess.CalledProcessError as e:
        raise SystemExit(f"node failed: {e.stderr.decode(errors='replace')}")


def load_tfjs(package: Path) -> tuple[dict, bytes]:
    """The TF.js model (topology + weights manifest) and the raw weight bytes of the package."""
    d = package / MODEL_DIR
    for f in ("model.min.js", "group1-shard1of1.min.js"):
        if not (d / f).is_file():
            raise SystemExit(f"{d / f} not found: --package must be the unpacked nsfwjs 4.3.0 package")
    model = json.loads(run_node("process.stdout.write(JSON.stringify(require(process.argv[1])))",
                                str(d / "model.min.js")))
    shard = run_node("process.stdout.write(require(process.argv[1]))", str(d / "group1-shard1of1.min.js"))
    return model, base64.b64decode(shard)


def dequantize(model: dict, data: bytes) -> dict[str, np.ndarray]:
    """Every weight of the manifest as float32 (uint8 quantised: q * scale + min)."""
    weights, off = {}, 0
    for group in model["weightsManifest"]:
        for w in group["weights"]:
            n = int(np.prod(w["shape"])) if w["shape"] else 1
            q = w.get("quantization")
            if q is None:
                arr = np.frombuffer(data, np.float32, n, off)
                off += 4 * n
            elif q["dtype"] == "uint8":
                raw = np.frombuffer(data, np.uint8, n, off)
                off += n
                arr = raw.astype(np.float32) * np.float32(q["scale"]) + np.float32(q["min"])
            else:
                raise SystemExit(f"unsupported quantisation {q} of {w['name']}")
            weights[w["name"]] = arr.reshape(w["shape"]).astype(np.float32)
    if off != len(data):
        raise SystemExit(f"weights manifest covers {off} bytes, the shard has {len(data)}")
    return weights


def frozen_layers(model: dict) -> set[str]:
    layers = model["modelTopology"]["model_config"]["config"]["layers"]
    return {l["name"] for l in layers if l["config"].get("trainable") is False}


def encoder_state_dict(model: dict, data: bytes) -> dict[str, torch.Tensor]:
    weights = dequantize(model, data)
    frozen = frozen_layers(model)
    sd = {}
    for tname, kname, kind in keras_to_torch_names():
        layer = kname.split("/")[0]
        if layer not in frozen:
            raise SystemExit(f"{layer} is not a frozen (ImageNet) layer of the package")
        w = weights[kname]
        if kind == "conv":  # HWIO -> OIHW
            w = w.transpose(3, 2, 0, 1)
        elif kind == "depthwise":  # H W C 1 -> C 1 H W
            w = w.transpose(2, 3, 0, 1)
        sd[tname] = torch.from_numpy(np.ascontiguousarray(w))
    enc = MobileNetV2Encoder()
    missing = set(enc.state_dict()) - set(sd) - {k for k in enc.state_dict() if k.endswith("num_batches_tracked")}
    if missing:
        raise SystemExit(f"no Keras weight for {sorted(missing)}")
    enc.load_state_dict(sd, strict=False)
    return enc.state_dict()


def fetch_package(workdir: Path) -> Path:
    """`npm pack nsfwjs@4.3.0` into workdir, integrity checked, unpacked; returns package/."""
    try:
        subprocess.run(["npm", "pack", NPM_PACKAGE, "--silent"], cwd=workdir, check=True,
                       capture_output=True)
    except (FileNotFoundError, subprocess.CalledProcessError) as e:
        raise SystemExit(f"npm pack {NPM_PACKAGE} failed: {e}")
    tgz = workdir / "nsfwjs-4.3.0.tgz"
    digest = "sha512-" + base64.b64encode(hashlib.sha512(tgz.read_bytes()).digest()).decode()
    if digest != NPM_INTEGRITY:
        raise SystemExit(f"{tgz}: integrity {digest} differs from the registry's {NPM_INTEGRITY}")
    subprocess.run(["tar", "xzf", str(tgz)], cwd=workdir, check=True)
    return workdir / "package"


def from_package(package: Path | None, use):
    """use(unpacked package): of `package`, or of nsfwjs 4.3.0 fetched into a scratch folder."""
    if package is not None:
        return use(package)
    with tempfile.TemporaryDirectory() as tmp:
        return use(fetch_package(Path(tmp)))


def import_weights(package: Path | None) -> dict[str, torch.Tensor]:
    return from_package(package, lambda p: encoder_state_dict(*load_tfjs(p)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--package", type=Path, help="unpacked nsfwjs 4.3.0 package (default: fetch with npm)")
    ap.add_argument("--out", type=Path, required=True, help="where to write the encoder state_dict (.pt)")
    args = ap.parse_args(argv)
    save_encoder(import_weights(args.package), args.out, f"MobileNetV2 stem .. block_{LAST_FROZEN_BLOCK}")
    return 0


def save_encoder(sd: dict[str, torch.Tensor], out: Path, what: str):
    """Writes an encoder state_dict for train_segnet --encoder-weights, saying what and how big."""
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.save(sd, out)
    print(f"wrote {out}: {what}, "
          f"{sum(v.numel() for k, v in sd.items() if not k.endswith('num_batches_tracked'))} values")


if __name__ == "__main__":
    sys.exit(main())
