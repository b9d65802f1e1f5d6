"""MobileNetV2 at width 1.4, every block (Sandler et al., CVPR 2018, Table 2), as a segmentation
encoder, with the ImageNet weights of TF-Hub's imagenet/mobilenet_v2_140_224 feature vector as the
npm package nsfwjs 4.3.0 ships them (dist/models/mobilenet_v2_mid).

That folder is a TF.js graph model (model.min.js: the graph and the weights manifest;
group1-shard1of2.min.js and group1-shard2of2.min.js: the weights, 8-bit quantised, base64) of
TF-Hub's feature vector as a Keras layer under a 5-class dense head that nsfwjs trained; whether
the hub layer was fine-tuned with it is not recorded, so these are ImageNet features possibly
adapted to photographs of people. The converter folded every batch norm into its convolution:
a kernel and an offset (the `_bn_offset` tensors) per convolution. Here each becomes the
convolution's kernel and a batch norm that adds the offset and nothing else (weight 1, mean 0,
variance 1 - eps), which train_segnet keeps in eval mode as it keeps every encoder batch norm, so
the encoder computes what the graph computes and fine-tunes its offsets as biases. The graph pads
'SAME', which for the stride-2 convolutions on even sizes is the one row and column at the bottom
and right that mobilenet_v2.ConvBN adds; inputs are RGB scaled to x / 127.5 - 1 (the graph's
hub_input Mul and Sub), as for the width-1.0 encoder. Blocks 13 .. 16 (stride 32 in the
classifier) run at stride 16, those after block_13 with their depthwise convolutions dilated by 2
(mobilenet_v2.encoder_layout, as DeepLab runs MobileNetV2 at output stride 16); the final 1x1
convolution to 1792 channels and the head are not used.

Usage:
  # fetch the package with npm and write the encoder weights (a torch state_dict)
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.mobilenet_v2_140 --out .device/mnv2_140_enc.pt
  # then: train_segnet --arch mobilenetv2 --encoder mnv2-140-b16 --encoder-weights .device/mnv2_140_enc.pt ...
  # the import against TF.js running the package's own graph (npm installs @tensorflow/tfjs-core,
  # -converter and -backend-cpu 4.22.0 into a scratch folder): block_2's and block_12's outputs on
  # a 224 x 224 crop of dubai-tile-1, exit 1 past a relative difference of 1e-3
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.mobilenet_v2_140 --check-tfjs [--package DIR]
(2026-12-04, 2-core AMD EPYC VM: 4.1e-5 and 3.3e-5 of the largest activation, 32.8 and 16.3.)

Decoding the JavaScript needs `node` (Debian nodejs); the rest is numpy and torch.
"""

from __future__ import annotations

import argparse
import base64
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
import torch

from . import REPO
from .mobilenet_v2 import (BN_EPS, ENCODERS, MobileNetV2Encoder, dequantize, from_package, run_node,
                           save_encoder)

ENCODER = "mnv2-140-b16"
MODEL_DIR = "dist/models/mobilenet_v2_mid"
SHARDS = ("group1-shard1of2.min.js", "group1-shard2of2.min.js")
GRAPH_SCOPE = "MobilenetV2/"  # every tensor name of the hub layer holds it


def load_graph(package: Path) -> tuple[dict, bytes]:
    """The TF.js graph model (graph + weights manifest) and its weight bytes, shards joined."""
    d = package / MODEL_DIR
    for f in ("model.min.js",) + SHARDS:
        if not (d / f).is_file():
            raise SystemExit(f"{d / f} not found: --package must be the unpacked nsfwjs 4.3.0 package")
    model = json.loads(run_node("process.stdout.write(JSON.stringify(require(process.argv[1])))",
                                str(d / "model.min.js")))
    data = b"".join(base64.b64decode(run_node("process.stdout.write(require(process.argv[1]))", str(d / f)))
                    for f in SHARDS)
    return model, data


def graph_to_torch_names(num_blocks: int) -> list[tuple[str, str, str]]:
    """(torch prefix of a ConvBN, graph name of its convolution without the suffix, kind)."""
    out = [("stem", "Conv/Conv2D", "conv")]
    for i in range(num_blocks):
        scope = "expanded_conv" if i == 0 else f"expanded_conv_{i}"
        parts = ("depthwise", "project") if i == 0 else ("expand", "depthwise", "project")
        for part in parts:
            conv = f"{scope}/{part}/depthwise" if part == "depthwise" else f"{scope}/{part}/Conv2D"
            out.append((f"blocks.{i}.{part}", conv, "depthwise" if part == "depthwise" else "conv"))
    return out


def encoder_state_dict(model: dict, data: bytes) -> dict[str, torch.Tensor]:
    """The width-1.4 encoder's state_dict from the graph's folded weights (module docstring)."""
    weights = {k.split(GRAPH_SCOPE, 1)[1]: v for k, v in dequantize(model, data).items() if GRAPH_SCOPE in k}
    enc = MobileNetV2Encoder(*ENCODERS[ENCODER])
    want = enc.state_dict()
    sd = {}
    for prefix, conv, kind in graph_to_torch_names(len(enc.blocks)):
        try:
            w, offset = weights[f"{conv}_weights"], weights[f"{conv}_bn_offset"]
        except KeyError as e:
            raise SystemExit(f"the package's graph has no {e.args[0]}: not TF-Hub's MobileNetV2 1.4")
        w = w.transpose(2, 3, 0, 1) if kind == "depthwise" else w.transpose(3, 2, 0, 1)  # HWC1 / HWIO
        sd[f"{prefix}.0.weight"] = torch.from_numpy(np.ascontiguousarray(w))
        n = offset.shape[0]
        sd[f"{prefix}.1.weight"] = torch.ones(n)
        sd[f"{prefix}.1.bias"] = torch.from_numpy(offset.copy())
        sd[f"{prefix}.1.running_mean"] = torch.zeros(n)
        sd[f"{prefix}.1.running_var"] = torch.full((n,), 1.0 - BN_EPS)
    for k, v in sd.items():
        if k not in want or want[k].shape != v.shape:
            raise SystemExit(f"{k}: the graph's {tuple(v.shape)} does not fit the encoder's "
                             f"{None if k not in want else tuple(want[k].shape)}")
    missing = {k for k in want if not k.endswith("num_batches_tracked")} - set(sd)
    if missing:
        raise SystemExit(f"no graph weight for {sorted(missing)}")
    enc.load_state_dict(sd, strict=False)
    return enc.state_dict()


TFJS = ("@tensorflow/tfjs-core@4.22.0", "@tensorflow/tfjs-converter@4.22.0", "@tensorflow/tfjs-backend-cpu@4.22.0")
# Runs the package's graph on the input (NHWC float32 in argv[2]) and writes the named nodes'
# outputs (argv[4..]) to argv[3].<i>.
TFJS_SCRIPT = """
const tf = require('@tensorflow/tfjs-core'); require('@tensorflow/tfjs-backend-cpu');
const converter = require('@tensorflow/tfjs-converter'); const fs = require('fs');
const [dir, input, out, ...names] = process.argv.slice(1);
(async () => {
  await tf.setBackend('cpu');
  const m = require(dir + '/model.min.js');
  const w = Buffer.concat(SHARDS.map(f => Buffer.from(require(dir + '/' + f), 'base64')));
  const model = await converter.loadGraphModel(tf.io.fromMemory({modelTopology: m.modelTopology,
    weightSpecs: m.weightsManifest[0].weights, weightData: w.buffer.slice(w.byteOffset, w.byteOffset + w.length)}));
  const x = tf.tensor4d(new Float32Array(fs.readFileSync(input).buffer.slice(0)), [1, 224, 224, 3]);
  const ys = model.execute(x, names);
  for (let i = 0; i < names.length; i++) fs.writeFileSync(out + '.' + i, Buffer.from((await ys[i].data()).buffer));
})().catch(e => { console.error(e); process.exit(1); });
"""


def check_tfjs(package: Path) -> int:
    """block_2's and block_12's outputs of the imported encoder against TF.js on the graph."""
    img = cv2.imread(str(REPO / "examples" / "data" / "dubai-tile-1" / "image.jpg"))
    if img is None:
        raise SystemExit("examples/data/dubai-tile-1/image.jpg not found")
    x = np.ascontiguousarray(img[500:724, 600:824, ::-1], np.float32) / 255.0  # RGB in [0, 1], 224 x 224
    enc = MobileNetV2Encoder(*ENCODERS[ENCODER])
    enc.load_state_dict(encoder_state_dict(*load_graph(package)))
    enc.eval()
    taps, feats = (2, 12), {}
    with torch.no_grad():
        y = enc.stem(torch.from_numpy(x.transpose(2, 0, 1)[None] * 2 - 1))
        for i, b in enumerate(enc.blocks):
            y = b(y)
            if i in taps:
                feats[i] = y[0].numpy().transpose(1, 2, 0)
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        try:
            subprocess.run(["npm", "install", "--no-save", "--no-audit", "--no-fund", "--silent", "--prefix", tmp,
                            *TFJS], check=True, capture_output=True)
        except (FileNotFoundError, subprocess.CalledProcessError) as e:
            raise SystemExit(f"npm install {' '.join(TFJS)} failed: {e}")
        (t / "input.bin").write_bytes(x[None].tobytes())
        script = TFJS_SCRIPT.replace("SHARDS", json.dumps(list(SHARDS)))
        names = [f"StatefulPartitionedCall/sequential/keras_layer/StatefulPartitionedCall/StatefulPartitionedCall/"
                 f"StatefulPartitionedCall/predict/{GRAPH_SCOPE}expanded_conv_{i}/add" for i in taps]
        proc = subprocess.run(["node", "-e", script, str(package / MODEL_DIR), str(t / "input.bin"), str(t / "out"),
                               *names], cwd=tmp, capture_output=True)
        if proc.returncode != 0:
            raise SystemExit(f"TF.js failed: {proc.stderr.decode(errors='replace')}")
        worst = 0.0
        for j, i in enumerate(taps):
            ref = np.frombuffer((t / f"out.{j}").read_bytes(), np.float32).reshape(feats[i].shape)
            rel = float(np.abs(feats[i] - ref).max() / np.abs(ref).max())
            worst = max(worst, rel)
            print(f"block_{i} {feats[i].shape}: max |PyTorch - TF.js| {np.abs(feats[i] - ref).max():.3g} "
                  f"of max |TF.js| {np.abs(ref).max():.3g} (relative {rel:.2g})")
    if worst > 1e-3:
        print("the import differs from TF.js")
        return 1
    return 0


def import_weights(package: Path | None) -> dict[str, torch.Tensor]:
    return from_package(package, lambda p: encoder_state_dict(*load_graph(p)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--package", type=Path, help="unpacked nsfwjs 4.3.0 package (default: fetch with npm)")
    ap.add_argument("--out", type=Path, help="where to write the encoder state_dict (.pt)")
    ap.add_argument("--check-tfjs", action="store_true", help="compare the import with TF.js instead (docstring)")
    args = ap.parse_args(argv)
    if args.check_tfjs:
        return from_package(args.package, check_tfjs)
    if args.out is None:
        ap.error("--out is required (or --check-tfjs)")
    save_encoder(import_weights(args.package), args.out, f"MobileNetV2 1.4 stem .. block_16 ({ENCODER})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
