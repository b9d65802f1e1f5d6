"""Export of a trained network (train_segnet.py): model.onnx, checked against PyTorch with OpenCV
DNN, model.pt and model.yaml, the metadata adaptseg's ONNX backend reads
(include/adaptseg/erfnet/onnx_model_info.hpp).
"""

from __future__ import annotations

import datetime
import warnings
from pathlib import Path

import cv2
import numpy as np
import torch
import yaml

from ..erfnet import ERFNetInference, erfnet_channels
from ..fieldio import IGNORE
from .. import mobilenet_v2
from .models import DEFAULT_ENCODER, net_spec


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
        # The default encoder's words as every bundled model.yaml has them (a re-export stays the
        # same file); another names itself (`encoder`, which load_exported reads).
        encoder = ckpt.get("encoder", DEFAULT_ENCODER)
        arch = {"architecture": "MobileNetV2 encoder (Sandler et al. 2018, width 1.0, stem .. block_10, "
                                "ImageNet weights from npm nsfwjs 4.3.0) + DeepLabv3+-style separable "
                                "decoder (examples/tools/mobilenet_v2.py)"}
        if encoder != DEFAULT_ENCODER:
            width, last = mobilenet_v2.ENCODERS[encoder]
            arch = {"architecture": f"MobileNetV2 encoder (Sandler et al. 2018, width {width:g}, stem .. "
                                    f"block_{last} at output stride 16, the blocks after block_13 dilated by 2; ImageNet weights of "
                                    "TF-Hub's mobilenet_v2_140_224 from npm nsfwjs 4.3.0) + DeepLabv3+-style "
                                    "separable decoder (python/adaptseg_tools/mobilenet_v2_140.py)",
                    "encoder": encoder}
        arch.update({"encoder_frozen_blocks": int(ckpt["frozen_blocks"]),
                     "image_pooling": bool(ckpt.get("image_pooling", False)),
                     "encoder_lr_scale": float(ckpt["encoder_lr_scale"])})
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
    # The metadata names the tools by their paths before the package (examples/tools/), as the
    # bundled models' model.yaml do: the export writes what it wrote.
    (model_dir / "model.yaml").write_text(
        "# Segmentation model metadata for adaptseg::ErfnetSegmenter (written by examples/tools/train_segnet.py)\n"
        + yaml.safe_dump(meta, sort_keys=False, default_flow_style=None, width=100))
    for name in ("train_log.csv", "val_log.csv", "val_ema_log.csv"):
        src = Path(args.work_dir) / name
        if src.exists():
            (model_dir / name).write_text(src.read_text())
    print(f"exported {onnx_path} and {model_dir / 'model.yaml'}", flush=True)
