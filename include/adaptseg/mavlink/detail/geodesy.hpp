#pragma once
/// @file
/// Local flat-earth geometry around a latitude: metres per degree on the WGS84 ellipsoid and
/// the horizontal distance between two nearby points (a site of a few kilometres: the error is
/// well under a centimetre per 100 m). Leaf internals of adaptseg::mavlink (CMake target
/// adaptseg::mavlink).

#include <cmath>
#include <numbers>

namespace adaptseg::detail {

/// Metres per degree of latitude at latitude `lat_deg` (WGS84, the usual series).
[[nodiscard]] inline double metres_per_degree_lat(double lat_deg) {
  const double p = lat_deg * std::numbers::pi / 180.0;
  return 111132.92 - 559.82 * std::cos(2.0 * p) + 1.175 * std::cos(4.0 * p) - 0.0023 * std::cos(6.0 * p);
}

/// Metres per degree of longitude at latitude `lat_deg` (WGS84, the usual series).
[[nodiscard]] inline double metres_per_degree_lon(double lat_deg) {
  const double p = lat_deg * std::numbers::pi / 180.0;
  return 111412.84 * std::cos(p) - 93.5 * std::cos(3.0 * p) + 0.118 * std::cos(5.0 * p);
}

/// North and east offsets [m] of (lat, lon) from (lat0, lon0), in the flat frame at their mean latitude.
struct NorthEast {
  double north_m = 0.0;
  double east_m = 0.0;
};
[[nodiscard]] inline NorthEast north_east_m(double lat0_deg, double lon0_deg, double lat_deg, double lon_deg) {
  const double mid = 0.5 * (lat0_deg + lat_deg);
  return {(lat_deg - lat0_deg) * metres_per_degree_lat(mid), (lon_deg - lon0_deg) * metres_per_degree_lon(mid)};
}

/// Horizontal distance [m] between two nearby points.
[[nodiscard]] inline double horizontal_distance_m(double lat0_deg, double lon0_deg, double lat_deg, double lon_deg) {
  const NorthEast d = north_east_m(lat0_deg, lon0_deg, lat_deg, lon_deg);
  return std::hypot(d.north_m, d.east_m);
}

/// The point `north_m`, `east_m` from (lat0, lon0) [deg].
struct LatLonDeg {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
};
[[nodiscard]] inline LatLonDeg offset_deg(double lat0_deg, double lon0_deg, double north_m, double east_m) {
  const double lat = lat0_deg + north_m / metres_per_degree_lat(lat0_deg);
  const double mid = 0.5 * (lat0_deg + lat);
  return {lat0_deg + north_m / metres_per_degree_lat(mid), lon0_deg + east_m / metres_per_degree_lon(mid)};
}

}  // namespace adaptseg::detail
