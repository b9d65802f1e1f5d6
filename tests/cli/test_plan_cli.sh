#!/usr/bin/env bash
# Black-box test of adaptseg_plan, the survey plan of a site without labels: an L-shaped
# GeoJSON site (long side 30 deg north of east, near Dubai) planned at 10 cm/px; every waypoint
# of the .plan inside the polygon's enclosing rectangle and over or beside the site, the files
# consistent with plan.json; then the command-line mistakes, each exit code 2 and one line.
#   test_plan_cli.sh ADAPTSEG_PLAN PYTHON
set -uo pipefail
mission=$1 python=$2
source "$(dirname "$0")/cli_common.sh"

"$python" - "$work/site.geojson" <<'PY' || fail "writing the site"
import json, math, sys
lat0, lon0, a = 25.2, 55.3, math.radians(30)
R = 6378137.0
ring = []
for x, y in [(0, 0), (240, 0), (240, 20), (160, 20), (160, 100), (0, 100), (0, 0)]:
    e, n = math.cos(a) * x - math.sin(a) * y, math.sin(a) * x + math.cos(a) * y
    ring.append([lon0 + math.degrees(e / (R * math.cos(math.radians(lat0)))), lat0 + math.degrees(n / R)])
json.dump({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
           "geometry": {"type": "Polygon", "coordinates": [ring]}}]}, open(sys.argv[1], "w"))
PY
"$mission" --area "$work/site.geojson" --gsd 10 --altitude-m 5 --out "$work/p" >"$work/out" 2>"$work/err" ||
  fail "adaptseg_plan: $(cat "$work/err")"
grep -q "site: 14 images at 10.0 cm/px (55.0 m above home)" "$work/out" || fail "summary: $(cat "$work/out")"
for f in mission.plan mission.waypoints mission.geojson plan.json site.png; do
  [ -s "$work/p/$f" ] || fail "missing $f"
done
"$python" - "$work/p" <<'PY' || fail "plan checks"
import json, math, sys
out = sys.argv[1]
p = json.load(open(f"{out}/plan.json"))
site, wps = p["site_frame"], p["waypoints"]
assert p["images"] == len(wps) == 14 and p["altitude_m"] == 55.0, p["images"]
# The frame along the long side (240 m at bearing 60 deg), the grid centred: waypoints inside
# the rectangle, the overhang split evenly.
assert abs(site["width_m"] - 240) < 1 and abs(site["height_m"] - 100) < 1, site
assert abs((site["heading_deg"] - 60 + 90) % 180 - 90) < 0.5, site["heading_deg"]
xs, ys = [w["x"] for w in wps], [w["y"] for w in wps]
assert 0 < min(xs) and max(xs) < site["width_m"] and 0 < min(ys) and max(ys) < site["height_m"], (xs, ys)
assert abs(min(xs) - (site["width_m"] - max(xs))) < 1e-6, (min(xs), max(xs))
# No waypoint over the bitten-out corner (x > 160 m, y > 20 m in the L's own frame) whose
# footprint (48 m x 36 m) misses the site: the cells there are skipped.
for w in wps:
    assert not (w["x"] - 24 > 161 and w["y"] - 18 > 21), w
# The .plan flies exactly these, at the GSD's altitude, one image each.
items = json.load(open(f"{out}/mission.plan"))["mission"]["items"]
navs = [i for i in items if i["command"] == 16]
assert len(navs) == len(wps) and sum(i["command"] == 2000 for i in items) == len(wps)
for nav, w in zip(navs, wps):
    assert abs(nav["params"][4] - w["latitude_deg"]) < 1e-7 and abs(nav["params"][5] - w["longitude_deg"]) < 1e-7
    assert abs(nav["params"][6] - 55.0) < 0.01
print(f"ok: {len(wps)} waypoints, site {site['width_m']:.1f} x {site['height_m']:.1f} m at {site['heading_deg']:.2f} deg")
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

expect_error "--area is required" --gsd 10 --out "$work/q"
expect_error "file not found" --area "$work/none.geojson" --gsd 10 --out "$work/q"
echo "a line of text" >"$work/text.geojson"
expect_error "neither a vector file nor a raster" --area "$work/text.geojson" --gsd 10 --out "$work/q"
expect_error "--gsd must be a finite positive GSD in cm/px, got 0.000" --area "$work/site.geojson" --gsd 0 --out "$work/q"
expect_error "--map-gsd-cm must be" --area "$work/site.geojson" --gsd 10 --map-gsd-cm nan --out "$work/q"
# 30 cm/px flies at 165 m: above the 120 m ceiling, refused before any file is written.
expect_error "the mission would fly 165.0 m above home at 30.00 cm/px, above --max-altitude-m 120.0: with this camera fly at most 21.82 cm/px" \
  --area "$work/site.geojson" --gsd 30 --out "$work/q"
[ ! -e "$work/q" ] || fail "a refused plan wrote $work/q"
echo "ok: adaptseg_plan"
