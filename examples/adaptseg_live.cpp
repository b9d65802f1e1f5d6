// adaptseg_live: the adaptive planner as a UAV companion computer runs it (paper §3.2, Fig.
// workflow), step by step: ask the planner for the next waypoint, fly there, take the image,
// report it, get the next waypoint. No simulator and no ground truth in the loop.
//
// Without a vehicle, the "UAV" is a folder of images with the poses they were taken at: for
// each waypoint the program takes the image whose recorded pose matches it (a missing one is
// what a real UAV would report as "no image": an error). Make such a folder from a bundled
// field with --record-from, which captures in simulation every waypoint the planner may ask for:
//
//   adaptseg_live --record-from examples/data/weedmap-000:0.5,0,1,0.5 --decision-model model.yaml --images DIR
//   adaptseg_live --images DIR --decision-model model.yaml [--budget-s 300] [--out OUT]
//
// (--record-yaw DEG records every image with the camera turned by DEG, as a UAV that does not
// hold the plan's heading would take them; the planner fuses each at its recorded yaw.)
//
// With --mavlink CONNECTION it flies a real (or SITL, or emulated) vehicle over MAVLink 2
// (docs/flying.md): the fence is checked before anything is sent, each waypoint is flown by
// guided reposition and waited for, the camera triggered, the image taken from the camera
// source (--images: the recorded image nearest the measured pose; --camera-folder DIR: the
// next new file there; --simulate-camera FIELD: rendered over a bundled field) and reported
// with the measured pose and the mission's real clock; at the end the vehicle returns to launch.
//
//   adaptseg_live --mavlink udpin:14550 --simulate-camera FIELD --geo-origin LAT,LON,ALT,HEADING
//       --decision-model model.yaml --out OUT
//
// The folder (docs/data_format.md, "The live image folder"): DIR/area.yaml (area, map GSD,
// classes, labels of interest, camera, and optionally its geo-reference), DIR/valid_mask.png
// (where the field is), DIR/poses.csv (in the area's frame, file,x,y,z,yaw_deg; or from GNSS,
// file,latitude_deg,longitude_deg,relative_altitude_m,heading_deg), and per image DIR/rgb/FILE
// (the camera image, for --segmenter network) and/or DIR/labels/FILE (ground-truth labels under
// the footprint at map resolution, in the camera's orientation, for --segmenter oracle).
// --record-gnss records GNSS poses; --area SITE (the file adaptseg_plan takes) gives the area
// and its frame for a folder of GNSS poses, and lays the top-level grid centred on it as
// adaptseg_plan does (--grid corner|centred chooses; record and fly with the same).
//
// Writes OUT/result.json (the path with each image and its yaw, σ and decisions; flown: the
// measured poses and the clock) and OUT/map.png (the fused map); where the area is
// georeferenced also OUT/map.tif, OUT/map_gsd.tif (built with GDAL) and the flown path as
// OUT/mission.{plan,waypoints,geojson}. When the loop stops on an error (no image at a
// waypoint, an unreadable file, a lost link, a refused command) it commands the vehicle no more,
// writes them all for what was flown, with the error in result.json's "stopped", and exits 2.

#include "common/camera_source.hpp"
#include "common/export.hpp"
#include "common/image_set.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"
#include "common/vehicle.hpp"

#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/planner.hpp>
#include <adaptseg/vision/adaptive_planner.hpp>
#ifdef ADAPTSEG_HAVE_GDAL
#include <adaptseg/gdal/exif_position.hpp>
#include <adaptseg/gdal/site_fence.hpp>
#include <adaptseg/gdal/site_lawnmower.hpp>
#include <adaptseg/gdal/survey_site.hpp>
#endif

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

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

/// The vehicle's settings (with --mavlink).
struct FlightSettings {
  std::string connection;             ///< --mavlink; empty: no vehicle (a recorded folder replayed)
  std::optional<double> tolerance_m;  ///< --arrival-tolerance-m (default: from the footprint)
  double max_speed_mps = 0.5;         ///< --arrival-max-speed-mps
  double stall_s = 10.0;              ///< --arrival-stall-s
  bool trigger = true;                ///< --trigger autopilot
  bool pose_from_exif = false;        ///< --image-pose exif: each picture at its EXIF GPS position
  double fence_margin_m = 0.0;        ///< --fence-margin-m
  double link_timeout_s = 3.0;        ///< --link-timeout-s
  cv::Mat site_mask;                  ///< the --area site's mask (the fence's outline), if any
};

/// The live loop's settings.
struct LiveSettings {
  fs::path out;
  std::string segmenter;  ///< oracle: labels from the camera source; erfnet: its RGB images
  ex::ExportCli exports;  ///< the flown path's mission files, where the area is georeferenced
  ex::CameraSource* camera = nullptr;
  FlightSettings flight;
};

/// `shot` at the position its file's EXIF GPS tags give (--image-pose exif): x, y from its
/// latitude and longitude in the flight frame `frame`, z its GPS altitude above the vehicle's
/// home (`at_trigger`: the vehicle's position at the trigger, whose altitude above sea level less
/// its altitude above home is home's; the vehicle's own where the picture has no altitude), the
/// yaw the vehicle's. A position farther than `max_offset_m` from the vehicle's at the trigger
/// is refused: another picture's, or a camera clock or receiver gone wrong.
/// @throws std::invalid_argument naming the file.
[[maybe_unused]] ex::CameraPose exif_pose(const ex::Shot& shot, const adaptseg::FieldGeo& frame,
                                          const adaptseg::mavlink::VehiclePosition& at_trigger, double max_offset_m) {
#ifdef ADAPTSEG_HAVE_GDAL
  if (shot.file.empty()) throw std::invalid_argument(shot.name + ": --image-pose exif needs a picture file");
  const std::optional<adaptseg::ExifPosition> e = adaptseg::read_exif_position(shot.file);
  if (!e)
    throw std::invalid_argument(
        shot.file.string() +
        ": no EXIF GPS position (--image-pose exif); fly with --image-pose vehicle to fuse each "
        "picture where the vehicle was at the trigger");
  const adaptseg::GeoReference geo(frame);
  ex::CameraPose pose = shot.pose;
  Eigen::Vector3d x = geo.to_field({e->latitude_deg, e->longitude_deg, frame.altitude_m});
  x.z() = e->altitude_msl_m ? *e->altitude_msl_m - at_trigger.home_alt_msl_m() : shot.pose.position.z();
  const double off = (x.head<2>() - shot.pose.position.head<2>()).norm();
  if (!(off <= max_offset_m) || !(x.z() > 0.0))
    throw std::invalid_argument(shot.file.string() + ": its EXIF GPS position lies " + ex::fmt(off, 1) +
                                " m from the " + "vehicle's at the trigger, " + ex::fmt(x.z(), 1) +
                                " m above home (allowed: " + ex::fmt(max_offset_m, 1) +
                                " m, above home): another picture's, or the camera's "
                                "receiver or clock is wrong; fly with --image-pose vehicle");
  pose.position = x;
  return pose;
#else
  (void)frame, (void)at_trigger, (void)max_offset_m;
  throw std::invalid_argument(shot.name + ": --image-pose exif needs GDAL (reads the EXIF tags)");
#endif
}

// --- what a mission leaves behind: written when it ends, and when it stops on an error ---

template <typename Planner>
void write_outputs(const Planner& planner, const ImageSetInfo& info, const std::string& policy_name,
                   const std::string& backend_name, const adaptseg::AdaptiveOptions& options, const nlohmann::json& wps,
                   const nlohmann::json& vehicle, const std::optional<std::string>& stopped, const LiveSettings& s) {
  if (s.out.empty()) return;
  fs::create_directories(s.out);
  nlohmann::json j{{"field", info.name},
                   {"strategy", policy_name},
                   {"schedule", adaptseg::to_string(options.schedule)},
                   {"map_fusion", adaptseg::to_string(options.mission.map_fusion)},
                   {"segmenter", backend_name},
                   {"top_gsd_cm", planner.top_gsd_cm()},
                   {"images", wps.size()},
                   {"time_s", {{"total", planner.elapsed_s()}}},
                   {"waypoints", wps},
                   {"adaptseg_version", adaptseg::kVersion}};
  ex::add_decisions(j, planner.decisions(), policy_name);
  if (options.budget_s) j["budget_s"] = *options.budget_s;
  if (!vehicle.is_null()) j["vehicle"] = vehicle;
  if (stopped) {
    // What stopped the mission, and the waypoint the UAV had flown to without an image from it.
    j["stopped"] = *stopped;
    if (const auto w = planner.pending())
      j["stopped_at"] = {{"x", w->waypoint.position.x()},
                         {"y", w->waypoint.position.y()},
                         {"z", w->waypoint.position.z()},
                         {"level", w->level},
                         {"index", w->index}};
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
    const adaptseg::gdal::MapGrid grid{info.name,    map.labels().cols, map.labels().rows, info.area.map_gsd_cm,
                                       std::nullopt, info.geo,          info.classes,      info.area.ignore_label};
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

/// The vehicle over MAVLink for `planner`'s mission, once the fence and the ceiling hold every
/// waypoint it may fly (nothing is sent otherwise); connected.
template <typename Planner>
std::unique_ptr<ex::MavlinkVehicle> connect_vehicle(const Planner& planner, const ImageSetInfo& info,
                                                    const LiveSettings& s, nlohmann::json& vehicle_json) {
  const FlightSettings& f = s.flight;
  const adaptseg::GeoReference frame(*info.geo);
  const double ceiling = s.exports.file_options.max_altitude_m;
  s.exports.check_altitude(planner.top_gsd_cm(), planner.camera().params(), /*always=*/true);
  const ex::Fence fence =
      ex::make_fence(info.area.area, f.site_mask, info.area.map_gsd_cm, f.fence_margin_m, frame, ceiling);
  const std::vector<adaptseg::Waypoint> reachable = planner.reachable_waypoints();
  ex::check_fence(fence, reachable, frame);

  ex::VehicleSettings v;
  v.connection = f.connection;
  v.trigger = f.trigger;
  const double derived =
      ex::footprint_tolerance_m(planner.camera(), planner.candidate_gsd_cm(), planner.top_gsd_cm(), 0.1);
  v.arrival.horizontal_m = f.tolerance_m.value_or(derived);
  v.arrival.vertical_m = v.arrival.horizontal_m;
  v.arrival.max_speed_mps = f.max_speed_mps;
  v.arrival.stall_s = f.stall_s;
  v.arrival.check();
  v.link.link_timeout_s = f.link_timeout_s;
  v.link.capture_wait_s = 0.5;
  std::printf(
      "fence: %zu vertices (%s, grown %.1f m), ceiling %.1f m above home; every one of the %zu waypoints the "
      "planner may fly is inside\n",
      fence.ring.size(), f.site_mask.empty() ? "the area's rectangle" : "the site's outline", f.fence_margin_m, ceiling,
      reachable.size());
  std::printf(
      "arrival: within %.2f m (%s), slower than %.2f m/s; camera: %s%s\n", v.arrival.horizontal_m,
      f.tolerance_m ? "--arrival-tolerance-m" : "a tenth of the finest footprint's smaller side; --arrival-tolerance-m",
      v.arrival.max_speed_mps, s.camera->description().c_str(), v.trigger ? ", triggered through the autopilot" : "");
  vehicle_json = {{"connection", f.connection},
                  {"arrival_tolerance_m", v.arrival.horizontal_m},
                  {"arrival_max_speed_mps", v.arrival.max_speed_mps},
                  {"fence_margin_m", f.fence_margin_m},
                  {"ceiling_m", ceiling},
                  {"trigger", v.trigger ? "autopilot" : "none"},
                  {"image_pose", f.pose_from_exif ? "exif" : "vehicle"},
                  {"returned_to_launch", false}};
  auto vehicle = std::make_unique<ex::MavlinkVehicle>(v, fence.limits, *info.geo);
  vehicle_json["connection"] = vehicle->link().description();
  std::printf("vehicle: waiting for the autopilot on %s\n", vehicle->link().description().c_str());
  std::fflush(stdout);
  vehicle->connect();
  vehicle_json["firmware"] = adaptseg::mavlink::to_string(vehicle->link().vehicle().firmware());
  return vehicle;
}

template <adaptseg::SegmentationBackend Backend, adaptseg::DecisionPolicy Policy>
void fly(const ImageSetInfo& info, Backend& backend, Policy& policy, const adaptseg::AdaptiveOptions& options,
         const LiveSettings& s) {
  adaptseg::AdaptivePlanner<Policy> planner(info.area, policy, options);
  // The GSD the top level is flown at: the model's, or the one its policy chose for this area.
  std::printf("%s: %zu top-level waypoints at %.2f cm/px", info.name.c_str(), planner.top_level().size(),
              planner.top_gsd_cm());
  if (planner.top_gsd_cm() != options.top_gsd_cm)
    std::printf(" (the policy's choice; the model's %.2f)", options.top_gsd_cm);
  std::printf(", candidates");
  for (double g : planner.candidate_gsd_cm()) std::printf(" %.2f", g);
  std::printf(" cm/px, policy %s, descents %s, segmenter %s\n", std::string(policy.name()).c_str(),
              adaptseg::descent_schedule_info(options.schedule).description, std::string(backend.name()).c_str());

  nlohmann::json wps = nlohmann::json::array();
  nlohmann::json vehicle_json;
  const auto write = [&](const std::optional<std::string>& stopped) {
    write_outputs(planner, info, std::string(policy.name()), std::string(backend.name()), options, wps, vehicle_json,
                  stopped, s);
  };
  std::unique_ptr<ex::MavlinkVehicle> vehicle;
  try {
    if (!s.flight.connection.empty()) vehicle = connect_vehicle(planner, info, s, vehicle_json);
    const ex::Idle idle = [&](double seconds) {
      if (vehicle)
        vehicle->idle(seconds);
      else
        std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    };
    while (const auto w = planner.next()) {
      // The UAV's part: fly to w, hover, take the image (replayed: the folder's image there).
      const ex::CameraPose at =
          vehicle ? vehicle->fly_to(w->waypoint, *s.camera) : ex::CameraPose{w->waypoint.position, 0.0};
      ex::Shot shot = s.camera->take(at, idle);
      if (vehicle && s.flight.pose_from_exif)
        shot.pose = exif_pose(shot, *info.geo, vehicle->last_position(), 0.5 * w->waypoint.footprint.height_m());
      if (s.segmenter == "network" && shot.bgr.empty())
        throw std::invalid_argument(shot.name + ": no camera image for the network (--segmenter network)");
      // The pose and heading measured, not the ones planned.
      adaptseg::Image image = planner.image_at(shot.pose.position, shot.bgr, shot.pose.yaw_deg);
      if (s.segmenter == "oracle") ex::attach_labels(image, std::move(shot.labels), shot.name + " (labels)");
      // The mission's real clock, from the first waypoint on: the budget learns each step's cost.
      const std::optional<double> elapsed = vehicle ? std::optional<double>(vehicle->elapsed_s()) : std::nullopt;
      const adaptseg::PlannerStep step =
          vehicle ? vehicle->while_busy([&] { return adaptseg::segment_and_report(planner, backend, image, elapsed); })
                  : adaptseg::segment_and_report(planner, backend, image);

      const auto& p = w->waypoint.position;
      std::printf("[%3zu] %s x=%7.2f y=%7.2f z=%6.2f m  %s  sigma=%.4f", w->index, w->level == 0 ? "top" : "sub", p.x(),
                  p.y(), p.z(), shot.name.c_str(), step.sigma);
      nlohmann::json wj{{"x", p.x()},
                        {"y", p.y()},
                        {"z", p.z()},
                        {"gsd_cm", w->waypoint.gsd_cm},
                        {"level", w->level},
                        {"image", shot.name},
                        {"yaw_deg", shot.pose.yaw_deg},
                        {"semantic_ratio", step.sigma}};
      if (info.geo) {
        const adaptseg::GeoPoint g = adaptseg::GeoReference(*info.geo).to_wgs84(p);
        wj["latitude_deg"] = g.latitude_deg;
        wj["longitude_deg"] = g.longitude_deg;
      }
      if (vehicle) {
        const auto& m = vehicle->last_position();
        const Eigen::Vector3d& q = shot.pose.position;
        wj["measured"] = {{"x", q.x()},
                          {"y", q.y()},
                          {"z", q.z()},
                          {"yaw_deg", shot.pose.yaw_deg},
                          {"latitude_deg", m.lat_deg},
                          {"longitude_deg", m.lon_deg},
                          {"relative_altitude_m", m.rel_alt_m}};
        wj["elapsed_s"] = *elapsed;
        std::printf("  %.2f m off, t=%.1f s", (q - p).norm(), *elapsed);
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
      }
      if (step.outcome)
        std::printf("  [descent done: sigma %.4f at %.1f m, %.4f at %.1f m]", step.outcome->sigma_top,
                    step.outcome->top_altitude_m, step.outcome->sigma_sub, step.outcome->sub_altitude_m);
      std::printf("\n");
      std::fflush(stdout);
      wps.push_back(wj);
    }
    if (vehicle) {
      vehicle->return_to_launch();
      vehicle_json["returned_to_launch"] = true;
      std::printf("return to launch acknowledged: the vehicle flies home and lands\n");
    }
  } catch (const std::exception& e) {
    // Nothing flown is lost: what the mission mapped so far, and where it flew, are written
    // before the error ends the program. The vehicle is commanded no more: its failsafe decides.
    if (!s.out.empty()) {
      write(std::string(e.what()));
      std::printf("stopped: the %zu images flown so far are written to %s\n", wps.size(), s.out.string().c_str());
    }
    throw;
  }
  int descents = 0;
  for (const auto& d : planner.decisions()) descents += d.decision.descend ? 1 : 0;
  std::printf("done: %zu images, %d descents, %.1f s mission time (%s)\n", planner.path().size(), descents,
              planner.elapsed_s(), vehicle ? "the vehicle's clock" : "planner's account");
  write(std::nullopt);
}

/// Runs the loop with the policy of `strategy` from `model`.
template <adaptseg::SegmentationBackend Backend>
void fly_strategy(const std::string& strategy, const adaptseg::DecisionModel& model, const ImageSetInfo& info,
                  Backend& backend, const adaptseg::AdaptiveOptions& options, const LiveSettings& s) {
  adaptseg::check_segmenter(model, backend.name());
  const adaptseg::StrategyInfo& row = adaptseg::strategy_info(strategy);
  if (row.policy == adaptseg::StrategyPolicy::linear) {
    adaptseg::LinearDecision policy(model.linear);
    fly(info, backend, policy, options, s);
    return;
  }
  adaptseg::DecisionFunction df = model.decision_function;
  df.set_online(row.online);
  adaptseg::AdaptiveOptions o = options;
  o.schedule = row.schedule;
  fly(info, backend, df, o, s);
}

/// The classes of a site without labels (--area alone): the model's, in a fixed palette.
std::vector<adaptseg::ClassInfo> model_classes(const adaptseg::DecisionModel& model) {
  static constexpr std::array<std::array<std::uint8_t, 3>, 8> kPalette{{{128, 64, 0},
                                                                        {0, 160, 0},
                                                                        {220, 30, 30},
                                                                        {30, 90, 220},
                                                                        {240, 200, 40},
                                                                        {150, 40, 190},
                                                                        {0, 190, 190},
                                                                        {128, 128, 128}}};
  std::vector<adaptseg::ClassInfo> out;
  for (std::size_t k = 0; k < model.classes.size(); ++k)
    out.push_back({model.classes[k], kPalette[k % kPalette.size()]});
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Run the adaptive planner step by step, as a UAV's companion computer does: over a folder of posed "
      "images, or flying a vehicle over MAVLink.",
      "adaptseg_live"};
  LiveSettings s;
  fs::path images_dir, decision_model, network, camera_folder;
  std::string record_from, strategy = "adaptive", segmenter = "oracle", simulate_field, trigger, image_pose = "vehicle";
  std::optional<double> budget_s, seg_time_s, plan_time_s, pose_tolerance_m;
  double record_yaw_deg = 0.0, camera_timeout_s = 10.0;
  CLI::Option* images_opt =
      app.add_option("--images", images_dir, "folder of posed images (area.yaml, poses.csv, rgb/, labels/)");
  CLI::Option* model_opt = app.add_option("--decision-model", decision_model, "decision model from adaptseg_calibrate");
  adaptseg::examples::accept_old_spelling(app, model_opt, "--model", decision_model);
  CLI::Option* record =
      app.add_option("--record-from", record_from,
                     "instead of flying: capture, in simulation, every waypoint the planner may ask for over this "
                     "field (DIR or DIR:x0,y0,x1,y1) into --images")
          ->needs(images_opt);
  app.add_option("--record-yaw", record_yaw_deg,
                 "with --record-from: the camera's yaw [deg, counter-clockwise from the field's x axis] in every "
                 "recorded image (the planner fuses each image at its recorded yaw)")
      ->check(CLI::Range(-360.0, 360.0))
      ->needs(record)
      ->capture_default_str();
  app.add_option("--strategy", strategy, "decision policy")
      ->check(CLI::IsMember(adaptseg::strategy_names(true)))
      ->capture_default_str();
  ex::accept_old_value(app.add_option("--segmenter", segmenter,
                                      "oracle: the ground-truth labels of the folder or the simulated camera; network: "
                                      "the camera's colour images segmented by --network"),
                       "erfnet", "network")
      ->check(CLI::IsMember({"oracle", "network"}))
      ->capture_default_str();
  CLI::Option* network_opt =
      app.add_option("--network", network,
                     "network of --segmenter network: a model directory (model.onnx, model.yaml) "
                     "or an ensemble directory (ensemble.yaml)");
  adaptseg::examples::accept_old_spelling(app, network_opt, "--model-file", network);
  app.add_option("--budget-s", budget_s,
                 "mission-time budget [s]: a descent is flown only where it and the rest fit, each image at a bound of "
                 "its processing learned in flight, and cut short where they no longer do");
  app.add_option("--pose-tolerance-m", pose_tolerance_m,
                 "how far [m] a recorded pose may be from the waypoint (or, flying, from the measured pose) "
                 "(default: 0.4 x the finest footprint's smaller side, printed)");
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
  // The vehicle (docs/flying.md).
  CLI::Option* mavlink_opt = app.add_option(
      "--mavlink", s.flight.connection,
      "fly a vehicle over MAVLink 2: udpin:[HOST:]PORT (listen: SITL and telemetry bridges send to 14550), "
      "udpout:HOST:PORT or serial:DEVICE[:BAUD]; needs a georeferenced area (area.yaml's geo:, --area, or the "
      "--simulate-camera field's geo: / --geo-origin)");
  CLI::Option* sim_opt =
      app.add_option("--simulate-camera", simulate_field,
                     "with --mavlink: render each image over this field (DIR or DIR:x0,y0,x1,y1) at the vehicle's "
                     "measured pose; the field is also the area to map unless --images or --area gives it")
          ->needs(mavlink_opt);
  CLI::Option* camera_folder_opt =
      app.add_option("--camera-folder", camera_folder,
                     "with --mavlink: after each trigger, the next new image file in this folder (a real camera's "
                     "download), taken at the pose measured at the trigger; any size of the camera's aspect ratio")
          ->needs(mavlink_opt)
          ->excludes(sim_opt);
  app.add_option(
         "--image-pose", image_pose,
         "with --camera-folder: where each picture is fused: vehicle (the vehicle's position at the trigger) or "
         "exif (the picture's EXIF GPS position, e.g. a camera with its own RTK receiver; its altitude above "
         "home from the vehicle's home; refused beyond half a footprint from the vehicle's)")
      ->check(CLI::IsMember({"vehicle", "exif"}))
      ->needs(camera_folder_opt)
      ->capture_default_str();
  app.add_option("--camera-timeout-s", camera_timeout_s, "with --camera-folder: the longest wait for the image [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--trigger", trigger,
                 "with --mavlink: autopilot (command the autopilot's camera at each waypoint: IMAGE_START_CAPTURE on "
                 "PX4, DO_DIGICAM_CONTROL on ArduPilot) or none; default none with --simulate-camera, else autopilot")
      ->check(CLI::IsMember({"autopilot", "none"}))
      ->needs(mavlink_opt);
  app.add_option("--arrival-tolerance-m", s.flight.tolerance_m,
                 "with --mavlink: how near a waypoint [m, horizontally and vertically] the image is taken (default: a "
                 "tenth of the finest footprint's smaller side, printed)")
      ->check(CLI::PositiveNumber)
      ->needs(mavlink_opt);
  app.add_option("--arrival-max-speed-mps", s.flight.max_speed_mps,
                 "with --mavlink: and once the vehicle is slower than this [m/s] (settled)")
      ->check(CLI::PositiveNumber)
      ->needs(mavlink_opt)
      ->capture_default_str();
  app.add_option("--arrival-stall-s", s.flight.stall_s,
                 "with --mavlink: no progress towards a waypoint this long [s]: the vehicle stopped short, the "
                 "mission stops")
      ->check(CLI::PositiveNumber)
      ->needs(mavlink_opt)
      ->capture_default_str();
  app.add_option("--fence-margin-m", s.flight.fence_margin_m,
                 "with --mavlink: how far [m] beyond the site (the --area outline, else the area's rectangle) the "
                 "vehicle may fly; every waypoint the planner may fly is checked against it before take-off")
      ->check(CLI::NonNegativeNumber)
      ->needs(mavlink_opt)
      ->capture_default_str();
  app.add_option("--link-timeout-s", s.flight.link_timeout_s,
                 "with --mavlink: no frame from the vehicle this long [s]: the link is lost, the mission stops")
      ->check(CLI::PositiveNumber)
      ->needs(mavlink_opt)
      ->capture_default_str();
  fs::path area_file;
  double map_gsd_cm = 0.0;
#ifdef ADAPTSEG_HAVE_GDAL
  CLI::Option* area_opt =
      app.add_option("--area", area_file,
                     "the site as adaptseg_plan takes it (a polygon file or an orthomosaic without labels): the area "
                     "and its frame, replacing area.yaml's (the poses must then be GNSS poses) or the simulated "
                     "field's; with --mavlink also the fence's outline");
  app.add_option("--map-gsd-cm", map_gsd_cm, "with --area: the map's resolution [cm/px] (default: area.yaml's, or 10)")
      ->needs(area_opt);
#endif
  s.exports.formats = {"plan", "wpl", "geojson"};
  s.exports.add_to(app);
  app.get_option("--export")
      ->description(
          "the flown path's mission files where the area is georeferenced: plan (QGroundControl), wpl (QGC WPL 110), "
          "geojson; repeat or comma-separate (default: all three)");
  app.get_option("--geo-origin")
      ->description(
          "with --record-from or --simulate-camera: LAT,LON,ALT,HEADING of the field directory's frame origin, "
          "replacing "
          "field.yaml's geo section (recorded into area.yaml)");
  app.get_option("--max-altitude-m")
      ->description(
          "the highest a waypoint may fly above home [m] (the usual legal ceiling): the exported files', and with "
          "--mavlink the fence's ceiling; a mission that would fly higher is refused before it flies");
  std::string grid_name;
  app.add_option("--grid", grid_name,
                 "where the top-level grid is laid: corner (from the area's corner, the paper's grid) or centred "
                 "(on the area, every waypoint inside it: adaptseg_plan's); default centred with --area, else corner; "
                 "record and fly with the same")
      ->check(CLI::IsMember(adaptseg::detail::names_of(adaptseg::kGridAnchors)));
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  if (decision_model.empty()) return adaptseg::examples::command_line_error(app, "--decision-model is required");
  s.segmenter = segmenter;
  s.flight.trigger = trigger.empty() ? simulate_field.empty() : trigger == "autopilot";
  s.flight.pose_from_exif = image_pose == "exif";
  const adaptseg::GridAnchor grid = !grid_name.empty()   ? adaptseg::parse_grid_anchor(grid_name)
                                    : !area_file.empty() ? adaptseg::GridAnchor::centred
                                                         : adaptseg::GridAnchor::corner;

  try {
    const adaptseg::DecisionModel model = adaptseg::DecisionModel::load(decision_model);
    if (!record_from.empty()) {
      const adaptseg::Field field = ex::load_field_spec(record_from, s.exports.geo_override());
      model.check_classes(field);
      const std::vector<int> interest = field.class_indices(model.interest);
      model.check_compatible(field, interest);
      const adaptseg::AdaptiveOptions o = model_options(model, interest, grid);
      adaptseg::DecisionFunction df = model.decision_function;
      const adaptseg::AdaptivePlanner planner(adaptseg::SurveyArea::of(field), df, o);
      const auto waypoints = planner.reachable_waypoints();
      ex::write_image_set(images_dir, field, model, waypoints, record_yaw_deg, record_gnss);
      std::printf("%s: recorded %zu images (%zu top-level, %zu for the descents) -> %s\n", field.name().c_str(),
                  waypoints.size(), planner.top_level().size(), waypoints.size() - planner.top_level().size(),
                  images_dir.string().c_str());
      return 0;
    }

    if (!camera_folder.empty() && segmenter == "oracle")
      throw std::invalid_argument(
          "--camera-folder gives camera images without labels: segment them with "
          "--segmenter network --network DIR (the oracle needs ground truth)");
    if (!s.exports.geo_origin.empty() && simulate_field.empty())
      throw std::invalid_argument(
          "--geo-origin is for --record-from and --simulate-camera; the folder's frame is area.yaml's geo: (or "
          "--area)");
    s.exports.file_options.validate();
    // The area to map: the folder's area.yaml, the simulated field, or the site alone.
    ImageSetInfo info;
    std::optional<adaptseg::Field> sim_field;
    if (!simulate_field.empty()) sim_field = ex::load_field_spec(simulate_field, s.exports.geo_override());
    if (!images_dir.empty()) {
      info = ex::read_image_set_info(images_dir, !area_file.empty());
    } else if (sim_field) {
      model.check_classes(*sim_field);
      info = ex::image_set_info_of(*sim_field, model);
    } else if (!area_file.empty()) {
      info.name = area_file.stem().string();
      info.classes = model_classes(model);
      info.area.num_classes = static_cast<int>(info.classes.size());
      info.interest = model.interest;
      info.camera = model.camera;
    } else {
      throw std::invalid_argument(
          "give the area to map: --images DIR (a recorded folder), --simulate-camera FIELD "
          "(with --mavlink) or --area SITE");
    }
#ifdef ADAPTSEG_HAVE_GDAL
    if (!area_file.empty()) {
      // The site's frame and mask replace area.yaml's (or the field's): poses are placed in it.
      const double gsd = map_gsd_cm > 0.0 ? map_gsd_cm : info.area.map_gsd_cm > 0.0 ? info.area.map_gsd_cm : 10.0;
      if (!(std::isfinite(gsd) && gsd > 0.0)) throw std::invalid_argument("--map-gsd-cm must be finite and positive");
      const adaptseg::SurveySite site =
          adaptseg::load_survey_site(area_file, gsd, info.geo ? info.geo->altitude_m : 0.0);
      info.area.area = site.area.area;
      info.area.map_gsd_cm = site.area.map_gsd_cm;
      info.area.valid_mask = site.area.valid_mask;
      info.geo = site.geo;
      s.flight.site_mask = site.area.valid_mask;
    }
#endif
    std::vector<std::string> names;
    for (const auto& c : info.classes) names.push_back(c.name);
    if (names != model.classes || info.interest != model.interest)
      throw std::invalid_argument("the decision model was calibrated for other classes or labels of interest than " +
                                  (images_dir.empty() ? std::string("the area") : (images_dir / "area.yaml").string()) +
                                  " names");
    const auto& c = info.camera;
    const auto& m = model.camera;
    if (c.image_width_px != m.image_width_px || c.image_height_px != m.image_height_px ||
        c.sensor_width_mm != m.sensor_width_mm || c.focal_length_mm != m.focal_length_mm)
      throw std::invalid_argument("the images were taken with another camera than the decision model's");
    if (!s.flight.connection.empty() && !info.geo)
      throw std::invalid_argument(
          "--mavlink needs a georeferenced area, to turn waypoints into latitudes and "
          "longitudes: a geo: section in area.yaml (or the simulated field's field.yaml, or "
          "--geo-origin LAT,LON,ALT,HEADING), or the site as --area SITE");
    std::vector<int> interest;
    for (const auto& n : model.interest)
      interest.push_back(static_cast<int>(std::find(names.begin(), names.end(), n) - names.begin()));
    adaptseg::AdaptiveOptions options = model_options(model, interest, grid);
    options.mission.fixed_segmentation_time_s = seg_time_s;
    options.mission.fixed_planning_time_s = plan_time_s;
    options.budget_s = budget_s;

    // The camera: the simulated one, a watched folder, or the recorded folder.
    std::unique_ptr<ex::CameraSource> camera;
    if (sim_field) {
      if (segmenter == "network" && !sim_field->has_image())
        throw std::invalid_argument("--simulate-camera: field '" + sim_field->name() +
                                    "' has no image for --segmenter network (its labels serve --segmenter oracle)");
      const bool other_frame = !area_file.empty() || !images_dir.empty();
      camera = std::make_unique<ex::SimulatedCamera>(
          *sim_field, model.camera, other_frame ? info.geo : std::optional<adaptseg::FieldGeo>{}, info.area.map_gsd_cm);
    } else if (!camera_folder.empty()) {
      camera = std::make_unique<ex::FolderCamera>(camera_folder, camera_timeout_s, model.camera);
    } else {
      if (images_dir.empty())
        throw std::invalid_argument(
            "no camera: give --images DIR (a recorded folder), or with --mavlink "
            "--simulate-camera FIELD or --camera-folder DIR");
      // A pose within this of its waypoint is nearer it than any other waypoint's image.
      const double tolerance = pose_tolerance_m.value_or(ex::footprint_tolerance_m(
          adaptseg::CameraModel(model.camera), options.candidate_gsd_cm, options.top_gsd_cm, 0.4));
      if (!(std::isfinite(tolerance) && tolerance > 0.0))
        throw std::invalid_argument("--pose-tolerance-m must be finite and positive");
      std::printf("poses: an image within %.3f m of its waypoint%s\n", tolerance,
                  pose_tolerance_m ? " (--pose-tolerance-m)"
                                   : " (0.4 x the finest footprint's smaller side; --pose-tolerance-m)");
      camera =
          std::make_unique<ex::RecordedCamera>(images_dir, ex::read_poses(images_dir, info, area_file.empty()),
                                               tolerance, segmenter == "network", segmenter == "oracle", model.camera);
    }
    s.camera = camera.get();
    if (info.geo && s.flight.connection.empty()) s.exports.check_altitude(options.top_gsd_cm, model.camera);
    if (segmenter == "oracle") {
      adaptseg::OracleSegmenter oracle(static_cast<int>(info.classes.size()));
      adaptseg::AnyBackend any(oracle);  // as with_network's: one backend type to compile for
      fly_strategy(strategy, model, info, any, options, s);
    } else {
      if (network.empty()) throw std::invalid_argument("--segmenter network needs --network");
      adaptseg::OnnxParams params;
      params.expected_classes = names;
      params.camera_width_px = m.image_width_px;
      params.camera_height_px = m.image_height_px;
      params.resize_to_network = true;
      adaptseg::with_network(network, std::move(params),
                             [&](auto& backend) { fly_strategy(strategy, model, info, backend, options, s); });
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_live: error: %s\n", e.what());
    return 2;
  }
}
