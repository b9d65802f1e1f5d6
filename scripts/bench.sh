#!/usr/bin/env bash
# Installs what is missing, builds in Release, and runs the benchmarks:
#   GaussianProcess vs scikit-learn, the per-waypoint decision time, the planner's own time per
#   waypoint over whole missions, and each bundled network
#   through the ONNX backend (OpenCV DNN vs PyTorch), the bundled ensemble against its members, and a 20000 x 20000 GeoTIFF field loaded.
#   Results: docs/benchmarks.md.
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
bash scripts/deps.sh bench
source scripts/configure.sh
configure_for bench build/release
cmake --build build/release -j"$(nproc 2>/dev/null || echo 2)" --target bench_gaussian_process bench_decision bench_planner adaptseg_calibrate bench_erfnet \
  bench_ensemble bench_geotiff
# GaussianProcess vs scikit-learn twice, side by side: numpy/scipy on Debian's reference BLAS and
# LAPACK (single-threaded), then on OpenBLAS (multi-threaded; what a pip user's numpy brings).
# The loader picks the BLAS by LD_LIBRARY_PATH; adaptseg's own code uses Eigen, not BLAS.
lib=/usr/lib/$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)
for blas in "reference:$lib/blas:$lib/lapack" "openblas:$lib/openblas-pthread"; do
  echo "## scikit-learn on the ${blas%%:*} BLAS"
  LD_LIBRARY_PATH="${blas#*:}" /usr/bin/python3 benchmarks/bench_gaussian_process.py \
      build/release/benchmarks/bench_gaussian_process "$@"
done
build/release/benchmarks/bench_decision
# The planner's own time per waypoint over whole missions (calibrates its models first, cached).
bash benchmarks/bench_planner.sh build/release
for m in erfnet-dubai mobilenetv2-dubai; do
  /usr/bin/python3 benchmarks/bench_erfnet.py --model-dir "examples/models/$m" \
      --bench-bin build/release/benchmarks/bench_erfnet --rounds 5 --iters 10
done
# The bundled ensemble against its members, side by side, at 1 and 2 OpenCV threads.
echo "| backend | threads | segment [ms] |"
echo "| --- | ---: | ---: |"
for t in 1 2; do
  build/release/benchmarks/bench_ensemble examples/models/ensemble-dubai examples/data/dubai-tile-6 --threads "$t"
done
# A large GeoTIFF field: load time and memory (writes ~1.6 GB of scratch GeoTIFFs, then removes them).
bash benchmarks/bench_geotiff.sh build/release/benchmarks/bench_geotiff 20000
