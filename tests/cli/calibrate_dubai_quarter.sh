#!/usr/bin/env bash
# The CTest fixture dubai_quarter_model: the decision model of a quarter of Dubai tile 4 with the
# bundled MobileNetV2, written to OUT, which cli:adaptseg_live:record_and_fly and
# cli:adaptseg_live:mavlink both fly (each calibrated its own before: about 50 s each under the
# sanitizers). Each of those scripts, run alone without OUT, calibrates the same model itself.
#   calibrate_dubai_quarter.sh CALIBRATE_BINARY EXAMPLES_DIR OUT
set -euo pipefail
calibrate=$1 examples=$2 out=$3
mkdir -p "$(dirname "$out")"
rm -f "$out"
"$calibrate" --field "$examples/data/dubai-tile-4:0,0,0.5,0.5" --segmenter network \
  --network "$examples/models/mobilenetv2-dubai" --seg-time-s 0.1 --plan-time-s 0 --out "$out" >/dev/null
