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
// The folder (docs/method.md, "Live use"): DIR/area.yaml (area, map GSD, classes, labels of
// interest, camera), DIR/valid_mask.png (where the field is), DIR/poses.csv
// (file,x,y,z,yaw_deg; yaw counter-clockwise from the field's x axis), and per image
// DIR/rgb/FILE (the camera image) and/or DIR/labels/FILE (ground-truth labels under the
// footprint at map resolution, in the camera's orientation, for --segmenter oracle).
// --segmenter erfnet segments the RGB images with the ERFNet model of --model-file.
//
// Writes OUT/result.json (the path with each image and its yaw, σ and decisions) and OUT/map.png
// (the fused map).

#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/erfnet_segmenter.hpp>
#include <adaptseg/planner.hpp>

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
#include <sstream>

namespace fs = std::filesystem;
namespace ex = adaptseg::examples;

namespace {

/// One image of the folder and the pose it was taken at.
struct PosedImage {
  std::string file;
  Eigen::Vector3d pose;
  double yaw_deg = 0.0;
};

/// What area.yaml says: the ground to cover, its classes, and the camera of the images.
struct ImageSetInfo {
  std::string name;
  adaptseg::SurveyArea area;
  std::vector<adaptseg::ClassInfo> classes;
  std::vector<std::string> interest;
  adaptseg::CameraParams camera;
};

[[noreturn]] void fail(const fs::path& file, const std::string& what) {
  throw std::invalid_argument(file.string() + ": " + what);
}

// --- recording (simulation) ---

void write_image_set(const fs::path& dir, const adaptseg::Field& field, const adaptseg::DecisionModel& model,
                     const std::vector<adaptseg::Waypoint>& waypoints, double yaw_deg) {
  fs::create_directories(dir / "labels");
  if (field.has_image()) fs::create_directories(dir / "rgb");
  ex::write_png(dir / "valid_mask.png", field.valid_mask());
  YAML::Emitter e;
  e << YAML::BeginMap << YAML::Key << "format" << YAML::Value << "adaptseg.image_set/1";
  e << YAML::Key << "name" << YAML::Value << field.name();
  const adaptseg::Area a = field.area();
  e << YAML::Key << "area_m" << YAML::Value << YAML::Flow
    << std::vector<double>{a.x_min_m, a.y_min_m, a.x_max_m, a.y_max_m};
  e << YAML::Key << "map_gsd_cm" << YAML::Value << field.gsd_cm();
  e << YAML::Key << "valid_mask" << YAML::Value << "valid_mask.png";
  e << YAML::Key << "ignore_label" << YAML::Value << field.ignore_label();
  e << YAML::Key << "classes" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : field.classes())
    e << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << c.name << YAML::Key << "color"
      << YAML::Value << YAML::Flow << std::vector<int>{c.color_rgb[0], c.color_rgb[1], c.color_rgb[2]}
      << YAML::EndMap;
  e << YAML::EndSeq;
  e << YAML::Key << "interest" << YAML::Value << YAML::Flow << model.interest;
  e << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "image_width_px"
    << YAML::Value << model.camera.image_width_px << YAML::Key << "image_height_px" << YAML::Value
    << model.camera.image_height_px << YAML::Key << "sensor_width_mm" << YAML::Value << model.camera.sensor_width_mm
    << YAML::Key << "focal_length_mm" << YAML::Value << model.camera.focal_length_mm << YAML::EndMap;
  e << YAML::EndMap;
  ex::write_text(dir / "area.yaml", std::string(e.c_str()) + "\n");

  const adaptseg::SimulatedSensor sensor(field, adaptseg::CameraModel(model.camera));
  std::ostringstream csv;
  csv << "file,x,y,z,yaw_deg\n";
  char buf[160];
  for (std::size_t k = 0; k < waypoints.size(); ++k) {
    const adaptseg::Image img = sensor.capture(waypoints[k], yaw_deg);
    std::snprintf(buf, sizeof buf, "%05zu.png", k);
    const std::string file = buf;
    ex::write_png(dir / "labels" / file, img.ground_truth);
    if (!img.rgb.empty()) ex::write_png(dir / "rgb" / file, img.rgb);
    const Eigen::Vector3d& p = waypoints[k].position;
    std::snprintf(buf, sizeof buf, "%s,%.9f,%.9f,%.9f,%.9g\n", file.c_str(), p.x(), p.y(), p.z(), yaw_deg);
    csv << buf;
  }
  ex::write_text(dir / "poses.csv", csv.str());
}

// --- reading the folder ---

ImageSetInfo read_image_set_info(const fs::path& dir) {
  const fs::path file = dir / "area.yaml";
  if (!fs::is_regular_file(file)) fail(file, "not found (is --images a folder written by --record-from?)");
  try {
    const YAML::Node root = YAML::LoadFile(file.string());
    if (!root["format"] || root["format"].as<std::string>() != "adaptseg.image_set/1")
      fail(file, "format must be adaptseg.image_set/1");
    ImageSetInfo info;
    info.name = root["name"].as<std::string>();
    const auto a = root["area_m"].as<std::vector<double>>();
    if (a.size() != 4) fail(file, "area_m must be [x_min, y_min, x_max, y_max]");
    info.area.area = {a[0], a[1], a[2], a[3]};
    info.area.map_gsd_cm = root["map_gsd_cm"].as<double>();
    info.area.ignore_label = root["ignore_label"].as<int>();
    if (root["valid_mask"]) {
      const fs::path mask = dir / root["valid_mask"].as<std::string>();
      info.area.valid_mask = cv::imread(mask.string(), cv::IMREAD_UNCHANGED);
      if (info.area.valid_mask.empty() || info.area.valid_mask.type() != CV_8UC1)
        fail(mask, "cannot read an 8-bit single-channel mask");
    }
    for (const auto& c : root["classes"]) {
      const auto rgb = c["color"].as<std::vector<int>>();
      if (rgb.size() != 3) fail(file, "a class colour must be [r, g, b]");
      info.classes.push_back({c["name"].as<std::string>(),
                              {static_cast<std::uint8_t>(rgb[0]), static_cast<std::uint8_t>(rgb[1]),
                               static_cast<std::uint8_t>(rgb[2])}});
    }
    info.area.num_classes = static_cast<int>(info.classes.size());
    info.interest = root["interest"].as<std::vector<std::string>>();
    const YAML::Node cam = root["camera"];
    info.camera = {cam["image_width_px"].as<int>(), cam["image_height_px"].as<int>(),
                   cam["sensor_width_mm"].as<double>(), cam["focal_length_mm"].as<double>()};
    return info;
  } catch (const YAML::Exception& e) {
    fail(file, std::string("YAML error: ") + e.what());
  }
}

std::vector<PosedImage> read_poses(const fs::path& dir) {
  const fs::path file = dir / "poses.csv";
  std::ifstream is(file);
  if (!is) fail(file, "not found");
  std::string line;
  std::getline(is, line);
  if (line.rfind("file,x,y,z", 0) != 0) fail(file, "the header must be file,x,y,z[,yaw_deg]");
  std::vector<PosedImage> out;
  for (int n = 2; std::getline(is, line); ++n) {
    if (line.empty()) continue;
    std::istringstream row(line);
    PosedImage p;
    std::string cell[5];
    int cells = 0;
    while (cells < 5 && std::getline(row, cell[cells], ',')) ++cells;
    try {
      if (cells < 4) throw std::invalid_argument("");
      p.file = cell[0];
      p.pose = {std::stod(cell[1]), std::stod(cell[2]), std::stod(cell[3])};
      if (cells == 5) p.yaw_deg = std::stod(cell[4]);
      if (!p.pose.allFinite() || !std::isfinite(p.yaw_deg)) throw std::invalid_argument("");
    } catch (const std::exception&) {
      fail(file, "line " + std::to_string(n) + " is not file,x,y,z[,yaw_deg] (finite numbers: metres, degrees): '" +
                     line + "'");
    }
    out.push_back(p);
  }
  if (out.empty()) fail(file, "no images");
  return out;
}

/// The recorded image nearest `position`, if within `tolerance_m`; otherwise the error a UAV
/// would give: no image at that waypoint.
const PosedImage& find_image(const std::vector<PosedImage>& images, const Eigen::Vector3d& position,
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

/// The planner's options from the decision model: its camera, speed, GSDs and coverage.
adaptseg::AdaptiveOptions model_options(const adaptseg::DecisionModel& model, std::vector<int> interest) {
  adaptseg::MissionOptions mission;
  mission.interest = std::move(interest);
  return model.adaptive_options(std::move(mission));
}

/// The live loop's settings.
struct LiveSettings {
  fs::path images;
  double tolerance_m = 0.05;
  fs::path out;
};

// --- the companion-computer loop ---

template <adaptseg::SegmentationBackend Backend, adaptseg::DecisionPolicy Policy>
void fly(const ImageSetInfo& info, const std::vector<PosedImage>& images, Backend& backend, Policy& policy,
         const adaptseg::AdaptiveOptions& options, const LiveSettings& s) {
  adaptseg::AdaptivePlanner<Backend, Policy> planner(info.area, backend, policy, options);
  std::printf("%s: %zu top-level waypoints at %.2f cm/px, candidates", info.name.c_str(),
              planner.top_level().size(), options.top_gsd_cm);
  for (double g : planner.candidate_gsd_cm()) std::printf(" %.2f", g);
  std::printf(" cm/px, policy %s, descents %s, segmenter %s\n", std::string(policy.name()).c_str(),
              options.schedule == adaptseg::DescentSchedule::tour  ? "at once or toured after the survey"
              : options.schedule == adaptseg::DescentSchedule::row ? "at once or toured after each row"
                                                                   : "at once",
              std::string(backend.name()).c_str());

  nlohmann::json wps = nlohmann::json::array();
  while (const auto w = planner.next()) {
    // The UAV's part: fly to w, hover, take the image; here, look it up in the folder.
    const PosedImage& shot = find_image(images, w->waypoint.position, s.tolerance_m);
    cv::Mat rgb;
    if (fs::is_regular_file(s.images / "rgb" / shot.file)) {
      rgb = cv::imread((s.images / "rgb" / shot.file).string(), cv::IMREAD_COLOR);
      if (rgb.empty()) fail(s.images / "rgb" / shot.file, "cannot decode image");
    }
    // The pose and heading measured, not the ones planned.
    adaptseg::Image image = planner.image_at(shot.pose, rgb, shot.yaw_deg);
    const fs::path labels_file = s.images / "labels" / shot.file;
    if (fs::is_regular_file(labels_file)) {
      image.ground_truth = cv::imread(labels_file.string(), cv::IMREAD_UNCHANGED);
      if (image.ground_truth.type() != CV_8UC1 || image.ground_truth.size() != image.footprint_px.size())
        fail(labels_file, "must be 8-bit single-channel labels of the footprint's " +
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
  int descents = 0, limited = 0;
  for (const auto& d : planner.decisions()) {
    descents += d.decision.descend ? 1 : 0;
    limited += d.budget_limited ? 1 : 0;
  }
  std::printf("done: %zu images, %d descents, %.1f s mission time (planner's account)\n", planner.path().size(),
              descents, planner.elapsed_s());
  if (s.out.empty()) return;
  fs::create_directories(s.out);
  nlohmann::json j{{"field", info.name},
                   {"strategy", std::string(policy.name())},
                   {"schedule", adaptseg::to_string(options.schedule)},
                   {"segmenter", std::string(backend.name())},
                   {"images", planner.path().size()},
                   {"time_s", {{"total", planner.elapsed_s()}}},
                   {"decisions",
                    {{"descend", descents},
                     {"continue", static_cast<int>(planner.decisions().size()) - descents},
                     {"budget_limited", limited}}},
                   {"waypoints", wps},
                   {"adaptseg_version", adaptseg::kVersion}};
  if (options.budget_s) j["budget_s"] = *options.budget_s;
  ex::write_text(s.out / "result.json", j.dump(2) + "\n");
  ex::write_png(s.out / "map.png",
                adaptseg::render_map(planner.map().labels(), info.classes,
                                     info.name + ": " + std::string(policy.name()) + ", " +
                                         std::to_string(planner.path().size()) + " images, " +
                                         ex::fmt(planner.elapsed_s(), 0) + " s (live)"));
}

/// Runs the loop with the policy of `strategy` from `model`.
template <adaptseg::SegmentationBackend Backend>
void fly_strategy(const std::string& strategy, const adaptseg::DecisionModel& model, const ImageSetInfo& info,
                  const std::vector<PosedImage>& images, Backend& backend, const adaptseg::AdaptiveOptions& options,
                  const LiveSettings& s) {
  adaptseg::examples::check_segmenter(model, backend.name());
  if (strategy == "linear") {
    adaptseg::LinearDecision policy(model.linear);
    fly(info, images, backend, policy, options, s);
    return;
  }
  adaptseg::DecisionFunction df = model.decision_function;
  df.set_online(strategy != "nonadaptive");
  adaptseg::AdaptiveOptions o = options;
  o.schedule = adaptseg::examples::schedule_of(strategy);
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
      ->check(CLI::IsMember({"adaptive", "nonadaptive", "tour", "row", "linear"}))
      ->capture_default_str();
  app.add_option("--segmenter", segmenter, "oracle: ground-truth labels/ of the folder; erfnet: its RGB images")
      ->check(CLI::IsMember({"oracle", "erfnet"}))
      ->capture_default_str();
  app.add_option("--model-file", erfnet_dir, "ERFNet model directory (model.onnx, model.yaml) for --segmenter erfnet");
  app.add_option("--budget-s", budget_s, "mission-time budget [s] (never exceeded)");
  app.add_option("--pose-tolerance-m", s.tolerance_m, "how far [m] a recorded pose may be from the waypoint")
      ->capture_default_str();
  app.add_option("--seg-time-s", seg_time_s, "fixed segmentation time per image [s] (default: measured)");
  app.add_option("--plan-time-s", plan_time_s, "fixed planning time per waypoint [s] (default: measured)");
  app.add_option("--out", s.out, "output directory for result.json and map.png");
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;

  try {
    const adaptseg::DecisionModel model = adaptseg::DecisionModel::load(model_file);
    if (!record_from.empty()) {
      const adaptseg::Field field = ex::load_field_spec(record_from);
      model.check_classes(field);
      const std::vector<int> interest = field.class_indices(model.interest);
      model.check_compatible(field, interest);
      const adaptseg::AdaptiveOptions o = model_options(model, interest);
      adaptseg::OracleSegmenter oracle(field.num_classes());
      adaptseg::DecisionFunction df = model.decision_function;
      const adaptseg::AdaptivePlanner planner(adaptseg::SurveyArea::of(field), oracle, df, o);
      const auto waypoints = planner.reachable_waypoints();
      write_image_set(s.images, field, model, waypoints, record_yaw_deg);
      std::printf("%s: recorded %zu images (%zu top-level, %zu for the descents) -> %s\n", field.name().c_str(),
                  waypoints.size(), planner.top_level().size(), waypoints.size() - planner.top_level().size(),
                  s.images.string().c_str());
      return 0;
    }

    const ImageSetInfo info = read_image_set_info(s.images);
    const std::vector<PosedImage> images = read_poses(s.images);
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
    adaptseg::AdaptiveOptions options = model_options(model, interest);
    options.mission.fixed_segmentation_time_s = seg_time_s;
    options.mission.fixed_planning_time_s = plan_time_s;
    options.budget_s = budget_s;
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
      params.name = adaptseg::examples::network_name(erfnet_dir / "model.onnx", erfnet_dir / "model.yaml");
      adaptseg::ErfnetSegmenter erfnet(erfnet_dir, params);
      fly_strategy(strategy, model, info, images, erfnet, options, s);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_live: error: %s\n", e.what());
    return 2;
  }
}
