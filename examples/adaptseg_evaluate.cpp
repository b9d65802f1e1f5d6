// adaptseg_evaluate: the paper's experiment (§5). Calibrates the decision function on a
// training field (or loads a model), then flies every strategy over every test field and
// writes results.csv, per_image.csv, per-mission results and the figures.
//
//   adaptseg_evaluate --train examples/data/weedmap-000:0,0,0.5,1
//                     --test examples/data/weedmap-000:0.5,0,1,1 --segmenter oracle --out out/eval
//   adaptseg_evaluate --train examples/data/dubai-tile-4 --test examples/data/dubai-tile-6
//                     --segmenter network --network examples/models/ensemble-dubai --out out/eval-ensemble

#include "common/cell_csv.hpp"
#include "common/host_memory.hpp"
#include "common/segmenters.hpp"
#include "common/strategies.hpp"

#include <adaptseg/sim/decision_table.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using adaptseg::examples::fmt;

std::string csv(const std::string& s) { return adaptseg::examples::csv_field(s); }

std::string csv(const std::optional<double>& v) { return v ? fmt(*v, 6) : ""; }

/// Legs of the mission between waypoints at different altitudes (climbs and descents).
int altitude_changes(const adaptseg::MissionResult& m) {
  int n = 0;
  for (std::size_t k = 1; k < m.waypoints.size(); ++k)
    n += m.waypoints[k].waypoint.position.z() != m.waypoints[k - 1].waypoint.position.z() ? 1 : 0;
  return n;
}

/// A field's name as a folder name: "weedmap-rededge-000[0.5,0,1,1]" (a region of a field)
/// -> "weedmap-rededge-000_region_0.5-0-1-1"; other characters than letters, digits, '-' and
/// '.' -> '_'. python/adaptseg_tools/plot_evaluation.py's slug() is the same function.
std::string slug(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '[')
      out += "_region_";
    else if (c == ',')
      out += '-';
    else if (c != ']')
      out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' ? c : '_';
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  adaptseg::examples::keep_freed_memory();  // each mission's maps reuse the last one's pages
  CLI::App app{"Run every strategy on test fields and write the paper's tables and figures.", "adaptseg_evaluate"};
  std::vector<std::string> train_specs;
  std::vector<std::string> test_specs;
  fs::path out_dir, decision_model;
  std::vector<double> lawnmower_factors{1.0, 1.5, 2.0, 2.5, 3.0};
  std::optional<double> budget_s;
  bool no_plots = false;
  adaptseg::examples::CalibrationCli calibration;
  adaptseg::examples::CommonOptions common;
  adaptseg::examples::SegmenterOptions segmenter;
  app.add_option("--train", train_specs,
                 "training field DIR[:x0,y0,x1,y1] (decision-function initialisation); repeatable");
  CLI::Option* model_opt =
      app.add_option("--decision-model", decision_model, "use this decision model instead of calibrating on --train");
  adaptseg::examples::accept_old_spelling(app, model_opt, "--model", decision_model);
  app.add_option("--test", test_specs, "test field DIR[:x0,y0,x1,y1]; repeatable")->required();
  app.add_option("--out", out_dir, "output directory")->required();
  app.add_option("--lawnmower-factors", lawnmower_factors, "lawnmower GSDs as multiples of each field's GSD")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--budget-s", budget_s, "mission-time budget [s] for the adaptive strategies");
  calibration.add_to(app);
  calibration.exclude(model_opt);  // the model file fixes them (and --model, its old spelling, alike)
  app.add_flag("--no-plots", no_plots, "do not run the plotting script");
  common.add_to(app);
  segmenter.add_to(app);
  segmenter.add_calibration_networks_to(app, {model_opt});
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;

  bool progress_open = false;  // a progress line on stderr waits for its end
  try {
    if (train_specs.empty() == decision_model.empty())
      throw std::invalid_argument("give exactly one of --train (calibrate) and --decision-model (load)");
    adaptseg::examples::check_gsd_factors(lawnmower_factors, "--lawnmower-factors");
    if (lawnmower_factors.size() < 2 || !std::is_sorted(lawnmower_factors.begin(), lawnmower_factors.end()) ||
        std::adjacent_find(lawnmower_factors.begin(), lawnmower_factors.end()) != lawnmower_factors.end())
      throw std::invalid_argument(
          "--lawnmower-factors needs at least two factors in increasing order (the last is the adaptive top level, "
          "the others its candidates)");
    std::vector<adaptseg::Field> tests;
    for (const auto& spec : test_specs) tests.push_back(adaptseg::examples::load_field_spec(spec));
    // Labels of interest: --interest, else the first test field's default.
    std::vector<std::string> interest_names = common.interest_names;
    if (interest_names.empty())
      for (int i : tests.front().interest())
        interest_names.push_back(tests.front().classes()[static_cast<std::size_t>(i)].name);
    if (interest_names.empty()) throw std::invalid_argument("no labels of interest: pass --interest");
    common.interest_names = interest_names;
    fs::create_directories(out_dir);

    const auto wall0 = std::chrono::steady_clock::now();
    const auto elapsed = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    };
    std::optional<adaptseg::DecisionModel> loaded;
    if (!decision_model.empty()) {
      loaded = adaptseg::DecisionModel::load(decision_model);
      for (const auto& t : tests) loaded->check_classes(t);
      common.check_camera_matches(app, *loaded);
    } else {
      std::vector<adaptseg::Field> trains;
      for (const auto& spec : train_specs) trains.push_back(adaptseg::examples::load_field_spec(spec));
      segmenter.validate();
      std::vector<std::size_t> grounds;
      const auto networks = segmenter.network_per_field(trains, &grounds);  // its mistakes before any work
      const adaptseg::Field& train = trains.front();
      adaptseg::CalibrationOptions co;
      co.adaptive.mission = common.resolve(train);
      const double g0 = train.gsd_cm();
      co.adaptive.top_gsd_cm = lawnmower_factors.back() * g0;
      for (std::size_t k = 0; k + 1 < lawnmower_factors.size(); ++k)
        co.adaptive.candidate_gsd_cm.push_back(lawnmower_factors[k] * g0);
      for (double f : lawnmower_factors) co.lawnmower_gsd_cm.push_back(f * g0);
      calibration.apply(co, common, g0);
      co.field_grounds = grounds;
      std::string names;
      for (const auto& f : trains) names += (names.empty() ? "" : ", ") + f.name();
      std::fprintf(stderr, "[%6.1f s] calibrating on %s ...\n", elapsed(), names.c_str());
      const auto cal = segmenter.with_backend(train, co.adaptive.mission.camera, [&](auto& backend) {
        adaptseg::CalibrationResult c = adaptseg::examples::calibrate_fields(segmenter, trains, networks, backend, co);
        loaded = adaptseg::make_decision_model(trains, backend.name(), co, c);
        return c;
      });
      std::fprintf(stderr, "[%6.1f s] calibrated: %zu samples, %s, train front margin %+.4f, %d descents\n", elapsed(),
                   cal.samples.size(), cal.trials.front().description.c_str(), loaded->train_front_margin,
                   cal.trials.front().descents);
      // Every setting the calibration tried, with each training field's margin: why this one.
      for (const auto& t : cal.trials) {
        std::fprintf(stderr, "           tried %s: front margin %+.4f, %d descents, per field", t.description.c_str(),
                     t.front_margin, t.descents);
        for (double m : t.margins) std::fprintf(stderr, " %+.4f", m);
        std::fprintf(stderr, "\n");
      }
      adaptseg::examples::print_field_segmenters(*loaded);
    }
    const adaptseg::DecisionModel& model = *loaded;
    model.save(out_dir / "model.yaml");

    std::ofstream results(out_dir / "results.csv"), per_image(out_dir / "per_image.csv"),
        decisions_csv(out_dir / "decisions.csv");
    results << "field,strategy,gsd_cm,miou_interest,miou_all,time_total,time_flight,time_segmentation,"
               "time_planning,images,front_margin,descents,altitude_changes,curve_front_margin\n";
    per_image
        << "field,strategy,gsd_cm,image,level,image_gsd_cm,sigma,image_miou_interest,image_miou_all,truth_sigma\n";
    decisions_csv << adaptseg::decisions_csv_header();
    // The strategies that fly the model, after the lawnmowers, in the table's order on every
    // test field; the table beside the results for the figures.
    const std::vector<std::string> model_strategies = adaptseg::strategy_names(true);
    adaptseg::examples::write_text(out_dir / "strategies.csv", adaptseg::strategies_csv());
    const std::size_t total_runs = tests.size() * (lawnmower_factors.size() + model_strategies.size());
    std::size_t run_index = 0;
    for (const auto& field : tests) {
      // Every strategy, the lawnmowers too, flies the model's camera, speed limits and map fusion (equal to
      // the options when the model is calibrated here; checked against explicit ones above).
      adaptseg::MissionOptions mo = common.resolve(field);
      mo.camera = model.camera;
      mo.timing = model.timing;
      mo.map_fusion = model.map_fusion;
      struct Row {
        std::string strategy;
        double gsd;
        adaptseg::StrategyRun run;
      };
      std::vector<Row> rows;
      std::vector<adaptseg::CurvePoint> curve;
      const auto fly = [&](const std::string& strategy, double gsd) {  // gsd: lawnmower GSD, or the model's top
        ++run_index;
        const bool flies_model = adaptseg::strategy_info(strategy).flies_model();
        std::fprintf(stderr, "[%6.1f s] (%zu/%zu) %s: %s%s ...", elapsed(), run_index, total_runs, field.name().c_str(),
                     strategy.c_str(), flies_model ? "" : (" " + fmt(gsd, 2) + " cm/px").c_str());
        progress_open = true;
        auto run = segmenter.with_backend(field, mo.camera, [&](auto& backend) {
          return adaptseg::run_strategy(field, backend, strategy, gsd, &model, mo,
                                        flies_model ? budget_s : std::nullopt);
        });
        std::fprintf(stderr, " %zu images, %.1f s, mIoU %.4f\n", run.mission.waypoints.size(), run.mission.total_s(),
                     run.mission.miou_interest().value_or(NAN));
        progress_open = false;
        // A model-based strategy reports the GSD its top level flew at (the policy may choose
        // another than the model's nominal one: ChoosesTopLevel).
        if (flies_model)
          for (const auto& w : run.mission.waypoints)
            if (w.level == 0) {
              gsd = w.waypoint.gsd_cm;
              break;
            }
        rows.push_back({strategy, gsd, std::move(run)});
      };
      for (double f : lawnmower_factors) {
        fly(adaptseg::kLawnmowerStrategy, f * field.gsd_cm());
        curve.push_back({rows.back().run.mission.total_s(), rows.back().run.mission.miou_interest().value_or(0.0)});
      }
      for (const std::string& s : model_strategies) fly(s, model.top_gsd_cm);

      const fs::path field_dir = out_dir / slug(field.name());
      for (const auto& row : rows) {
        const auto& m = row.run.mission;
        // Against the curve's upper envelope (the honest margin), and against the curve itself,
        // which differs where a lawnmower is slower and maps worse than a faster one.
        const double margin = adaptseg::front_margin(curve, m.total_s(), m.miou_interest().value_or(0.0));
        const double curve_margin = adaptseg::curve_front_margin(curve, m.total_s(), m.miou_interest().value_or(0.0));
        const int descents = row.run.decisions
                                 ? static_cast<int>(std::count_if(row.run.decisions->begin(), row.run.decisions->end(),
                                                                  [](const auto& d) { return d.decision.descend; }))
                                 : 0;
        results << csv(field.name()) << ',' << row.strategy << ',' << fmt(row.gsd, 3) << ',' << csv(m.miou_interest())
                << ',' << csv(m.miou_all()) << ',' << fmt(m.total_s(), 3) << ',' << fmt(m.time.flight_s, 3) << ','
                << fmt(m.time.segmentation_s, 4) << ',' << fmt(m.time.planning_s, 4) << ',' << m.waypoints.size() << ','
                << fmt(margin, 6) << ',' << descents << ',' << altitude_changes(m) << ',' << fmt(curve_margin, 6)
                << '\n';
        for (std::size_t k = 0; k < m.waypoints.size(); ++k) {
          const auto& w = m.waypoints[k];
          per_image << csv(field.name()) << ',' << row.strategy << ',' << fmt(row.gsd, 3) << ',' << k << ',' << w.level
                    << ',' << fmt(w.waypoint.gsd_cm, 3) << ',' << fmt(w.semantic_ratio, 6) << ','
                    << csv(w.image_miou_interest) << ',' << csv(w.image_miou_all) << ',' << csv(w.truth_ratio) << '\n';
        }
        if (row.run.decisions)
          adaptseg::write_decisions_csv(decisions_csv, field.name(), row.strategy, *row.run.decisions,
                                        row.run.realised);
        const bool lawnmower = !adaptseg::strategy_info(row.strategy).flies_model();
        const std::string name = row.strategy + (lawnmower ? "-" + fmt(row.gsd, 2) : "");
        const fs::path dir = field_dir / name;
        fs::create_directories(dir);
        auto json = adaptseg::examples::result_json(field, m, mo, row.run.decisions ? &*row.run.decisions : nullptr);
        json["gsd_cm"] = row.gsd;
        json["front_margin"] = margin;
        json["curve_front_margin"] = curve_margin;
        adaptseg::examples::write_text(dir / "result.json", json.dump(2) + "\n");
        std::vector<adaptseg::Waypoint> path;
        for (const auto& w : m.waypoints) path.push_back(w.waypoint);
        const std::string label = field.name() + ": " + name;
        adaptseg::examples::write_png(
            dir / "path.png",
            adaptseg::render_path(
                field, path, label + ", " + std::to_string(path.size()) + " images, " + fmt(m.total_s(), 0) + " s"));
        adaptseg::examples::write_png(
            dir / "map.png",
            adaptseg::render_map_comparison(field, m.fused_labels,
                                            label + " | mIoU interest " + fmt(m.miou_interest().value_or(NAN), 3) +
                                                ", front margin " + fmt(margin, 3)));
        adaptseg::examples::write_geo_maps(field, m.fused_labels, m.fused_gsd_cm, dir);
      }
      results.flush();
      per_image.flush();
      decisions_csv.flush();
    }
    if (!results || !per_image || !decisions_csv)
      throw std::runtime_error("error writing the CSV files in " + out_dir.string());
    results.close();
    per_image.close();
    decisions_csv.close();
    std::fprintf(stderr, "[%6.1f s] wrote %s/results.csv, per_image.csv, decisions.csv and per-mission results\n",
                 elapsed(), out_dir.string().c_str());
    if (!no_plots) {
      // The package from the source tree, ahead of any PYTHONPATH of the caller's.
      const std::string cmd = "PYTHONPATH='" + std::string(ADAPTSEG_PYTHON_TOOLS_DIR) +
                              "'${PYTHONPATH:+:$PYTHONPATH} /usr/bin/python3 -m adaptseg_tools.plot_evaluation '" +
                              out_dir.string() + "'";
      if (std::system(cmd.c_str()) != 0)
        std::fprintf(stderr, "adaptseg_evaluate: warning: plotting failed; run: %s\n", cmd.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%sadaptseg_evaluate: error: %s\n", progress_open ? "\n" : "", e.what());
    return 2;
  }
}
