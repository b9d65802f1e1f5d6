#!/usr/bin/env bash
# Black-box test of adaptseg_live's --area on a recorded folder: a folder
# recorded on the centred grid, in the frame of its area.yaml, flown with --area, the same
# rectangle as a GeoJSON polygon, whose site frame adaptseg_plan's way rebuilds from the polygon:
# to a centimetre the folder's, and its axes the folder's or turned half a turn. Every waypoint
# the mission asks for must be one the folder recorded (its image's GNSS pose within 5 cm).
# Before the fix, a descent's sub-lawnmower was laid from a corner of its region chosen by the
# frame (which corner the waypoint, the region's centre, is nearest: a tie that round-off broke),
# so its waypoints moved by the region's width less the sub-lawnmower's (12 m on Dubai tile 4,
# 15 m on tile 6) with the frame.
#   test_live_area_cli.sh LIVE_BINARY CALIBRATE_BINARY EXAMPLES_DIR PYTHON
set -uo pipefail
live=$1 calibrate=$2 examples=$3 python=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
times=(--seg-time-s 0.1 --plan-time-s 0)
fail() { echo "FAIL: $*" >&2; exit 1; }

"$calibrate" --field "$examples/data/dubai-tile-1" --segmenter oracle "${times[@]}" --out "$work/model.yaml" \
  >/dev/null 2>"$work/err" || fail "calibration: $(cat "$work/err")"
# TILE HEADING: tile 4 at 30 deg (the site frame the folder's, to a centimetre), tile 6 at 0 deg
# (the site frame turned half a turn).
for case in "4 30" "6 0"; do
  read -r tile heading <<<"$case"
  dir="$work/tile$tile"
  "$live" --record-from "$examples/data/dubai-tile-$tile" --decision-model "$work/model.yaml" --images "$dir" --record-gnss \
    --geo-origin "25.2,55.3,10,$heading" --grid centred >/dev/null || fail "recording tile $tile"
  "$python" "$(dirname "$0")/area_polygon.py" "$dir" "$dir.geojson" || fail "writing the area polygon"
  "$live" --images "$dir" --decision-model "$work/model.yaml" "${times[@]}" --area "$dir.geojson" --pose-tolerance-m 0.05 \
    --out "$dir-live" >"$dir.out" 2>"$work/err" || fail "tile $tile, heading $heading, --area: $(cat "$work/err")"
  "$python" - "$dir" <<'PY' || fail "tile $tile: a waypoint the folder did not record"
import json, math, sys
d = sys.argv[1]
r = json.load(open(f"{d}-live/result.json"))
pose = {l.split(",")[0]: tuple(map(float, l.split(",")[1:4])) for l in open(f"{d}/poses.csv").read().splitlines()[1:]}
for w in r["waypoints"]:
    lat, lon, alt = pose[w["image"]]
    off = math.hypot((lat - w["latitude_deg"]) * 111195.0, (lon - w["longitude_deg"]) * 111195.0 * math.cos(math.radians(lat)))
    assert off < 0.05 and abs(alt - w["z"]) < 0.05, (w["image"], off)
subs = sum(w["level"] == 1 for w in r["waypoints"])
assert subs > 0, "no descent: the test would not cover sub-lawnmowers"
print(f"{d}: {r['images']} waypoints ({subs} in descents), each the folder's own image; decisions {r['decisions']}")
PY
done
echo "PASS: live --area"
