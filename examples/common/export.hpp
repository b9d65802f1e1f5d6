#pragma once
// `--export FORMAT` of adaptseg_mission: the geo-reference of the flown field (field.yaml's
// `geo:` section or --geo-origin) and the mission files of the flown path. Not part of the
// library; the formats are adaptseg/geo/mission_export.hpp's.

#include "strategies.hpp"

#include <adaptseg/geo/mission_export.hpp>

#include <CLI/CLI.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// The export options and what they need of the field.
struct ExportCli {
  std::vector<std::string> formats;
  std::string geo_origin;
  ExportOptions file_options;

  void add_to(CLI::App& app) {
    app.add_option("--export", formats,
                   "write the flown path as OUT/mission.plan (plan: QGroundControl), OUT/mission.waypoints "
                   "(wpl: QGC WPL 110), OUT/mission.geojson (geojson); repeat or comma-separate; needs a "
                   "geo-reference")
        ->delimiter(',')
        ->check(CLI::IsMember(detail::names_of(kExportFormats)));
    app.add_option("--geo-origin", geo_origin,
                   "LAT,LON,ALT,HEADING: WGS84 position [deg] and ellipsoidal height [m] of the field "
                   "directory's frame origin, and the compass bearing [deg] of its +x axis; replaces "
                   "field.yaml's geo section");
    app.add_option("--hold-s", file_options.hold_s, "hold time at every exported waypoint [s]")->capture_default_str();
    app.add_option("--max-altitude-m", file_options.max_altitude_m,
                   "the highest an exported waypoint may fly above home [m] (the usual legal ceiling); a mission "
                   "that would fly higher is refused before it flies, with the GSD it may fly at")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--firmware", file_options.firmware_type,
                   "the autopilot of the exported .plan: px4 (default) or ardupilot")
        ->transform(CLI::CheckedTransformer(
            std::map<std::string, int>{{"px4", mavlink::kAutopilotPx4}, {"ardupilot", mavlink::kAutopilotArduPilot}}));
    app.add_flag("!--no-takeoff", file_options.takeoff,
                 "begin the exported mission without a take-off, for a UAV already airborne (default: a "
                 "take-off at home to the first waypoint's altitude)");
    app.add_option("--mission-end", file_options.end,
                   "after the last exported waypoint: rtl (return to launch, default), land (at home) or none")
        ->transform(CLI::CheckedTransformer(std::map<std::string, MissionEnd>{
            {"rtl", MissionEnd::return_to_launch}, {"land", MissionEnd::land}, {"none", MissionEnd::none}}));
    app.add_option_function<CameraTrigger>(
           "--camera-trigger", [this](const CameraTrigger& t) { file_options.camera_trigger = t; },
           "the item after every exported waypoint that takes its image: capture (IMAGE_START_CAPTURE, as "
           "QGroundControl writes it) or digicam (DO_DIGICAM_CONTROL, as Mission Planner writes it); default: "
           "the firmware's own, capture for px4 and digicam for ardupilot")
        ->transform(CLI::CheckedTransformer(std::map<std::string, CameraTrigger>{
            {"capture", CameraTrigger::image_start_capture}, {"digicam", CameraTrigger::digicam_control}}));
    app.add_option_function<std::size_t>(
           "--max-mission-items", [this](const std::size_t& n) { file_options.max_mission_items = n; },
           "the most mission items an exported file may hold (default: the firmware's, px4 500, ardupilot 717; "
           "raise it for an autopilot configured for more)")
        ->check(CLI::PositiveNumber);
  }

  /// --geo-origin as a FieldGeo, if given.
  /// @throws std::invalid_argument for a malformed or out-of-range value.
  [[nodiscard]] std::optional<FieldGeo> geo_override() const {
    if (geo_origin.empty()) return std::nullopt;
    const auto v = parse_four_numbers(geo_origin, "--geo-origin LAT,LON,ALT,HEADING");
    const FieldGeo g{v[0], v[1], v[2], v[3]};
    detail::validate_field_geo(g, "--geo-origin");
    return g;
  }

  /// Loads the field of `spec` with --geo-origin applied; when exporting, checks before the
  /// mission flies that the field has a geo-reference.
  /// @throws std::invalid_argument for a bad field, a bad --geo-origin, or none at all.
  [[nodiscard]] Field load_field(const std::string& spec) const {
    Field field = load_field_spec(spec, geo_override());
    if (!formats.empty() && !field.geo())
      throw std::invalid_argument("--export needs a geo-reference: field '" + field.name() +
                                  "' has no 'geo:' section in field.yaml; pass --geo-origin LAT,LON,ALT,HEADING");
    file_options.validate();
    return field;
  }

  /// Throws, before a mission flies, if exporting it (or, `always`, flying it: adaptseg_live
  /// --mavlink) would fly above --max-altitude-m: the highest waypoint of a mission is its top
  /// level's (or a lawnmower's) at `gsd_cm` with `camera`; the message names the coarsest GSD
  /// that stays below the ceiling.
  /// @throws std::invalid_argument naming the altitude, the ceiling and that GSD.
  void check_altitude(double gsd_cm, const CameraParams& camera, bool always = false) const {
    if (formats.empty() && !always) return;
    const CameraModel model(camera);
    const double altitude = model.altitude_m(gsd_cm);
    if (altitude <= file_options.max_altitude_m) return;
    throw std::invalid_argument("the mission would fly " + fmt(altitude, 1) + " m above home at " + fmt(gsd_cm, 2) +
                                " cm/px, above --max-altitude-m " + fmt(file_options.max_altitude_m, 1) +
                                ": with this camera fly at most " + fmt(model.gsd_cm(file_options.max_altitude_m), 2) +
                                " cm/px, or raise the ceiling where the law allows");
  }

  /// Writes one file per requested format into `out_dir`; hover speed (and the speed item) from
  /// the mission's timing.
  void write(const Field& field, const MissionResult& result, const MissionOptions& options,
             const std::filesystem::path& out_dir) const {
    if (formats.empty()) return;  // before GeoReference, which needs a geo-reference
    write(make_export_path(result, GeoReference(field)), options.timing.max_speed_mps, out_dir);
  }

  /// Writes `path` in every requested format into `out_dir`, flown at `speed_mps`.
  void write(const ExportPath& path, double speed_mps, const std::filesystem::path& out_dir) const {
    for (const auto& [name, text] : files(path, speed_mps, "mission")) write_text(out_dir / name, text);
  }

  /// The files of `path` in every requested format, `stem` with each format's extension, flown at
  /// `speed_mps`: (file name, text), made before any is written so that a refused mission
  /// (too many items, a fence too large) writes nothing.
  [[nodiscard]] std::vector<std::pair<std::string, std::string>> files(const ExportPath& path, double speed_mps,
                                                                       const std::string& stem) const {
    std::vector<std::pair<std::string, std::string>> out;
    ExportOptions opt = file_options;
    opt.hover_speed_mps = speed_mps;
    for (const std::string& name : std::set<std::string>(formats.begin(), formats.end())) {
      const ExportFormat format = parse_export_format(name);
      out.emplace_back(export_file_name(format, stem), write_mission(format, path, opt));
    }
    return out;
  }
};

}  // namespace adaptseg::examples
