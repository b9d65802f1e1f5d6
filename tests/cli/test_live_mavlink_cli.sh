#!/usr/bin/env bash
# Black-box test of adaptseg_live flying a vehicle over MAVLink (docs/flying.md): a whole
# adaptive mission over a quarter of the bundled WeedMap field, georeferenced near Zurich, flown
# through the emulated PX4 autopilot of tests/mavlink/emulator.mjs (node-mavlink, UDP on
# 127.0.0.1, 8 m/s) with the camera simulated over the field at the vehicle's measured pose, must
# fly the waypoints, decisions and descents of the same mission flown in simulation
# (adaptseg_mission); and then:
#   fence      waypoints outside the area's rectangle: refused before anything is sent, naming
#              the margin that takes them in (which the flights then use)
#   complete   the mission: every waypoint repositioned and photographed, RTL sent, map.tif
#   lost       the link lost mid-mission: exit 2, one line, result.json's "stopped" and the map of
#              what was flown written, no RTL sent (the vehicle is left to its failsafe)
#   refused    the reposition denied: exit 2 at once, nothing flown, one reposition sent
#   budget     --budget-s 40 (the mission takes 58.6 s unbounded), the emulator at the timing
#              model's 2 m/s: the planner, checking each decision and each step of a descent
#              against the vehicle's clock, descends where it still fits and ends within 40 s
#   exif       a real camera's way (a quarter of Dubai tile 4, MobileNetV2): the emulator writes,
#              at each capture, the picture of its memory card nearest the vehicle into the folder
#              the loop watches (--camera-folder), JPEGs whose EXIF GPS tags lie 0.3 m east of the
#              vehicle's fix: --image-pose exif fuses each at its tags
#   untagged   the same card without tags: refused at the first picture, exit 2, one line
# The model is calibrated with the paper's utility rule, whose decisions do not read the clock:
# the emulated vehicle flies faster than the timing model, and the mission's real clock is what
# the planner is given. Waiting until the vehicle is slower than 0.1 m/s puts it within
# millimetres of each waypoint (the emulator brakes to a stop), so that its images are the
# simulation's to the pixel but where GNSS round-off (1e-7 deg, about a centimetre) moves a
# footprint edge across a map pixel: the maps may differ in 0.5 % of their pixels at most.
# Two utility thresholds per weighting are tried, not ten: the setting chosen, and the model, are
# the same (it descends everywhere), in about half the time (121 s -> 70 s under the sanitizers).
#   test_live_mavlink_cli.sh LIVE_BINARY MISSION_BINARY CALIBRATE_BINARY EXAMPLES_DIR PYTHON [DUBAI_MODEL]
# DUBAI_MODEL: the Dubai quarter's model (the CTest fixture dubai_quarter_model,
# calibrate_dubai_quarter.sh); without it the script calibrates the same model itself.
# Exit 77 (CTest's SKIP_RETURN_CODE) without node or the pinned node-mavlink:
#   (cd tests/mavlink && npm ci)     # scripts/test.sh does it where npm exists
set -uo pipefail
live=$1 mission=$2 calibrate=$3 examples=$4 python=$5 dubai_model=${6:-}
emulator="$(cd "$(dirname "$0")/../mavlink" && pwd)/emulator.mjs"
source "$(dirname "$emulator")/require_node_mavlink.sh" "the emulated autopilot"
work=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
region="$examples/data/weedmap-000:0.5,0,1,0.5"
geo=47.4,8.5,500,30  # the field's frame origin and the bearing of its +x axis (its geo: section)
times=(--seg-time-s 0.1 --plan-time-s 0)

"$calibrate" --field "$examples/data/weedmap-000" --region 0,0,0.5,0.5 --segmenter oracle --rule utility \
  --threshold-steps 2 "${times[@]}" --out "$work/model.yaml" >/dev/null 2>"$work/err" || fail "calibration: $(cat "$work/err")"
"$mission" --field "$region" --geo-origin "$geo" --strategy adaptive --decision-model "$work/model.yaml" "${times[@]}" \
  --out "$work/sim" >/dev/null || fail "the simulated mission"
flight=(--mavlink udpin:127.0.0.1:0 --simulate-camera "$region" --geo-origin "$geo" --decision-model "$work/model.yaml"
        "${times[@]}" --arrival-max-speed-mps 0.1 --link-timeout-s 2)

# The corner grid's far row sticks out of the area: refused before a socket is opened.
"$live" "${flight[@]}" --out "$work/fence" >/dev/null 2>"$work/fence.err"
rc=$?
[ "$rc" -eq 2 ] && [ "$(wc -l <"$work/fence.err")" -eq 1 ] &&
  grep -qE "waypoints the planner may fly are outside the site's fence .*give --fence-margin-m [0-9.]+ .*nothing was sent to the vehicle$" "$work/fence.err" ||
  fail "fence: exit code $rc, $(cat "$work/fence.err")"
margin=$(sed -n 's/.*give --fence-margin-m \([0-9.]*\) .*/\1/p' "$work/fence.err")
echo "ok: $(cat "$work/fence.err")"

# fly NAME "EMULATOR OPTIONS" LIVE OPTIONS...: adaptseg_live and the emulated autopilot it talks to
# (started once the program says which port it listens on; home where the options say, the
# nose at the bearing of the frame's -y axis, the image's top: yaw 0), in the background.
fly() {
  local name=$1 emulator_options=$2; shift 2
  (
    "$live" "$@" --out "$work/$name" >"$work/$name.out" 2>"$work/$name.err" &
    local live_pid=$!
    local port=""
    for _ in $(seq 200); do
      port=$(sed -n 's/^vehicle: waiting for the autopilot on udpin:127\.0\.0\.1:\([0-9]*\)$/\1/p' "$work/$name.out")
      [ -n "$port" ] && break
      kill -0 "$live_pid" 2>/dev/null || break
      sleep 0.05
    done
    if [ -z "$port" ]; then
      kill "$live_pid" 2>/dev/null
      wait "$live_pid"
      echo "$?" >"$work/$name.rc"
      exit 0
    fi
    # shellcheck disable=SC2086  # the options are words
    node "$emulator" --port "$port" --heading 300 --speed 8 --accel 4 --max-time 100 \
      --report "$work/$name.report.json" $emulator_options >"$work/$name.emulator" 2>&1 &
    local emulator_pid=$!
    wait "$live_pid"
    echo "$?" >"$work/$name.rc"
    kill -TERM "$emulator_pid" 2>/dev/null
    wait "$emulator_pid"
  ) &
  pids+=($!)
}
# A real camera's way: the pictures land in a folder the loop watches (--camera-folder), JPEGs
# tagged by the camera's own receiver (EXIF GPS), segmented by a network; a quarter of Dubai
# tile 4 with MobileNetV2, its grids laid centred (inside the area: the fence). The emulated
# autopilot writes, at each capture, the card's picture nearest the vehicle into the folder. The tags put every picture 0.3 m east of where the vehicle
# was (the card recorded at the waypoints, then shifted): --image-pose exif fuses each at its tags
# (0.3 m from the waypoint, the vehicle's fix within centimetres of it), a card without tags is
# refused at the first picture (exit 2, one line, nothing lost).
dubai="$examples/data/dubai-tile-4:0,0,0.5,0.5"
net="$examples/models/mobilenetv2-dubai"
bash "$(dirname "$0")/calibrate_dubai_quarter.sh" "$calibrate" "$examples" "$work/dubai.yaml" "$dubai_model" \
  2>"$work/err" || fail "calibrating with the network: $(cat "$work/err")"
"$live" --record-from "$dubai" --decision-model "$work/dubai.yaml" --images "$work/dubai" --record-gnss --geo-origin 25.2,55.3,10,30 --grid centred \
  >/dev/null || fail "recording Dubai"
mkdir -p "$work/card" "$work/plain" "$work/camera" "$work/camera-plain"
"$python" - "$work" <<'PY' || fail "writing the camera's cards"
import csv, math, sys
from PIL import Image
from PIL.TiffImagePlugin import IFDRational
work = sys.argv[1]
def dms(x):
    d = int(x); m = int((x - d) * 60); s = (x - d - m / 60) * 3600
    return (IFDRational(d), IFDRational(m), IFDRational(round(s * 1e6), 1000000))
with open(f"{work}/card/card.csv", "w") as card, open(f"{work}/plain/card.csv", "w") as plain:
    card.write("file,lat,lon\n"), plain.write("file,lat,lon\n")
    for r in csv.DictReader(open(f"{work}/dubai/poses.csv")):
        lat, lon = float(r["latitude_deg"]), float(r["longitude_deg"])
        shifted = lon + math.degrees(0.3 / (6378137.0 * math.cos(math.radians(lat))))  # 0.3 m east
        name = r["file"].replace(".png", ".jpg")
        img = Image.open(f"{work}/dubai/rgb/{r['file']}").convert("RGB")
        exif = Image.Exif()
        exif[0x8825] = {1: "N", 2: dms(lat), 3: "E", 4: dms(shifted), 5: b"\x00",
                        6: IFDRational(round((10.0 + float(r["relative_altitude_m"])) * 1000), 1000)}
        img.save(f"{work}/card/{name}", quality=95, exif=exif.tobytes())
        img.save(f"{work}/plain/{name}", quality=95)
        card.write(f"{name},{lat},{shifted}\n"), plain.write(f"{name},{lat},{lon}\n")
PY
# The WeedMap flights (home at the field's frame origin) and the camera folder's (home at the
# Dubai quarter's), side by side.
weedmap=("${flight[@]}" --fence-margin-m "$margin")
camera=(--mavlink udpin:127.0.0.1:0 --images "$work/dubai" --image-pose exif --segmenter network --network "$net"
        --decision-model "$work/dubai.yaml" "${times[@]}" --arrival-max-speed-mps 0.1 --link-timeout-s 2 --camera-timeout-s 5
        --grid centred)
fly complete "--home 47.4,8.5" "${weedmap[@]}" --trigger autopilot
fly lost "--home 47.4,8.5 --lose-link-after 12" "${weedmap[@]}"
fly refused "--home 47.4,8.5 --refuse 192" "${weedmap[@]}"
fly budget "--home 47.4,8.5 --speed 2 --accel 2" "${weedmap[@]}" --budget-s 40
fly exif "--home 25.2,55.3 --camera-card $work/card --camera-dir $work/camera" "${camera[@]}" --camera-folder "$work/camera"
fly untagged "--home 25.2,55.3 --camera-card $work/plain --camera-dir $work/camera-plain" "${camera[@]}" \
  --camera-folder "$work/camera-plain"
wait "${pids[@]}"
pids=()
for name in complete lost refused budget exif untagged; do
  echo "--- $name: exit code $(cat "$work/$name.rc" 2>/dev/null), $(tail -n 1 "$work/$name.out")"
  cat "$work/$name.err"
done
[ "$(cat "$work/complete.rc")" = 0 ] || fail "complete: exit code $(cat "$work/complete.rc"), $(cat "$work/complete.err")"
[ "$(cat "$work/lost.rc")" = 2 ] && [ "$(wc -l <"$work/lost.err")" -eq 1 ] &&
  grep -qE "^adaptseg_live: error: (go_to|wait_arrival|trigger_camera|poll): no frame from the vehicle \(system 1\) for 2\.[0-9] s on udpin:127\.0\.0\.1:[0-9]+: the link is lost; the vehicle is left to its own failsafe$" "$work/lost.err" ||
  fail "lost: exit code $(cat "$work/lost.rc"), $(cat "$work/lost.err")"
[ "$(cat "$work/refused.rc")" = 2 ] && [ "$(wc -l <"$work/refused.err")" -eq 1 ] &&
  grep -qF "adaptseg_live: error: go_to: the vehicle refused DO_REPOSITION (192): MAV_RESULT_DENIED" "$work/refused.err" ||
  fail "refused: exit code $(cat "$work/refused.rc"), $(cat "$work/refused.err")"
grep -qF "arrival: within 0.36 m (a tenth of the finest footprint's smaller side" "$work/complete.out" ||
  fail "the arrival tolerance is not printed: $(head -4 "$work/complete.out")"

"$python" - "$work" <<'PY' || fail "the flown mission"
import json, os, sys
import cv2
work = sys.argv[1]
flown = json.load(open(f"{work}/complete/result.json"))
sim = json.load(open(f"{work}/sim/result.json"))
report = json.load(open(f"{work}/complete.report.json"))
c = lambda r, cmd: r["commands"].get(str(cmd), 0)
# The same waypoints, levels, decisions and descents as in simulation.
assert flown["images"] == sim["images"] == len(sim["waypoints"]), (flown["images"], sim["images"])
assert flown["decisions"] == sim["decisions"], (flown["decisions"], sim["decisions"])
assert flown["decisions"]["descend"] > 0, "no descent: the comparison would not cover sub-lawnmowers"
for a, b in zip(flown["waypoints"], sim["waypoints"]):
    assert all(abs(a[k] - b[k]) < 1e-9 for k in "xyz") and a["level"] == b["level"], (a, b)
    assert ("decision" in a) == ("decision" in b), (a, b)
    if "decision" in a:
        assert a["decision"]["action"] == b["decision"]["action"] and \
            a["decision"].get("gsd_cm") == b["decision"].get("gsd_cm"), (a["decision"], b["decision"])
    m = a["measured"]  # within the arrival tolerance, at the plan's heading
    assert max(abs(m[k] - a[k]) for k in "xyz") < 0.36 and m["yaw_deg"] == 0.0, m
    assert abs(a["semantic_ratio"] - b["semantic_ratio"]) < 2e-3, (a, b)
# The real clock, from the first waypoint on.
times = [w["elapsed_s"] for w in flown["waypoints"]]
assert times[0] < 2.0 and times == sorted(times) and flown["time_s"]["total"] == times[-1], times
differ = (cv2.imread(f"{work}/complete/map.tif", cv2.IMREAD_UNCHANGED) !=
          cv2.imread(f"{work}/sim/map.tif", cv2.IMREAD_UNCHANGED)).any(axis=-1).mean()
assert differ <= 0.005, differ
# The autopilot saw one reposition and one capture per image, then one RTL; every frame checked.
assert report["bad_crc"] == 0 and c(report, 192) == flown["images"] and c(report, 2000) == flown["images"], report
assert report["captures"] == flown["images"] and c(report, 20) == 1, report
assert flown["vehicle"]["returned_to_launch"] and flown["vehicle"]["firmware"] == "PX4", flown["vehicle"]
print(f"flown as simulated: {flown['images']} images, decisions {flown['decisions']}, map pixels differing "
      f"{differ:.4f}, {times[-1]:.1f} s on the vehicle's clock; RTL sent")

# Link lost: what was flown written, with the error; nothing sent after it.
lost = json.load(open(f"{work}/lost/result.json"))
lost_report = json.load(open(f"{work}/lost.report.json"))
n = lost["images"]
assert 0 < n < flown["images"] and "the link is lost" in lost["stopped"], (n, lost.get("stopped"))
assert [(w["x"], w["y"], w["z"]) for w in lost["waypoints"]] == [(w["x"], w["y"], w["z"]) for w in flown["waypoints"][:n]]
assert not lost["vehicle"]["returned_to_launch"] and c(lost_report, 20) == 0 and lost_report["lost_link"], lost_report
for f in ["map.png", "map.tif", "map_gsd.tif", "mission.geojson"]:
    assert f in lost["files"] and os.path.getsize(f"{work}/lost/{f}") > 0, f
print(f"link lost after {n} images: {lost['stopped']}")

# Refused: nothing flown, one reposition sent and no RTL.
refused = json.load(open(f"{work}/refused/result.json"))
refused_report = json.load(open(f"{work}/refused.report.json"))
assert refused["images"] == 0 and "refused DO_REPOSITION" in refused["stopped"], refused
assert c(refused_report, 192) == 1 and c(refused_report, 20) == 0, refused_report
PY

[ "$(cat "$work/budget.rc")" = 0 ] || fail "budget: exit code $(cat "$work/budget.rc"), $(cat "$work/budget.err")"
"$python" - "$work" <<'PY' || fail "the budget flight"
import json, sys
r = json.load(open(f"{sys.argv[1]}/budget/result.json"))
assert r["budget_s"] == 40.0 and r["time_s"]["total"] <= 40.0, r["time_s"]
assert r["decisions"]["descend"] > 0 and r["decisions"]["budget_limited"] > 0, r["decisions"]
print(f"budget: {r['images']} images, decisions {r['decisions']}, {r['time_s']['total']:.1f} s of 40 on the vehicle's clock")
PY
[ "$(cat "$work/exif.rc")" = 0 ] || fail "camera folder: exit code $(cat "$work/exif.rc"), $(cat "$work/exif.err")"
[ "$(cat "$work/untagged.rc")" = 2 ] && [ "$(wc -l <"$work/untagged.err")" -eq 1 ] &&
  grep -qE "^adaptseg_live: error: .*/camera-plain/IMG_0000\.jpg: no EXIF GPS position \(--image-pose exif\); fly with --image-pose vehicle" "$work/untagged.err" ||
  fail "untagged pictures: exit code $(cat "$work/untagged.rc"), $(cat "$work/untagged.err")"
"$python" - "$work" <<'PY' || fail "the camera folder's flight"
import json, math, sys
work = sys.argv[1]
r = json.load(open(f"{work}/exif/result.json"))
report = json.load(open(f"{work}/exif.report.json"))
assert r["vehicle"]["image_pose"] == "exif" and r["vehicle"]["returned_to_launch"], r["vehicle"]
assert r["images"] == len(r["waypoints"]) == report["captures"] == len(report["pictures"]) > 0, (r["images"], report)
for w, pic in zip(r["waypoints"], report["pictures"]):
    m = w["measured"]
    assert w["image"].startswith("IMG_") and pic.endswith(".jpg"), (w["image"], pic)
    # The vehicle's own fix: at the waypoint; the picture's tags: 0.3 m from it, at the same height.
    fix = math.hypot((m["latitude_deg"] - w["latitude_deg"]) * 111195.0,
                     (m["longitude_deg"] - w["longitude_deg"]) * 111195.0 * math.cos(math.radians(25.2)))
    off = math.hypot(m["x"] - w["x"], m["y"] - w["y"])
    assert fix < 0.05 and abs(off - 0.3) < 0.02 and abs(m["z"] - w["z"]) < 0.01, (w, fix, off)
subs = sum(w["level"] == 1 for w in r["waypoints"])
u = json.load(open(f"{work}/untagged/result.json"))
assert u["images"] == 0 and "no EXIF GPS position" in u["stopped"], u
print(f"camera folder: {r['images']} JPEGs ({subs} in descents) fused at their EXIF positions, 0.3 m from the "
      f"vehicle's fixes; untagged pictures refused: {u['stopped']}")
PY
echo "PASS: live over MAVLink"
