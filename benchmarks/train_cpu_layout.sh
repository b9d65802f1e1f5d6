#!/usr/bin/env bash
# The MobileNetV2 deployment recipe's training step on the CPU, channels-last against contiguous
# (train_segnet.py --memory-format; docs/benchmarks.md, "Training on the CPU: the layout").
#
#   bash benchmarks/train_cpu_layout.sh ENCODER_WEIGHTS.pt [STEPS] [ROUNDS]
#
# ENCODER_WEIGHTS.pt: MobileNetV2's ImageNet encoder (`bash scripts/loto.sh weights` writes
# .device/mnv2_enc.pt). ROUNDS (default 2) pairs of runs, contiguous then channels-last, each alone:
# recipe-cpu's settings (scripts/loto.sh; tile 1 held out, seed 1, batch 32, crops of 300 px, two
# threads, one data worker) for STEPS steps (default 12, a multiple of 4; the learning rate still
# in its warm-up). Prints each run's seconds per training step (train_log.csv elapsed_s, the step
# itself without waiting for its batch) over the steps after the fourth (the first
# four start the worker and the caches) and its last logged loss, then the median ratio. About 10
# minutes on the 2-core VM with nothing else running.
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
enc=${1:?MobileNetV2 encoder weights}
steps=${2:-12}
rounds=${3:-2}
[ $((steps % 4)) -eq 0 ] && [ "$steps" -ge 8 ] || { echo "STEPS: a multiple of 4, at least 8" >&2; exit 2; }
# The interpreter with PyTorch and OpenCV: a device machine's plain python3, else Debian's.
py=${PYTHON:-$(python3 -c 'import torch, cv2' 2>/dev/null && echo python3 || echo /usr/bin/python3)}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for r in $(seq "$rounds"); do
  for layout in contiguous channels-last; do
    "$py" -m adaptseg_tools.train_segnet --arch mobilenetv2 --encoder-weights "$enc" --frozen-blocks 4 \
      --no-image-pooling --lr 1e-3 --weight-decay 0.01 --ema 0.998 --augment altitude --seed 1 --sampler cpu \
      --device cpu --workers 1 --threads 2 --train-fields dubai-tile-2,dubai-tile-3,dubai-tile-4,dubai-tile-5,dubai-tile-6 \
      --val-field dubai-tile-1 --test-field none --val-every 0 --ckpt-every 100000 --log-every 4 --no-export \
      --steps "$steps" --batch 32 --crop 300 --warmup 100 --memory-format "$layout" \
      --work-dir "$work/$layout-$r" --model-dir "$work/unused" >"$work/$layout-$r.log" 2>&1 ||
      { echo "$layout run $r failed:"; tail -5 "$work/$layout-$r.log"; exit 1; } >&2
  done
done
"$py" - "$work" "$rounds" <<'PY'
import csv, statistics, sys
from pathlib import Path
work, rounds = Path(sys.argv[1]), int(sys.argv[2])
print("| round | layout | s per training step (after step 4) | last loss |")
print("| ---: | --- | ---: | ---: |")
per = {}
for r in range(1, rounds + 1):
    for layout in ("contiguous", "channels-last"):
        rows = list(csv.DictReader(open(work / f"{layout}-{r}" / "train_log.csv")))
        first = next(x for x in rows if int(x["step"]) == 4)
        s = (float(rows[-1]["elapsed_s"]) - float(first["elapsed_s"])) / (int(rows[-1]["step"]) - 4)
        per[(r, layout)] = s
        print(f"| {r} | {layout} | {s:.2f} | {float(rows[-1]['loss']):.5f} |")
ratios = [per[(r, "channels-last")] / per[(r, "contiguous")] for r in range(1, rounds + 1)]
print(f"\nchannels-last / contiguous, median over the rounds: {statistics.median(ratios):.2f}")
PY
