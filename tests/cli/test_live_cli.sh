#!/usr/bin/env bash
# Black-box test of adaptseg_live, the companion-computer loop: record a folder of posed
# images from a small region of the bundled WeedMap field, fly the planner over it step by
# step, and check that it visits exactly the waypoints adaptseg_mission visits in simulation
# with the same model on the same region; a folder lacking a requested image is an error.
#   test_live_cli.sh LIVE_BINARY MISSION_BINARY CALIBRATE_BINARY EXAMPLES_DIR PYTHON
set -uo pipefail
live=$1 mission=$2 calibrate=$3 examples=$4 python=$5
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
field="$examples/data/weedmap-000"
region="$field:0.5,0,1,0.5"
times=(--seg-time-s 0.1 --plan-time-s 0)
fail() { echo "FAIL: $*" >&2; exit 1; }

"$calibrate" --field "$field" --region 0,0,0.5,0.5 --segmenter oracle "${times[@]}" --out "$work/model.yaml" \
  >/dev/null 2>"$work/calibrate.log" || fail "calibration: $(cat "$work/calibrate.log")"
"$live" --record-from "$region" --model "$work/model.yaml" --images "$work/images" || fail "recording"
for f in area.yaml poses.csv valid_mask.png; do [ -s "$work/images/$f" ] || fail "recording wrote no $f"; done

# run NAME ARGS...: the live loop and the simulated mission with the same arguments.
run() {
  local name=$1; shift
  "$live" --images "$work/images" --model "$work/model.yaml" "$@" "${times[@]}" --out "$work/live-$name" ||
    fail "live $name"
  "$mission" --field "$region" --model "$work/model.yaml" "$@" "${times[@]}" --out "$work/mission-$name" \
    >/dev/null || fail "mission $name"
}
run adaptive --strategy adaptive
run row --strategy row
run linear --strategy linear
run linear-budget --strategy linear --budget-s 45

"$python" - "$work" <<'PY' || fail "live and simulated missions differ"
import json, sys
work = sys.argv[1]
descents = 0
for strategy in ["adaptive", "row", "linear", "linear-budget"]:
    live = json.load(open(f"{work}/live-{strategy}/result.json"))
    sim = json.load(open(f"{work}/mission-{strategy}/result.json"))
    assert live["images"] == sim["images"] == len(sim["waypoints"]), (strategy, live["images"], sim["images"])
    for a, b in zip(live["waypoints"], sim["waypoints"]):
        for k in ["x", "y", "z"]:
            assert abs(a[k] - b[k]) < 1e-9, (strategy, a, b)
        assert a["level"] == b["level"], (strategy, a, b)
        assert abs(a["semantic_ratio"] - b["semantic_ratio"]) < 1e-12, (strategy, a, b)
    assert live["decisions"] == sim["decisions"], (strategy, live["decisions"], sim["decisions"])
    assert abs(live["time_s"]["total"] - sim["time_s"]["total"]) < 1e-6, (strategy, live["time_s"], sim["time_s"])
    descents += live["decisions"]["descend"]
    print(strategy, "images", live["images"], "decisions", live["decisions"])
assert descents > 0, "no descent at all: the comparison would not cover sub-lawnmowers"
limited = json.load(open(f"{work}/live-linear-budget/result.json"))
assert limited["decisions"]["budget_limited"] > 0 and limited["time_s"]["total"] <= 45 + 1e-9, limited["decisions"]
PY

# A camera that does not hold the plan's heading: the same waypoints recorded with the camera
# turned half a turn (every image and its labels upside down) fly the same mission to the same
# map; turned 30 deg, the images are fused turned (the map differs at the footprints' edges).
for yaw in 180 30; do
  "$live" --record-from "$region" --model "$work/model.yaml" --images "$work/images-$yaw" --record-yaw $yaw \
    >/dev/null || fail "recording at yaw $yaw"
  grep -q ",$yaw\$" "$work/images-$yaw/poses.csv" || fail "yaw $yaw not in poses.csv: $(sed -n 2p "$work/images-$yaw/poses.csv")"
  "$live" --images "$work/images-$yaw" --model "$work/model.yaml" --strategy adaptive "${times[@]}" \
    --out "$work/live-yaw$yaw" >/dev/null || fail "live at yaw $yaw"
done
"$python" - "$work" <<'PY' || fail "turned cameras"
import json, sys
import cv2
work = sys.argv[1]
upright = json.load(open(f"{work}/live-adaptive/result.json"))
upright_map = cv2.imread(f"{work}/live-adaptive/map.png")
for yaw in ["180", "30"]:
    turned = json.load(open(f"{work}/live-yaw{yaw}/result.json"))
    assert [(w["x"], w["y"], w["z"]) for w in turned["waypoints"]] == \
        [(w["x"], w["y"], w["z"]) for w in upright["waypoints"]], yaw
    assert all(w["yaw_deg"] == float(yaw) for w in turned["waypoints"]), yaw
    differ = (cv2.imread(f"{work}/live-yaw{yaw}/map.png") != upright_map).any(axis=2).mean()
    print(f"yaw {yaw}: {turned['images']} images, decisions {turned['decisions']}, map pixels differing {differ:.4f}")
    if yaw == "180":
        assert differ == 0.0 and turned["decisions"] == upright["decisions"], (differ, turned["decisions"])
        for a, b in zip(turned["waypoints"], upright["waypoints"]):
            assert abs(a["semantic_ratio"] - b["semantic_ratio"]) < 1e-12, (a, b)
    else:
        assert 0.0 < differ < 0.1, differ
PY
# A yaw that is no number: one error line naming the line, exit code 2.
sed -i '3s/,30$/,nan/' "$work/images-30/poses.csv"
"$live" --images "$work/images-30" --model "$work/model.yaml" "${times[@]}" >/dev/null 2>"$work/err"
rc=$?
[ "$rc" -eq 2 ] && [ "$(wc -l <"$work/err")" -eq 1 ] && grep -qF "line 3 is not file,x,y,z[,yaw_deg]" "$work/err" ||
  fail "yaw nan: exit code $rc, $(cat "$work/err")"

# A folder without the image of a requested waypoint: one error line, exit code 2.
sed -i '2d' "$work/images/poses.csv"  # the first top-level waypoint's image
"$live" --images "$work/images" --model "$work/model.yaml" "${times[@]}" >/dev/null 2>"$work/err"
rc=$?
[ "$rc" -eq 2 ] || fail "missing image: exit code $rc (want 2)"
[ "$(wc -l <"$work/err")" -eq 1 ] || fail "missing image: want one error line, got: $(cat "$work/err")"
grep -qF "no image recorded at waypoint" "$work/err" || fail "missing image: $(cat "$work/err")"
echo "ok: $(cat "$work/err")"
echo "PASS: live"
