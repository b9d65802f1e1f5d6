// adaptseg_plan: the survey plan of a site nobody has labelled: the area as a polygon (GeoJSON, KML,
// any vector file GDAL reads) or an orthomosaic without labels, a camera and a GSD in, mission
// files out: every waypoint inside the site, the site as the geofence, from a take-off point on
// the site, above a minimum height, over the terrain of a DEM, in sorties that fit a battery.
//
//   adaptseg_plan --area site.geojson --gsd 15 --home 25.2003,55.3004 --out out/site
//   adaptseg_plan --area site.geojson --gsd 10 --dem dem.tif --max-flight-min 15 --firmware ardupilot --out out/site
//
// Writes OUT/mission.{plan,waypoints,geojson} (OUT/mission-1.*, mission-2.*, ... with several
// sorties; as adaptseg_mission --export: take-off, the modelled speed, a hold and one image at
// every waypoint, return to launch; relative altitudes; the .plan with the site as its geofence),
// OUT/site.png (the site, footprints, path, home, a north arrow and a scale bar) and OUT/plan.json.
// Prints where the site is, its area, the flight time and the coverage; warnings on stderr. The
// plan is the library's (adaptseg::plan_site, <adaptseg/gdal/site_plan.hpp>). Needs GDAL.

#include "common/cli.hpp"
#include "common/export.hpp"

#include <adaptseg/gdal/elevation_model.hpp>
#include <adaptseg/gdal/site_picture.hpp>
#include <adaptseg/gdal/site_plan.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <locale>
#include <sstream>

namespace {

/// "LAT,LON" -> GeoPoint.
adaptseg::GeoPoint parse_home(const std::string& text) {
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  adaptseg::GeoPoint g;
  char comma = 0;
  const bool ok =
      (is >> g.latitude_deg) && (is >> comma) && comma == ',' && (is >> g.longitude_deg) && (is >> std::ws).eof();
  if (!ok || !(std::abs(g.latitude_deg) <= 90.0) || !(std::abs(g.longitude_deg) <= 180.0))
    throw std::invalid_argument("--home '" + text +
                                "' is not LAT,LON with a latitude in [-90, 90] and a longitude in "
                                "[-180, 180] (degrees, latitude first)");
  return g;
}

std::string hemisphere(double lat, double lon) {
  return adaptseg::examples::fmt(std::abs(lat), 6) + (lat >= 0.0 ? " N, " : " S, ") +
         adaptseg::examples::fmt(std::abs(lon), 6) + (lon >= 0.0 ? " E" : " W");
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  namespace ex = adaptseg::examples;
  CLI::App app{"Plan the survey of a site that has no labels: an area polygon or an orthomosaic in, mission files out.",
               "adaptseg_plan"};
  fs::path area_file, out_dir, dem_file;
  double map_gsd_cm = 10.0, altitude_m = 0.0;
  std::string overlap_text, home_text;
  std::optional<double> max_flight_min;
  adaptseg::SitePlanOptions plan_options;
  ex::CommonOptions common;
  ex::ExportCli exports;
  exports.formats = {"plan", "wpl", "geojson"};
  app.add_option("--area", area_file,
                 "the site: a polygon file (GeoJSON, KML, ...: its first layer's polygons, inner rings as holes) or an "
                 "orthomosaic without labels (its pixels with data)")
      ->required();
  app.add_option("--gsd", plan_options.gsd_cm, "GSD of the survey [cm/px]")->required();
  app.add_option(
      "--home", home_text,
      "LAT,LON: the take-off and home point [deg], on the site (default: the ground under the first waypoint)");
  app.add_option(
      "--dem", dem_file,
      "a DEM (GeoTIFF, any raster GDAL reads with a CRS): follow its terrain, each waypoint the GSD's height "
      "above the mean ground under its footprint, altitudes relative to home's ground");
  app.add_option("--min-altitude-m", plan_options.min_altitude_m,
                 "the lowest a waypoint may fly above the ground [m] (with --dem: above the highest ground under its "
                 "footprint and along every leg)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option(
         "--max-flight-min", max_flight_min,
         "the longest sortie [min], from take-off to landing (a battery, less its reserve): the survey is split "
         "into sorties, one mission file each (default: one sortie)")
      ->check(CLI::PositiveNumber);
  app.add_option("--inside-margin-m", plan_options.survey.inside_margin_m,
                 "how far inside the site's outline (and outside its holes) every waypoint lies [m]")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
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
  if (const auto code = ex::parse_command_line(app, argc, argv)) return *code;
  try {
    const double gsd_cm = plan_options.gsd_cm;
    if (!(std::isfinite(gsd_cm) && gsd_cm > 0.0))
      throw std::invalid_argument("--gsd must be a finite positive GSD in cm/px, got " + ex::fmt(gsd_cm, 3));
    if (!(std::isfinite(map_gsd_cm) && map_gsd_cm > 0.0))
      throw std::invalid_argument("--map-gsd-cm must be a finite positive GSD in cm/px, got " + ex::fmt(map_gsd_cm, 3));
    if (!std::isfinite(altitude_m)) throw std::invalid_argument("--altitude-m must be finite");
    if (!overlap_text.empty()) plan_options.survey.overlap = ex::parse_overlap(overlap_text);
    if (!home_text.empty()) plan_options.home = parse_home(home_text);
    if (max_flight_min) plan_options.max_flight_s = *max_flight_min * 60.0;
    plan_options.camera = common.mission.camera;
    plan_options.timing = common.mission.timing;
    plan_options.hold_s = exports.file_options.hold_s;
    plan_options.fence_max_vertices = adaptseg::firmware_fence_vertex_limit(exports.file_options.firmware_type);
    exports.file_options.validate();
    exports.check_altitude(gsd_cm, common.mission.camera);
    const adaptseg::SurveySite site = adaptseg::load_survey_site(area_file, map_gsd_cm, altitude_m);
    const std::optional<adaptseg::ElevationModel> dem =
        dem_file.empty() ? std::nullopt : std::optional<adaptseg::ElevationModel>(std::in_place, dem_file);
    const adaptseg::SitePlan plan = adaptseg::plan_site(site, plan_options, dem ? &*dem : nullptr);
    const auto& wps = plan.survey.waypoints;
    const adaptseg::GeoReference geo(site.geo);

    // Every file made before any is written: a mission over the firmware's item limit writes nothing.
    const bool split = plan.sorties.size() > 1;
    std::vector<std::pair<std::string, std::string>> files;
    nlohmann::json sorties = nlohmann::json::array();
    for (std::size_t k = 0; k < plan.sorties.size(); ++k) {
      const std::string stem = split ? "mission-" + std::to_string(k + 1) : "mission";
      for (auto& f : exports.files(plan.sortie_path(k, site), common.mission.timing.max_speed_mps, stem))
        files.push_back(std::move(f));
      const adaptseg::Sortie& s = plan.sorties[k];
      const adaptseg::GeoPoint at = geo.to_wgs84(wps[s.first].position);
      sorties.push_back({{"mission", stem},
                         {"first_waypoint", s.first},
                         {"end_waypoint", s.end},
                         {"flight_s", s.flight_s},
                         {"resume_latitude_deg", at.latitude_deg},
                         {"resume_longitude_deg", at.longitude_deg}});
    }
    fs::create_directories(out_dir);
    for (const auto& [name, text] : files) ex::write_text(out_dir / name, text);

    nlohmann::json j;
    j["area"] = area_file.string();
    j["gsd_cm"] = gsd_cm;
    j["altitude_m"] = plan.height_m;
    j["images"] = wps.size();
    j["flight_s"] = plan.survey_s;
    j["total_flight_s"] = plan.flight_s;
    j["site"] = {{"centre_latitude_deg", site.centre().latitude_deg},
                 {"centre_longitude_deg", site.centre().longitude_deg},
                 {"area_m2", site.area_m2()}};
    j["home"] = {{"latitude_deg", plan.home.latitude_deg},
                 {"longitude_deg", plan.home.longitude_deg},
                 {"x", plan.home_xy.x()},
                 {"y", plan.home_xy.y()},
                 {"given", plan.home_given}};
    j["inside_margin_m"] = plan_options.survey.inside_margin_m;
    j["min_altitude_m"] = plan_options.min_altitude_m;
    j["coverage"] = {{"site_m2", plan.survey.site_m2},
                     {"uncovered_m2", plan.survey.uncovered_m2},
                     {"moved", plan.survey.moved},
                     {"dropped", plan.survey.dropped}};
    j["sorties"] = sorties;
    j["via_points"] = plan.via_points;
    std::size_t fence_vertices = 0;
    for (const auto& f : plan.geofence) fence_vertices += f.vertices.size();
    j["geofence_vertices"] = fence_vertices;
    if (plan.terrain)
      j["terrain"] = {{"dem", dem_file.string()},
                      {"home_ground_m", plan.terrain->home_ground_m},
                      {"highest_rise_m", plan.terrain->highest_rise_m},
                      {"lowest_clearance_m", plan.terrain->lowest_clearance_m()}};
    j["warnings"] = plan.warnings;
    j["site_frame"] = {{"latitude_deg", site.geo.latitude_deg}, {"longitude_deg", site.geo.longitude_deg},
                       {"altitude_m", site.geo.altitude_m},     {"heading_deg", site.geo.heading_deg},
                       {"anchor_x_m", site.geo.anchor_x_m},     {"anchor_y_m", site.geo.anchor_y_m},
                       {"width_m", site.area.area.width_m()},   {"height_m", site.area.area.height_m()}};
    nlohmann::json points = nlohmann::json::array();
    for (std::size_t i = 0; i < wps.size(); ++i) {
      const adaptseg::Waypoint& w = wps[i];
      const adaptseg::GeoPoint g = geo.to_wgs84(w.position);
      nlohmann::json p = {{"x", w.position.x()},
                          {"y", w.position.y()},
                          {"z", w.position.z()},
                          {"latitude_deg", g.latitude_deg},
                          {"longitude_deg", g.longitude_deg}};
      if (plan.terrain) p["ground_m"] = plan.terrain->ground_m[i];
      points.push_back(std::move(p));
    }
    j["waypoints"] = points;
    const adaptseg::FieldGeo origin = site.origin_geo();
    j["geo"] = {{"latitude_deg", origin.latitude_deg},
                {"longitude_deg", origin.longitude_deg},
                {"altitude_m", origin.altitude_m},
                {"heading_deg", origin.heading_deg}};
    ex::write_text(out_dir / "plan.json", j.dump(2) + "\n");
    ex::write_png(out_dir / "site.png",
                  adaptseg::render_site_picture(site, plan,
                                                site.name + ": " + std::to_string(wps.size()) + " images at " +
                                                    ex::fmt(gsd_cm, 1) + " cm/px, " +
                                                    std::to_string(plan.sorties.size()) + " sortie(s)"));

    for (const auto& w : plan.warnings) std::fprintf(stderr, "adaptseg_plan: warning: %s\n", w.c_str());
    std::printf(
        "%s: %zu images at %.1f cm/px (%.1f m above %s), flight %.0f s; site %.0f x %.0f m, +x at bearing "
        "%.1f deg -> %s\n",
        site.name.c_str(), wps.size(), gsd_cm, plan.height_m, plan.terrain ? "the ground" : "home", plan.survey_s,
        site.area.area.width_m(), site.area.area.height_m(), site.geo.heading_deg, out_dir.string().c_str());
    std::printf("where: centre %s, area %.2f ha; take-off %s (%s); %zu sortie(s), %.1f min from home and back\n",
                hemisphere(site.centre().latitude_deg, site.centre().longitude_deg).c_str(), site.area_m2() / 1e4,
                hemisphere(plan.home.latitude_deg, plan.home.longitude_deg).c_str(),
                plan.home_given ? "--home" : "under the first waypoint", plan.sorties.size(), plan.flight_s / 60.0);
    std::printf(
        "coverage: %.1f %% of the site under a footprint; %.0f m^2 left at the edges (waypoints kept %.1f m "
        "inside the outline: %zu moved inward, %zu dropped)\n",
        100.0 * plan.survey.coverage(), plan.survey.uncovered_m2, plan_options.survey.inside_margin_m,
        plan.survey.moved, plan.survey.dropped);
    for (std::size_t k = 0; split && k < plan.sorties.size(); ++k) {
      const adaptseg::Sortie& s = plan.sorties[k];
      const adaptseg::GeoPoint at = geo.to_wgs84(wps[s.first].position);
      std::printf("sortie %zu: mission-%zu.*, waypoints %zu-%zu, resumes at waypoint %zu (%s), %.1f min\n", k + 1,
                  k + 1, s.first, s.end - 1, s.first, hemisphere(at.latitude_deg, at.longitude_deg).c_str(),
                  s.flight_s / 60.0);
    }
    if (plan.terrain)
      std::printf(
          "terrain: home's ground %.1f m (DEM), highest ground under the survey %.1f m above it, lowest "
          "clearance %.1f m\n",
          plan.terrain->home_ground_m, plan.terrain->highest_rise_m, plan.terrain->lowest_clearance_m());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_plan: error: %s\n", e.what());
    return 2;
  }
}
