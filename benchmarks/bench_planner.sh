#!/usr/bin/env bash
# The planner's own time per waypoint (benchmarks/bench_planner.cpp): whole adaptive missions at
# the default settings, the segmentation made before the clock starts, with the oracle and with
# each bundled network, the planner at 1 and 2 OpenCV threads. Models: calibrated here with each
# backend on Dubai tiles 1, 2, 3, 5 (vegetation and buildings; networks' segmentations cached in
# out/bench-planner/cache) and on WeedMap's left half (oracle), then flown over tiles 4 and 6 (and
# WeedMap's right half). Prints one Markdown table; docs/benchmarks.md, "The planner's own time".
#   bash benchmarks/bench_planner.sh [BUILD_DIR]     (default build/release, built by scripts/bench.sh)
#   BEFORE=OTHER/bench_planner bash benchmarks/bench_planner.sh
#       also runs another build's bench_planner (e.g. of an earlier commit, this benchmark copied
#       in) on every row right after this one's, labelled "(before)": side by side in one run.
#   MODELS_ONLY=1 bash benchmarks/bench_planner.sh
#       only calibrates the models (the slow part, which need not run on a quiet machine).
# About 25 minutes on the 2-core VM, most of it the networks' calibrations (once: cached).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
out=out/bench-planner
mkdir -p "$out"
calibrate=$build/examples/adaptseg_calibrate
bench=$build/benchmarks/bench_planner
train=(--train examples/data/dubai-tile-1 --train examples/data/dubai-tile-2 --train examples/data/dubai-tile-3
       --train examples/data/dubai-tile-5)
# One model per backend and class; a model file already there is reused.
model() {  # NAME CLASS ARGS... -> $out/NAME-CLASS.yaml
  local name=$1 cls=$2
  shift 2
  [ -s "$out/$name-$cls.yaml" ] ||
    "$calibrate" "${train[@]}" --interest "$cls" --out "$out/$name-$cls.yaml" --seg-time-s 0.1 "$@" >"$out/$name-$cls.log" 2>&1
}
# Each row, and with BEFORE the same row of the other build right after it.
bench_row() {
  "$bench" "$@"
  if [ -n "${BEFORE:-}" ]; then
    local -a args=() in=("$@")
    local i label=oracle
    for ((i = 0; i < ${#in[@]}; ++i)); do
      if [ "${in[i]}" = --label ]; then
        label=${in[i + 1]}
        i=$((i + 1))
      else
        args+=("${in[i]}")
      fi
    done
    "$BEFORE" "${args[@]}" --label "$label (before)"
  fi
}
if [ -n "${MODELS_ONLY:-}" ]; then
  w=examples/data/weedmap-000
  [ -s "$out/oracle-weedmap.yaml" ] ||
    "$calibrate" --field "$w" --region 0,0,0.5,1 --out "$out/oracle-weedmap.yaml" --seg-time-s 0.1 >"$out/oracle-weedmap.log" 2>&1
  for backend in oracle mobilenetv2-dubai erfnet-dubai; do
    args=()
    [ "$backend" = oracle ] || args=(--segmenter network --network "examples/models/$backend" --threads 2
                                     --segmentation-cache "$out/cache")
    for cls in vegetation building; do model "$backend" "$cls" "${args[@]}"; done
  done
  exit 0
fi
echo "| segmenter | field | planner threads | waypoints | descents / decisions | step median [ms] | p95 [ms] | max [ms] | top-level median [ms] | descent median [ms] | mission's steps [ms] | set-up [ms] |"
echo "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
w=examples/data/weedmap-000
[ -s "$out/oracle-weedmap.yaml" ] ||
  "$calibrate" --field "$w" --region 0,0,0.5,1 --out "$out/oracle-weedmap.yaml" --seg-time-s 0.1 >"$out/oracle-weedmap.log" 2>&1
for threads in 1 2; do
  bench_row --decision-model "$out/oracle-weedmap.yaml" --field "$w:0.5,0,1,1" --planner-threads "$threads" --repeat 3
done
for backend in oracle mobilenetv2-dubai erfnet-dubai; do
  args=()
  [ "$backend" = oracle ] || args=(--segmenter network --network "examples/models/$backend" --threads 2)
  for cls in vegetation building; do
    cache=()
    [ "$backend" = oracle ] || cache=(--segmentation-cache "$out/cache")
    model "$backend" "$cls" "${args[@]}" "${cache[@]}"
    for threads in 1 2; do
      bench_row --decision-model "$out/$backend-$cls.yaml" --field examples/data/dubai-tile-4 --field examples/data/dubai-tile-6 \
        --planner-threads "$threads" --repeat 3 --label "$backend ($cls)" "${args[@]}"
    done
  done
done
