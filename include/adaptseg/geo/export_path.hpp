#pragma once
/// @file
/// A planned or flown path in WGS84, ready to export (`ExportPath`, make_export_path()), and the
/// MAVLink mission items an autopilot flies it by (mission_items(): take-off, a waypoint and one
/// camera trigger per image, return to launch), with the firmware's limits and the export's
/// settings (`ExportOptions`). The files that carry them: qgc_plan.hpp, wpl.hpp, geojson.hpp;
/// all three, and write_mission(), through mission_export.hpp. CMake target adaptseg::geo.

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/geo/detail/export_text.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/vision/mission.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
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

}  // namespace adaptseg
