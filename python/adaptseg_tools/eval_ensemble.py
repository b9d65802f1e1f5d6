"""Field mIoU of several networks and of their ensembles, side by side, on the same images.

Every band is a whole-field lawnmower at that GSD (footprints as adaptseg's LawnmowerPlanner
places them, images rendered as its SimulatedSensor renders them, as in eval_segnet.py). Each
member runs on the path of the C++ backend (resampled to its input size, logits back to the
camera size) in PyTorch on the weights its model.onnx was exported from (model.pt), or, where the
folder has only its model.onnx (the bundled leave-one-tile-out networks), through OpenCV's DNN
module as the C++ backend runs it; its probabilities are
softmax(logits / T) with the temperature of its model.yaml (1 where it has none). An ensemble's
labels are the argmax of its members' weighted mean probabilities (ties to the lower class), as
adaptseg::EnsembleSegmenter gives them. Labels are scored against the orthomosaic labels at
orthomosaic resolution; field mIoU over the classes present in truth or prediction.

Members are named NAME=MODEL_DIR, NAME=MODEL_DIR@mirror for the network with test-time mirror
(OnnxParams::test_time_mirror: the mean of its probabilities over the image and its left-right
mirror), NAME=MODEL_DIR@coarseG for the network with a test-time coarser look
(OnnxParams::test_time_coarse_gsd_cm G: an image finer than G cm/px also segmented shrunk to
min(G, 2 x its GSD), the mean of the passes), or both (@mirror@coarseG); an ensemble is
NAME=MEMBER+MEMBER[+...] (equal weights) or an ensemble directory (ensemble.yaml, its members
resolved relative to it, each matched to the member of that directory and those settings).

With --match-colour each member sees the field's images matched, per channel, to the mean and
standard deviation of the fields it trained on (model.yaml's training fields, read from
examples/data): x' = (x - mu_field) / sd_field * sd_train + mu_train, mu_field and sd_field over the
field's labelled ground (what a flight would estimate from its top-level images), mu_train and
sd_train the means of its training fields' own. A diagnosis of whether new ground differs from the
training fields in colour alone; the C++ backend has no such step.

Usage:
  PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.eval_ensemble \\
      --members mnv2=examples/models/mobilenetv2-dubai,erf=examples/models/erfnet-dubai \\
      --ensembles both=mnv2+erf [--fields F1,F2] [--bands 1,3] [--json out.json]
  (a mirrored member: mnv2m=examples/models/mobilenetv2-dubai@mirror; with the coarser look:
   c=examples/models/mobilenetv2-dubai-loto/tile-5@coarse10)
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch
import yaml

from . import REPO
from .fieldio import IGNORE
from .training.fields import capture, lawnmower_rects, load_field
from .training.models import exported_checkpoint, load_exported, net_spec
from .training.network_path import logits_to, to_network_size, to_tensor
from .training.validation import confusion, miou


def coarse_gsd(coarse_gsd_cm: float, gsd_cm: float) -> float:
    """OnnxSegmenter::coarse_gsd_cm: the GSD of the coarser pass for an image at `gsd_cm`,
    min(G, 2 x gsd_cm) where at least 10 % coarser, else 0 (none)."""
    if coarse_gsd_cm <= 0:
        return 0.0
    g = min(coarse_gsd_cm, 2.0 * gsd_cm)
    return g if g >= 1.1 * gsd_cm else 0.0


def one_pass(model, spec, meta, bgr: np.ndarray, input_wh, flip: bool) -> np.ndarray:
    """softmax(logits / T) of one pass at input size `input_wh`, mirrored (and flipped back)
    where `flip`."""
    image = np.ascontiguousarray(bgr[:, ::-1]) if flip else bgr
    x = torch.from_numpy(to_tensor(to_network_size(image, input_wh), spec.mean, spec.std))[None]
    with torch.no_grad():
        logits = logits_to(model(x).float(), bgr.shape[:2])[0]
    p = torch.softmax(logits / float(meta.get("temperature", 1.0)), dim=0).numpy()
    return np.ascontiguousarray(p[:, :, ::-1]) if flip else p


def member_probabilities(model, spec, meta, bgr: np.ndarray, mirror: bool = False,
                         coarse_gsd_cm: float = 0.0, gsd_cm: float = 0.0) -> np.ndarray:
    """C x H x W probabilities of a camera image, the C++ backend's path (OnnxSegmenter): with
    `mirror` the mean of those of the image and of its left-right mirror (flipped back); with
    `coarse_gsd_cm` also those of the image shrunk to coarse_gsd() (each side of the input a
    multiple of 32 px, halves rounded up as C++'s std::lround does), the mean over every pass."""
    sizes = [tuple(spec.input_wh)]
    g = coarse_gsd(coarse_gsd_cm, gsd_cm)
    if g > 0:
        sizes.append(tuple(max(32, int(np.floor(v * gsd_cm / g / 32.0 + 0.5)) * 32) for v in spec.input_wh))
    passes = [one_pass(model, spec, meta, bgr, wh, flip) for wh in sizes for flip in ((False, True) if mirror else (False,))]
    return passes[0] if len(passes) == 1 else sum(passes) / len(passes)


def colour_stats(field) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel (BGR) mean and standard deviation of a field's image over its labelled ground."""
    pixels = field.image[field.labels != IGNORE].astype(np.float64)
    return pixels.mean(0), pixels.std(0)


def training_colour(meta: dict, cache: dict) -> tuple[np.ndarray, np.ndarray]:
    """The mean over a member's training fields (model.yaml) of their per-channel means and
    standard deviations."""
    names = (meta.get("training") or {}).get("fields") or []
    if not names:
        raise SystemExit("--match-colour: a member's model.yaml names no training fields")
    for name in names:
        if name not in cache:
            d = REPO / "examples" / "data" / name
            if not (d / "field.yaml").is_file():
                raise SystemExit(f"--match-colour: training field {name} is not in {d.parent}")
            cache[name] = colour_stats(load_field(d))
    return np.mean([cache[n][0] for n in names], 0), np.mean([cache[n][1] for n in names], 0)


def match_colour(bgr: np.ndarray, field_colour, train_colour) -> np.ndarray:
    """An 8-bit image with each channel moved from the field's mean and standard deviation to the
    training fields' (--match-colour), rounded and clipped to 0..255."""
    (mu_f, sd_f), (mu_t, sd_t) = field_colour, train_colour
    return np.clip((bgr - mu_f) / np.maximum(sd_f, 1e-6) * sd_t + mu_t + 0.5, 0, 255).astype(np.uint8)


def load_member(model_dir: Path):
    """A member's network, NetSpec and metadata: its PyTorch weights (model.pt) where the folder has
    them, else its model.onnx run by OpenCV's DNN module, the C++ backend's runtime (the bundled
    networks ship no model.pt; their export checked both agree, model.yaml's `check`)."""
    model_dir = Path(model_dir)
    if (model_dir / "model.pt").is_file():
        return load_exported(model_dir)
    if not (model_dir / "model.onnx").is_file():
        raise SystemExit(f"{model_dir}: neither model.pt nor model.onnx")
    meta = yaml.safe_load((model_dir / "model.yaml").read_text())
    spec = net_spec(exported_checkpoint(meta))
    net = cv2.dnn.readNetFromONNX(str(model_dir / "model.onnx"))

    def model(x: torch.Tensor) -> torch.Tensor:
        net.setInput(np.ascontiguousarray(x.numpy()))
        return torch.from_numpy(net.forward().copy())

    return model, spec, meta


def member_dir(value: str) -> tuple[Path, bool, float]:
    """NAME=VALUE's model directory (resolved), whether it is mirrored (@mirror) and its coarser
    look's GSD (@coarseG; 0: none)."""
    path, *tags = value.split("@")
    mirror, coarse = False, 0.0
    for tag in tags:
        g = re.fullmatch(r"coarse(\d+\.?\d*|\.\d+)", tag)
        if tag == "mirror":
            mirror = True
        elif g and float(g.group(1)) > 0:
            coarse = float(g.group(1))
        else:
            raise SystemExit(f"{value}: unknown setting @{tag} (known: @mirror, @coarseG with G > 0 in cm/px)")
    return Path(path).resolve(), mirror, coarse


def parse_pairs(text: str) -> dict[str, str]:
    out = {}
    for item in filter(None, text.split(",")):
        name, _, value = item.partition("=")
        if not value:
            raise SystemExit(f"'{item}': expected NAME=VALUE")
        out[name] = value
    return out


def ensemble_members(spec: str, members: dict) -> list[tuple[str, float]]:
    """[(member name, weight)] of NAME+NAME or of an ensemble directory's ensemble.yaml."""
    path = Path(spec)
    if (path / "ensemble.yaml").is_file():
        doc = yaml.safe_load((path / "ensemble.yaml").read_text())
        out = []
        for m in doc["members"]:
            want = ((path / m["model"]).resolve(), bool(m.get("mirror", False)), float(m.get("coarse_gsd_cm", 0.0)))
            name = next((k for k, v in members.items() if member_dir(v) == want), None)
            if name is None:
                tags = ("@mirror" if want[1] else "") + (f"@coarse{want[2]:g}" if want[2] else "")
                raise SystemExit(f"{spec}: member {m['model']}{tags} is not among --members")
            out.append((name, float(m.get("weight", 1.0))))
        return out
    names = spec.split("+")
    for n in names:
        if n not in members:
            raise SystemExit(f"ensemble '{spec}': unknown member '{n}'")
    return [(n, 1.0) for n in names]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--members", required=True, help="NAME=MODEL_DIR,...")
    ap.add_argument("--ensembles", default="", help="NAME=M1+M2[+...] or NAME=ENSEMBLE_DIR, ...")
    ap.add_argument("--fields", default=",".join(str(REPO / "examples" / "data" / f"dubai-tile-{k}") for k in (4, 6)))
    ap.add_argument("--bands", default="1,3", help="GSD factors of the fields' GSD")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--match-colour", action="store_true",
                    help="match each field's colour to each member's training fields (a diagnosis)")
    ap.add_argument("--json")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)

    member_dirs = parse_pairs(args.members)
    ensembles = {name: ensemble_members(spec, member_dirs) for name, spec in parse_pairs(args.ensembles).items()}
    nets = {}
    for name, d in member_dirs.items():
        model_dir, mirror, coarse = member_dir(d)
        model, spec, meta = load_member(model_dir)
        nets[name] = (model, spec, meta, mirror, coarse)
    classes = next(iter(nets.values()))[2]["classes"]
    for name, (_, _, meta, _, _) in nets.items():
        if meta["classes"] != classes:
            raise SystemExit(f"member {name}: classes {meta['classes']} differ from {classes}")
    cams = {tuple(s.camera_wh) for _, s, _, _, _ in nets.values()}
    if len(cams) != 1:
        raise SystemExit(f"members trained for different cameras: {sorted(cams)}")
    cam_wh = cams.pop()
    stats_cache: dict = {}
    train_colour = {n: training_colour(meta, stats_cache) for n, (_, _, meta, _, _) in nets.items()} if args.match_colour else {}
    nc = len(classes)
    bands = [float(v) for v in args.bands.split(",")]
    rows = list(member_dirs) + list(ensembles)
    results = {}
    seconds = {n: 0.0 for n in member_dirs}
    for fdir in args.fields.split(","):
        field = load_field(Path(fdir))
        if field.classes != classes:
            raise SystemExit(f"{fdir}: classes {field.classes} differ from the members' {classes}")
        results[field.name] = {}
        field_colour = colour_stats(field) if args.match_colour else None
        for fac in bands:
            gsd = field.gsd_cm * fac
            cms = {r: np.zeros((nc, nc + 1), np.int64) for r in rows}
            n_img = 0
            for (c0, r0, fw, fh) in lawnmower_rects(field, gsd, cam_wh):
                rgb, _, gt = capture(field, c0, r0, fw, fh, cam_wh)
                if (gt != IGNORE).sum() == 0:
                    continue
                probs = {}
                for name, (model, spec, meta, mirror, coarse) in nets.items():
                    image = rgb if field_colour is None else match_colour(rgb, field_colour, train_colour[name])
                    t0 = time.perf_counter()
                    probs[name] = member_probabilities(model, spec, meta, image, mirror, coarse, gsd)
                    seconds[name] += time.perf_counter() - t0
                labels = {n: p.argmax(0) for n, p in probs.items()}
                for ens, mem in ensembles.items():
                    w = sum(wt for _, wt in mem)
                    labels[ens] = (sum(wt * probs[n] for n, wt in mem) / w).argmax(0)
                for r in rows:
                    up = cv2.resize(labels[r].astype(np.uint8), (fw, fh), interpolation=cv2.INTER_NEAREST_EXACT)
                    cms[r] += confusion(gt, up, nc)
                n_img += 1
            results[field.name][fac] = {"gsd_cm": gsd, "images": n_img,
                                        **{r: dict(zip(("miou", "iou"), miou(cms[r]))) for r in rows}}
        print(f"{field.name}: done", file=sys.stderr, flush=True)

    header = [f"{f} {b['gsd_cm']:.0f} cm/px" for f, fr in results.items() for b in fr.values()]
    print("| network | " + " | ".join(header) + " |")
    print("| --- | " + " | ".join("---:" for _ in header) + " |")
    for r in rows:
        label = r if r in member_dirs else f"{r} ({' + '.join(n for n, _ in ensembles[r])})"
        print(f"| {label} | " + " | ".join(f"{b[r]['miou']:.3f}" for fr in results.values() for b in fr.values()) + " |")
    print("\ntime per image and member (this machine, "
          f"{args.threads} threads): " + ", ".join(f"{n} {1000 * s / max(1, sum(b['images'] for fr in results.values() for b in fr.values())):.0f} ms"
                                                  for n, s in seconds.items()))
    if args.json:
        Path(args.json).write_text(json.dumps({"classes": classes, "members": member_dirs, "match_colour": args.match_colour,
                                               "ensembles": {k: v for k, v in ensembles.items()},
                                               "fields": results}, indent=2) + "\n")


if __name__ == "__main__":
    main()
