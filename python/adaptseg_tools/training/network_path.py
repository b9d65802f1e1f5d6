"""The backend's path: camera image -> network input -> logits at camera size (mirrors
OnnxSegmenter::logits in include/adaptseg/erfnet/onnx_segmenter.hpp), and the input
normalisation's statistics.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import torch
import torch.nn.functional as F

from ..fieldio import IGNORE
from .fields import FieldData


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
