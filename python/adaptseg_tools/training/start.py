"""A training run's start (train_segnet.py): the device, the fields, the checkpoint (a new run's
or the one it resumes), the network with its optimizer and weight average, and the learning-rate
cycles.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch
import torch.nn as nn

from .. import mobilenet_v2, mobilenet_v2_140
from .fields import FieldData, load_field
from .host_memory import keep_freed_memory
from .models import DEFAULT_ENCODER, build_model, frozen_encoder_modules, net_spec
from .network_path import NetSpec, channel_stats


@dataclass
class Run:
    """A training run as it starts: what the training loop (loop.py) and --export-only work on."""
    device: torch.device
    cuda: bool
    work: Path                   # --work-dir: checkpoint.pt and the logs
    ckpt_path: Path
    val_factors: list[float]
    train_fields: list[FieldData]
    val_field: FieldData
    classes: list[str]
    resume: bool                 # the checkpoint is an earlier run's (--resume, --export-only)
    ckpt: dict                   # the run's settings and state, what checkpoint.pt holds
    spec: NetSpec
    model: nn.Module
    opt: torch.optim.Optimizer
    lr_scales: list[float]       # per parameter group, its share of the cycle's learning rate
    ema_decay: float
    ema_model: nn.Module | None  # --ema: the weights' moving average
    stages: list[dict]           # the learning-rate cycles

    @property
    def exported_model(self) -> nn.Module:
        """What validation reports and export writes: the weight average with --ema, else the weights."""
        return self.model if self.ema_model is None else self.ema_model


def parse_wh(text: str, what: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise SystemExit(f"{what}: expected WxH, got '{text}'")
    return w, h


def start(args) -> Run:
    """Everything before the first step, in this order: the device, the fields, the checkpoint, the
    network and its optimizer, the weight average and the learning-rate cycles."""
    if args.device == "auto":
        args.device = "cuda" if torch.cuda.is_available() else "cpu"
    if args.device == "cuda" and not torch.cuda.is_available():
        raise SystemExit("--device cuda: no CUDA device is available to PyTorch")
    device = torch.device(args.device)
    cuda = device.type == "cuda"
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    if not cuda and args.keep_freed_memory:
        print("host memory: " + ("freed memory kept for reuse (glibc mallopt)" if keep_freed_memory()
                                 else "this C library has no mallopt; freed memory goes back to the system"),
              flush=True)
    work = Path(args.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    ckpt_path = work / "checkpoint.pt"
    val_factors = [float(v) for v in args.val_factors.split(",")]

    train_names, train_fields, val_field, classes = load_fields(args, device)

    if args.extend < 0 or (args.extend and not args.resume):
        raise SystemExit("--extend needs --resume and a step count >= 0")
    resume = (args.resume or args.export_only) and ckpt_path.exists()
    if (args.resume or args.export_only) and not resume:
        if args.export_only:
            raise SystemExit(f"--export-only: no checkpoint at {ckpt_path}")
        print(f"--resume: no checkpoint at {ckpt_path}, starting from scratch", flush=True)

    torch.manual_seed(args.seed)
    if resume:
        ckpt = resumed_checkpoint(ckpt_path, classes)
    else:
        ckpt = new_checkpoint(args, train_names, train_fields, classes, cuda)
    spec, model, trainable, opt, lr_scales = network(args, ckpt, resume, ckpt_path, device, cuda)
    ema_decay, ema_model = weight_average(model, ckpt, resume)
    stages = lr_cycles(args, ckpt)
    print(f"{ckpt['arch']}: {sum(p.numel() for p in model.parameters())} parameters "
          f"({sum(p.numel() for p in trainable)} trained); input {spec.input_wh} for camera {spec.camera_wh}, "
          f"logits at stride {spec.stride}; augment {ckpt['augment']}, crop {ckpt['crop']}, batch {ckpt['batch']}; "
          f"mean {np.round(spec.mean, 4).tolist()} std {np.round(spec.std, 4).tolist()}; "
          f"class weights {np.round(ckpt['class_weights'], 3).tolist()}", flush=True)
    return Run(device, cuda, work, ckpt_path, val_factors, train_fields, val_field, classes, resume, ckpt, spec,
               model, opt, lr_scales, ema_decay, ema_model, stages)


def load_fields(args, device):
    """The training fields' names, the training fields and the validation field, and their classes."""
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
    print(f"loaded {len(train_fields)} training fields + {val_field.name} in {time.time() - t0:.1f} s; "
          f"classes {classes}; device {device}", flush=True)
    return train_names, train_fields, val_field, classes


def resumed_checkpoint(ckpt_path: Path, classes: list[str]) -> dict:
    """The checkpoint a run resumes, checked against the fields' classes; older checkpoints' keys
    renamed."""
    ckpt = torch.load(ckpt_path, map_location="cpu", weights_only=False)  # our own file
    if ckpt["classes"] != classes:
        raise SystemExit("checkpoint classes differ from the fields' classes")
    if "arch" not in ckpt:
        raise SystemExit(f"{ckpt_path}: a checkpoint of the former train_erfnet.py (its data sampling "
                         "differs); start a new run")
    if isinstance(ckpt["optimizer"], dict):  # checkpoints before 2026-11-23 kept the state under this key
        ckpt["optimizer_state"] = ckpt["optimizer"]
        ckpt["optimizer"] = "Adam" if ckpt["arch"] == "erfnet" else "AdamW"
    return ckpt


def new_checkpoint(args, train_names: list[str], train_fields: list[FieldData], classes: list[str],
                   cuda: bool) -> dict:
    """A new run's settings, from the command line and the training fields (input normalisation,
    class weights)."""
    nc = len(classes)
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
        if args.encoder != DEFAULT_ENCODER:
            raise SystemExit(f"--encoder {args.encoder}: a MobileNetV2 option (--arch mobilenetv2)")
        ckpt.update(width=args.width, dropout_scale=args.dropout_scale)
    else:
        ckpt.update(dropout=args.dropout, frozen_blocks=args.frozen_blocks,
                    encoder_lr_scale=args.encoder_lr_scale, image_pooling=not args.no_image_pooling,
                    encoder=args.encoder)
    return ckpt


def memory_format(args):
    """The torch layout --memory-format names."""
    return torch.contiguous_format if args.memory_format == "contiguous" else torch.channels_last


def network(args, ckpt: dict, resume: bool, ckpt_path: Path, device, cuda: bool):
    """The checkpoint's network on the device (initialised as the command line says, or resumed)
    and its optimizer: NetSpec, network, trained parameters, optimizer and per-group learning-rate
    scales."""
    nc = len(ckpt["classes"])
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
        importer = mobilenet_v2_140 if ckpt.get("encoder") == mobilenet_v2_140.ENCODER else mobilenet_v2
        enc = (torch.load(args.encoder_weights, map_location="cpu") if args.encoder_weights
               else importer.import_weights(None))
        try:
            model.encoder.load_state_dict(enc)
        except RuntimeError as e:
            raise SystemExit(f"--encoder-weights {args.encoder_weights}: not the weights of --encoder "
                             f"{ckpt.get('encoder')} ({importer.__name__} writes those): {e}") from None
    for m in frozen_encoder_modules(model, ckpt.get("frozen_blocks", 0)):
        for p in m.parameters():
            p.requires_grad = False
    model = model.to(device, memory_format=memory_format(args))
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
        if ckpt.get("optimizer_state") is not None:
            opt.load_state_dict(ckpt["optimizer_state"])
        elif not args.export_only:  # slim_checkpoint's: the exported weights alone
            raise SystemExit(f"{ckpt_path} holds the exported weights alone (no optimiser state): "
                             "it can be exported (--export-only), not resumed")
        torch.set_rng_state(ckpt["torch_rng"])
        if cuda and ckpt.get("cuda_rng") is not None:
            torch.cuda.set_rng_state(ckpt["cuda_rng"])
        print(f"resumed from {ckpt_path} at step {ckpt['step']}", flush=True)
    return spec, model, trainable, opt, lr_scales


def weight_average(model, ckpt: dict, resume: bool):
    """Weight averaging (--ema): a copy of the network whose weights and buffers follow the trained
    ones as an exponential moving average, debiased over the first steps; what --ema exports.
    Returns the decay (0: none) and the copy (None without --ema)."""
    ema_decay = float(ckpt.get("ema_decay", 0.0))
    ema_model = None
    if ema_decay > 0.0:
        ema_model = copy.deepcopy(model).eval()
        for p in ema_model.parameters():
            p.requires_grad = False
        if resume:
            ema_model.load_state_dict(ckpt["ema_model"])
    return ema_decay, ema_model


def lr_cycles(args, ckpt: dict) -> list[dict]:
    """Learning-rate cycles: the first from step 0 to --steps (--lr, --warmup); each --extend
    appends one. The checkpoint keeps them, so --resume continues the schedule it was in."""
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
    return stages
