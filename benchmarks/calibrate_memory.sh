#!/usr/bin/env bash
# A leave-one-tile-out calibration with freed memory given back to the system (glibc's default,
# ADAPTSEG_KEEP_FREED_MEMORY=0) and kept (the programs' default, examples/common/host_memory.hpp),
# side by side (docs/benchmarks.md, "Calibration: freed memory kept"):
#
#   bash benchmarks/calibrate_memory.sh [ROUNDS] [CLASS] [TILE]
#
# The calibration `scripts/results.sh loto` runs for CLASS (default road) with TILE (default 3)
# held out: the five other bundled Dubai tiles, each segmented by the leave-one-tile-out
# MobileNetV2 that never saw it, the deployment's flags when it was measured (2026-12-04: pooled
# maps, β a line in the field's entropy tried first, then `cells` and `fields`), one thread,
# segmentations from out/results/segmentation-cache. One warm-up run (it fills the cache where it
# is cold), then ROUNDS (default 2) pairs, given back then kept, each alone. Prints each run's
# wall-clock seconds, user and kernel CPU seconds, minor page faults and peak resident size, the
# median ratio of the wall-clock seconds, and checks that the two settings wrote the same model
# byte for byte. About 8 minutes on the 2-core VM with nothing else running.
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-2}
cls=${2:-road}
held=${3:-3}
source scripts/configure.sh
configure_for results build/release >/dev/null
cmake --build build/release -j2 --target adaptseg_calibrate >/dev/null
nets=examples/models/mobilenetv2-dubai-loto
# shellcheck disable=SC2054  # the slope poolings are one comma-separated word
args=(--interest "$cls" --network "$nets/tile-$held" --segmenter network --threads 1
      --segmentation-cache out/results/segmentation-cache --map-fusion pooled
      --slope-pooling field-entropy,cells,fields)
for k in 1 2 3 4 5 6; do
  [ "$k" = "$held" ] || args+=(--train "examples/data/dubai-tile-$k" --calibration-network "$nets/tile-$k")
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# run NAME KEEP: one calibration under a parent that records its resource use.
run() {
  ADAPTSEG_KEEP_FREED_MEMORY=$2 /usr/bin/python3 - "$work/$1.usage" build/release/examples/adaptseg_calibrate \
    "${args[@]}" --out "$work/$1.yaml" >"$work/$1.log" 2>&1 <<'PY' || { echo "run $1 failed:"; tail -5 "$work/$1.log"; exit 1; } >&2
import resource, subprocess, sys, time
t = time.monotonic()
rc = subprocess.run(sys.argv[2:]).returncode
u = resource.getrusage(resource.RUSAGE_CHILDREN)
open(sys.argv[1], "w").write(f"{time.monotonic() - t:.1f} {u.ru_utime:.1f} {u.ru_stime:.1f} {u.ru_minflt} {u.ru_maxrss}\n")
sys.exit(rc)
PY
}
run warmup 1
for r in $(seq "$rounds"); do
  run "given-$r" 0
  run "kept-$r" 1
done
/usr/bin/python3 - "$work" "$rounds" <<'PY'
import filecmp, os, statistics, sys
work, rounds = sys.argv[1], int(sys.argv[2])
print("| round | freed memory | wall [s] | user CPU [s] | kernel CPU [s] | minor faults | peak resident [MB] |")
print("| ---: | --- | ---: | ---: | ---: | ---: | ---: |")
wall = {}
for r in range(1, rounds + 1):
    for name in ("given", "kept"):
        w, user, kernel, faults, rss = open(os.path.join(work, f"{name}-{r}.usage")).read().split()
        wall[name, r] = float(w)
        label = "given back (ADAPTSEG_KEEP_FREED_MEMORY=0)" if name == "given" else "kept (default)"
        print(f"| {r} | {label} | {w} | {user} | {kernel} | {int(faults):,} | {int(rss) / 1024:.0f} |")
ratio = statistics.median(wall["kept", r] / wall["given", r] for r in range(1, rounds + 1))
print(f"\nkept / given back, wall clock (median over rounds): {ratio:.2f}")
same = all(filecmp.cmp(os.path.join(work, f"given-{r}.yaml"), os.path.join(work, f"kept-{r}.yaml"), shallow=False)
           for r in range(1, rounds + 1))
print("models byte-identical" if same else "MODELS DIFFER")
sys.exit(0 if same else 1)
PY
