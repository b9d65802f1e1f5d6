// adaptseg_live: the adaptive planner as a UAV companion computer runs it (paper §3.2, Fig.
// workflow), step by step: ask the planner for the next waypoint, fly there, take the image,
// report it, get the next waypoint. No simulator and no ground truth in the loop.
//
// Here the "UAV" is a folder of images with the poses they were taken at: for each waypoint
// the program takes the image whose recorded pose matches it (a missing one is what a real
// UAV would report as "no image": an error). Make such a folder from a bundled field with
// --record-from, which captures in simulation every waypoint the planner may ask for:
//
//   adaptseg_live --record-from examples/data/weedmap-000:0.5,0,1,0.5 --model model.yaml --images DIR
//   adaptseg_live --images DIR --model model.yaml [--budget-s 300] [--out OUT]
//
// (--record-yaw DEG records every image with the camera turned by DEG, as a UAV that does not
// hold the plan's heading would take them; the planner fuses each at its recorded yaw.)
//
// The folder (docs/data_format.md, "The live image folder"): DIR/area.yaml (area, map GSD,
// classes, labels of interest, camera, and optionally its geo-reference), DIR/valid_mask.png
// (where the field is), DIR/poses.csv (in the area's frame, file,x,y,z,yaw_deg; or from GNSS,
// file,latitude_deg,longitude_deg,relative_altitude_m,heading_deg), and per image DIR/rgb/FILE
// (the camera image, for --segmenter erfnet) and/or DIR/labels/FILE (ground-truth labels under
// the footprint at map resolution, in the camera's orientation, for --segmenter oracle).
// --record-gnss records GNSS poses; --area SITE (the file adaptseg_plan takes) gives the area
// and its frame for a folder of GNSS poses, and lays the top-level grid centred on it as
// adaptseg_plan does (--grid corner|centred chooses; record and fly with the same).
//
// Writes OUT/result.json (the path with each image and its yaw, σ and decisions) and OUT/map.png
// (the fused map); where the area is georeferenced also OUT/map.tif, OUT/map_gsd.tif (built
// with GDAL) and the flown path as OUT/mission.{plan,waypoints,geojson}. When the loop stops on
// an error (no image at a waypoint, an unreadable file) it writes them all for what was flown,
// with the error in result.json's "stopped", and exits 2.

#include "common/export.hpp"
#include "common/image_set.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <adaptseg/erfnet/erfnet_segmenter.hpp>
#include <adaptseg/planner.hpp>
#include <adaptseg/vision/adaptive_planner.hpp>
#ifdef ADAPTSEG_HAVE_GDAL
#include <adaptseg/gdal/survey_site.hpp>
#endif

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
namespace ex = adaptseg::examples;

namespace {

using ex::ImageSetInfo;
using ex::PosedImage;

/// The planner's options from the decision model: its camera, speed, GSDs and coverage.
adaptseg::AdaptiveOptions model_options(const adaptseg::DecisionModel& model, std::vector<int> interest,
                                        adaptseg::GridAnchor grid) {
  adaptseg::MissionOptions mission;
  mission.interest = std::move(interest);
  adaptseg::AdaptiveOptions o = model.adaptive_options(std::move(mission));
  o.grid_anchor = grid;
  return o;
}

/// The live loop's settings.
struct LiveSettings {
  fs::path images;
  double tolerance_m = 0.05;
  fs::path out;
  std::string segmenter;  ///< oracle: labels/FILE; erfnet: rgb/FILE
  ex::ExportCli exports;  ///< the flown path's mission files, where the area is georeferenced
};

// --- what a mission leaves behind: written when it ends, and when it stops on an error ---

template <typename Planner>
void write_outputs(const Planner& planner, const ImageSetInfo& info, const std::string& policy_name,
                   const std::string& backend_name, const adaptseg::AdaptiveOptions& options,
                   const nlohmann::json& wps, const std::optional<std::string>& stopped, const LiveSettings& s) {
  if (s.out.empty()) return;
  fs::create_directories(s.out);
  int descents = 0, limited = 0;
  for (const auto& d : planner.decisions()) {
    descents += d.decision.descend ? 1 : 0;
    limited += d.budget_limited ? 1 : 0;
  }
  nlohmann::json j{{"field", info.name},
                   {"strategy", policy_name},
                   {"schedule", adaptseg::to_string(options.schedule)},
                   {"segmenter", backend_name},
                   {"images", wps.size()},
                   {"time_s", {{"total", planner.elapsed_s()}}},
                   {"decisions",
                    {{"descend", descents},
                     {"continue", static_cast<int>(planner.decisions().size()) - descents},
                     {"budget_limited", limited}}},
                   {"waypoints", wps},
                   {"adaptseg_version", adaptseg::kVersion}};
  if (options.budget_s) j["budget_s"] = *options.budget_s;
  if (stopped) {
    // What stopped the mission, and the waypoint the UAV had flown to without an image from it.
    j["stopped"] = *stopped;
    if (const auto w = planner.pending())
      j["stopped_at"] = {{"x", w->waypoint.position.x()}, {"y", w->waypoint.position.y()},
                         {"z", w->waypoint.position.z()}, {"level", w->level}, {"index", w->index}};
  }
  std::vector<std::string> written{"result.json", "map.png"};
  if (info.geo) {
    // The flown path (the pending waypoint included: the UAV flew there) as mission files.
    std::vector<adaptseg::Waypoint> path;
    std::vector<int> levels;
    for (const auto& w : planner.path()) path.push_back(w.waypoint), levels.push_back(w.level);
    const adaptseg::GeoReference geo(*info.geo);
    if (!path.empty() && !s.exports.formats.empty()) {
      s.exports.write(adaptseg::make_export_path(path, levels, geo, info.name + " " + policy_name + " (live)"),
                      options.mission.timing.max_speed_mps, s.out);
      for (const auto& f : std::set<std::string>(s.exports.formats.begin(), s.exports.formats.end()))
        written.push_back(adaptseg::export_file_name(adaptseg::parse_export_format(f)));
    }
#ifdef ADAPTSEG_HAVE_GDAL
    const adaptseg::SemanticMap& map = planner.map();
    const adaptseg::gdal::MapGrid grid{info.name, map.labels().cols, map.labels().rows, info.area.map_gsd_cm,
                                       std::nullopt, info.geo, info.classes, info.area.ignore_label};
    adaptseg::gdal::write_map_geotiff(s.out / "map.tif", grid, map.labels());
    adaptseg::gdal::write_gsd_geotiff(s.out / "map_gsd.tif", grid, map.gsd_cm());
    written.insert(written.end(), {"map.tif", "map_gsd.tif"});
#endif
  }
  j["files"] = written;
  ex::write_text(s.out / "result.json", j.dump(2) + "\n");
  ex::write_png(s.out / "map.png",
                adaptseg::render_map(planner.map().labels(), info.classes,
                                     info.name + ": " + policy_name + ", " + std::to_string(wps.size()) + " images, " +
                                         ex::fmt(planner.elapsed_s(), 0) + " s (live" +
                                         (stopped ? ", stopped on an error)" : ")")));
}

// --- the companion-computer loop ---

/// The image file of `shot` the backend needs: labels/FILE for the oracle, rgb/FILE for a
/// network; a missing or unreadable one is named.
cv::Mat read_shot(const fs::path& dir, const std::string& file, int flags, const char* what) {
  const fs::path path = dir / file;
  if (!fs::is_regular_file(path))
    throw std::invalid_argument(path.string() + ": no " + what + " for this waypoint's image (poses.csv names it)");
  cv::Mat m = cv::imread(path.string(), flags);
  if (m.empty()) throw std::invalid_argument(path.string() + ": cannot decode the " + what);
  return m;
}

template <adaptseg::SegmentationBackend Backend, adaptseg::DecisionPolicy Policy>
void fly(const ImageSetInfo& info, const std::vector<PosedImage>& images, Backend& backend, Policy& policy,
         const adaptseg::AdaptiveOptions& options, const LiveSettings& s) {
  adaptseg::AdaptivePlanner<Backend, Policy> planner(info.area, backend, policy, options);
  std::printf("%s: %zu top-level waypoints at %.2f cm/px, candidates", info.name.c_str(),
              planner.top_level().size(), options.top_gsd_cm);
  for (double g : planner.candidate_gsd_cm()) std::printf(" %.2f", g);
  std::printf(" cm/px, policy %s, descents %s, segmenter %s\n", std::string(policy.name()).c_str(),
              adaptseg::descent_schedule_rule(options.schedule).description,
              std::string(backend.name()).c_str());

  nlohmann::json wps = nlohmann::json::array();
  const auto write = [&](const std::optional<std::string>& stopped) {
    write_outputs(planner, info, std::string(policy.name()), std::string(backend.name()), options, wps, stopped, s);
  };
  try {
    while (const auto w = planner.next()) {
      // The UAV's part: fly to w, hover, take the image; here, look it up in the folder.
      const PosedImage& shot = ex::find_image(images, w->waypoint.position, s.tolerance_m);
      cv::Mat rgb;
      if (s.segmenter == "erfnet") rgb = read_shot(s.images / "rgb", shot.file, cv::IMREAD_COLOR, "camera image");
      // The pose and heading measured, not the ones planned.
      adaptseg::Image image = planner.image_at(shot.pose, rgb, shot.yaw_deg);
      if (s.segmenter == "oracle") {
        image.ground_truth = read_shot(s.images / "labels", shot.file, cv::IMREAD_UNCHANGED, "labels");
        // A recorded pose (a GNSS fix) is the planned one to within rounding, which can move each
        // footprint edge that lies half-way between map pixels by one pixel: such labels (at most
        // 2 pixels off each way) are stretched to the footprint (nearest neighbour); any other
        // size is an error.
        const cv::Size want = image.footprint_px.size(), got = image.ground_truth.size();
        if (image.ground_truth.type() == CV_8UC1 && got != want && std::abs(got.width - want.width) <= 2 &&
            std::abs(got.height - want.height) <= 2)
          cv::resize(cv::Mat(image.ground_truth), image.ground_truth, want, 0, 0, cv::INTER_NEAREST);
        if (image.ground_truth.type() != CV_8UC1 || image.ground_truth.size() != image.footprint_px.size())
          throw std::invalid_argument((s.images / "labels" / shot.file).string() +
                                      ": must be 8-bit single-channel labels of the footprint's " +
                                      std::to_string(image.footprint_px.width) + "x" +
                                      std::to_string(image.footprint_px.height) + " map pixels");
      }
      const adaptseg::PlannerStep step = planner.report(image);  // segment, fuse, σ, decide

      const auto& p = w->waypoint.position;
      std::printf("[%3zu] %s x=%7.2f y=%7.2f z=%6.2f m  %s  sigma=%.4f", w->index, w->level == 0 ? "top" : "sub",
                  p.x(), p.y(), p.z(), shot.file.c_str(), step.sigma);
      nlohmann::json wj{{"x", p.x()},       {"y", p.y()},          {"z", p.z()},
                        {"gsd_cm", w->waypoint.gsd_cm}, {"level", w->level}, {"image", shot.file},
                        {"yaw_deg", shot.yaw_deg},
                        {"semantic_ratio", step.sigma}};
      if (info.geo) {
        const adaptseg::GeoPoint g = adaptseg::GeoReference(*info.geo).to_wgs84(p);
        wj["latitude_deg"] = g.latitude_deg;
        wj["longitude_deg"] = g.longitude_deg;
      }
      if (step.decision) {
        const auto& d = step.decision->decision;
        if (d.descend) {
          const adaptseg::Candidate& c =
              step.decision->candidates[adaptseg::chosen_candidate(d, step.decision->candidates, policy.name())];
          std::printf("  -> descend to %.2f cm/px (%d images, +%.1f s)", d.gsd_cm, c.images, c.extra_time_s);
        } else {
          std::printf("  -> continue (%zu candidates%s)", step.decision->candidates.size(),
                      step.decision->budget_limited ? ", budget-limited" : "");
        }
        wj["decision"] = {{"action", d.descend ? "descend" : "continue"},
                          {"budget_limited", step.decision->budget_limited}};
        if (d.descend) wj["decision"]["gsd_cm"] = d.gsd_cm;
      }
      if (step.outcome) {
        std::printf("  [descent done: sigma %.4f at %.1f m, %.4f at %.1f m]", step.outcome->sigma_top,
                    step.outcome->top_altitude_m, step.outcome->sigma_sub, step.outcome->sub_altitude_m);
        wj["observed_sigma_sub"] = step.outcome->sigma_sub;
      }
      std::printf("\n");
      wps.push_back(wj);
    }
  } catch (const std::exception& e) {
    // Nothing flown is lost: what the mission mapped so far, and where it flew, are written
    // before the error ends the program.
    if (!s.out.empty()) {
      write(std::string(e.what()));
      std::printf("stopped: the %zu images flown so far are written to %s\n", wps.size(), s.out.string().c_str());
    }
    throw;
  }
  int descents = 0;
  for (const auto& d : planner.decisions()) descents += d.decision.descend ? 1 : 0;
  std::printf("done: %zu images, %d descents, %.1f s mission time (planner's account)\n", planner.path().size(),
              descents, planner.elapsed_s());
  write(std::nullopt);
}

/// Runs the loop with the policy of `strategy` from `model`.
template <adaptseg::SegmentationBackend Backend>
void fly_strategy(const std::string& strategy, const adaptseg::DecisionModel& model, const ImageSetInfo& info,
                  const std::vector<PosedImage>& images, Backend& backend, const adaptseg::AdaptiveOptions& options,
                  const LiveSettings& s) {
  adaptseg::examples::check_segmenter(model, backend.name());
  const adaptseg::examples::StrategyInfo& row = adaptseg::examples::strategy_info(strategy);
  if (row.policy == adaptseg::examples::StrategyPolicy::linear) {
    adaptseg::LinearDecision policy(model.linear);
    fly(info, images, backend, policy, options, s);
    return;
  }
  adaptseg::DecisionFunction df = model.decision_function;
  df.set_online(row.online);
  adaptseg::AdaptiveOptions o = options;
  o.schedule = row.schedule;
  fly(info, images, backend, df, o, s);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Run the adaptive planner step by step over a folder of posed images, as a UAV would.",
               "adaptseg_live"};
  LiveSettings s;
  fs::path model_file, erfnet_dir;
  std::string record_from, strategy = "adaptive", segmenter = "oracle";
  std::optional<double> budget_s, seg_time_s, plan_time_s;
  double record_yaw_deg = 0.0;
  app.add_option("--images", s.images, "folder of posed images (area.yaml, poses.csv, rgb/, labels/)")->required();
  app.add_option("--model", model_file, "decision model from adaptseg_calibrate")->required();
  CLI::Option* record =
      app.add_option("--record-from", record_from,
                     "instead of flying: capture, in simulation, every waypoint the planner may ask for over this "
                     "field (DIR or DIR:x0,y0,x1,y1) into --images");
  app.add_option("--record-yaw", record_yaw_deg,
                 "with --record-from: the camera's yaw [deg, counter-clockwise from the field's x axis] in every "
                 "recorded image (the planner fuses each image at its recorded yaw)")
      ->check(CLI::Range(-360.0, 360.0))
      ->needs(record)
      ->capture_default_str();
  app.add_option("--strategy", strategy, "decision policy")
      ->check(CLI::IsMember(adaptseg::examples::strategy_names(true)))
      ->capture_default_str();
  app.add_option("--segmenter", segmenter, "oracle: ground-truth labels/ of the folder; erfnet: its RGB images")
      ->check(CLI::IsMember({"oracle", "erfnet"}))
      ->capture_default_str();
  app.add_option("--model-file", erfnet_dir, "network of --segmenter erfnet: a model directory (model.onnx, model.yaml) or an ensemble directory (ensemble.yaml)");
  app.add_option("--budget-s", budget_s, "mission-time budget [s]: a descent is flown only where it and the rest fit, each image at a bound of its processing learned in flight, and cut short where they no longer do");
  app.add_option("--pose-tolerance-m", s.tolerance_m, "how far [m] a recorded pose may be from the waypoint")
      ->capture_default_str();
  app.add_option("--seg-time-s", seg_time_s, "fixed segmentation time per image [s] (default: measured)");
  app.add_option("--plan-time-s", plan_time_s, "fixed planning time per waypoint [s] (default: measured)");
  app.add_option("--out", s.out,
                 "output directory: result.json and map.png; for a georeferenced area also map.tif, map_gsd.tif "
                 "(with GDAL) and the flown path's mission files (--export); written too when the loop stops on "
                 "an error");
  bool record_gnss = false;
  app.add_flag("--record-gnss", record_gnss,
               "with --record-from: write poses.csv as a GNSS receiver gives them (latitude, longitude, relative "
               "altitude, heading of the image's top); needs the field's geo-reference (geo:, --geo-origin or a "
               "GeoTIFF field)")
      ->needs(record);
  fs::path area_file;
  double map_gsd_cm = 0.0;
#ifdef ADAPTSEG_HAVE_GDAL
  CLI::Option* area_opt =
      app.add_option("--area", area_file,
                     "the site as adaptseg_plan takes it (a polygon file or an orthomosaic without labels): the area "
                     "and its frame, replacing area.yaml's; the poses must then be GNSS poses");
  app.add_option("--map-gsd-cm", map_gsd_cm, "with --area: the map's resolution [cm/px] (default: area.yaml's, or 10)")
      ->needs(area_opt);
#endif
  s.exports.formats = {"plan", "wpl", "geojson"};
  s.exports.add_to(app);
  app.get_option("--export")->description(
      "the flown path's mission files where the area is georeferenced: plan (QGroundControl), wpl (QGC WPL 110), "
      "geojson; repeat or comma-separate (default: all three)");
  app.get_option("--geo-origin")->description(
      "with --record-from: LAT,LON,ALT,HEADING of the field directory's frame origin, replacing field.yaml's geo "
      "section (recorded into area.yaml)");
  std::string grid_name;
  app.add_option("--grid", grid_name,
                 "where the top-level grid is laid: corner (from the area's corner, the paper's grid) or centred "
                 "(on the area, every waypoint inside it: adaptseg_plan's); default centred with --area, else corner; "
                 "record and fly with the same")
      ->check(CLI::IsMember({"corner", "centred"}));
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  s.segmenter = segmenter;
  const adaptseg::GridAnchor grid = grid_name == "centred" || (grid_name.empty() && !area_file.empty())
                                        ? adaptseg::GridAnchor::centred
                                        : adaptseg::GridAnchor::corner;

  try {
    const adaptseg::DecisionModel model = adaptseg::DecisionModel::load(model_file);
    if (!record_from.empty()) {
      const adaptseg::Field field = ex::load_field_spec(record_from, s.exports.geo_override());
      model.check_classes(field);
      const std::vector<int> interest = field.class_indices(model.interest);
      model.check_compatible(field, interest);
      const adaptseg::AdaptiveOptions o = model_options(model, interest, grid);
      adaptseg::OracleSegmenter oracle(field.num_classes());
      adaptseg::DecisionFunction df = model.decision_function;
      const adaptseg::AdaptivePlanner planner(adaptseg::SurveyArea::of(field), oracle, df, o);
      const auto waypoints = planner.reachable_waypoints();
      ex::write_image_set(s.images, field, model, waypoints, record_yaw_deg, record_gnss);
      std::printf("%s: recorded %zu images (%zu top-level, %zu for the descents) -> %s\n", field.name().c_str(),
                  waypoints.size(), planner.top_level().size(), waypoints.size() - planner.top_level().size(),
                  s.images.string().c_str());
      return 0;
    }

    if (!s.exports.geo_origin.empty())
      throw std::invalid_argument("--geo-origin is for --record-from; the folder's frame is area.yaml's geo: (or --area)");
    s.exports.file_options.validate();
    ImageSetInfo info = ex::read_image_set_info(s.images, !area_file.empty());
#ifdef ADAPTSEG_HAVE_GDAL
    if (!area_file.empty()) {
      // The site's frame and mask replace area.yaml's: the poses must be GNSS ones, placed in it.
      const double gsd = map_gsd_cm > 0.0 ? map_gsd_cm : info.area.map_gsd_cm > 0.0 ? info.area.map_gsd_cm : 10.0;
      if (!(std::isfinite(gsd) && gsd > 0.0)) throw std::invalid_argument("--map-gsd-cm must be finite and positive");
      const adaptseg::SurveySite site = adaptseg::load_survey_site(area_file, gsd, info.geo ? info.geo->altitude_m : 0.0);
      info.area.area = site.area.area;
      info.area.map_gsd_cm = site.area.map_gsd_cm;
      info.area.valid_mask = site.area.valid_mask;
      info.geo = site.geo;
    }
#endif
    const std::vector<PosedImage> images = ex::read_poses(s.images, info, area_file.empty());
    std::vector<std::string> names;
    for (const auto& c : info.classes) names.push_back(c.name);
    if (names != model.classes || info.interest != model.interest)
      throw std::invalid_argument("the decision model was calibrated for other classes or labels of interest than " +
                                  (s.images / "area.yaml").string() + " names");
    const auto& c = info.camera;
    const auto& m = model.camera;
    if (c.image_width_px != m.image_width_px || c.image_height_px != m.image_height_px ||
        c.sensor_width_mm != m.sensor_width_mm || c.focal_length_mm != m.focal_length_mm)
      throw std::invalid_argument("the images were taken with another camera than the decision model's");
    std::vector<int> interest;
    for (const auto& n : model.interest)
      interest.push_back(static_cast<int>(std::find(names.begin(), names.end(), n) - names.begin()));
    adaptseg::AdaptiveOptions options = model_options(model, interest, grid);
    options.mission.fixed_segmentation_time_s = seg_time_s;
    options.mission.fixed_planning_time_s = plan_time_s;
    options.budget_s = budget_s;
    if (info.geo) s.exports.check_altitude(options.top_gsd_cm, model.camera);
    if (segmenter == "oracle") {
      adaptseg::OracleSegmenter oracle(static_cast<int>(info.classes.size()));
      fly_strategy(strategy, model, info, images, oracle, options, s);
    } else {
      if (erfnet_dir.empty()) throw std::invalid_argument("--segmenter erfnet needs --model-file");
      adaptseg::ErfnetParams params;
      params.expected_classes = names;
      params.camera_width_px = m.image_width_px;
      params.camera_height_px = m.image_height_px;
      params.resize_to_network = true;
      adaptseg::examples::with_network(erfnet_dir, std::move(params), [&](auto& network) {
        fly_strategy(strategy, model, info, images, network, options, s);
      });
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_live: error: %s\n", e.what());
    return 2;
  }
}
