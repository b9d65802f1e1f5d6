// adaptseg_mission: fly one mission over a field in simulation and score it.
//
//   adaptseg_mission --field examples/data/weedmap-000 --strategy lawnmower --gsd 3.0
//                    --segmenter oracle --out out/lawnmower-3.0
//   adaptseg_mission --field examples/data/dubai-tile-6 --strategy lawnmower --gsd 15
//                    --segmenter network --network examples/models/ensemble-dubai --out out/ensemble-15
//   adaptseg_mission --field DIR --strategy adaptive --decision-model model.yaml --out OUT [--budget-s 900]
//
// Writes OUT/result.json (scores, time, waypoints, decisions), OUT/path.png and OUT/map.png
// (and OUT/map.tif + OUT/map_gsd.tif in the field's CRS for a georeferenced field, built with GDAL);
// with --export plan,wpl,geojson also OUT/mission.{plan,waypoints,geojson}.

#include "common/export.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <adaptseg/planner.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  CLI::App app{"Fly one UAV mapping mission over a field (simulated) and score it.", "adaptseg_mission"};
  std::string field_spec;
  fs::path out_dir, decision_model;
  std::string strategy = adaptseg::kLawnmowerStrategy;
  double gsd_cm = 0.0;
  std::optional<double> budget_s;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;
  app.add_option("--field", field_spec, "field directory (field.yaml, labels.png, [image]), optionally DIR:x0,y0,x1,y1")
      ->required();
  app.add_option("--strategy", strategy, "mission strategy")
      ->check(CLI::IsMember(adaptseg::strategy_names()))
      ->capture_default_str();
  app.add_option("--gsd", gsd_cm, "lawnmower GSD [cm/px] (>= the field's GSD)");
  CLI::Option* model_opt = app.add_option("--decision-model", decision_model,
                                          "decision model from adaptseg_calibrate (adaptive, nonadaptive, linear)");
  adaptseg::examples::accept_old_spelling(app, model_opt, "--model", decision_model);
  app.add_option("--budget-s", budget_s,
                 "mission-time budget [s] for adaptive strategies: a descent is flown only where it and the rest fit, "
                 "each image at a bound of its processing learned in flight, and cut short where they no longer do");
  std::string overlap_text;
  app.add_option("--overlap", overlap_text,
                 "OVERLAP or ALONG,ACROSS: image overlap of the lawnmower strategy, fractions of a footprint in "
                 "[0, 0.9] along and across its rows (default 0: the paper's footprints that only touch)");
  app.add_option("--out", out_dir, "output directory")->required();
  common.add_to(app);
  segmenter.add_to(app);
  adaptseg::examples::ExportCli exports;
  exports.add_to(app);
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;

  try {
    const adaptseg::Field field = exports.load_field(field_spec);
    adaptseg::MissionOptions options = common.resolve(field);
    std::optional<adaptseg::DecisionModel> model;
    if (!decision_model.empty()) model = adaptseg::DecisionModel::load(decision_model);
    const bool lawnmower = !adaptseg::strategy_info(strategy).flies_model();
    if (!lawnmower && model) common.check_camera_matches(app, *model);
    if (budget_s && lawnmower) throw std::invalid_argument("--budget-s applies to adaptive strategies only");
    const adaptseg::LawnmowerOverlap overlap =
        overlap_text.empty() ? adaptseg::LawnmowerOverlap{} : adaptseg::examples::parse_overlap(overlap_text);
    if (!lawnmower && overlap != adaptseg::LawnmowerOverlap{})
      throw std::invalid_argument("--overlap applies to --strategy lawnmower only");
    segmenter.validate();
    const auto camera = !lawnmower && model ? model->camera : options.camera;
    // Before flying: a mission whose export would fly above the ceiling is refused.
    if (lawnmower && gsd_cm > 0.0) exports.check_altitude(gsd_cm, camera);
    if (!lawnmower && model) exports.check_altitude(model->top_gsd_cm, camera);
    const auto run = segmenter.with_backend(field, camera, [&](auto& backend) {
      return adaptseg::run_strategy(field, backend, strategy, gsd_cm, model ? &*model : nullptr, options, budget_s,
                                    overlap);
    });
    const adaptseg::MissionResult& result = run.mission;
    if (!lawnmower)
      options.camera = model->camera, options.timing = model->timing, options.map_fusion = model->map_fusion;

    fs::create_directories(out_dir);
    auto json = adaptseg::examples::result_json(field, result, options, run.decisions ? &*run.decisions : nullptr);
    if (lawnmower) {
      json["gsd_cm"] = gsd_cm;
      json["overlap"] = {{"along", overlap.along}, {"across", overlap.across}};
    }
    if (budget_s) json["budget_s"] = *budget_s;
    adaptseg::examples::write_text(out_dir / "result.json", json.dump(2) + "\n");
    exports.write(field, result, options, out_dir);
    std::vector<adaptseg::Waypoint> path;
    for (const auto& w : result.waypoints) path.push_back(w.waypoint);
    const std::string what = lawnmower ? strategy + " at " + adaptseg::examples::fmt(gsd_cm, 2) + " cm/px" : strategy;
    const auto mi = result.miou_interest();
    const auto ma = result.miou_all();
    adaptseg::examples::write_png(
        out_dir / "path.png",
        adaptseg::render_path(field, path,
                              field.name() + ": " + what + ", " + std::to_string(path.size()) + " images, " +
                                  adaptseg::examples::fmt(result.total_s(), 0) + " s"));
    adaptseg::examples::write_png(out_dir / "map.png", adaptseg::render_map_comparison(
                                                           field, result.fused_labels,
                                                           field.name() + ": " + what + " | mIoU interest " +
                                                               adaptseg::examples::fmt(mi.value_or(NAN), 3) + ", all " +
                                                               adaptseg::examples::fmt(ma.value_or(NAN), 3)));
    adaptseg::examples::write_geo_maps(field, result.fused_labels, result.fused_gsd_cm, out_dir);
    std::printf(
        "%s: %s images=%zu time=%.1f s (flight %.1f, segmentation %.2f, planning %.4f) "
        "mIoU interest=%.4f all=%.4f -> %s\n",
        field.name().c_str(), what.c_str(), result.waypoints.size(), result.total_s(), result.time.flight_s,
        result.time.segmentation_s, result.time.planning_s, mi.value_or(NAN), ma.value_or(NAN),
        out_dir.string().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "adaptseg_mission: error: %s\n", e.what());
    return 2;
  }
}
