#!/usr/bin/env bash
# The decision model of a quarter of Dubai tile 4 with the bundled MobileNetV2, written to OUT:
# the CTest fixture dubai_quarter_model (calibrated once for cli:adaptseg_live:record_and_fly and
# cli:adaptseg_live:mavlink, which both fly it; each calibrated its own before, about 50 s each
# under the sanitizers), and how those scripts get it: copied from FROM where given (the
# fixture's file), calibrated here otherwise (a script run alone).
#   calibrate_dubai_quarter.sh CALIBRATE_BINARY EXAMPLES_DIR OUT [FROM]
set -euo pipefail
calibrate=$1 examples=$2 out=$3 from=${4:-}
mkdir -p "$(dirname "$out")"
rm -f "$out"
if [ -n "$from" ]; then
  cp "$from" "$out" || { echo "no Dubai model at $from (the fixture cli:adaptseg_calibrate:dubai_quarter)" >&2; exit 1; }
  exit 0
fi
"$calibrate" --field "$examples/data/dubai-tile-4:0,0,0.5,0.5" --segmenter network \
  --network "$examples/models/mobilenetv2-dubai" --seg-time-s 0.1 --plan-time-s 0 --out "$out" >/dev/null
