// adaptseg_plan: the survey plan of a site nobody has labelled: the area as a polygon (GeoJSON, KML,
// any vector file GDAL reads) or an orthomosaic without labels, a camera and a GSD in, mission
// files out, the lawnmower laid centred on the area so that no waypoint lies outside it.
//
//   adaptseg_plan --area site.geojson --gsd 15 --export plan,wpl,geojson --out out/site
//   adaptseg_plan --area ortho.tif --gsd 15 --altitude-m 512 --overlap 0.2 --out out/site
//
// Writes OUT/mission.{plan,waypoints,geojson} (as adaptseg_mission --export: take-off, the
// modelled speed, a hold and one image at every waypoint, return to launch; relative altitudes),
// OUT/site.png (the area, the footprints and the path in the site frame) and OUT/plan.json (the
// site frame, the waypoints, the flight time: the timing model between waypoints and the holds,
// without the take-off and the return). Needs GDAL.

#include "common/cli.hpp"
#include "common/export.hpp"

#include <adaptseg/gdal/survey_site.hpp>
#include <adaptseg/vision/visualization.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  CLI::App app{"Plan the survey of a site that has no labels: an area polygon or an orthomosaic in, mission files out.",
               "adaptseg_plan"};
  fs::path area_file, out_dir;
  double gsd_cm = 0.0, map_gsd_cm = 10.0, altitude_m = 0.0;
  std::string overlap_text;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::ExportCli exports;
  exports.formats = {"plan", "wpl", "geojson"};
  app.add_option("--area", area_file,
                 "the site: a polygon file (GeoJSON, KML, ...: its first layer's polygons) or an orthomosaic "
                 "without labels (its pixels with data)")
      ->required();
  app.add_option("--gsd", gsd_cm, "GSD of the survey [cm/px]")->required();
  app.add_option("--map-gsd-cm", map_gsd_cm, "resolution of the site's mask [cm/px]")->capture_default_str();
  app.add_option("--altitude-m", altitude_m,
                 "height of the take-off point above the WGS84 ellipsoid [m] (the home altitude of the files)")
      ->capture_default_str();
  app.add_option("--overlap", overlap_text, "OVERLAP or ALONG,ACROSS: image overlap, fractions in [0, 0.9]");
  app.add_option("--out", out_dir, "output directory")->required();
  common.add_to(app);
  exports.add_to(app);
  // The site file is the geo-reference; nothing is segmented, and no class is of interest.
  for (const char* unused : {"--geo-origin", "--seg-time-s", "--plan-time-s", "--interest"})
    app.remove_option(app.get_option(unused));
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  try {
    if (!(std::isfinite(gsd_cm) && gsd_cm > 0.0))
      throw std::invalid_argument("--gsd must be a finite positive GSD in cm/px, got " + adaptseg::examples::fmt(gsd_cm, 3));
    if (!(std::isfinite(map_gsd_cm) && map_gsd_cm > 0.0))
      throw std::invalid_argument("--map-gsd-cm must be a finite positive GSD in cm/px, got " +
                                  adaptseg::examples::fmt(map_gsd_cm, 3));
    if (!std::isfinite(altitude_m)) throw std::invalid_argument("--altitude-m must be finite");
    const adaptseg::LawnmowerOverlap overlap =
        overlap_text.empty() ? adaptseg::LawnmowerOverlap{} : adaptseg::examples::parse_overlap(overlap_text);
    const adaptseg::CameraModel camera(common.mission.camera);
    const adaptseg::TimingModel timing(common.mission.timing);
    exports.check_altitude(gsd_cm, common.mission.camera);
    const adaptseg::SurveySite site = adaptseg::load_survey_site(area_file, map_gsd_cm, altitude_m);
    const std::vector<adaptseg::Waypoint> plan = adaptseg::plan_site_survey(site, camera, gsd_cm, overlap);
    if (plan.empty()) throw std::invalid_argument("no footprint covers the area");
    const adaptseg::GeoReference geo(site.geo);
    fs::create_directories(out_dir);
    exports.write(adaptseg::make_export_path(plan, std::vector<int>(plan.size(), 0), geo, site.name), common.mission.timing.max_speed_mps, out_dir);
    // Between waypoints as the timing model flies them, and the hold at each (the take-off and the
    // return depend on where the UAV starts: not counted).
    double flight_s = exports.file_options.hold_s * static_cast<double>(plan.size());
    for (std::size_t k = 1; k < plan.size(); ++k) flight_s += timing.segment_time_s(plan[k - 1].position, plan[k].position);
    nlohmann::json j;
    j["area"] = area_file.string();
    j["gsd_cm"] = gsd_cm;
    j["altitude_m"] = camera.altitude_m(gsd_cm);
    j["images"] = plan.size();
    j["flight_s"] = flight_s;
    j["site_frame"] = {{"latitude_deg", site.geo.latitude_deg},   {"longitude_deg", site.geo.longitude_deg},
                       {"altitude_m", site.geo.altitude_m},       {"heading_deg", site.geo.heading_deg},
                       {"anchor_x_m", site.geo.anchor_x_m},       {"anchor_y_m", site.geo.anchor_y_m},
                       {"width_m", site.area.area.width_m()},    {"height_m", site.area.area.height_m()}};
    nlohmann::json wps = nlohmann::json::array();
    for (const auto& w : plan) {
      const adaptseg::GeoPoint g = geo.to_wgs84(w.position);
      wps.push_back({{"x", w.position.x()}, {"y", w.position.y()}, {"z", w.position.z()},
                     {"latitude_deg", g.latitude_deg}, {"longitude_deg", g.longitude_deg}});
    }
    j["waypoints"] = wps;
    const adaptseg::FieldGeo origin = site.origin_geo();
    j["geo"] = {{"latitude_deg", origin.latitude_deg},
                {"longitude_deg", origin.longitude_deg},
                {"altitude_m", origin.altitude_m},
                {"heading_deg", origin.heading_deg}};
    adaptseg::examples::write_text(out_dir / "plan.json", j.dump(2) + "\n");
    adaptseg::examples::write_png(out_dir / "site.png", adaptseg::render_site_plan(site.area.valid_mask, site.area.map_gsd_cm, plan,
                                                                                site.name + ": " + std::to_string(plan.size()) +
                                                                                    " images at " +
                                                                                    adaptseg::examples::fmt(gsd_cm, 1) +
                                                                                    " cm/px"));
    std::printf("%s: %zu images at %.1f cm/px (%.1f m above home), flight %.0f s; site %.0f x %.0f m, +x at bearing "
                "%.1f deg -> %s\n",
                site.name.c_str(), plan.size(), gsd_cm, camera.altitude_m(gsd_cm), flight_s, site.area.area.width_m(),
                site.area.area.height_m(), site.geo.heading_deg, out_dir.string().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_plan: error: %s\n", e.what());
    return 2;
  }
}
