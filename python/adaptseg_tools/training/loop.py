"""The training loop (train_segnet.py): batches from the CPU workers or the device sampler, the
learning-rate schedule, the weight average, the logs, validation, checkpoints, --max-minutes and
--minutes, and the export at the end.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import torch
import torch.nn as nn

from .. import device_sampler
from ..fieldio import IGNORE
from .export import export
from .models import set_train_mode
from .network_path import logits_to
from .samples import Sampler, StepBatches
from .start import Run, memory_format
from .validation import evaluate


def train(run: Run, args, t_start: float) -> int:
    """Trains from the run's step to the end of its last learning-rate cycle (or until --max-minutes,
    with a checkpoint), validates, checkpoints and exports; `t_start`: when the command started."""
    device, cuda, work, ckpt, ckpt_path, resume = run.device, run.cuda, run.work, run.ckpt, run.ckpt_path, run.resume
    model, opt, lr_scales, ema_model, ema_decay = run.model, run.opt, run.lr_scales, run.ema_model, run.ema_decay
    train_fields, val_field, val_factors, spec = run.train_fields, run.val_field, run.val_factors, run.spec
    classes, stages, exported_model = run.classes, run.stages, run.exported_model
    total_steps = stages[-1]["end"]
    sampler = Sampler(train_fields, spec, ckpt["crop"], *ckpt["gsd_factor_range"], ckpt["augment"], ckpt["seed"])
    criterion = nn.CrossEntropyLoss(weight=torch.tensor(ckpt["class_weights"], dtype=torch.float32),
                                    ignore_index=IGNORE).to(device)
    train_log = work / "train_log.csv"
    val_log = work / "val_log.csv"
    val_ema_log = work / "val_ema_log.csv"
    iou_cols = ",".join(f"iou_{c}" for c in classes)
    if not resume:
        train_log.write_text("step,elapsed_s,loss,lr,img_per_s\n")
        for log in (val_log, val_ema_log) if ema_model is not None else (val_log,):
            log.write_text(f"step,elapsed_s,gsd_factor,gsd_cm,images,miou_camera,miou_ortho,{iou_cols}\n")
    else:  # drop log rows written after the checkpoint: they will be redone
        for log in (train_log, val_log, val_ema_log):
            if log.exists():
                lines = log.read_text().splitlines(keepends=True)
                log.write_text("".join(lines[:1] + [ln for ln in lines[1:] if int(ln.split(",")[0]) <= ckpt["step"]]))

    def lr_at(step):
        st = next(c for c in stages if c["start"] <= step < c["end"])
        i, n, w = step - st["start"], st["end"] - st["start"], st["warmup"]
        if i < w:
            return st["lr"] * (i + 1) / w
        return st["lr"] * (1.0 - (i - w) / max(1, n - w)) ** 0.9

    def save_checkpoint():
        if ema_model is not None:
            ckpt["ema_model"] = {k: v.detach().cpu() for k, v in ema_model.state_dict().items()}
        ckpt.update({"model": {k: v.detach().cpu() for k, v in model.state_dict().items()},
                     "optimizer_state": opt.state_dict(), "torch_rng": torch.get_rng_state(),
                     "cuda_rng": torch.cuda.get_rng_state() if cuda else None})
        tmp = ckpt_path.with_suffix(".tmp")
        torch.save(ckpt, tmp)
        os.replace(tmp, ckpt_path)

    def validate(step):
        """Validates the trained weights (val_log.csv) and, with --ema, their average
        (val_ema_log.csv); returns the result of the weights that are exported."""
        for net, log, name in ((model, val_log, "val"), (ema_model, val_ema_log, "val ema")):
            if net is None:
                continue
            tv = time.time()
            res = evaluate(net, val_field, val_factors, spec, args.val_max_images or None, device)
            with log.open("a") as fh:
                for fac, r in res.items():
                    ious = ",".join("" if u is None else f"{u:.4f}" for u in r["iou_ortho"])
                    fh.write(f"{step},{ckpt['train_seconds']:.1f},{fac},{r['gsd_cm']:.3f},{r['images']},"
                             f"{r['miou_camera']:.4f},{r['miou_ortho']:.4f},{ious}\n")
            summary = " ".join(f"x{fac:g}:{r['miou_camera']:.3f}/{r['miou_ortho']:.3f}" for fac, r in res.items())
            print(f"[{name} step {step}] mIoU camera/ortho per GSD factor: {summary} ({time.time() - tv:.0f} s)",
                  flush=True)
        ckpt["last_val"] = {str(k): v for k, v in res.items()}
        return res

    # --minutes: the last cycle's length is fitted at the end of its warm-up (the learning rate of
    # the warm-up does not depend on it), from the time per step over its second half (or from the
    # step a resumed run starts at). A run resumed before that point fits it on resuming.
    fit_stage = stages[-1] if stages[-1].get("minutes") and "fitted_steps" not in stages[-1] else None
    fit_step = fit_stage["start"] + fit_stage["warmup"] if fit_stage else -1
    fit_from = max(fit_step - fit_stage["warmup"] // 2, ckpt["step"]) if fit_stage else -1
    if fit_stage and fit_step - fit_from < 10:
        raise SystemExit(f"--minutes: the checkpoint (step {ckpt['step']}) leaves fewer than 10 warm-up steps "
                         f"(to step {fit_step}) to measure the time per step; the cycle cannot be fitted")
    fit_t0 = None

    def fit_cycle(step):
        """Sets the cycle's end so that the steps left, their validations and the final one end
        within the budget (validating once here to measure a validation's time)."""
        nonlocal total_steps
        t_step = (time.time() - fit_t0) / (fit_step - fit_from)
        tv = time.time()
        validate(step)
        t_val = time.time() - tv
        left = 60.0 * fit_stage["minutes"] - (time.time() - t_start) - t_val - 15.0  # final validation, checkpoint
        per_step = t_step + (t_val / args.val_every if args.val_every > 0 else 0.0)
        n = max(1, int(0.97 * left / per_step))
        fit_stage["end"] = min(fit_stage["end"], step + n)
        fit_stage["fitted_steps"] = fit_stage["end"] - fit_stage["start"]
        fit_stage["measured_s_per_step"] = round(t_step, 5)
        fit_stage["measured_s_per_validation"] = round(t_val, 2)
        total_steps = stages[-1]["end"]
        print(f"--minutes {fit_stage['minutes']:g}: {t_step * 1000:.1f} ms per step, {t_val:.1f} s per "
              f"validation -> the cycle ends at step {total_steps}", flush=True)

    if ckpt.get("sampler", "cpu") == "device":  # resumed runs keep the sampler they started with
        loader = device_sampler.Prefetcher(device_sampler.DeviceSampler(sampler, device), ckpt["step"], total_steps,
                                           ckpt["batch"], depth=args.prefetch)
    else:
        workers = args.workers if args.workers >= 0 else (min(12, max(0, (os.cpu_count() or 1) - 2)) if cuda else 0)
        loader = torch.utils.data.DataLoader(
            StepBatches(sampler, ckpt["step"], total_steps, ckpt["batch"]), batch_size=None, shuffle=False,
            num_workers=workers, pin_memory=cuda, persistent_workers=False,
            **({"prefetch_factor": 4} if workers > 0 else {}))
    ckpt["devices"] = sorted(set(ckpt.get("devices", [])) | {args.device})
    ckpt["torch_versions"] = sorted(set(ckpt.get("torch_versions", [])) | {str(torch.__version__)})
    set_train_mode(model, ckpt)
    layout = memory_format(args)
    step = ckpt["step"]
    run_loss, run_n, t_log = 0.0, 0, time.time()
    if fit_stage and fit_from == step:  # resumed inside the measurement: it starts now (data start-up included)
        fit_t0 = time.time()
    paused = False
    for x, y in loader:
        if step >= total_steps:
            break
        ts = time.time()
        lr = lr_at(step)
        for g, s in zip(opt.param_groups, lr_scales):
            g["lr"] = lr * s
        x = x.to(device, non_blocking=True)
        y = y.to(device, non_blocking=True)
        x = x.contiguous(memory_format=layout)
        with torch.autocast(device_type=device.type, dtype=torch.bfloat16, enabled=cuda):
            logits = logits_to(model(x), y.shape[-2:])
        loss = criterion(logits.float(), y)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if ema_model is not None:
            with torch.no_grad():
                d = min(ema_decay, (1.0 + step) / (10.0 + step))
                for e, w in zip(ema_model.state_dict().values(), model.state_dict().values()):
                    if e.dtype.is_floating_point:
                        e.mul_(d).add_(w.detach(), alpha=1.0 - d)
                    else:
                        e.copy_(w)
        step += 1
        ckpt["step"] = step
        ckpt["train_seconds"] += time.time() - ts
        run_loss += float(loss)
        run_n += 1
        if step % args.log_every == 0 or step == total_steps:
            ips = run_n * ckpt["batch"] / (time.time() - t_log)
            with train_log.open("a") as fh:
                fh.write(f"{step},{ckpt['train_seconds']:.1f},{run_loss / run_n:.5f},{lr:.3e},{ips:.2f}\n")
            eta = (total_steps - step) * (time.time() - t_log) / run_n / 60
            print(f"step {step}/{total_steps} loss {run_loss / run_n:.4f} lr {lr:.2e} {ips:.2f} img/s "
                  f"elapsed {ckpt['train_seconds'] / 60:.1f} min, eta {eta:.1f} min", flush=True)
            run_loss, run_n, t_log = 0.0, 0, time.time()
        if fit_stage and step == fit_from:
            fit_t0 = time.time()
        if fit_stage and step == fit_step:
            fit_cycle(step)  # validates too
            fit_stage = None
            set_train_mode(model, ckpt)
            t_log = time.time()
        elif args.val_every > 0 and step % args.val_every == 0 and step < total_steps:
            validate(step)
            set_train_mode(model, ckpt)
            t_log = time.time()
        if step % args.ckpt_every == 0:
            save_checkpoint()
        if args.max_minutes > 0 and time.time() - t_start > 60.0 * args.max_minutes and step < total_steps:
            paused = True
            break
    if isinstance(loader, device_sampler.Prefetcher):
        loader.close()  # its thread may be making batches past the end
    if paused:
        save_checkpoint()
        print(f"stopped at step {step}/{total_steps} after {args.max_minutes:g} min (--max-minutes); "
              "continue with --resume", flush=True)
        return 0
    val = validate(step)
    save_checkpoint()
    print(f"training done: {step} steps, {ckpt['train_seconds'] / 60:.1f} min of training", flush=True)
    if not args.no_export:
        export(exported_model, ckpt, args, Path(args.model_dir), val)
    return 0
