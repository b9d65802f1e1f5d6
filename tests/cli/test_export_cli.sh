#!/usr/bin/env bash
# Black-box tests of adaptseg_mission --export on the bundled WeedMap field: the mission files
# parse back, their first waypoint is result.json's first waypoint in WGS84, and GDAL's
# ogrinfo (a real GeoJSON client) reads the GeoJSON with the right features and coordinates.
#   test_export_cli.sh MISSION_BINARY EXAMPLES_DIR PYTHON CASE
# Exit 77 (CTest SKIP_RETURN_CODE) when the gdal case finds no ogrinfo.
set -uo pipefail
mission=$1 examples=$2 python=$3 case=$4
source "$(dirname "$0")/cli_common.sh"
field="$examples/data/weedmap-000"
# The bundled field has no documented location: an arbitrary origin, +x at bearing 30 degrees.
origin="47.4,8.5,500,30"

# fly OUT ARGS...: a deterministic 3 cm/px lawnmower over the right half, exported.
fly() {
  local out=$1; shift
  "$mission" --field "$field:0.5,0,1,1" --strategy lawnmower --gsd 3.0 --seg-time-s 0.1 --plan-time-s 0 \
    --out "$out" "$@" >/dev/null || fail "mission with $* failed"
}

case "$case" in
bad_inputs)
  expect_error "needs a geo-reference" --field "$field" --gsd 3 --export geojson --out "$work/o"
  expect_error "--geo-origin LAT,LON,ALT,HEADING" --field "$field" --gsd 3 --export wpl --geo-origin 47,8 --out "$work/o"
  expect_error "latitude_deg" --field "$field" --gsd 3 --export wpl --geo-origin 91,8,0,0 --out "$work/o"
  expect_error "hold_s" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --hold-s -1 --out "$work/o"
  [ ! -e "$work/o" ] || fail "an error must be reported before the mission writes anything"
  "$mission" --field "$field" --gsd 3 --export kml --geo-origin "$origin" --out "$work/o" >/dev/null 2>&1
  rc=$?; [ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] || fail "--export kml: exit code $rc"
  expect_error "--mission-end" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --mission-end hover \
    --out "$work/o"
  expect_error "--camera-trigger" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --camera-trigger shutter \
    --out "$work/o"
  ;;
files)
  fly "$work/m" --export plan,wpl --export geojson --geo-origin "$origin" --hold-s 2
  for f in mission.plan mission.waypoints mission.geojson; do [ -s "$work/m/$f" ] || fail "missing $f"; done
  # The same mission without --export writes no mission file.
  fly "$work/plain"
  [ ! -e "$work/plain/mission.plan" ] || fail "mission.plan without --export"
  # No take-off, a landing at home, Mission Planner's camera item.
  fly "$work/mp" --export wpl --geo-origin "$origin" --no-takeoff --mission-end land --camera-trigger digicam
  sed -n 3,4p "$work/mp/mission.waypoints" | cut -f2-4 | tr '\n' ' ' | grep -qx "0	3	16 0	2	203 " ||
    fail "--no-takeoff --camera-trigger digicam: want a waypoint then DO_DIGICAM_CONTROL first: $(sed -n 3,4p "$work/mp/mission.waypoints")"
  tail -1 "$work/mp/mission.waypoints" | cut -f2-4 | grep -qx "0	3	21" || fail "--mission-end land: last item $(tail -1 "$work/mp/mission.waypoints")"
  "$python" - "$work/m" "$origin" <<'PY' || fail "mission file checks"
import json, math, sys
out, origin = sys.argv[1], [float(v) for v in sys.argv[2].split(",")]
res = json.load(open(f"{out}/result.json"))
wps = res["waypoints"]
n = len(wps)

def wgs84(x, y):
    # First-order WGS84 local tangent plane (error ~1e-9 deg over this field); the sub-field's
    # frame origin is the full field's (1366.5 px -> 13.67 m) column 1367 at 1 cm/px.
    lat0, lon0, _, heading = origin
    x += 1367 * 0.01
    h = math.radians(heading)
    east, north = x * math.sin(h) - y * math.cos(h), x * math.cos(h) + y * math.sin(h)
    a, e2 = 6378137.0, 6.69437999014e-3
    s = math.sin(math.radians(lat0))
    m = a * (1 - e2) / (1 - e2 * s * s) ** 1.5
    nn = a / math.sqrt(1 - e2 * s * s)
    return lat0 + math.degrees(north / m), lon0 + math.degrees(east / (nn * math.cos(math.radians(lat0))))

want = [wgs84(w["x"], w["y"]) for w in wps]
plan = json.load(open(f"{out}/mission.plan"))
assert plan["fileType"] == "Plan" and plan["version"] == 1
items = plan["mission"]["items"]
assert len(items) == 2 * n + 2, (len(items), n)
takeoff, rtl = items[0], items[-1]
assert takeoff["command"] == 22 and takeoff["frame"] == 3 and abs(takeoff["params"][6] - wps[0]["z"]) < 0.01, takeoff
assert rtl["command"] == 20 and rtl["params"] == [0] * 7, rtl
for k, w in enumerate(wps[:50]):
    nav, cap = items[1 + 2 * k], items[2 + 2 * k]
    assert nav["command"] == 16 and nav["frame"] == 3 and nav["params"][0] == 2, nav
    assert abs(nav["params"][4] - want[k][0]) < 1e-7 and abs(nav["params"][5] - want[k][1]) < 1e-7, (nav, want[k])
    assert abs(nav["params"][6] - w["z"]) < 0.01
    assert cap["command"] == 2000 and cap["params"][2] == 1
lines = open(f"{out}/mission.waypoints").read().splitlines()
assert lines[0] == "QGC WPL 110" and len(lines) == 4 + 2 * n, len(lines)
home = lines[1].split("\t")
assert home[:4] == ["0", "1", "0", "16"] and float(home[10]) == 500.0, home
assert lines[2].split("\t")[:4] == ["1", "0", "3", "22"], lines[2]
assert lines[-1].split("\t")[1:4] == ["0", "2", "20"], lines[-1]
f1 = lines[3].split("\t")
assert f1[:4] == ["2", "0", "3", "16"] and len(f1) == 12, f1
assert abs(float(f1[8]) - want[0][0]) < 1e-7 and abs(float(f1[9]) - want[0][1]) < 1e-7
gj = json.load(open(f"{out}/mission.geojson"))
assert gj["type"] == "FeatureCollection" and len(gj["features"]) == n + 1
levels = {f["properties"]["role"] for f in gj["features"][1:]}
assert levels == {"top-level"}, levels
print(f"ok: {n} waypoints; first at {want[0][0]:.8f}, {want[0][1]:.8f}")
PY
  ;;
gdal)
  command -v ogrinfo >/dev/null || { echo "SKIP: ogrinfo (gdal-bin) not installed"; exit 77; }
  fly "$work/m" --export geojson --geo-origin "$origin"
  ogrinfo -ro -al -so "$work/m/mission.geojson" >"$work/summary" 2>&1 || fail "ogrinfo -so: $(cat "$work/summary")"
  ogrinfo -ro -al "$work/m/mission.geojson" >"$work/full" 2>&1 || fail "ogrinfo: $(cat "$work/full")"
  "$python" - "$work/m" "$work/summary" "$work/full" <<'PY' || fail "GDAL checks"
import json, re, sys
out, summary, full = sys.argv[1], open(sys.argv[2]).read(), open(sys.argv[3]).read()
res = json.load(open(f"{out}/result.json"))
n = len(res["waypoints"])
count = int(re.search(r"Feature Count: (\d+)", summary).group(1))
assert count == n + 1, f"GDAL sees {count} features, want {n} waypoints + 1 path"
assert re.search(r"Geometry: .*(Unknown|Geometry)", summary) or "Point" in summary, summary
# Our own reader of the same file is checked by the doctest suite; here GDAL's view of the
# first waypoint must equal the file's, and its height must be home + the relative altitude.
gj = json.load(open(f"{out}/mission.geojson"))
lon, lat, h = gj["features"][1]["geometry"]["coordinates"]
pts = re.findall(r"POINT Z \(([-0-9.e+]+) ([-0-9.e+]+) ([-0-9.e+]+)\)", full)
lines = re.findall(r"LINESTRING Z \(([^)]*)\)", full)
assert len(pts) == n and len(lines) == 1, (len(pts), len(lines))
glon, glat, gh = map(float, pts[0])
assert abs(glon - lon) < 1e-7 and abs(glat - lat) < 1e-7, (pts[0], lon, lat)
assert abs(gh - (500.0 + res["waypoints"][0]["z"])) < 0.01, (gh, res["waypoints"][0]["z"])
first = lines[0].split(",")[0].split()
assert abs(float(first[0]) - lon) < 1e-7 and abs(float(first[1]) - lat) < 1e-7, first
for key in ("role (String) = top-level", "gsd_cm (Real) = 3", "level (Integer) = 0"):
    assert key in full, f"GDAL does not show '{key}'"
print(f"ok: GDAL reads {count} features; first waypoint {glat:.8f}, {glon:.8f}, {gh:.2f} m")
PY
  ;;
*) fail "unknown case $case" ;;
esac
echo "PASS: $case"
