#pragma once
/// @file
/// Export of a planned or flown mission for ground stations and GIS, and readers of the
/// same files: QGroundControl `.plan` (JSON), the MAVLink plain-text waypoint format
/// (`QGC WPL 110`) and GeoJSON (RFC 7946). CMake target adaptseg::geo.
///
/// A mission file is one an autopilot flies from the ground and back: a MAV_CMD_NAV_TAKEOFF
/// above home to the first waypoint's altitude; every waypoint a MAV_CMD_NAV_WAYPOINT that
/// holds there (the UAV stops at each waypoint, paper §3.2.1) followed by one camera trigger
/// (the firmware's own: MAV_CMD_IMAGE_START_CAPTURE of one image for PX4, as QGroundControl
/// writes "Take photo"; MAV_CMD_DO_DIGICAM_CONTROL for ArduPilot, as Mission Planner writes it);
/// then MAV_CMD_NAV_RETURN_TO_LAUNCH (or a landing at home, or nothing: ExportOptions).
/// Altitudes are relative (MAV_FRAME_GLOBAL_RELATIVE_ALT): the waypoint's z, its height above
/// the field plane, on which the UAV takes off (the home position). A path may carry a geofence
/// (the .plan's `geoFence`; WPL and GeoJSON have no place for one), and a mission longer than
/// the firmware stores is refused. Formats and conventions: docs/data_format.md, "Mission
/// export".
///
/// @code
/// const adaptseg::GeoReference geo(field);
/// const adaptseg::ExportPath path = adaptseg::make_export_path(result, geo);  // a MissionResult
/// const std::string plan = adaptseg::write_qgc_plan(path);
/// const adaptseg::MissionFile back = adaptseg::read_qgc_plan(plan);
/// @endcode

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/geo/detail/export_text.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/vision/mission.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// The MAVLink enumeration values the exports use (MAVLink common.xml).
namespace mavlink {
inline constexpr int kCmdNavWaypoint = 16;        ///< MAV_CMD_NAV_WAYPOINT: p1 hold [s], p4 yaw, p5-7 position
inline constexpr int kCmdNavReturnToLaunch = 20;  ///< MAV_CMD_NAV_RETURN_TO_LAUNCH: no parameters
inline constexpr int kCmdNavLand = 21;            ///< MAV_CMD_NAV_LAND: p4 yaw, p5-7 position (altitude ignored)
inline constexpr int kCmdNavTakeoff = 22;         ///< MAV_CMD_NAV_TAKEOFF: p1 pitch, p4 yaw, p5-6 position, p7 altitude
inline constexpr int kCmdDoChangeSpeed =
    178;  ///< MAV_CMD_DO_CHANGE_SPEED: p1 speed type (1 ground), p2 speed [m/s], p3 throttle (-1: unchanged)
inline constexpr int kCmdDoDigicamControl = 203;  ///< MAV_CMD_DO_DIGICAM_CONTROL: p5 1 = take one shot
inline constexpr int kCmdImageStartCapture =
    2000;                                ///< MAV_CMD_IMAGE_START_CAPTURE: p1 camera, p2 interval, p3 count, p4 sequence
inline constexpr int kFrameGlobal = 0;   ///< MAV_FRAME_GLOBAL: altitude above mean sea level
inline constexpr int kFrameMission = 2;  ///< MAV_FRAME_MISSION: the item has no position
inline constexpr int kFrameGlobalRelativeAlt = 3;  ///< MAV_FRAME_GLOBAL_RELATIVE_ALT: altitude above home
inline constexpr int kAutopilotArduPilot = 3;      ///< MAV_AUTOPILOT_ARDUPILOTMEGA
inline constexpr int kAutopilotPx4 = 12;           ///< MAV_AUTOPILOT_PX4
inline constexpr int kTypeQuadrotor = 2;           ///< MAV_TYPE_QUADROTOR
}  // namespace mavlink

/// One waypoint of an exported path.
struct ExportWaypoint {
  double latitude_deg = 0.0;         ///< WGS84 [deg]
  double longitude_deg = 0.0;        ///< WGS84 [deg]
  double relative_altitude_m = 0.0;  ///< height above the field plane (= home) [m]: the waypoint's z
  double gsd_cm = 0.0;               ///< GSD of the image taken here [cm/px]
  int level = 0;                     ///< 0: top-level plan; 1 (or more): a descent (sub-lawnmower)
  /// A via point: flown through without a hold or an image (a leg routed inside the geofence).
  bool via = false;

  friend bool operator==(const ExportWaypoint&, const ExportWaypoint&) = default;
};

/// One polygon of a geofence: the vehicle must stay inside an inclusion polygon and outside an
/// exclusion one (QGroundControl's `geoFence.polygons[]`, MAVLink's
/// MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION / _EXCLUSION, 5001 / 5002).
struct GeoFencePolygon {
  bool inclusion = true;           ///< true: stay inside; false: stay outside (a hole of the site)
  std::vector<GeoPoint> vertices;  ///< at least 3, not closed (the first is not repeated); altitudes unused

  friend bool operator==(const GeoFencePolygon&, const GeoFencePolygon&) = default;
};

/// A path in WGS84, ready to export: built from field-frame waypoints by make_export_path().
struct ExportPath {
  std::string name;                       ///< the GeoJSON's name (the .plan and WPL formats have no place for it)
  GeoPoint home;                          ///< take-off: the field frame's origin on the field plane (or the caller's)
  std::vector<ExportWaypoint> waypoints;  ///< in visiting order
  /// The geofence the .plan carries (empty: none). adaptseg_plan gives the site's polygon, its
  /// holes as exclusion polygons.
  std::vector<GeoFencePolygon> geofence;
};

/// What a mission file does after its last waypoint.
enum class MissionEnd {
  return_to_launch,  ///< MAV_CMD_NAV_RETURN_TO_LAUNCH: the autopilot flies home at its RTL altitude and lands
  land,              ///< MAV_CMD_NAV_LAND at home: flies there at the last waypoint's altitude and lands
  none,              ///< nothing: the autopilot's end-of-mission behaviour (often: hover at the last waypoint)
};

/// The mission item that takes each image.
enum class CameraTrigger {
  image_start_capture,  ///< MAV_CMD_IMAGE_START_CAPTURE of one image, as QGroundControl writes "Take photo" (PX4's)
  digicam_control,      ///< MAV_CMD_DO_DIGICAM_CONTROL with shoot = 1, as Mission Planner writes it (ArduPilot's)
};

/// The camera item a firmware's own ground station writes into a mission: DO_DIGICAM_CONTROL
/// for ArduPilot (Mission Planner's "DO_DIGICAM_CONTROL", the item ArduPilot's camera library
/// has triggered since its first missions; ArduPilot also reads IMAGE_START_CAPTURE since 4.x,
/// but its users and their cameras expect the digicam item), IMAGE_START_CAPTURE for anything
/// else (QGroundControl's "Take photo", which PX4 executes through its camera trigger). Not
/// DO_SET_CAM_TRIGG_DIST: that triggers by distance flown through, while the UAV here stops at
/// every waypoint and takes exactly one image there (paper §3.2.1).
[[nodiscard]] constexpr CameraTrigger firmware_camera_trigger(int firmware_type) noexcept {
  return firmware_type == mavlink::kAutopilotArduPilot ? CameraTrigger::digicam_control
                                                       : CameraTrigger::image_start_capture;
}

/// How many mission items a firmware stores, in its default configuration (the home position
/// not counted); nullopt for a firmware adaptseg knows no limit of.
/// - PX4: 500, `CONFIG_NUM_MISSION_ITMES_SUPPORTED` (dataman's mission storage; 2000 before
///   PX4 v1.13, PX4-Autopilot pull request 18827, "reduce NUM_MISSIONS_SUPPORTED from 2000->500";
///   a board may be built with more).
/// - ArduPilot: 717, Copter on a board with 16 KB of storage (libraries/StorageManager/
///   StorageManager.cpp: "On Pixhawk this gives 718 waypoints", 15 bytes per command,
///   AP_Mission.h `AP_MISSION_EEPROM_COMMAND_SIZE`, command 0 being home); more with
///   BRD_SD_MISSION (mission storage on the SD card).
/// An autopilot configured for more: ExportOptions::max_mission_items.
[[nodiscard]] constexpr std::optional<std::size_t> firmware_mission_item_limit(int firmware_type) noexcept {
  if (firmware_type == mavlink::kAutopilotPx4) return 500;
  if (firmware_type == mavlink::kAutopilotArduPilot) return 717;
  return std::nullopt;
}

/// How many geofence vertices a .plan for `firmware_type` may carry (all polygons together):
/// 63 for PX4 (dataman's `DM_KEY_FENCE_POINTS_MAX` 64, one slot of which holds the fence's
/// statistics in the PX4 releases that keep it there) and, as the same conservative bound, for
/// ArduPilot (about 70 fence points on a Copter with 16 KB of storage, StorageManager.cpp, less
/// the polygon loader's headers); nullopt for a firmware adaptseg knows no limit of.
[[nodiscard]] constexpr std::optional<std::size_t> firmware_fence_vertex_limit(int firmware_type) noexcept {
  if (firmware_type == mavlink::kAutopilotPx4 || firmware_type == mavlink::kAutopilotArduPilot) return 63;
  return std::nullopt;
}

/// A firmware's name for messages: "PX4", "ArduPilot", or "firmware N".
inline std::string firmware_name(int firmware_type) {
  if (firmware_type == mavlink::kAutopilotPx4) return "PX4";
  if (firmware_type == mavlink::kAutopilotArduPilot) return "ArduPilot";
  return "firmware " + std::to_string(firmware_type);
}

/// Settings of the mission files.
struct ExportOptions {
  double hold_s = 1.0;         ///< hold time at every waypoint before the image [s] (NAV_WAYPOINT param1)
  bool capture_images = true;  ///< a camera trigger after every waypoint
  /// Which item triggers the camera; empty: the firmware's own (firmware_camera_trigger()).
  std::optional<CameraTrigger> camera_trigger;
  bool takeoff = true;                            ///< a NAV_TAKEOFF at home to the first waypoint's altitude, first
  MissionEnd end = MissionEnd::return_to_launch;  ///< the item after the last waypoint
  /// Multicopter speed [m/s]: .plan `hoverSpeed`, and the DO_CHANGE_SPEED item (`set_speed`);
  /// the programs set the mission's modelled speed.
  double hover_speed_mps = 2.0;
  /// A DO_CHANGE_SPEED to `hover_speed_mps` (ground speed) before the first waypoint: without
  /// it the autopilot flies its own default speed, and the mission's times and budget do not hold.
  bool set_speed = true;
  /// The highest a waypoint may fly above home [m] (120: the usual legal ceiling for small
  /// UAVs); a path above it is refused.
  double max_altitude_m = 120.0;
  double cruise_speed_mps = 15.0;              ///< fixed-wing speed [m/s] (.plan `cruiseSpeed`, required by QGC)
  int firmware_type = mavlink::kAutopilotPx4;  ///< MAV_AUTOPILOT of the .plan (mavlink::kAutopilotArduPilot: 3)
  int vehicle_type = mavlink::kTypeQuadrotor;  ///< MAV_TYPE of the .plan
  /// The most mission items a file may hold; empty: the firmware's (firmware_mission_item_limit()).
  std::optional<std::size_t> max_mission_items;

  /// The camera item: `camera_trigger`, or the firmware's own.
  [[nodiscard]] CameraTrigger trigger() const noexcept {
    return camera_trigger.value_or(firmware_camera_trigger(firmware_type));
  }

  /// @throws std::invalid_argument naming the first invalid member.
  void validate() const {
    detail::require(std::isfinite(hold_s) && hold_s >= 0.0, "ExportOptions: hold_s must be finite and >= 0", hold_s);
    detail::require_positive(hover_speed_mps, "ExportOptions: hover_speed_mps");
    detail::require_positive(cruise_speed_mps, "ExportOptions: cruise_speed_mps");
    detail::require_positive(max_altitude_m, "ExportOptions: max_altitude_m");
    detail::require(firmware_type >= 0 && firmware_type <= 255, "ExportOptions: firmware_type must be in 0..255",
                    firmware_type);
    detail::require(vehicle_type >= 0 && vehicle_type <= 255, "ExportOptions: vehicle_type must be in 0..255",
                    vehicle_type);
    detail::require(end == MissionEnd::return_to_launch || end == MissionEnd::land || end == MissionEnd::none,
                    "ExportOptions: end must be a MissionEnd", static_cast<int>(end));
    detail::require(trigger() == CameraTrigger::image_start_capture || trigger() == CameraTrigger::digicam_control,
                    "ExportOptions: camera_trigger must be a CameraTrigger", static_cast<int>(trigger()));
    detail::require(!max_mission_items || *max_mission_items > 0, "ExportOptions: max_mission_items must be > 0",
                    max_mission_items.value_or(0));
  }
};

/// One MAVLink mission item (the fields of MISSION_ITEM_INT that mission files carry).
struct MissionItem {
  int command = 0;                 ///< MAV_CMD
  int frame = 0;                   ///< MAV_FRAME
  std::array<double, 7> params{};  ///< param1..4, x (latitude), y (longitude), z (altitude); NaN: unset
  bool autocontinue = true;
};

/// A mission file read back: the home position and the items after it.
struct MissionFile {
  GeoPoint home;  ///< .plan `plannedHomePosition`; WPL line 0
  std::vector<MissionItem> items;
  std::vector<GeoFencePolygon> geofence;  ///< .plan `geoFence.polygons` (a WPL file has none)
};

/// The file formats.
enum class ExportFormat {
  qgc_plan,  ///< QGroundControl plan (JSON), `mission.plan`
  wpl,       ///< MAVLink plain-text waypoint file `QGC WPL 110`, `mission.waypoints`
  geojson,   ///< GeoJSON (RFC 7946), `mission.geojson`
};

/// Every format by its name on the command line.
inline constexpr std::array<detail::NamedValue<ExportFormat>, 3> kExportFormats{{
    {ExportFormat::qgc_plan, "plan"},
    {ExportFormat::wpl, "wpl"},
    {ExportFormat::geojson, "geojson"},
}};

/// "plan", "wpl" or "geojson" -> ExportFormat.
/// @throws std::invalid_argument for anything else.
inline ExportFormat parse_export_format(std::string_view name) {
  return detail::value_named(kExportFormats, name, "export format");
}

/// The conventional file name of a format: mission.plan, mission.waypoints, mission.geojson.
inline std::string export_file_name(ExportFormat format) {
  switch (format) {
    case ExportFormat::qgc_plan: return "mission.plan";
    case ExportFormat::wpl: return "mission.waypoints";
    case ExportFormat::geojson: return "mission.geojson";
  }
  throw std::invalid_argument("export_file_name: invalid ExportFormat");
}

/// `stem` with a format's extension: mission-2.plan, mission-2.waypoints, mission-2.geojson (one
/// file per sortie of a split survey).
inline std::string export_file_name(ExportFormat format, const std::string& stem) {
  const std::string name = export_file_name(format);
  return stem + name.substr(name.find('.'));
}

/// A field-frame path in WGS84: each waypoint's (x, y) through `geo`, its z as the relative
/// altitude; `levels[i]` is waypoint i's level (0 top-level, 1 descent). Home is the field
/// frame's origin at the field plane's height (`FieldGeo::altitude_m`).
/// @throws std::invalid_argument if the sizes differ, a level is negative or a position is
///         not finite.
inline ExportPath make_export_path(const std::vector<Waypoint>& path, const std::vector<int>& levels,
                                   const GeoReference& geo, std::string name) {
  detail::require(
      levels.size() == path.size(),
      "make_export_path: one level per waypoint is needed, waypoints " + std::to_string(path.size()) + ", levels",
      levels.size());
  ExportPath out;
  out.name = std::move(name);
  out.home = geo.to_wgs84(Eigen::Vector3d::Zero());
  out.home.altitude_m = geo.geo().altitude_m;
  out.waypoints.reserve(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Eigen::Vector3d& p = path[i].position;
    detail::require(p.allFinite(), "make_export_path: waypoint " + std::to_string(i) + " has a non-finite position",
                    p.transpose());
    detail::require(levels[i] >= 0, "make_export_path: level of waypoint " + std::to_string(i) + " must be >= 0",
                    levels[i]);
    const GeoPoint g = geo.to_wgs84(p);
    // Altitudes to the centimetre: 165.00000000001054 m is what a GSD's arithmetic gives, not
    // what an autopilot should be told.
    out.waypoints.push_back(
        {g.latitude_deg, g.longitude_deg, std::round(p.z() * 100.0) / 100.0, path[i].gsd_cm, levels[i], false});
  }
  return out;
}

/// A planned path (e.g. from LawnmowerPlanner): every waypoint top-level.
inline ExportPath make_export_path(const std::vector<Waypoint>& path, const GeoReference& geo, std::string name) {
  return make_export_path(path, std::vector<int>(path.size(), 0), geo, std::move(name));
}

/// The path a mission flew, named "<field> <strategy>".
inline ExportPath make_export_path(const MissionResult& result, const GeoReference& geo) {
  std::vector<Waypoint> path;
  std::vector<int> levels;
  for (const auto& r : result.waypoints) {
    path.push_back(r.waypoint);
    levels.push_back(r.level);
  }
  return make_export_path(path, levels, geo, result.field + " " + result.strategy);
}

/// The mission items of `path` (home excluded), in the relative altitude frame where they
/// have a position (yaw NaN: the autopilot's yaw mode):
/// - if `takeoff`, a NAV_TAKEOFF at home (pitch 0) to the first waypoint's altitude;
/// - if `set_speed`, a DO_CHANGE_SPEED to `hover_speed_mps` (ground speed, throttle unchanged);
/// - per waypoint a NAV_WAYPOINT holding `hold_s` (a via point: 0 s, and no image), then, if
///   `capture_images`, one camera trigger: an IMAGE_START_CAPTURE of one image (all cameras,
///   sequence 1, 2, ...) or a
///   DO_DIGICAM_CONTROL with shoot = 1 (ExportOptions::trigger(): the firmware's own unless set);
/// - `end`: a RETURN_TO_LAUNCH, a NAV_LAND at home, or nothing.
/// @throws std::invalid_argument for invalid options, a take-off with the first waypoint not
///         above home, a waypoint above `max_altitude_m`, or more items than the firmware
///         stores (ExportOptions::max_mission_items, firmware_mission_item_limit()), naming the
///         count and the limit.
inline std::vector<MissionItem> mission_items(const ExportPath& path, const ExportOptions& options = {}) {
  options.validate();
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < path.waypoints.size(); ++i)
    detail::require(path.waypoints[i].relative_altitude_m <= options.max_altitude_m,
                    "mission_items: waypoint " + std::to_string(i) + " flies above max_altitude_m " +
                        std::to_string(options.max_altitude_m) + " m; relative altitude",
                    path.waypoints[i].relative_altitude_m);
  std::vector<MissionItem> items;
  if (options.takeoff && !path.waypoints.empty()) {
    const double altitude = path.waypoints.front().relative_altitude_m;
    detail::require(altitude > 0.0, "mission_items: a take-off needs the first waypoint above home, relative altitude",
                    altitude);
    items.push_back({mavlink::kCmdNavTakeoff,
                     mavlink::kFrameGlobalRelativeAlt,
                     {0.0, 0.0, 0.0, kNaN, path.home.latitude_deg, path.home.longitude_deg, altitude},
                     true});
  }
  if (options.set_speed)
    items.push_back({mavlink::kCmdDoChangeSpeed,
                     mavlink::kFrameMission,
                     {1.0, options.hover_speed_mps, -1.0, 0.0, kNaN, kNaN, kNaN},
                     true});
  int sequence = 0;
  for (const auto& w : path.waypoints) {
    items.push_back(
        {mavlink::kCmdNavWaypoint,
         mavlink::kFrameGlobalRelativeAlt,
         {w.via ? 0.0 : options.hold_s, 0.0, 0.0, kNaN, w.latitude_deg, w.longitude_deg, w.relative_altitude_m},
         true});
    if (!options.capture_images || w.via) continue;
    if (options.trigger() == CameraTrigger::image_start_capture)
      items.push_back({mavlink::kCmdImageStartCapture,
                       mavlink::kFrameMission,
                       {0.0, 0.0, 1.0, static_cast<double>(++sequence), kNaN, kNaN, kNaN},
                       true});
    else
      items.push_back(
          {mavlink::kCmdDoDigicamControl, mavlink::kFrameMission, {0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0}, true});
  }
  if (options.end == MissionEnd::return_to_launch)
    items.push_back({mavlink::kCmdNavReturnToLaunch, mavlink::kFrameMission, {}, true});
  else if (options.end == MissionEnd::land)
    items.push_back({mavlink::kCmdNavLand,
                     mavlink::kFrameGlobalRelativeAlt,
                     {0.0, 0.0, 0.0, kNaN, path.home.latitude_deg, path.home.longitude_deg, 0.0},
                     true});
  if (const auto limit =
          options.max_mission_items ? options.max_mission_items : firmware_mission_item_limit(options.firmware_type);
      limit && items.size() > *limit)
    throw std::invalid_argument("mission_items: the mission has " + std::to_string(items.size()) + " mission items (" +
                                std::to_string(path.waypoints.size()) + " waypoints), more than " +
                                (options.max_mission_items
                                     ? std::string("max_mission_items ")
                                     : "the " + firmware_name(options.firmware_type) + " limit of ") +
                                std::to_string(*limit) + ": split it into sorties, or fly fewer waypoints");
  return items;
}

namespace detail {

/// [lon, lat, h] (GeoJSON position order) -> GeoPoint, validated.
inline GeoPoint json_position(const nlohmann::json& j, const char* format, const std::string& where) {
  if (!j.is_array() || j.size() != 3) export_parse_error(format, where + " must be [longitude, latitude, height]");
  const GeoPoint g{json_number(j[1], format, where + "[1]"), json_number(j[0], format, where + "[0]"),
                   json_number(j[2], format, where + "[2]")};
  if (!(std::isfinite(g.latitude_deg) && g.latitude_deg >= -90.0 && g.latitude_deg <= 90.0 &&
        std::isfinite(g.longitude_deg) && g.longitude_deg >= -180.0 && g.longitude_deg <= 180.0 &&
        std::isfinite(g.altitude_m)))
    export_parse_error(format, where + ": latitude must be in [-90, 90], longitude in [-180, 180], height finite");
  return g;
}

inline void require_exportable(const ExportPath& path, const char* who) {
  if (path.waypoints.empty()) throw std::invalid_argument(std::string(who) + ": the path has no waypoint");
}

/// Checks the position of an item in a global frame (latitude, longitude in range, finite
/// altitude); items without a position (other frames) are not checked.
inline void check_item_position(const MissionItem& item, const char* format, const std::string& where) {
  static constexpr int kGlobalFrames[] = {0, 3, 5, 6, 10, 11};
  bool global = false;
  for (int f : kGlobalFrames) global = global || item.frame == f;
  if (!global) return;
  const auto& p = item.params;
  if (!(std::isfinite(p[4]) && p[4] >= -90.0 && p[4] <= 90.0))
    export_parse_error(format, where + ": latitude must be in [-90, 90] (got " + std::to_string(p[4]) + ")");
  if (!(std::isfinite(p[5]) && p[5] >= -180.0 && p[5] <= 180.0))
    export_parse_error(format, where + ": longitude must be in [-180, 180] (got " + std::to_string(p[5]) + ")");
  if (!std::isfinite(p[6])) export_parse_error(format, where + ": altitude must be finite");
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
  using fence_json = nlohmann::ordered_json;
  fence_json polygons = fence_json::array();
  std::size_t fence_vertices = 0;
  for (std::size_t k = 0; k < path.geofence.size(); ++k) {
    const GeoFencePolygon& f = path.geofence[k];
    detail::require(f.vertices.size() >= 3,
                    "write_qgc_plan: geofence polygon " + std::to_string(k) + " needs at least 3 vertices; vertices",
                    f.vertices.size());
    fence_json ring = fence_json::array();
    for (const GeoPoint& v : f.vertices) {
      detail::require(std::isfinite(v.latitude_deg) && std::abs(v.latitude_deg) <= 90.0 &&
                          std::isfinite(v.longitude_deg) && std::abs(v.longitude_deg) <= 180.0,
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
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::string where = "mission.items[" + std::to_string(i) + "]";
    const nlohmann::json& j = items[i];
    const std::string& type = detail::json_string(detail::json_member(j, "type", kFmt, where), kFmt, where + ".type");
    if (type != "SimpleItem")
      detail::export_parse_error(kFmt, where + ": item type '" + type + "' is not supported (only SimpleItem)");
    MissionItem item;
    item.command = static_cast<int>(
        detail::json_integer(detail::json_member(j, "command", kFmt, where), 0, 65535, kFmt, where + ".command"));
    item.frame = static_cast<int>(
        detail::json_integer(detail::json_member(j, "frame", kFmt, where), 0, 255, kFmt, where + ".frame"));
    const nlohmann::json& ac = detail::json_member(j, "autoContinue", kFmt, where);
    if (!ac.is_boolean()) detail::export_parse_error(kFmt, where + ".autoContinue must be true or false");
    item.autocontinue = ac.get<bool>();
    const nlohmann::json& params = detail::json_member(j, "params", kFmt, where);
    if (!params.is_array() || params.size() != 7)
      detail::export_parse_error(kFmt, where + ".params must be an array of 7 numbers or nulls");
    for (std::size_t k = 0; k < 7; ++k)
      item.params[k] = params[k].is_null()
                           ? std::numeric_limits<double>::quiet_NaN()
                           : detail::json_number(params[k], kFmt, where + ".params[" + std::to_string(k) + "]");
    detail::check_item_position(item, kFmt, where);
    out.items.push_back(item);
  }
  if (plan.contains("geoFence")) {
    const nlohmann::json& fence = plan["geoFence"];
    if (!fence.is_object()) detail::export_parse_error(kFmt, "geoFence must be an object");
    if (fence.contains("polygons")) {
      const nlohmann::json& polygons = fence["polygons"];
      if (!polygons.is_array()) detail::export_parse_error(kFmt, "geoFence.polygons must be an array");
      for (std::size_t k = 0; k < polygons.size(); ++k) {
        const std::string where = "geoFence.polygons[" + std::to_string(k) + "]";
        const nlohmann::json& inclusion = detail::json_member(polygons[k], "inclusion", kFmt, where);
        if (!inclusion.is_boolean()) detail::export_parse_error(kFmt, where + ".inclusion must be true or false");
        const nlohmann::json& ring = detail::json_member(polygons[k], "polygon", kFmt, where);
        if (!ring.is_array() || ring.size() < 3)
          detail::export_parse_error(kFmt, where + ".polygon must be an array of at least 3 [latitude, longitude]");
        GeoFencePolygon f;
        f.inclusion = inclusion.get<bool>();
        for (std::size_t i = 0; i < ring.size(); ++i) {
          const std::string vwhere = where + ".polygon[" + std::to_string(i) + "]";
          if (!ring[i].is_array() || ring[i].size() != 2)
            detail::export_parse_error(kFmt, vwhere + " must be [latitude, longitude]");
          f.vertices.push_back(
              detail::json_position(nlohmann::json::array({ring[i][1], ring[i][0], 0.0}), kFmt, vwhere));
        }
        out.geofence.push_back(std::move(f));
      }
    }
  }
  return out;
}

/// The MAVLink plain-text waypoint file of `path` (mavlink.io, "File Formats: Mission
/// Plain-Text File Format"): the line `QGC WPL 110`, then one tab-separated line per item,
/// `seq current frame command p1 p2 p3 p4 lat lon alt autocontinue`; line 0 is the home
/// position (current 1, MAV_FRAME_GLOBAL, NAV_WAYPOINT). Numbers are written in the C locale
/// with the shortest text that reads back exactly; NaN as `nan`, as QGroundControl does.
/// @throws std::invalid_argument for an empty path or invalid options.
inline std::string write_wpl(const ExportPath& path, const ExportOptions& options = {}) {
  detail::require_exportable(path, "write_wpl");
  std::string out = "QGC WPL 110\n";
  const auto line = [&](std::size_t seq, bool current, const MissionItem& item) {
    out += std::to_string(seq) + '\t' + (current ? '1' : '0') + '\t' + std::to_string(item.frame) + '\t' +
           std::to_string(item.command);
    for (double p : item.params) out += '\t' + detail::format_number(p);
    out += item.autocontinue ? "\t1\n" : "\t0\n";
  };
  line(0, true,
       {mavlink::kCmdNavWaypoint,
        mavlink::kFrameGlobal,
        {0.0, 0.0, 0.0, 0.0, path.home.latitude_deg, path.home.longitude_deg, path.home.altitude_m},
        true});
  const std::vector<MissionItem> items = mission_items(path, options);
  for (std::size_t i = 0; i < items.size(); ++i) line(i + 1, false, items[i]);
  return out;
}

/// Reads a MAVLink plain-text waypoint file (`QGC WPL 110`): line 0 is the home position,
/// the rest the mission items. Fields may be separated by tabs or spaces; blank lines and a
/// final newline are allowed; `\r\n` line ends and a UTF-8 byte-order mark are accepted.
/// Safe on any input: every failure is an exception.
/// @throws std::invalid_argument naming the line (1-based, the header is line 1) and field:
///         a wrong header, a line without 12 fields, a field that is not a number of the
///         right kind, a sequence number out of order, a position out of range, no home line.
inline MissionFile read_wpl(std::string_view text) {
  constexpr const char* kFmt = "WPL";
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  MissionFile out;
  bool header = false, home = false;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    const std::string at = "line " + std::to_string(line_no);
    // Split on runs of tabs, spaces and a trailing '\r'.
    std::vector<std::string_view> fields;
    std::size_t i = 0;
    const auto is_space = [](char c) { return c == '\t' || c == ' ' || c == '\r'; };
    while (i < line.size()) {
      while (i < line.size() && is_space(line[i])) ++i;
      const std::size_t start = i;
      while (i < line.size() && !is_space(line[i])) ++i;
      if (i > start) fields.push_back(line.substr(start, i - start));
    }
    if (!header) {
      if (fields.size() != 3 || fields[0] != "QGC" || fields[1] != "WPL" || fields[2] != "110")
        detail::export_parse_error(kFmt, at + ": the first line must be 'QGC WPL 110'");
      header = true;
      continue;
    }
    if (fields.empty()) continue;
    if (fields.size() != 12)
      detail::export_parse_error(kFmt, at +
                                           ": want 12 fields (seq current frame command p1..p4 lat lon alt "
                                           "autocontinue), got " +
                                           std::to_string(fields.size()));
    long long ints[4];
    static constexpr const char* kIntNames[] = {"seq", "current", "frame", "command"};
    static constexpr long long kIntMax[] = {65535, 1, 255, 65535};
    for (int k = 0; k < 4; ++k)
      if (const auto v = detail::parse_integer(fields[static_cast<std::size_t>(k)], 0, kIntMax[k]))
        ints[k] = *v;
      else
        detail::export_parse_error(kFmt, at + ": " + kIntNames[k] + " must be an integer in 0.." +
                                             std::to_string(kIntMax[k]) + " (got '" +
                                             std::string(fields[static_cast<std::size_t>(k)]) + "')");
    const std::size_t want_seq = home ? out.items.size() + 1 : 0;
    if (static_cast<std::size_t>(ints[0]) != want_seq)
      detail::export_parse_error(
          kFmt, at + ": seq " + std::to_string(ints[0]) + " out of order (want " + std::to_string(want_seq) + ")");
    MissionItem item;
    item.frame = static_cast<int>(ints[2]);
    item.command = static_cast<int>(ints[3]);
    for (std::size_t k = 0; k < 7; ++k)
      if (!detail::wpl_parse(fields[4 + k], item.params[k]))
        detail::export_parse_error(kFmt, at + ": field " + std::to_string(5 + k) + " (param" + std::to_string(k + 1) +
                                             ") is not a number: '" + std::string(fields[4 + k]) + "'");
    if (fields[11] != "0" && fields[11] != "1")
      detail::export_parse_error(kFmt, at + ": autocontinue must be 0 or 1 (got '" + std::string(fields[11]) + "')");
    item.autocontinue = fields[11] == "1";
    detail::check_item_position(item, kFmt, at);
    if (!home) {
      if (!std::isfinite(item.params[4]) || !std::isfinite(item.params[5]) || !std::isfinite(item.params[6]))
        detail::export_parse_error(kFmt,
                                   at + ": the home position must have a finite latitude, longitude and altitude");
      out.home = {item.params[4], item.params[5], item.params[6]};
      home = true;
    } else {
      out.items.push_back(item);
    }
  }
  if (!header) detail::export_parse_error(kFmt, "empty file (want 'QGC WPL 110' and a home line)");
  if (!home) detail::export_parse_error(kFmt, "no home line (seq 0) after the header");
  return out;
}

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
      const nlohmann::json& props = detail::json_member(f, "properties", kFmt, where);
      const std::string pwhere = where + ".properties";
      const long long index = detail::json_integer(detail::json_member(props, "index", kFmt, pwhere), 0,
                                                   std::numeric_limits<int>::max(), kFmt, pwhere + ".index");
      ExportWaypoint w;
      w.latitude_deg = g.latitude_deg;
      w.longitude_deg = g.longitude_deg;
      w.level = static_cast<int>(detail::json_integer(detail::json_member(props, "level", kFmt, pwhere), 0,
                                                      std::numeric_limits<int>::max(), kFmt, pwhere + ".level"));
      w.gsd_cm = detail::json_number(detail::json_member(props, "gsd_cm", kFmt, pwhere), kFmt, pwhere + ".gsd_cm");
      w.relative_altitude_m = detail::json_number(detail::json_member(props, "relative_altitude_m", kFmt, pwhere), kFmt,
                                                  pwhere + ".relative_altitude_m");
      w.via = props.contains("role") && props["role"] == "via";
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

/// The file of `path` in `format` (write_qgc_plan, write_wpl or write_geojson).
/// @throws std::invalid_argument for an empty path or invalid options.
inline std::string write_mission(ExportFormat format, const ExportPath& path, const ExportOptions& options = {}) {
  switch (format) {
    case ExportFormat::qgc_plan: return write_qgc_plan(path, options);
    case ExportFormat::wpl: return write_wpl(path, options);
    case ExportFormat::geojson: return write_geojson(path);
  }
  throw std::invalid_argument("write_mission: invalid ExportFormat");
}

}  // namespace adaptseg
