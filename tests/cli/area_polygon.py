"""The rectangle of a recorded folder's area (its area.yaml's area_m, in its geo: frame) as a
GeoJSON polygon in WGS84, through a first-order WGS84 tangent plane (~1e-9 deg over a field).

    area_polygon.py FOLDER OUT.geojson
"""
import json
import math
import sys

import yaml

folder, out = sys.argv[1], sys.argv[2]
info = yaml.safe_load(open(f"{folder}/area.yaml"))
g, a = info["geo"], info["area_m"]


def wgs84(x, y):
    lat0, lon0, h = g["latitude_deg"], g["longitude_deg"], math.radians(g["heading_deg"])
    x, y = x - g["anchor_x_m"], y - g["anchor_y_m"]
    east, north = x * math.sin(h) - y * math.cos(h), x * math.cos(h) + y * math.sin(h)
    A, e2 = 6378137.0, 6.69437999014e-3
    s = math.sin(math.radians(lat0))
    m, n = A * (1 - e2) / (1 - e2 * s * s) ** 1.5, A / math.sqrt(1 - e2 * s * s)
    return [lon0 + math.degrees(east / (n * math.cos(math.radians(lat0)))), lat0 + math.degrees(north / m)]


ring = [wgs84(a[0], a[1]), wgs84(a[2], a[1]), wgs84(a[2], a[3]), wgs84(a[0], a[3]), wgs84(a[0], a[1])]
json.dump({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
           "geometry": {"type": "Polygon", "coordinates": [ring]}}]}, open(out, "w"))
