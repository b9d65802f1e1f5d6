"""The networks of a training checkpoint (ERFNet, MobileNetV2 with its decoder), their train mode,
their NetSpec, and an exported model directory loaded back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import yaml

from .. import mobilenet_v2
from ..erfnet import ERFNet
from .network_path import NetSpec

DEFAULT_ENCODER = mobilenet_v2.DEFAULT_ENCODER  # export.py and start.py read it from here


def build_model(ckpt: dict, nc: int) -> nn.Module:
    if ckpt["arch"] == "erfnet":
        d = ckpt["dropout_scale"]
        return ERFNet(nc, ckpt["width"], 0.03 * d, 0.3 * d)
    return mobilenet_v2.MobileNetV2Seg(nc, ckpt["dropout"], image_pooling=ckpt.get("image_pooling", False),
                                       encoder=ckpt.get("encoder", DEFAULT_ENCODER))


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


def exported_checkpoint(meta: dict) -> dict:
    """What net_spec reads, from an exported model.yaml's metadata (train_segnet.py's, or
    train_erfnet.py's before it, which names no arch)."""
    return {"arch": meta.get("arch", "erfnet"), "camera_wh": list(meta["training"]["camera"]),
            "input_wh": [meta["input"]["width"], meta["input"]["height"]],
            "mean": meta["input"]["mean"], "std": meta["input"]["std"]}


def load_exported(model_dir: Path):
    """The network of an exported model directory (model.yaml + model.pt), in eval mode, with its
    NetSpec and metadata. Reads the metadata of train_segnet.py and of train_erfnet.py before it."""
    meta = yaml.safe_load((Path(model_dir) / "model.yaml").read_text())
    ckpt = exported_checkpoint(meta)
    arch = ckpt["arch"]
    if arch == "erfnet":
        ckpt.update(width=meta["width"], dropout_scale=1.0)
    else:
        ckpt.update(dropout=0.0, image_pooling=bool(meta.get("image_pooling", False)),
                    encoder=meta.get("encoder", DEFAULT_ENCODER))
    model = build_model(ckpt, len(meta["classes"]))
    model.load_state_dict(torch.load(Path(model_dir) / "model.pt", map_location="cpu"))
    model.eval()
    return model, net_spec(ckpt), meta


def net_spec(ckpt) -> NetSpec:
    stride = 1 if ckpt["arch"] == "erfnet" else mobilenet_v2.MobileNetV2Seg.stride
    return NetSpec(ckpt["arch"], tuple(ckpt["camera_wh"]), tuple(ckpt["input_wh"]), stride,
                   np.array(ckpt["mean"]), np.array(ckpt["std"]))
