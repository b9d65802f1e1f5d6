#!/usr/bin/env bash
# Reproduces docs/results.md: the paper's experiment with the ground-truth oracle on the
# bundled WeedMap field (train on one half, test on the other, then swapped) and on the Dubai
# tiles (decision function initialised on tile 4, tested on tiles 1, 2, 3, 5, 6; one target
# class at a time). Deterministic: fixed segmentation (0.1 s/image) and planning (0 s) times.
# Then the ERFNet experiment (measured segmentation times, so its times vary from run to run).
# Outputs under out/results/; prints the tables. About 25 minutes on 2 cores.
#   bash scripts/results.sh [all|oracle|erfnet]   (default all; erfnet alone: ~4 minutes)
set -euo pipefail
part=${1:-all}
case "$part" in all | oracle | erfnet) ;; *) echo "usage: $0 [all|oracle|erfnet]" >&2; exit 2 ;; esac
cd "$(dirname "$0")/.."
bash scripts/deps.sh plots
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc 2>/dev/null || echo 2)" --target adaptseg_evaluate
eval=build/release/examples/adaptseg_evaluate
fixed=(--seg-time-s 0.1 --plan-time-s 0)
paper=(--gain-inputs delta-sigma --coverage region)
height=(--gain-inputs delta-sigma-height --coverage region)
classes="building land road vegetation water"
if [ "$part" != erfnet ]; then
  w=examples/data/weedmap-000
  $eval --train "$w:0,0,0.5,1" --test "$w:0.5,0,1,1" --out out/results/weedmap-train-left "${fixed[@]}"
  $eval --train "$w:0.5,0,1,1" --test "$w:0,0,0.5,1" --out out/results/weedmap-train-right "${fixed[@]}"
  tests=()
  for t in 1 2 3 5 6; do tests+=(--test examples/data/dubai-tile-$t); done
  # Dubai with the defaults (I on delta sigma and delta h, descents over the cells showing the
  # class), then the same with the paper's I and sub-lawnmower, and with the paper's
  # sub-lawnmower alone (ablation; no figures).
  for cls in $classes; do
    $eval --train examples/data/dubai-tile-4 "${tests[@]}" --interest "$cls" --out "out/results/dubai-$cls" "${fixed[@]}"
    $eval --train examples/data/dubai-tile-4 "${tests[@]}" --interest "$cls" --out "out/results/ablation-paper/dubai-$cls" \
      "${fixed[@]}" "${paper[@]}" --no-plots
    $eval --train examples/data/dubai-tile-4 "${tests[@]}" --interest "$cls" --out "out/results/ablation-height/dubai-$cls" \
      "${fixed[@]}" "${height[@]}" --no-plots
  done
  /usr/bin/python3 examples/tools/results_table.py out/results/weedmap-train-left out/results/weedmap-train-right
  /usr/bin/python3 examples/tools/results_table.py out/results/dubai-*
  /usr/bin/python3 examples/tools/margin_table.py \
    "paper: I(Δσ), whole region=$(for c in $classes; do printf 'out/results/ablation-paper/dubai-%s,' "$c"; done | sed 's/,$//')" \
    "I(Δσ, Δh), whole region=$(for c in $classes; do printf 'out/results/ablation-height/dubai-%s,' "$c"; done | sed 's/,$//')" \
    "I(Δσ, Δh), cells of interest (default)=$(for c in $classes; do printf 'out/results/dubai-%s,' "$c"; done | sed 's/,$//')"
  /usr/bin/python3 examples/tools/per_image_table.py out/results/weedmap-train-left out/results/weedmap-train-right
fi
if [ "$part" != oracle ]; then
  # The ERFNet backend (measured segmentation times): initialised on tile 4, flown on tile 6;
  # the defaults, then the paper's I and sub-lawnmower.
  $eval --train examples/data/dubai-tile-4 --test examples/data/dubai-tile-6 --segmenter erfnet \
    --model-file examples/models/erfnet-dubai --threads 2 --out out/results/erfnet-veg
  $eval --train examples/data/dubai-tile-4 --test examples/data/dubai-tile-6 --segmenter erfnet \
    --model-file examples/models/erfnet-dubai --threads 2 --out out/results/ablation-paper/erfnet-veg "${paper[@]}" --no-plots
  /usr/bin/python3 examples/tools/results_table.py out/results/erfnet-veg
  /usr/bin/python3 examples/tools/margin_table.py "paper=out/results/ablation-paper/erfnet-veg" "default=out/results/erfnet-veg"
  # Per-image mIoU by GSD also on the calibration tile 4 (the network's validation tile): its
  # lawnmower rows (the adaptive rows there fly the tile the model was calibrated on).
  $eval --model out/results/erfnet-veg/model.yaml --test examples/data/dubai-tile-4 --interest vegetation \
    --segmenter erfnet --model-file examples/models/erfnet-dubai --threads 2 --out out/results/erfnet-tile4 --no-plots
  /usr/bin/python3 examples/tools/per_image_table.py out/results/erfnet-veg out/results/erfnet-tile4
fi
