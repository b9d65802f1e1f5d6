"""Validation: a network's mIoU per GSD band on a whole-field lawnmower, against the oracle at
camera resolution and against the orthomosaic labels (adaptseg::image_confusion,
ConfusionMatrix::miou_all).
"""

from __future__ import annotations

import cv2
import numpy as np
import torch

from ..fieldio import IGNORE
from .fields import FieldData, capture, lawnmower_rects
from .network_path import NetSpec, predict_labels


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
