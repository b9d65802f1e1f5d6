#!/usr/bin/env bash
# The MobileNetV2 deployment recipe's training step on the CPU, two settings of train_segnet.py
# side by side (docs/benchmarks.md, "Training on the CPU"):
#
#   bash benchmarks/train_cpu.sh layout|memory [STEPS] [ROUNDS]
#
# layout: --memory-format contiguous against channels-last (freed memory kept in both).
# memory: --no-keep-freed-memory (glibc's default: large allocations mapped and unmapped each
#         time) against --keep-freed-memory (channels-last in both).
# The recipe's ImageNet encoder weights first: `bash scripts/loto.sh weights` writes
# .device/mnv2_enc.pt. ROUNDS (default 2) pairs of runs, the first setting then the second, each
# alone: recipe-cpu's settings (scripts/loto_recipe.sh and scripts/loto.sh; tile 1 held out,
# seed 1, batch 32, crops of 300 px, two threads, one data worker) for STEPS steps (default 12,
# a multiple of 4; the learning rate still in its warm-up). Prints each run's seconds per training
# step (train_log.csv elapsed_s, the step itself without waiting for its batch) over the steps
# after the fourth (the first four start the worker and the caches), its wall-clock seconds, kernel
# CPU seconds and minor page faults (the whole run with its data worker, startup included), its
# last logged loss, then the median ratio of the seconds per step. About 10 minutes on the 2-core
# VM with nothing else running.
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
compare=${1:?layout or memory}
steps=${2:-12}
rounds=${3:-2}
source scripts/loto_recipe.sh
[ -s .device/mnv2_enc.pt ] || { echo "no .device/mnv2_enc.pt: run 'bash scripts/loto.sh weights' first" >&2; exit 2; }
case "$compare" in
  layout) settings=("--memory-format contiguous" "--memory-format channels-last") ;;
  memory) settings=("--no-keep-freed-memory" "--keep-freed-memory") ;;
  *) echo "compare: layout or memory, not '$compare'" >&2; exit 2 ;;
esac
[ $((steps % 4)) -eq 0 ] && [ "$steps" -ge 8 ] || { echo "STEPS: a multiple of 4, at least 8" >&2; exit 2; }
# The interpreter with PyTorch and OpenCV: a device machine's plain python3, else Debian's.
py=${PYTHON:-$(python3 -c 'import torch, cv2' 2>/dev/null && echo python3 || echo /usr/bin/python3)}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for r in $(seq "$rounds"); do
  for i in 0 1; do
    # Run under a parent that records its children's (the run's and its worker's) resource use.
    # shellcheck disable=SC2086  # the setting is two words or one, split on purpose
    "$py" - "$work/$i-$r.usage" "$py" -m adaptseg_tools.train_segnet "${loto_recipe[@]}" \
      --seed 1 --sampler cpu --device cpu --workers 1 --threads 2 \
      --train-fields dubai-tile-2,dubai-tile-3,dubai-tile-4,dubai-tile-5,dubai-tile-6 \
      --val-field dubai-tile-1 --test-field none --val-every 0 --ckpt-every 100000 --log-every 4 --no-export \
      --steps "$steps" "${loto_batch[@]}" ${settings[$i]} \
      --work-dir "$work/$i-$r" --model-dir "$work/unused" >"$work/$i-$r.log" 2>&1 <<'PY' ||
import resource, subprocess, sys, time
t = time.monotonic()
rc = subprocess.run(sys.argv[2:]).returncode
u = resource.getrusage(resource.RUSAGE_CHILDREN)
open(sys.argv[1], "w").write(f"{time.monotonic() - t:.1f} {u.ru_stime:.1f} {u.ru_minflt}\n")
sys.exit(rc)
PY
      { echo "${settings[$i]} run $r failed:"; tail -5 "$work/$i-$r.log"; exit 1; } >&2
  done
done
"$py" - "$work" "$rounds" "${settings[@]}" <<'PY'
import csv, statistics, sys
from pathlib import Path
work, rounds, names = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
print("| round | setting | s per training step (after step 4) | wall s | kernel CPU s | minor faults | last loss |")
print("| ---: | --- | ---: | ---: | ---: | ---: | ---: |")
per = {}
for r in range(1, rounds + 1):
    for i, name in enumerate(names):
        rows = list(csv.DictReader(open(work / f"{i}-{r}" / "train_log.csv")))
        first = next(x for x in rows if int(x["step"]) == 4)
        s = (float(rows[-1]["elapsed_s"]) - float(first["elapsed_s"])) / (int(rows[-1]["step"]) - 4)
        per[(r, i)] = s
        wall, sys_s, faults = (work / f"{i}-{r}.usage").read_text().split()
        print(f"| {r} | `{name}` | {s:.2f} | {wall} | {sys_s} | {int(faults):,} | {float(rows[-1]['loss']):.5f} |")
ratios = [per[(r, 1)] / per[(r, 0)] for r in range(1, rounds + 1)]
print(f"\n`{names[1]}` / `{names[0]}`, median over the rounds: {statistics.median(ratios):.2f}")
PY
