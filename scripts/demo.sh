#!/usr/bin/env bash
# Installs what is missing, builds, and runs the main job on the bundled data: the paper's
# experiment on the WeedMap field with the ground-truth oracle (decision function initialised
# on the left half, every strategy flown over the right half). Results and figures: out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh demo
source scripts/configure.sh
configure_for demo build/release
# Only the program the demo runs (the others: cmake --build build/release, docs/quickstart.md).
cmake --build build/release -j"$(nproc 2>/dev/null || echo 2)" --target adaptseg_evaluate
build/release/examples/adaptseg_evaluate --train examples/data/weedmap-000:0,0,0.5,1 \
  --test examples/data/weedmap-000:0.5,0,1,1 --segmenter oracle --out out/demo
echo "demo: results in out/demo/ (results.csv, per_image.csv, miou_vs_time.png, paths.png, maps.png, ...)"
