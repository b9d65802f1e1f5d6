#pragma once
// The folder of posed images adaptseg_live flies over (docs/data_format.md, "The live image
// folder"): area.yaml, poses.csv, rgb/ and labels/. Written by --record-from, read by the loop.
// Not part of the library.

#include "common/cli.hpp"

#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>
#ifdef ADAPTSEG_HAVE_GDAL
#include <adaptseg/gdal/gdal_io.hpp>
#endif

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace adaptseg::examples {

/// One image of the folder and the pose it was taken at, in the area's frame.
struct PosedImage {
  std::string file;
  Eigen::Vector3d pose;
  double yaw_deg = 0.0;  ///< counter-clockwise from the frame's +x axis to the image's x axis
};

/// What area.yaml says: the ground to cover, its classes, the camera of the images, and where
/// the area's frame lies on the Earth (optional).
struct ImageSetInfo {
  std::string name;
  SurveyArea area;  ///< area_m and valid_mask; empty area when area.yaml leaves them to --area
  std::vector<ClassInfo> classes;
  std::vector<std::string> interest;
  CameraParams camera;
  std::optional<FieldGeo> geo;  ///< `geo:` of area.yaml (or the --area site's frame)
  std::string crs;              ///< `crs:` of area.yaml: the projected CRS of easting/northing poses
};

/// What area.yaml would say of `field` flown with `model`: its area, classes and geo-reference,
/// the model's labels of interest and camera (--simulate-camera's area).
inline ImageSetInfo image_set_info_of(const Field& field, const DecisionModel& model) {
  ImageSetInfo info;
  info.name = field.name();
  info.area = SurveyArea::of(field);
  info.classes = field.classes();
  info.interest = model.interest;
  info.camera = model.camera;
  info.geo = field.geo();
  return info;
}

/// The three forms of poses.csv's header (the optional last column in brackets).
inline constexpr const char* kPoseHeaders =
    "file,x,y,z[,yaw_deg] (the area's frame [m]), file,latitude_deg,longitude_deg,relative_altitude_m"
    "[,heading_deg] (WGS84; needs geo: in area.yaml or --area) or file,easting_m,northing_m,"
    "relative_altitude_m[,heading_deg] (area.yaml's crs:; needs GDAL)";

namespace detail_image_set {

[[noreturn]] inline void fail(const std::filesystem::path& file, const std::string& what) {
  throw std::invalid_argument(file.string() + ": " + what);
}

/// (-180, 180]
inline double wrap_deg(double a) {
  a = std::remainder(a, 360.0);
  return a == -180.0 ? 180.0 : a;
}

}  // namespace detail_image_set

/// Writes the folder for `waypoints` over `field` (simulated captures), poses in the frame's
/// metres (`gnss` false) or as a GNSS receiver gives them (`gnss`: WGS84 and the compass heading
/// of the image's top; needs the field's geo-reference).
inline void write_image_set(const std::filesystem::path& dir, const Field& field, const DecisionModel& model,
                            const std::vector<Waypoint>& waypoints, double yaw_deg, bool gnss) {
  if (gnss && !field.geo())
    throw std::invalid_argument(
        "--record-gnss needs the field's geo-reference (a geo: section, --geo-origin or a "
        "GeoTIFF field)");
  std::filesystem::create_directories(dir / "labels");
  if (field.has_image()) std::filesystem::create_directories(dir / "rgb");
  write_png(dir / "valid_mask.png", field.valid_mask());
  YAML::Emitter e;
  e.SetDoublePrecision(15);
  e << YAML::BeginMap << YAML::Key << "format" << YAML::Value << "adaptseg.image_set/1";
  e << YAML::Key << "name" << YAML::Value << field.name();
  const Area a = field.area();
  e << YAML::Key << "area_m" << YAML::Value << YAML::Flow
    << std::vector<double>{a.x_min_m, a.y_min_m, a.x_max_m, a.y_max_m};
  e << YAML::Key << "map_gsd_cm" << YAML::Value << field.gsd_cm();
  e << YAML::Key << "valid_mask" << YAML::Value << "valid_mask.png";
  e << YAML::Key << "ignore_label" << YAML::Value << field.ignore_label();
  e << YAML::Key << "classes" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : field.classes())
    e << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << c.name << YAML::Key << "color"
      << YAML::Value << YAML::Flow << std::vector<int>{c.color_rgb[0], c.color_rgb[1], c.color_rgb[2]} << YAML::EndMap;
  e << YAML::EndSeq;
  e << YAML::Key << "interest" << YAML::Value << YAML::Flow << model.interest;
  e << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "image_width_px"
    << YAML::Value << model.camera.image_width_px << YAML::Key << "image_height_px" << YAML::Value
    << model.camera.image_height_px << YAML::Key << "sensor_width_mm" << YAML::Value << model.camera.sensor_width_mm
    << YAML::Key << "focal_length_mm" << YAML::Value << model.camera.focal_length_mm << YAML::EndMap;
  if (field.geo()) {
    const FieldGeo& g = *field.geo();
    e << YAML::Key << "geo" << YAML::Value << YAML::BeginMap << YAML::Key << "latitude_deg" << YAML::Value
      << g.latitude_deg << YAML::Key << "longitude_deg" << YAML::Value << g.longitude_deg << YAML::Key << "altitude_m"
      << YAML::Value << g.altitude_m << YAML::Key << "heading_deg" << YAML::Value << g.heading_deg << YAML::Key
      << "anchor_x_m" << YAML::Value << g.anchor_x_m << YAML::Key << "anchor_y_m" << YAML::Value << g.anchor_y_m
      << YAML::Key << "scale" << YAML::Value << g.scale << YAML::EndMap;
  }
  e << YAML::EndMap;
  write_text(dir / "area.yaml", std::string(e.c_str()) + "\n");

  const SimulatedSensor sensor(field, CameraModel(model.camera));
  std::optional<GeoReference> geo;
  if (gnss) geo.emplace(*field.geo());
  std::ostringstream csv;
  csv << (gnss ? "file,latitude_deg,longitude_deg,relative_altitude_m,heading_deg\n" : "file,x,y,z,yaw_deg\n");
  char buf[200];
  for (std::size_t k = 0; k < waypoints.size(); ++k) {
    const Image img = sensor.capture(waypoints[k], yaw_deg);
    std::snprintf(buf, sizeof buf, "%05zu.png", k);
    const std::string file = buf;
    write_png(dir / "labels" / file, img.ground_truth);
    if (!img.bgr.empty()) write_png(dir / "rgb" / file, img.bgr);
    const Eigen::Vector3d& p = waypoints[k].position;
    if (gnss) {
      // The GNSS fix of the camera and the compass bearing of the image's top (the frame's
      // +y turned by the yaw): what a UAV logs with each image.
      const GeoPoint g = geo->to_wgs84(p);
      const double heading = detail_image_set::wrap_deg(field.geo()->heading_deg - 90.0 - yaw_deg);
      std::snprintf(buf, sizeof buf, "%s,%.10f,%.10f,%.4f,%.9g\n", file.c_str(), g.latitude_deg, g.longitude_deg,
                    g.altitude_m - field.geo()->altitude_m, heading < 0.0 ? heading + 360.0 : heading);
    } else {
      std::snprintf(buf, sizeof buf, "%s,%.9f,%.9f,%.9f,%.9g\n", file.c_str(), p.x(), p.y(), p.z(), yaw_deg);
    }
    csv << buf;
  }
  write_text(dir / "poses.csv", csv.str());
}

/// Reads area.yaml; `area_from_elsewhere`: the area (area_m, valid_mask, map_gsd_cm) comes from
/// --area, so area.yaml may leave it out.
inline ImageSetInfo read_image_set_info(const std::filesystem::path& dir, bool area_from_elsewhere = false) {
  const std::filesystem::path file = dir / "area.yaml";
  if (!std::filesystem::is_regular_file(file))
    detail_image_set::fail(file,
                           "not found (is --images a folder written by --record-from? docs/data_format.md, "
                           "\"The live image folder\")");
  namespace d = adaptseg::detail;
  const d::YamlReader r(
      d::yaml_mapping(file.string(), "an image set description", [&] { return YAML::LoadFile(file.string()); }),
      file.string());
  r.only_keys({"format", "name", "area_m", "map_gsd_cm", "valid_mask", "ignore_label", "classes", "interest", "camera",
               "geo", "crs"});
  if (!r.has("format") || r.text("format") != "adaptseg.image_set/1")
    detail_image_set::fail(file, "format must be adaptseg.image_set/1");
  ImageSetInfo info;
  info.name = r.has("name") ? r.text("name") : dir.filename().string();
  if (r.has("area_m")) {
    const auto a = r.numbers("area_m");
    if (a.size() != 4) detail_image_set::fail(file, "area_m must be [x_min, y_min, x_max, y_max]");
    info.area.area = {a[0], a[1], a[2], a[3]};
  } else if (!area_from_elsewhere) {
    detail_image_set::fail(file, "missing key 'area_m' (or give the area as --area FILE)");
  }
  if (r.has("map_gsd_cm"))
    info.area.map_gsd_cm = r.number("map_gsd_cm");
  else if (!area_from_elsewhere)
    detail_image_set::fail(file, "missing key 'map_gsd_cm'");
  info.area.ignore_label = r.has("ignore_label") ? static_cast<int>(r.integer("ignore_label", 0, 255)) : 255;
  if (r.has("valid_mask") && !area_from_elsewhere) {
    const std::filesystem::path mask = dir / r.text("valid_mask");
    info.area.valid_mask = cv::imread(mask.string(), cv::IMREAD_UNCHANGED);
    if (info.area.valid_mask.empty() || info.area.valid_mask.type() != CV_8UC1)
      detail_image_set::fail(mask, "cannot read an 8-bit single-channel mask");
  }
  info.classes = d::field_read_classes(r);
  info.area.num_classes = static_cast<int>(info.classes.size());
  info.interest = r.texts("interest");
  const d::YamlReader cam = r.map("camera");
  cam.only_keys({"image_width_px", "image_height_px", "sensor_width_mm", "focal_length_mm"});
  info.camera = {static_cast<int>(cam.integer("image_width_px", 1, 1000000)),
                 static_cast<int>(cam.integer("image_height_px", 1, 1000000)), cam.number("sensor_width_mm"),
                 cam.number("focal_length_mm")};
  if (r.has("geo")) info.geo = d::field_read_geo(r.map("geo"), /*anchored=*/true);
  if (r.has("crs")) info.crs = r.text("crs");
  return info;
}

/// Reads poses.csv in any of its three forms (kPoseHeaders) into the area's frame: GNSS poses
/// through `info.geo` (WGS84: GeographicLib's tangent plane, exact), the heading of the image's
/// top turned into the frame's yaw (the frame's bearing at its anchor: off by the meridians'
/// convergence, 0.004 deg per km east-west at 30 deg latitude).
/// `frame_allowed` false (the area from --area, whose frame area.yaml's poses cannot know): only
/// GNSS forms.
inline std::vector<PosedImage> read_poses(const std::filesystem::path& dir, const ImageSetInfo& info,
                                          bool frame_allowed = true) {
  const std::filesystem::path file = dir / "poses.csv";
  std::ifstream is(file);
  if (!is) detail_image_set::fail(file, "not found");
  std::string line;
  std::getline(is, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  enum class Form { frame, wgs84, projected } form{};
  if (line.rfind("file,x,y,z", 0) == 0)
    form = Form::frame;
  else if (line.rfind("file,latitude_deg,longitude_deg,relative_altitude_m", 0) == 0)
    form = Form::wgs84;
  else if (line.rfind("file,easting_m,northing_m,relative_altitude_m", 0) == 0)
    form = Form::projected;
  else
    detail_image_set::fail(file, std::string("the header must be one of ") + kPoseHeaders);
  if (form == Form::frame && !frame_allowed)
    detail_image_set::fail(file,
                           "with --area the poses must be GNSS poses (file,latitude_deg,longitude_deg,"
                           "relative_altitude_m[,heading_deg] or easting/northing): frame metres belong to "
                           "area.yaml's frame, not the site's");
  std::optional<GeoReference> geo;
  if (form != Form::frame) {
    if (!info.geo)
      detail_image_set::fail(file, "GNSS poses need the area's geo-reference: a geo: section in area.yaml, or --area");
    geo.emplace(*info.geo);
  }
#ifdef ADAPTSEG_HAVE_GDAL
  std::optional<gdal::detail::CrsToWgs84> to_wgs84;
#endif
  if (form == Form::projected) {
#ifdef ADAPTSEG_HAVE_GDAL
    if (info.crs.empty())
      detail_image_set::fail(file, "easting/northing poses need crs: in area.yaml (e.g. EPSG:32640)");
    gdal::detail::register_drivers();
    OGRSpatialReference srs;
    if (srs.SetFromUserInput(info.crs.c_str()) != OGRERR_NONE)
      detail_image_set::fail(dir / "area.yaml", "crs: '" + info.crs + "' is not a CRS GDAL knows");
    char* wkt = nullptr;
    srs.exportToWkt(&wkt);
    const std::string text = wkt ? wkt : "";
    CPLFree(wkt);
    to_wgs84.emplace(text, dir / "area.yaml");
#else
    detail_image_set::fail(file, "easting/northing poses need a build with GDAL (libgdal-dev)");
#endif
  }
  std::vector<PosedImage> out;
  for (int n = 2; std::getline(is, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::istringstream row(line);
    PosedImage p;
    std::string cell[5];
    int cells = 0;
    while (cells < 5 && std::getline(row, cell[cells], ',')) ++cells;
    try {
      if (cells < 4) throw std::invalid_argument("");
      p.file = cell[0];
      const double a = std::stod(cell[1]), b = std::stod(cell[2]), c = std::stod(cell[3]);
      const double angle = cells == 5 ? std::stod(cell[4]) : std::numeric_limits<double>::quiet_NaN();
      if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c) || (cells == 5 && !std::isfinite(angle)))
        throw std::invalid_argument("");
      if (form == Form::frame) {
        p.pose = {a, b, c};
        p.yaw_deg = cells == 5 ? angle : 0.0;
      } else {
        GeoPoint g{a, b, info.geo->altitude_m + c};
#ifdef ADAPTSEG_HAVE_GDAL
        if (form == Form::projected) std::tie(g.latitude_deg, g.longitude_deg) = (*to_wgs84)(a, b);
#endif
        if (!(std::abs(g.latitude_deg) <= 90.0 && std::abs(g.longitude_deg) <= 180.0)) throw std::invalid_argument("");
        p.pose = geo->to_field(g);
        // Without a heading, the image is taken with its top along the frame's +y (yaw 0).
        p.yaw_deg = cells == 5 ? detail_image_set::wrap_deg(info.geo->heading_deg - 90.0 - angle) : 0.0;
      }
    } catch (const std::exception&) {
      detail_image_set::fail(
          file, "line " + std::to_string(n) + " is not " +
                    (form == Form::frame   ? "file,x,y,z[,yaw_deg]"
                     : form == Form::wgs84 ? "file,latitude_deg,longitude_deg,relative_altitude_m[,heading_deg]"
                                           : "file,easting_m,northing_m,relative_altitude_m[,heading_deg]") +
                    " (finite numbers): '" + line + "'");
    }
    out.push_back(p);
  }
  if (out.empty()) detail_image_set::fail(file, "no images");
  return out;
}

/// The recorded image nearest `position`, if within `tolerance_m`; otherwise the error a UAV
/// would give: no image at that waypoint.
inline const PosedImage& find_image(const std::vector<PosedImage>& images, const Eigen::Vector3d& position,
                                    double tolerance_m) {
  const PosedImage* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& p : images) {
    const double d = (p.pose - position).norm();
    if (d < best_d) best = &p, best_d = d;
  }
  if (best_d > tolerance_m) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "no image recorded at waypoint (%.3f, %.3f, %.3f) m: the nearest, %s, is %.3f m away "
                  "(--pose-tolerance-m %.3f)",
                  position.x(), position.y(), position.z(), best->file.c_str(), best_d, tolerance_m);
    throw std::invalid_argument(buf);
  }
  return *best;
}

}  // namespace adaptseg::examples
