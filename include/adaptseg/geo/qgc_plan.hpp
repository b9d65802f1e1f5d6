#pragma once
/// @file
/// QGroundControl's `.plan` (JSON) of an export path, and the reader of it (mission items and
/// geofence). CMake target adaptseg::geo; docs/data_format.md, "Mission export".

#include <adaptseg/core/error.hpp>
#include <adaptseg/geo/detail/export_text.hpp>
#include <adaptseg/geo/export_path.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

namespace detail {

/// write_qgc_plan's geofence polygons, as QGCFencePolygon::saveToJson writes them.
/// @throws std::invalid_argument for a polygon of fewer than 3 vertices, a vertex out of range,
///         more vertices than the firmware keeps.
inline nlohmann::ordered_json qgc_fence_polygons(const ExportPath& path, const ExportOptions& options) {
  using fence_json = nlohmann::ordered_json;
  fence_json polygons = fence_json::array();
  std::size_t fence_vertices = 0;
  for (std::size_t k = 0; k < path.geofence.size(); ++k) {
    const GeoFencePolygon& f = path.geofence[k];
    require(f.vertices.size() >= 3,
            "write_qgc_plan: geofence polygon " + std::to_string(k) + " needs at least 3 vertices; vertices",
            f.vertices.size());
    fence_json ring = fence_json::array();
    for (const GeoPoint& v : f.vertices) {
      require(std::isfinite(v.latitude_deg) && std::abs(v.latitude_deg) <= 90.0 && std::isfinite(v.longitude_deg) &&
                  std::abs(v.longitude_deg) <= 180.0,
              "write_qgc_plan: geofence polygon " + std::to_string(k) +
                  " has a vertex outside latitude [-90, 90], longitude [-180, 180]; latitude",
              v.latitude_deg);
      ring.push_back(fence_json::array({v.latitude_deg, v.longitude_deg}));
    }
    fence_vertices += f.vertices.size();
    fence_json poly = fence_json::object();
    poly["inclusion"] = f.inclusion;
    poly["polygon"] = std::move(ring);
    poly["version"] = 1;
    polygons.push_back(std::move(poly));
  }
  if (const auto limit = firmware_fence_vertex_limit(options.firmware_type); limit && fence_vertices > *limit)
    throw std::invalid_argument("write_qgc_plan: the geofence has " + std::to_string(fence_vertices) +
                                " vertices, more than the " + firmware_name(options.firmware_type) + " limit of " +
                                std::to_string(*limit) + ": simplify its polygons");
  return polygons;
}

/// write_qgc_plan's mission items as QGC's `SimpleItem`s (NaN parameters null).
inline nlohmann::ordered_json qgc_items(const ExportPath& path, const ExportOptions& options) {
  using nlohmann::ordered_json;
  ordered_json items = ordered_json::array();
  int jump_id = 0;
  for (const MissionItem& item : mission_items(path, options)) {
    ordered_json params = ordered_json::array();
    for (double p : item.params) params.push_back(std::isfinite(p) ? ordered_json(p) : ordered_json(nullptr));
    ordered_json j = ordered_json::object();
    if (item.frame == mavlink::kFrameGlobalRelativeAlt) {
      j["AMSLAltAboveTerrain"] = nullptr;
      j["Altitude"] = item.params[6];
      j["AltitudeMode"] = 1;
    }
    j["autoContinue"] = item.autocontinue;
    j["command"] = item.command;
    j["doJumpId"] = ++jump_id;
    j["frame"] = item.frame;
    j["params"] = std::move(params);
    j["type"] = "SimpleItem";
    items.push_back(std::move(j));
  }
  return items;
}

/// read_qgc_plan's mission item `j` (at `where`): a `SimpleItem`, null parameters read as NaN.
inline MissionItem qgc_item(const nlohmann::json& j, const std::string& where) {
  constexpr const char* kFmt = "QGC plan";
  const std::string& type = json_string(json_member(j, "type", kFmt, where), kFmt, where + ".type");
  if (type != "SimpleItem")
    export_parse_error(kFmt, where + ": item type '" + type + "' is not supported (only SimpleItem)");
  MissionItem item;
  item.command =
      static_cast<int>(json_integer(json_member(j, "command", kFmt, where), 0, 65535, kFmt, where + ".command"));
  item.frame = static_cast<int>(json_integer(json_member(j, "frame", kFmt, where), 0, 255, kFmt, where + ".frame"));
  const nlohmann::json& ac = json_member(j, "autoContinue", kFmt, where);
  if (!ac.is_boolean()) export_parse_error(kFmt, where + ".autoContinue must be true or false");
  item.autocontinue = ac.get<bool>();
  const nlohmann::json& params = json_member(j, "params", kFmt, where);
  if (!params.is_array() || params.size() != 7)
    export_parse_error(kFmt, where + ".params must be an array of 7 numbers or nulls");
  for (std::size_t k = 0; k < 7; ++k)
    item.params[k] = params[k].is_null() ? std::numeric_limits<double>::quiet_NaN()
                                         : json_number(params[k], kFmt, where + ".params[" + std::to_string(k) + "]");
  check_item_position(item, kFmt, where);
  return item;
}

/// read_qgc_plan's geofence polygons (`geoFence`; its circles are not read).
inline std::vector<GeoFencePolygon> qgc_geofence(const nlohmann::json& fence) {
  constexpr const char* kFmt = "QGC plan";
  std::vector<GeoFencePolygon> out;
  if (!fence.is_object()) export_parse_error(kFmt, "geoFence must be an object");
  if (!fence.contains("polygons")) return out;
  const nlohmann::json& polygons = fence["polygons"];
  if (!polygons.is_array()) export_parse_error(kFmt, "geoFence.polygons must be an array");
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    const std::string where = "geoFence.polygons[" + std::to_string(k) + "]";
    const nlohmann::json& inclusion = json_member(polygons[k], "inclusion", kFmt, where);
    if (!inclusion.is_boolean()) export_parse_error(kFmt, where + ".inclusion must be true or false");
    const nlohmann::json& ring = json_member(polygons[k], "polygon", kFmt, where);
    if (!ring.is_array() || ring.size() < 3)
      export_parse_error(kFmt, where + ".polygon must be an array of at least 3 [latitude, longitude]");
    GeoFencePolygon f;
    f.inclusion = inclusion.get<bool>();
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const std::string vwhere = where + ".polygon[" + std::to_string(i) + "]";
      if (!ring[i].is_array() || ring[i].size() != 2)
        export_parse_error(kFmt, vwhere + " must be [latitude, longitude]");
      f.vertices.push_back(json_position(nlohmann::json::array({ring[i][1], ring[i][0], 0.0}), kFmt, vwhere));
    }
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace detail

/// The QGroundControl plan file of `path` (QGC developer guide, "Plan File Format":
/// `fileType` "Plan", `version` 1, `mission` version 2 with `plannedHomePosition`
/// [lat, lon, alt] and `SimpleItem`s; `geoFence` version 2 with the path's geofence, empty
/// `rallyPoints`). Waypoint items carry QGC's altitude keys (`Altitude`, `AltitudeMode` 1 =
/// relative, `AMSLAltAboveTerrain` null); NaN parameters are written as null, as QGC does. Each
/// fence polygon is `{"inclusion": bool, "polygon": [[lat, lon], ...], "version": 1}`, as QGC's
/// QGCFencePolygon::saveToJson writes it (src/MissionManager/QGCFencePolygon.cc: the version key,
/// `inclusion`, then QGCMapPolygon's `polygon` of [latitude, longitude] pairs, not closed).
/// @throws std::invalid_argument for an empty path, invalid options, a fence polygon of fewer
///         than 3 vertices or outside the coordinate ranges, more fence vertices than the
///         firmware keeps (firmware_fence_vertex_limit()), or as mission_items().
inline std::string write_qgc_plan(const ExportPath& path, const ExportOptions& options = {}) {
  detail::require_exportable(path, "write_qgc_plan");
  using nlohmann::ordered_json;
  ordered_json polygons = detail::qgc_fence_polygons(path, options);
  ordered_json items = detail::qgc_items(path, options);
  ordered_json mission = ordered_json::object();
  mission["cruiseSpeed"] = options.cruise_speed_mps;
  mission["firmwareType"] = options.firmware_type;
  mission["globalPlanAltitudeMode"] = 1;
  mission["hoverSpeed"] = options.hover_speed_mps;
  mission["items"] = std::move(items);
  mission["plannedHomePosition"] = {path.home.latitude_deg, path.home.longitude_deg, path.home.altitude_m};
  mission["vehicleType"] = options.vehicle_type;
  mission["version"] = 2;
  ordered_json plan = ordered_json::object();
  plan["fileType"] = "Plan";
  plan["geoFence"] = {{"circles", ordered_json::array()}, {"polygons", std::move(polygons)}, {"version", 2}};
  plan["groundStation"] = "adaptseg";
  plan["mission"] = std::move(mission);
  plan["rallyPoints"] = {{"points", ordered_json::array()}, {"version", 2}};
  plan["version"] = 1;
  return plan.dump(2) + "\n";
}

/// Reads a QGroundControl plan file: its home position, mission items (`SimpleItem`s; null
/// parameters read as NaN) and geofence polygons (`geoFence` is optional; its circles are not
/// read).
/// @throws std::invalid_argument naming the offending member: not JSON, not a plan, a
///         missing or mistyped key, a complex item, a position out of range, a fence polygon
///         of fewer than 3 vertices.
inline MissionFile read_qgc_plan(std::string_view text) {
  constexpr const char* kFmt = "QGC plan";
  const nlohmann::json plan = detail::json_parse(text, kFmt);
  detail::json_expect(plan, "fileType", "Plan", kFmt);
  if (detail::json_integer(detail::json_member(plan, "version", kFmt, "the file"), 0, 1000, kFmt, "version") != 1)
    detail::export_parse_error(kFmt, "unsupported version (want 1)");
  const nlohmann::json& mission = detail::json_member(plan, "mission", kFmt, "the file");
  MissionFile out;
  const nlohmann::json& home = detail::json_member(mission, "plannedHomePosition", kFmt, "mission");
  if (!home.is_array() || home.size() != 3)
    detail::export_parse_error(kFmt, "mission.plannedHomePosition must be [latitude, longitude, altitude]");
  // [lat, lon, alt] is the reverse of GeoJSON's order: swap into it for json_position.
  out.home =
      detail::json_position(nlohmann::json::array({home[1], home[0], home[2]}), kFmt, "mission.plannedHomePosition");
  const nlohmann::json& items = detail::json_member(mission, "items", kFmt, "mission");
  if (!items.is_array()) detail::export_parse_error(kFmt, "mission.items must be an array");
  for (std::size_t i = 0; i < items.size(); ++i)
    out.items.push_back(detail::qgc_item(items[i], "mission.items[" + std::to_string(i) + "]"));
  if (plan.contains("geoFence")) out.geofence = detail::qgc_geofence(plan["geoFence"]);
  return out;
}

}  // namespace adaptseg
