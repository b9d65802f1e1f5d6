#!/usr/bin/env bash
# One training alone on a CUDA GPU, per sampler: how fast it steps and what share of the wall clock
# the training step itself takes (docs/benchmarks.md, "Training batches on the GPU").
#
#   bash benchmarks/train_pace.sh SERIAL_SAMPLER.py ENCODER_WEIGHTS.pt
#
# SERIAL_SAMPLER.py: an earlier python/adaptseg_tools/device_sampler.py to compare with (e.g.
# `git show 9b046a1:examples/tools/device_sampler.py`, from before the tools were a package),
# swapped in for the module's DeviceSampler;
# ENCODER_WEIGHTS.pt: MobileNetV2's ImageNet encoder (`bash scripts/loto.sh weights` writes
# .device/mnv2_enc.pt). Five runs, each alone: MobileNetV2 (300 steps) with the serial sampler,
# the batched one made when the step asks (--prefetch 0) and made ahead (--prefetch 2); ERFNet
# (full width, 200 steps) serial and batched with --prefetch 2. Batch 32, 100 warm-up steps; the
# table is over the train_log.csv rows after the warm-up. About 4 minutes on an H200.
set -uo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
serial=${1:?earlier device_sampler.py}
enc=${2:?MobileNetV2 encoder weights}
export PYTHONUNBUFFERED=1
# The interpreter with PyTorch and OpenCV: a device machine's plain python3, else Debian's.
py=${PYTHON:-$(python3 -c 'import torch, cv2' 2>/dev/null && echo python3 || echo /usr/bin/python3)}
work=$(mktemp -d)
cat >"$work/run.py" <<'PY'
import importlib.util, sys
from adaptseg_tools import device_sampler, train_segnet
if sys.argv[1] != "batched":
    spec = importlib.util.spec_from_file_location("serial_sampler", sys.argv[1])
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    device_sampler.DeviceSampler = mod.DeviceSampler
sys.exit(train_segnet.main(sys.argv[2:]))
PY
common=(--augment altitude --sampler device --device cuda --train-fields dubai-tile-1,dubai-tile-2,dubai-tile-3,dubai-tile-5
        --val-field dubai-tile-4 --test-field none --threads 1 --val-every 0 --ckpt-every 100000 --log-every 50
        --no-export --val-max-images 2 --batch 32 --warmup 100 --seed 0)
mnv2=(--arch mobilenetv2 --encoder-weights "$enc" --frozen-blocks 4 --no-image-pooling --lr 1e-3 --weight-decay 0.01
      --ema 0.998 --crop 300 --steps 300)
erf=(--arch erfnet --width 1.0 --crop 352 --lr 2e-3 --ema 0.999 --steps 200)
for cfg in "mobilenetv2 serial 0" "mobilenetv2 batched 0" "mobilenetv2 batched 2" "erfnet serial 0" "erfnet batched 2"; do
  set -- $cfg
  if [ "$1" = mobilenetv2 ]; then a=("${mnv2[@]}"); else a=("${erf[@]}"); fi
  src=batched
  [ "$2" = serial ] && src=$serial
  "$py" "$work/run.py" "$src" "${a[@]}" "${common[@]}" --prefetch "$3" --work-dir "$work/$1-$2-$3" \
    --model-dir "$work/unused" >"$work/$1-$2-$3.log" 2>&1 || { echo "$cfg failed: $work/$1-$2-$3.log" >&2; exit 1; }
done
"$py" - "$work" <<'PY'
import csv, statistics, sys
from pathlib import Path
print("| network | sampler | --prefetch | crops/s | training step's share of the wall clock | ms per step (training) |")
print("| --- | --- | ---: | ---: | ---: | ---: |")
for cfg in ("mobilenetv2-serial-0", "mobilenetv2-batched-0", "mobilenetv2-batched-2", "erfnet-serial-0", "erfnet-batched-2"):
    rows = list(csv.DictReader(open(Path(sys.argv[1]) / cfg / "train_log.csv")))
    warm = next(r for r in rows if int(r["step"]) == 100)
    post = [r for r in rows if int(r["step"]) > 100]
    ips = [float(r["img_per_s"]) for r in post]
    wall = sum(50 * 32 / x for x in ips)  # rows every 50 steps of 32 crops
    train = float(post[-1]["elapsed_s"]) - float(warm["elapsed_s"])
    steps = int(post[-1]["step"]) - 100
    net, sampler, prefetch = cfg.split("-")
    print(f"| {net} | {sampler} | {prefetch} | {statistics.median(ips):.0f} | {100 * train / wall:.0f} % | "
          f"{1000 * train / steps:.1f} |")
PY
