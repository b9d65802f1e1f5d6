#!/usr/bin/env bash
# Black-box test of adaptseg_plan, the survey plan of a site without labels:
# - an L-shaped GeoJSON site (long side 30 deg north of east, near Dubai) at 10 cm/px: every
#   waypoint, and every leg flown, inside the L by the margin, the files consistent with
#   plan.json, the L as the .plan's geofence; the same site as KML plans the same;
# - an irregular 5 ha site with a hole, taken off from a given point: every waypoint inside the
#   polygon and out of the hole, every leg too, the hole an exclusion fence;
# - a DEM (an ESRI ASCII grid in WGS84) with a 20 m slope: every image's height above its own
#   ground within 5 % of the GSD's;
# - sorties of at most 5 min: one mission file each, each within the limit (timed here from the
#   files), resuming where the last stopped;
# - --firmware ardupilot: DO_DIGICAM_CONTROL; swapped latitude and longitude named; the sanity
#   limits (minimum altitude, firmware item limit, warnings of size and hours, the mask size);
# then the command-line mistakes, each exit code 2 and one line.
#   test_plan_cli.sh ADAPTSEG_PLAN PYTHON
set -uo pipefail
mission=$1 python=$2
source "$(dirname "$0")/cli_common.sh"

# Sites, a DEM and the checks, written once.
cat >"$work/sites.py" <<'PY'
import json, math
R = 6378137.0
def to_ll(lat0, lon0, x, y, angle_deg=0.0):
    a = math.radians(angle_deg)
    e, n = math.cos(a) * x - math.sin(a) * y, math.sin(a) * x + math.cos(a) * y
    return lat0 + math.degrees(n / R), lon0 + math.degrees(e / (R * math.cos(math.radians(lat0))))
def to_local(lat0, lon0, lat, lon, angle_deg=0.0):
    e = math.radians(lon - lon0) * R * math.cos(math.radians(lat0))
    n = math.radians(lat - lat0) * R
    a = math.radians(angle_deg)
    return math.cos(a) * e + math.sin(a) * n, -math.sin(a) * e + math.cos(a) * n
L = dict(lat0=25.2, lon0=55.3, angle=30.0, rings=[[(0, 0), (240, 0), (240, 20), (160, 20), (160, 100), (0, 100)]])
HOLE = dict(lat0=47.4, lon0=8.5, angle=0.0, rings=[[(0, 0), (250, -30), (290, 110), (170, 200), (30, 170), (-30, 80)],
                                                   [(100, 60), (150, 60), (150, 110), (100, 110)]])
BIG = dict(lat0=25.2, lon0=55.3, angle=0.0, rings=[[(0, 0), (1500, 0), (1500, 1500), (0, 1500)]])
def geojson(site, path, swap=False):
    rings = []
    for r in site["rings"]:
        ring = [to_ll(site["lat0"], site["lon0"], x, y, site["angle"]) for x, y in r + [r[0]]]
        rings.append([[lat, lon] if swap else [lon, lat] for lat, lon in ring])
    json.dump({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
               "geometry": {"type": "Polygon", "coordinates": rings}}]}, open(path, "w"))
def inside(r, p):
    c = False
    for i in range(len(r)):
        (x1, y1), (x2, y2) = r[i - 1], r[i]
        if (y1 > p[1]) != (y2 > p[1]) and p[0] < (x2 - x1) * (p[1] - y1) / (y2 - y1) + x1:
            c = not c
    return c
def edge_distance(rings, p):
    best = 1e18
    for r in rings:
        for i in range(len(r)):
            (x1, y1), (x2, y2) = r[i - 1], r[i]
            dx, dy = x2 - x1, y2 - y1
            t = max(0.0, min(1.0, ((p[0] - x1) * dx + (p[1] - y1) * dy) / (dx * dx + dy * dy)))
            best = min(best, math.hypot(x1 + t * dx - p[0], y1 + t * dy - p[1]))
    return best
def on_site(site, lat, lon):
    """(inside the outer ring and out of the holes, distance to the nearest edge [m])"""
    p = to_local(site["lat0"], site["lon0"], lat, lon, site["angle"])
    ok = inside(site["rings"][0], p) and not any(inside(h, p) for h in site["rings"][1:])
    return ok, edge_distance(site["rings"], p)
def plan_items(path):
    return json.load(open(path))["mission"]["items"]
def flown(path):
    """home, then every NAV_WAYPOINT of a .plan as (lat, lon, alt, hold, image)"""
    plan = json.load(open(path))
    items = plan["mission"]["items"]
    out = []
    for k, it in enumerate(items):
        if it["command"] == 16:
            image = k + 1 < len(items) and items[k + 1]["command"] in (2000, 203)
            out.append((it["params"][4], it["params"][5], it["params"][6], it["params"][0], image))
    return plan["mission"]["plannedHomePosition"], out
def check_legs(site, path, margin):
    """every leg of a .plan (home, waypoints, home) sampled every 0.5 m: on the site, `margin` from its edges"""
    home, pts = flown(path)
    chain = [(home[0], home[1])] + [(p[0], p[1]) for p in pts] + [(home[0], home[1])]
    worst = 1e18
    for (a, b) in zip(chain, chain[1:]):
        pa = to_local(site["lat0"], site["lon0"], *a)
        pb = to_local(site["lat0"], site["lon0"], *b)
        n = max(1, int(math.hypot(pb[0] - pa[0], pb[1] - pa[1]) / 0.5))
        for s in range(n + 1):
            lat, lon = a[0] + (b[0] - a[0]) * s / n, a[1] + (b[1] - a[1]) * s / n
            ok, d = on_site(site, lat, lon)
            assert ok, ("leg leaves the site", a, b, s)
            worst = min(worst, d)
    assert worst >= margin, ("a leg comes", worst, "m from an edge")
    return worst
PY

"$python" - "$work" <<'PY' || fail "writing the sites"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
geojson(L, f"{sys.argv[1]}/site.geojson")
geojson(HOLE, f"{sys.argv[1]}/hole.geojson")
geojson(L, f"{sys.argv[1]}/swapped.geojson", swap=True)
geojson(BIG, f"{sys.argv[1]}/big.geojson")
PY
"$mission" --area "$work/site.geojson" --gsd 10 --altitude-m 5 --out "$work/p" >"$work/out" 2>"$work/err" ||
  fail "adaptseg_plan: $(cat "$work/err")"
grep -q "site: 14 images at 10.0 cm/px (55.0 m above home)" "$work/out" || fail "summary: $(cat "$work/out")"
grep -q "^where: centre 25.2007.. N, 55.3007.. E, area 1.75 ha; take-off .* (under the first waypoint); 1 sortie(s)" "$work/out" ||
  fail "where the site is: $(cat "$work/out")"
grep -q "^coverage: 99\.[0-9] % of the site under a footprint" "$work/out" || fail "coverage: $(cat "$work/out")"
[ ! -s "$work/err" ] || fail "warnings for a plain site: $(cat "$work/err")"
for f in mission.plan mission.waypoints mission.geojson plan.json site.png; do
  [ -s "$work/p/$f" ] || fail "missing $f"
done
"$python" - "$work" <<'PY' || fail "plan checks"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
out = f"{sys.argv[1]}/p"
p = json.load(open(f"{out}/plan.json"))
site, wps = p["site_frame"], p["waypoints"]
assert p["images"] == len(wps) == 14 and p["altitude_m"] == 55.0, p["images"]
# The frame along the long side (240 m at bearing 60 deg), every waypoint over the rectangle.
assert abs(site["width_m"] - 240) < 1 and abs(site["height_m"] - 100) < 1, site
assert abs((site["heading_deg"] - 60 + 90) % 180 - 90) < 0.5, site["heading_deg"]
xs, ys = [w["x"] for w in wps], [w["y"] for w in wps]
assert 0 < min(xs) and max(xs) < site["width_m"] and 0 < min(ys) and max(ys) < site["height_m"], (xs, ys)
# Every waypoint inside the L, 2 m (the default margin) from its edges; none over the bitten-out corner.
for w in wps:
    ok, d = on_site(L, w["latitude_deg"], w["longitude_deg"])
    assert ok and d >= 1.95, (w, ok, d)
# Every leg flown, the take-off's and the return's included, inside the L, a metre from its edges.
check_legs(L, f"{out}/mission.plan", 0.95)
# The .plan flies these, at the GSD's altitude, one image each; via points between, no image.
home, pts = flown(f"{out}/mission.plan")
images = [q for q in pts if q[4]]
assert len(images) == len(wps) and sum(i["command"] == 2000 for i in plan_items(f"{out}/mission.plan")) == len(wps)
for q, w in zip(images, wps):
    assert abs(q[0] - w["latitude_deg"]) < 1e-7 and abs(q[1] - w["longitude_deg"]) < 1e-7 and abs(q[2] - 55.0) < 0.01
assert all(q[3] == 0 for q in pts if not q[4]) and len(pts) - len(images) == p["via_points"]
# Home: the ground under the first waypoint; the geofence: the L itself.
assert abs(home[0] - p["home"]["latitude_deg"]) < 1e-9 and abs(home[0] - wps[0]["latitude_deg"]) < 1e-7
fence = json.load(open(f"{out}/mission.plan"))["geoFence"]
assert fence["version"] == 2 and len(fence["polygons"]) == 1 and fence["polygons"][0]["inclusion"] is True
ring = fence["polygons"][0]["polygon"]
assert len(ring) == 6 and fence["polygons"][0]["version"] == 1, ring
for (lat, lon), (x, y) in zip(ring, L["rings"][0]):
    lx, ly = to_local(L["lat0"], L["lon0"], lat, lon, L["angle"])
    assert math.hypot(lx - x, ly - y) < 0.05, ((lat, lon), (x, y))
print(f"ok: {len(wps)} waypoints and {p['via_points']} via points inside the L, its outline the geofence")
PY

# The same site as KML (Google Earth's format; OGR's KML driver): the same plan.
"$python" - "$work/site.geojson" "$work/site.kml" <<'PY' || fail "writing the KML site"
import json, sys
ring = json.load(open(sys.argv[1]))["features"][0]["geometry"]["coordinates"][0]
coords = " ".join(f"{lon:.12f},{lat:.12f},0" for lon, lat in ring)
open(sys.argv[2], "w").write(f"""<?xml version="1.0" encoding="UTF-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark><name>site</name>
<Polygon><outerBoundaryIs><LinearRing><coordinates>{coords}</coordinates></LinearRing></outerBoundaryIs></Polygon>
</Placemark></Document></kml>
""")
PY
"$mission" --area "$work/site.kml" --gsd 10 --altitude-m 5 --out "$work/k" >"$work/out" 2>"$work/err" ||
  fail "adaptseg_plan --area KML: $(cat "$work/err")"
"$python" - "$work/p/plan.json" "$work/k/plan.json" <<'PY' || fail "the KML site planned otherwise than the GeoJSON one"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:])
assert len(a["waypoints"]) == len(b["waypoints"]) == 14, (len(a["waypoints"]), len(b["waypoints"]))
for u, v in zip(a["waypoints"], b["waypoints"]):
    assert abs(u["latitude_deg"] - v["latitude_deg"]) < 1e-9 and abs(u["longitude_deg"] - v["longitude_deg"]) < 1e-9, (u, v)
print("ok: the KML site, the same 14 waypoints")
PY

# An irregular site with a hole, taken off from a point on it: nothing in the hole or beyond the
# outline (adaptseg_plan 0.1 put 13 of 23 waypoints there at 15 cm/px), no leg across either.
home=$("$python" -c "import sys; sys.path.insert(0, '$work'); from sites import *; print('%.9f,%.9f' % to_ll(47.4, 8.5, 20, 80))")
"$mission" --area "$work/hole.geojson" --gsd 15 --home "$home" --out "$work/h" >"$work/out" 2>"$work/err" ||
  fail "adaptseg_plan, the site with a hole: $(cat "$work/err")"
grep -q "take-off 47.40071. N, 8.50026. E (--home)" "$work/out" || fail "the take-off point: $(cat "$work/out")"
"$python" - "$work" "$home" <<'PY' || fail "the site with a hole"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
out = f"{sys.argv[1]}/h"
lat_h, lon_h = (float(v) for v in sys.argv[2].split(","))
p = json.load(open(f"{out}/plan.json"))
for w in p["waypoints"]:
    ok, d = on_site(HOLE, w["latitude_deg"], w["longitude_deg"])
    assert ok and d >= 1.95, (w, ok, d)
check_legs(HOLE, f"{out}/mission.plan", 0.95)
assert p["via_points"] > 0, "no leg bent around the hole"
plan = json.load(open(f"{out}/mission.plan"))
home = plan["mission"]["plannedHomePosition"]
assert abs(home[0] - lat_h) < 1e-9 and abs(home[1] - lon_h) < 1e-9, home
takeoff = plan["mission"]["items"][0]
assert takeoff["command"] == 22 and abs(takeoff["params"][4] - lat_h) < 1e-9 and abs(takeoff["params"][5] - lon_h) < 1e-9
polys = plan["geoFence"]["polygons"]
assert [q["inclusion"] for q in polys] == [True, False] and [len(q["polygon"]) for q in polys] == [6, 4], polys
print(f"ok: {len(p['waypoints'])} waypoints and {p['via_points']} via points on the site with a hole, from the take-off point")
PY

# A DEM with a 20 m slope across the L (ESRI ASCII grid, WGS84): each image the GSD's height
# above its own ground, within 5 %; the altitudes relative to home's ground.
"$python" - "$work" <<'PY' || fail "writing the DEM"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
lons = [to_ll(L["lat0"], L["lon0"], x, y, L["angle"])[1] for x, y in L["rings"][0]]
w, e = min(lons), max(lons)
json.dump({"west": w, "east": e}, open(f"{sys.argv[1]}/slope.json", "w"))
cell, n, x0, y0 = 0.00005, 240, 55.3 - 0.006, 25.2 - 0.006
rows = []
for r in range(n):
    lon = [x0 + (c + 0.5) * cell for c in range(n)]
    rows.append(" ".join(f"{100 + 20 * (v - w) / (e - w):.4f}" for v in lon))
open(f"{sys.argv[1]}/dem.asc", "w").write(f"ncols {n}\nnrows {n}\nxllcorner {x0}\nyllcorner {y0}\ncellsize {cell}\n"
                                          f"NODATA_value -9999\n" + "\n".join(rows) + "\n")
open(f"{sys.argv[1]}/dem.prj", "w").write('GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,'
                                          '298.257223563]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]]')
PY
"$mission" --area "$work/site.geojson" --gsd 10 --dem "$work/dem.asc" --out "$work/d" >"$work/out" 2>"$work/err" ||
  fail "adaptseg_plan --dem: $(cat "$work/err")"
grep -q "(55.0 m above the ground)" "$work/out" || fail "terrain summary: $(cat "$work/out")"
grep -q "warning: the ground under the survey rises 1[0-9].[0-9] m above home: set the autopilot's return altitude" "$work/err" ||
  fail "the return-altitude warning: $(cat "$work/err")"
"$python" - "$work" <<'PY' || fail "terrain following"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
s = json.load(open(f"{sys.argv[1]}/slope.json"))
ground = lambda lon: 100 + 20 * (lon - s["west"]) / (s["east"] - s["west"])
home, pts = flown(f"{sys.argv[1]}/d/mission.plan")
worst = 0
alts = []
for lat, lon, alt, hold, image in pts:
    if not image:
        continue
    above = alt + ground(home[1]) - ground(lon)
    worst = max(worst, abs(above / 55.0 - 1))
    alts.append(alt)
assert worst < 0.05, worst
assert max(alts) - min(alts) > 10, alts  # the altitudes above home follow the slope
for it in plan_items(f"{sys.argv[1]}/d/mission.plan"):
    if it["command"] in (16, 22):
        assert it["frame"] == 3 and it["AltitudeMode"] == 1, it  # relative to home, as QGC and both firmwares take it
print(f"ok: every image within {100 * worst:.2f} % of 55 m above its own ground; altitudes {min(alts):.1f}..{max(alts):.1f} m above home")
PY

# Sorties of at most 5 min (the L's far end is 4 min from home and back at 27.5 m): mission-1.*, mission-2.*, ..., each within the limit, timed here.
lhome=$("$python" -c "import sys; sys.path.insert(0, '$work'); from sites import *; print('%.9f,%.9f' % to_ll(25.2, 55.3, 5, 50, 30))")
"$mission" --area "$work/site.geojson" --gsd 5 --home "$lhome" \
  --max-flight-min 5 --out "$work/s" >"$work/out" 2>"$work/err" || fail "adaptseg_plan --max-flight-min: $(cat "$work/err")"
[ ! -e "$work/s/mission.plan" ] || fail "a split survey wrote mission.plan"
grep -q "^sortie 2: mission-2.\*, waypoints [0-9]*-[0-9]*, resumes at waypoint [0-9]* (25.2" "$work/out" ||
  fail "where sortie 2 resumes: $(cat "$work/out")"
"$python" - "$work" <<'PY' || fail "the sorties"
import sys, os; sys.path.insert(0, sys.argv[1]); from sites import *
out = f"{sys.argv[1]}/s"
p = json.load(open(f"{out}/plan.json"))
def ramp(d, v=2.0, a=2.0):
    return 2 * math.sqrt(d / a) if d < v * v / a else d / v + v / a
def seg(u, w):
    return ramp(math.dist(u, w))
assert len(p["sorties"]) >= 3, p["sorties"]
images = []
for k, s in enumerate(p["sorties"]):
    path = f"{out}/mission-{k + 1}.plan"
    assert os.path.exists(path) and os.path.exists(f"{out}/mission-{k + 1}.waypoints"), path
    home, pts = flown(path)
    takeoff = plan_items(path)[0]
    hx, hy = to_local(L["lat0"], L["lon0"], home[0], home[1])
    at = (hx, hy, takeoff["params"][6])
    t = seg((hx, hy, 0.0), at)
    for lat, lon, alt, hold, image in pts:
        q = (*to_local(L["lat0"], L["lon0"], lat, lon), alt)
        t += seg(at, q) + hold
        at = q
        if image:
            images.append((lat, lon))
    t += seg(at, (hx, hy, at[2])) + seg((hx, hy, at[2]), (hx, hy, 0.0))
    assert t <= 300.0 + 0.05 and abs(t - s["flight_s"]) < 0.5, (k, t, s["flight_s"])
    assert s["first_waypoint"] == (p["sorties"][k - 1]["end_waypoint"] if k else 0)
    assert len(json.load(open(path))["geoFence"]["polygons"]) == 1
assert len(images) == len(p["waypoints"]), (len(images), len(p["waypoints"]))
for (lat, lon), w in zip(images, p["waypoints"]):
    assert abs(lat - w["latitude_deg"]) < 1e-7 and abs(lon - w["longitude_deg"]) < 1e-7
print(f"ok: {len(p['sorties'])} sorties of at most 5 min, {len(images)} images in order")
PY

# ArduPilot's own camera item; the flag still chooses.
"$mission" --area "$work/site.geojson" --gsd 10 --firmware ardupilot --out "$work/a" >/dev/null 2>&1 || fail "--firmware ardupilot"
"$mission" --area "$work/site.geojson" --gsd 10 --firmware ardupilot --camera-trigger capture --out "$work/ac" >/dev/null 2>&1 ||
  fail "--firmware ardupilot --camera-trigger capture"
"$python" - "$work" <<'PY' || fail "the camera items"
import sys; sys.path.insert(0, sys.argv[1]); from sites import *
count = lambda d, c: sum(i["command"] == c for i in plan_items(f"{sys.argv[1]}/{d}/mission.plan"))
assert (count("a", 203), count("a", 2000)) == (14, 0) and (count("ac", 203), count("ac", 2000)) == (0, 14)
assert (count("p", 203), count("p", 2000)) == (0, 14)
assert json.load(open(f"{sys.argv[1]}/a/mission.plan"))["mission"]["firmwareType"] == 3
print("ok: DO_DIGICAM_CONTROL for ArduPilot, IMAGE_START_CAPTURE for PX4 and on request")
PY
cut -f4 "$work/a/mission.waypoints" | grep -qx 203 || fail "--firmware ardupilot: no DO_DIGICAM_CONTROL in mission.waypoints"

# Camera presets: a Phantom 4 RTK flies 2.74 cm/px at 100 m (DJI's own figure), at full resolution
# or with its images processed at 684 px wide (8 times coarser at the same height); an unknown
# camera is refused, naming the presets.
"$mission" --area "$work/site.geojson" --gsd 2.74 --camera dji-phantom4-rtk --out "$work/cam" >/dev/null 2>&1 ||
  fail "--camera dji-phantom4-rtk"
"$mission" --area "$work/site.geojson" --gsd 21.92 --camera dji-phantom4-rtk --image-width 684 --out "$work/cam684" \
  >/dev/null 2>&1 || fail "--camera dji-phantom4-rtk --image-width 684"
"$python" - "$work" <<'PY' || fail "the camera presets' altitudes"
import json, sys
for d in ("cam", "cam684"):
    p = json.load(open(f"{sys.argv[1]}/{d}/plan.json"))
    assert abs(p["altitude_m"] - 100.0) < 0.2, (d, p["altitude_m"])
print("ok: the Phantom 4 RTK preset flies 2.74 cm/px at 100 m, 684 px wide 21.92 cm/px at 100 m")
PY
expect_error "unknown camera 'gopro': the presets are default, micasense-rededge-mx, dji-phantom4-rtk" \
  --area "$work/site.geojson" --gsd 10 --camera gopro --out "$work/q"

# Latitude and longitude swapped: named, not planned in another country.
expect_error "swapped, it would lie on the site: are the site's latitude and longitude swapped" \
  --area "$work/swapped.geojson" --gsd 10 --home "$lhome" --out "$work/q"
expect_error "swapped, the site would lie on it" --area "$work/swapped.geojson" --gsd 10 --dem "$work/dem.asc" --out "$work/q"
echo '{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [[[-33.90, 151.20], [-33.90, 151.21], [-33.91, 151.21], [-33.90, 151.20]]]}}]}' \
  >"$work/sydney.geojson"
expect_error "are latitude and longitude swapped? GeoJSON and KML list longitude first" --area "$work/sydney.geojson" --gsd 10 --out "$work/q"

# Sanity limits: too low; more items than PX4 stores; the size and hours named; the mask.
expect_error "the survey would fly 2.75 m above the ground at 0.50 cm/px, below the minimum altitude 10.0 m: with this camera fly at least 1.82 cm/px" \
  --area "$work/site.geojson" --gsd 0.5 --out "$work/q"
expect_error "below the minimum altitude 60.0 m: with this camera fly at least 10.91 cm/px" \
  --area "$work/site.geojson" --gsd 10 --min-altitude-m 60 --out "$work/q"
expect_error "more than the PX4 limit of 500: split it into sorties, or fly fewer waypoints" \
  --area "$work/big.geojson" --gsd 5 --map-gsd-cm 50 --out "$work/q"
expect_error "pixels, more than the 400000000 allowed: a map GSD of at least 7.5 cm/px fits (--map-gsd-cm)" \
  --area "$work/big.geojson" --gsd 5 --map-gsd-cm 1 --out "$work/q"
[ ! -e "$work/q" ] || fail "a refused plan wrote $work/q"
centre=$("$python" -c "import sys; sys.path.insert(0, '$work'); from sites import *; print('%.9f,%.9f' % to_ll(25.2, 55.3, 750, 750))")
"$mission" --area "$work/big.geojson" --gsd 5 --map-gsd-cm 50 --home "$centre" --max-flight-min 30 --export plan \
  --out "$work/b" >"$work/out" 2>"$work/err" || fail "the big site in sorties: $(cat "$work/err")"
grep -q "warning: the plan has [0-9]* waypoints, more than 1000: check the GSD (5.00 cm/px) against the site's 224.0 ha" "$work/err" ||
  fail "no waypoint warning: $(cat "$work/err")"
grep -q "warning: the plan flies [0-9.]* h in [0-9]* sortie(s), more than 2.0 h" "$work/err" || fail "no hours warning: $(cat "$work/err")"
echo "ok: $(wc -l <"$work/err") warnings for 2.25 km^2 at 5 cm/px, $(ls "$work/b" | grep -c '^mission-.*plan$') sorties"

expect_error "--area is required" --gsd 10 --out "$work/q"
expect_error "file not found" --area "$work/none.geojson" --gsd 10 --out "$work/q"
echo "a line of text" >"$work/text.geojson"
expect_error "neither a vector file nor a raster" --area "$work/text.geojson" --gsd 10 --out "$work/q"
expect_error "--gsd must be a finite positive GSD in cm/px, got 0.000" --area "$work/site.geojson" --gsd 0 --out "$work/q"
expect_error "--map-gsd-cm must be" --area "$work/site.geojson" --gsd 10 --map-gsd-cm nan --out "$work/q"
expect_error "--home '25.2' is not LAT,LON" --area "$work/site.geojson" --gsd 10 --home 25.2 --out "$work/q"
expect_error "m off the site (outside its outline or in a hole)" --area "$work/hole.geojson" --gsd 15 \
  --home "$("$python" -c "import sys; sys.path.insert(0, '$work'); from sites import *; print('%.9f,%.9f' % to_ll(47.4, 8.5, 125, 85))")" \
  --out "$work/q"
expect_error "--max-flight-min" --area "$work/site.geojson" --gsd 10 --max-flight-min 0 --out "$work/q"
expect_error "alone takes" --area "$work/site.geojson" --gsd 10 --max-flight-min 0.2 --out "$work/q"
cp "$work/dem.asc" "$work/nocrs.asc"
expect_error "nocrs.asc: the DEM has no coordinate reference system" --area "$work/site.geojson" --gsd 10 --dem "$work/nocrs.asc" \
  --out "$work/q"
# 30 cm/px flies at 165 m: above the 120 m ceiling, refused before any file is written.
expect_error "the mission would fly 165.0 m above home at 30.00 cm/px, above --max-altitude-m 120.0: with this camera fly at most 21.82 cm/px" \
  --area "$work/site.geojson" --gsd 30 --out "$work/q"
[ ! -e "$work/q" ] || fail "a refused plan wrote $work/q"
echo "ok: adaptseg_plan"
