#pragma once
/// @file
/// The GeoJSON (RFC 7946) of an export path, for GIS, and the reader of it. CMake target
/// adaptseg::geo; docs/data_format.md, "Mission export".

#include <adaptseg/core/error.hpp>
#include <adaptseg/geo/detail/export_text.hpp>
#include <adaptseg/geo/export_path.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// The GeoJSON (RFC 7946) of `path`: a FeatureCollection with the path as a LineString
/// (properties `kind` "path", `waypoints`), then one Point per waypoint (properties `kind`
/// "waypoint", `index`, `level`, `role` "top-level", "descent" or "via" (no image), `gsd_cm`,
/// `relative_altitude_m`). Positions are [longitude, latitude, height] with the height, as
/// RFC 7946 requires, above the WGS84 ellipsoid: home altitude + relative altitude. A path of
/// one waypoint gives a LineString of that position twice (a LineString needs two). Foreign
/// members `name` (GDAL's layer name) and `home` ([lon, lat, height]) keep the rest.
/// @throws std::invalid_argument for an empty path.
inline std::string write_geojson(const ExportPath& path) {
  detail::require_exportable(path, "write_geojson");
  using nlohmann::ordered_json;
  const auto position = [&](const ExportWaypoint& w) {
    return ordered_json::array({w.longitude_deg, w.latitude_deg, path.home.altitude_m + w.relative_altitude_m});
  };
  ordered_json line = ordered_json::array();
  for (const auto& w : path.waypoints) line.push_back(position(w));
  if (path.waypoints.size() == 1) line.push_back(position(path.waypoints.front()));
  ordered_json features = ordered_json::array();
  features.push_back({{"type", "Feature"},
                      {"properties", {{"kind", "path"}, {"waypoints", path.waypoints.size()}}},
                      {"geometry", {{"type", "LineString"}, {"coordinates", std::move(line)}}}});
  for (std::size_t i = 0; i < path.waypoints.size(); ++i) {
    const ExportWaypoint& w = path.waypoints[i];
    features.push_back({{"type", "Feature"},
                        {"properties",
                         {{"kind", "waypoint"},
                          {"index", i},
                          {"level", w.level},
                          {"role", w.via          ? "via"
                                   : w.level == 0 ? "top-level"
                                                  : "descent"},
                          {"gsd_cm", w.gsd_cm},
                          {"relative_altitude_m", w.relative_altitude_m}}},
                        {"geometry", {{"type", "Point"}, {"coordinates", position(w)}}}});
  }
  ordered_json doc = ordered_json::object();
  doc["type"] = "FeatureCollection";
  doc["name"] = path.name;
  doc["home"] = ordered_json::array({path.home.longitude_deg, path.home.latitude_deg, path.home.altitude_m});
  doc["features"] = std::move(features);
  return doc.dump(2) + "\n";
}

namespace detail {

/// read_geojson's waypoint at `g` from a Point feature's `properties` (at `where`): its index
/// and the waypoint.
inline std::pair<long long, ExportWaypoint> geojson_waypoint(const nlohmann::json& props, const GeoPoint& g,
                                                             const std::string& where) {
  constexpr const char* kFmt = "GeoJSON";
  const long long index = json_integer(json_member(props, "index", kFmt, where), 0, std::numeric_limits<int>::max(),
                                       kFmt, where + ".index");
  ExportWaypoint w;
  w.latitude_deg = g.latitude_deg;
  w.longitude_deg = g.longitude_deg;
  w.level = static_cast<int>(json_integer(json_member(props, "level", kFmt, where), 0, std::numeric_limits<int>::max(),
                                          kFmt, where + ".level"));
  w.gsd_cm = json_number(json_member(props, "gsd_cm", kFmt, where), kFmt, where + ".gsd_cm");
  w.relative_altitude_m =
      json_number(json_member(props, "relative_altitude_m", kFmt, where), kFmt, where + ".relative_altitude_m");
  w.via = props.contains("role") && props["role"] == "via";
  return {index, w};
}

}  // namespace detail

/// Reads what write_geojson() writes back into an ExportPath.
/// @throws std::invalid_argument naming the offending member: not JSON, not a
///         FeatureCollection, a missing or mistyped member, not exactly one LineString, point
///         indices not 0..n-1, a LineString that does not join the points in order.
inline ExportPath read_geojson(std::string_view text) {
  constexpr const char* kFmt = "GeoJSON";
  const nlohmann::json doc = detail::json_parse(text, kFmt);
  detail::json_expect(doc, "type", "FeatureCollection", kFmt);
  ExportPath out;
  out.name = detail::json_string(detail::json_member(doc, "name", kFmt, "the file"), kFmt, "name");
  out.home = detail::json_position(detail::json_member(doc, "home", kFmt, "the file"), kFmt, "home");
  const nlohmann::json& features = detail::json_member(doc, "features", kFmt, "the file");
  if (!features.is_array()) detail::export_parse_error(kFmt, "features must be an array");
  std::optional<std::vector<GeoPoint>> line;
  std::map<long long, std::pair<ExportWaypoint, GeoPoint>> points;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const std::string where = "features[" + std::to_string(i) + "]";
    const nlohmann::json& f = features[i];
    if (detail::json_string(detail::json_member(f, "type", kFmt, where), kFmt, where + ".type") != "Feature")
      detail::export_parse_error(kFmt, where + ".type must be \"Feature\"");
    const nlohmann::json& geometry = detail::json_member(f, "geometry", kFmt, where);
    const std::string& type = detail::json_string(detail::json_member(geometry, "type", kFmt, where + ".geometry"),
                                                  kFmt, where + ".geometry.type");
    const nlohmann::json& coords = detail::json_member(geometry, "coordinates", kFmt, where + ".geometry");
    const std::string cwhere = where + ".geometry.coordinates";
    if (type == "LineString") {
      if (line) detail::export_parse_error(kFmt, where + ": a second LineString (want one path)");
      if (!coords.is_array() || coords.size() < 2)
        detail::export_parse_error(kFmt, cwhere + " must be an array of at least 2 positions");
      line.emplace();
      for (std::size_t k = 0; k < coords.size(); ++k)
        line->push_back(detail::json_position(coords[k], kFmt, cwhere + "[" + std::to_string(k) + "]"));
    } else if (type == "Point") {
      const GeoPoint g = detail::json_position(coords, kFmt, cwhere);
      const std::string pwhere = where + ".properties";
      const auto [index, w] = detail::geojson_waypoint(detail::json_member(f, "properties", kFmt, where), g, pwhere);
      if (!points.emplace(index, std::make_pair(w, g)).second)
        detail::export_parse_error(kFmt, pwhere + ".index " + std::to_string(index) + " appears twice");
    } else {
      detail::export_parse_error(kFmt, where + ": geometry type '" + type + "' (want LineString or Point)");
    }
  }
  if (!line) detail::export_parse_error(kFmt, "no LineString (the path)");
  if (points.empty()) detail::export_parse_error(kFmt, "no Point (waypoints)");
  if (points.rbegin()->first != static_cast<long long>(points.size()) - 1)
    detail::export_parse_error(kFmt, "waypoint indices must be 0.." + std::to_string(points.size() - 1));
  const std::size_t want = points.size() == 1 ? 2 : points.size();
  if (line->size() != want)
    detail::export_parse_error(kFmt, "the LineString has " + std::to_string(line->size()) + " positions, want " +
                                         std::to_string(want) + " (one per waypoint)");
  for (const auto& [index, wg] : points) {
    const GeoPoint& p = (*line)[static_cast<std::size_t>(index)];
    const GeoPoint& g = wg.second;
    if (std::abs(p.latitude_deg - g.latitude_deg) > 1e-9 || std::abs(p.longitude_deg - g.longitude_deg) > 1e-9 ||
        std::abs(p.altitude_m - g.altitude_m) > 1e-6)
      detail::export_parse_error(
          kFmt, "LineString position " + std::to_string(index) + " differs from the waypoint Point of that index");
    out.waypoints.push_back(wg.first);
  }
  return out;
}

}  // namespace adaptseg
