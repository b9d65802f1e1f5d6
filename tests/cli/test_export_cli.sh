#!/usr/bin/env bash
# Black-box tests of adaptseg_mission --export on the bundled WeedMap field: the mission files
# parse back, their first waypoint is result.json's first waypoint in WGS84, and GDAL's
# ogrinfo (a real GeoJSON client) reads the GeoJSON with the right features and coordinates.
#   test_export_cli.sh MISSION_BINARY EXAMPLES_DIR PYTHON CASE
# Exit 77 (CTest SKIP_RETURN_CODE) when the gdal case finds no ogrinfo (geotiff: no gdal-bin).
# The geotiff case flies a bundled tile written to GeoTIFF (programs built with adaptseg::gdal).
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
  expect_error "--export: kml not in {plan,wpl,geojson}" --field "$field" --gsd 3 --export kml --geo-origin "$origin" \
    --out "$work/o"
  expect_error "--mission-end" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --mission-end hover \
    --out "$work/o"
  expect_error "--camera-trigger" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --camera-trigger shutter \
    --out "$work/o"
  # Above the legal ceiling: refused before the mission flies, with the GSD that stays below it
  # (the default camera flies 1 cm/px at 5.5 m: 120 m is 21.82 cm/px).
  expect_error "the mission would fly 165.0 m above home at 30.00 cm/px, above --max-altitude-m 120.0: with this camera fly at most 21.82 cm/px" \
    --field "$field" --gsd 30 --export plan --geo-origin "$origin" --out "$work/o"
  expect_error "--firmware" --field "$field" --gsd 3 --export plan --geo-origin "$origin" --firmware betaflight --out "$work/o"
  [ ! -e "$work/o" ] || fail "an error must be reported before the mission writes anything"
  ;;
files)
  fly "$work/m" --export plan,wpl --export geojson --geo-origin "$origin" --hold-s 2 --speed 3
  for f in mission.plan mission.waypoints mission.geojson; do [ -s "$work/m/$f" ] || fail "missing $f"; done
  # The same mission without --export writes no mission file.
  fly "$work/plain"
  [ ! -e "$work/plain/mission.plan" ] || fail "mission.plan without --export"
  # No take-off, a landing at home, Mission Planner's camera item; ArduPilot's .plan.
  fly "$work/mp" --export wpl,plan --geo-origin "$origin" --no-takeoff --mission-end land --camera-trigger digicam \
    --firmware ardupilot
  sed -n 3,5p "$work/mp/mission.waypoints" | cut -f2-4 | tr '\n' ' ' | grep -qx "0	2	178 0	3	16 0	2	203 " ||
    fail "--no-takeoff --camera-trigger digicam: want the speed, a waypoint then DO_DIGICAM_CONTROL first: $(sed -n 3,5p "$work/mp/mission.waypoints")"
  grep -q '"firmwareType": 3' "$work/mp/mission.plan" || fail "--firmware ardupilot: firmwareType is not 3"
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
assert len(items) == 2 * n + 3, (len(items), n)
takeoff, speed, rtl = items[0], items[1], items[-1]
assert takeoff["command"] == 22 and takeoff["frame"] == 3 and abs(takeoff["params"][6] - wps[0]["z"]) < 0.01, takeoff
# The speed the mission's times were computed at (--speed 3), as the autopilot's ground speed.
assert speed["command"] == 178 and speed["frame"] == 2 and speed["params"][:3] == [1, 3, -1], speed
assert plan["mission"]["hoverSpeed"] == 3 and plan["mission"]["firmwareType"] == 12, plan["mission"]
assert rtl["command"] == 20 and rtl["params"] == [0] * 7, rtl
for k, w in enumerate(wps[:50]):
    nav, cap = items[2 + 2 * k], items[3 + 2 * k]
    assert nav["command"] == 16 and nav["frame"] == 3 and nav["params"][0] == 2, nav
    assert abs(nav["params"][4] - want[k][0]) < 1e-7 and abs(nav["params"][5] - want[k][1]) < 1e-7, (nav, want[k])
    assert abs(nav["params"][6] - w["z"]) < 0.01
    assert nav["params"][6] == round(nav["params"][6], 2), nav["params"][6]  # to the centimetre
    assert cap["command"] == 2000 and cap["params"][2] == 1
lines = open(f"{out}/mission.waypoints").read().splitlines()
assert lines[0] == "QGC WPL 110" and len(lines) == 5 + 2 * n, len(lines)
home = lines[1].split("\t")
assert home[:4] == ["0", "1", "0", "16"] and float(home[10]) == 500.0, home
assert lines[2].split("\t")[:4] == ["1", "0", "3", "22"], lines[2]
assert lines[-1].split("\t")[1:4] == ["0", "2", "20"], lines[-1]
assert lines[3].split("\t")[:4] == ["2", "0", "2", "178"], lines[3]
f1 = lines[4].split("\t")
assert f1[:4] == ["3", "0", "3", "16"] and len(f1) == 12, f1
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
geotiff)
  # A bundled tile as GeoTIFFs under UTM 40N (gdal_translate), flown: map.tif and map_gsd.tif in
  # the tile's CRS and extent (gdalinfo), and every exported waypoint where the frame puts it in
  # that CRS (GDAL's gdaltransform, not our code).
  for t in gdal_translate gdalinfo gdaltransform; do
    command -v "$t" >/dev/null || { echo "SKIP: $t (gdal-bin) not installed"; exit 77; }
  done
  tile="$examples/data/dubai-tile-6"  # 2577 x 2514 px at 5 cm/px: 128.85 x 125.7 m
  d="$work/field"; mkdir -p "$d"
  ullr=(-a_ullr 329000 2787125.7 329128.85 2787000)
  gdal_translate -q -of GTiff -a_srs EPSG:32640 "${ullr[@]}" "$tile/labels.png" "$d/labels.tif" || fail "gdal_translate labels"
  gdal_translate -q -of GTiff -a_srs EPSG:32640 "${ullr[@]}" "$tile/image.jpg" "$d/ortho.tif" || fail "gdal_translate image"
  sed -e '/^gsd_cm:/d' -e 's/^labels: .*/labels: labels.tif/' -e 's/^image: .*/image: ortho.tif/' \
    "$tile/field.yaml" >"$d/field.yaml"
  "$mission" --field "$d" --strategy lawnmower --gsd 15 --seg-time-s 0.1 --plan-time-s 0 --export geojson \
    --out "$work/g" >/dev/null || fail "mission over the GeoTIFF field failed"
  expect_error "cannot replace that" --field "$d" --gsd 15 --export geojson --geo-origin "$origin" --out "$work/o"
  gdalinfo -json "$work/g/map.tif" >"$work/map.json" 2>&1 || fail "gdalinfo map.tif: $(cat "$work/map.json")"
  gdalinfo -json "$work/g/map_gsd.tif" >"$work/gsd.json" 2>&1 || fail "gdalinfo map_gsd.tif: $(cat "$work/gsd.json")"
  "$python" - "$work/g" "$work/map.json" "$work/gsd.json" <<'PY' >"$work/lonlat" || fail "map.tif checks"
import json, sys
out, info, gsd = sys.argv[1], json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
for i in (info, gsd):
    assert 'ID["EPSG",32640]' in i["coordinateSystem"]["wkt"], i["coordinateSystem"]["wkt"][-200:]
    assert i["size"] == [2577, 2514], i["size"]
    ul, lr = i["cornerCoordinates"]["upperLeft"], i["cornerCoordinates"]["lowerRight"]
    assert abs(ul[0] - 329000) < 1e-6 and abs(ul[1] - 2787125.7) < 1e-6, ul
    assert abs(lr[0] - 329128.85) < 1e-6 and abs(lr[1] - 2787000) < 1e-6, lr
band = info["bands"][0]
assert band["type"] == "Byte" and band["noDataValue"] == 255, band
assert band["colorInterpretation"] == "Palette", band
assert band["colorTable"]["entries"][3][:3] == [254, 221, 58], band["colorTable"]["entries"][3]
assert band.get("categories", [])[:5] == ["building", "land", "road", "vegetation", "water"], band.get("categories")
assert gsd["bands"][0]["type"] == "Float32" and gsd["bands"][0]["noDataValue"] == 0, gsd["bands"][0]
for f in json.load(open(f"{out}/mission.geojson"))["features"]:
    if f["geometry"]["type"] == "Point":
        lon, lat, _ = f["geometry"]["coordinates"]
        print(f"{lon:.10f} {lat:.10f}")
PY
  gdaltransform -s_srs EPSG:4326 -t_srs EPSG:32640 <"$work/lonlat" >"$work/en" || fail "gdaltransform"
  "$python" - "$work/g" "$work/en" <<'PY' || fail "waypoints against the GeoTIFF's grid"
import json, sys
res = json.load(open(f"{sys.argv[1]}/result.json"))
en = [list(map(float, l.split()[:2])) for l in open(sys.argv[2]) if l.strip()]
wps = res["waypoints"]
assert len(en) == len(wps) > 0, (len(en), len(wps))
worst, inside = 0.0, 0
for w, (e, n) in zip(wps, en):
    # The lawnmower's last row and column may be centred beyond the field's edge: a waypoint is
    # inside map.tif's extent exactly when it is inside the field.
    in_field = 0 <= w["x"] <= 128.85 and 0 <= w["y"] <= 125.7
    in_extent = 329000 <= e <= 329128.85 and 2787000 <= n <= 2787125.7
    assert in_field == in_extent, (w["x"], w["y"], e, n)
    inside += in_extent
    worst = max(worst, abs(e - (329000 + w["x"])), abs(n - (2787000 + w["y"])))
assert inside > 0 and worst < 0.01, f"{inside} inside; a waypoint is {worst:.4f} m off its grid position"
print(f"ok: {inside} of {len(wps)} waypoints inside map.tif's extent (the others beyond the field's edge, "
      f"as planned); all at most {worst * 1000:.2f} mm off their grid position")
PY
  ;;
*) fail "unknown case $case" ;;
esac
echo "PASS: $case"
