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
///
/// This header holds the formats by name and write_mission(); the path and its items are in
/// export_path.hpp, each format in its own header (qgc_plan.hpp, wpl.hpp, geojson.hpp), all
/// included here.

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/geo/export_path.hpp>
#include <adaptseg/geo/geojson.hpp>
#include <adaptseg/geo/qgc_plan.hpp>
#include <adaptseg/geo/wpl.hpp>

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg {

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
