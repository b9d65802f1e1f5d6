// The planner's own time per waypoint: everything AdaptivePlanner does between two images
// (report() of an image with its segmentation given, then next()), over whole adaptive missions
// on a field, flown with a calibrated decision model. The segmentation is made before the clock
// starts (by the oracle or a network), so the network's time is not in it; the simulated camera
// and the scoring are outside it too.
//
//   bench_planner --decision-model MODEL.yaml --field DIR [--field DIR ...] [--segmenter network --network NET]
//                 [--planner-threads N] [--repeat R] [--strategy adaptive|nonadaptive|tour|row]
//
// Prints one Markdown row per field: waypoints, descents / decisions, median / 95th percentile /
// max of the step [ms], the top-level steps' and the descent steps' medians, the mission's total
// of steps, and the median set-up before the first waypoint (planning the top level and the
// lawnmowers a front-aware rule compares with; once per mission, before take-off).
// benchmarks/bench_planner.sh calibrates the models and runs it (docs/benchmarks.md).
#include "../examples/common/segmenters.hpp"
#include "../examples/common/strategies.hpp"

#include <adaptseg/planner.hpp>

#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

/// Per-waypoint planner steps [ms] of one mission, split by the level of the image reported,
/// and the planner's set-up before the first waypoint (constructor and first next()).
struct Steps {
  std::vector<double> all, top, descent, setup;
  int decisions = 0, descents = 0;
};

template <class Backend>
Steps fly(const adaptseg::Field& field, Backend& backend, const adaptseg::DecisionModel& model,
          const adaptseg::StrategyInfo& strategy) {
  using namespace adaptseg;
  MissionOptions mo;
  mo.interest = field.class_indices(model.interest);
  mo.fixed_segmentation_time_s = 0.1;  // the budget and the time account as in the oracle sweep
  mo.fixed_planning_time_s = 0.0;
  AdaptiveOptions ao = model.adaptive_options(mo, std::nullopt);
  ao.schedule = strategy.schedule;
  DecisionFunction policy = model.decision_function;
  policy.set_online(strategy.online);
  Mission<Backend> mission(field, backend, ao.mission, std::string(strategy.name));
  Steps out;
  const auto t_start = std::chrono::steady_clock::now();
  AdaptivePlanner<DecisionFunction> planner(SurveyArea::of(field), policy, ao);
  auto w = planner.next();
  out.setup.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count());
  while (w) {
    // Segmented and checked by the mission, not timed.
    const auto visit = mission.visit(w->waypoint, w->level, planner.wants_probabilities());
    const auto t0 = std::chrono::steady_clock::now();
    const PlannerStep step =
        planner.report(visit.image, visit.segmentation, visit.record->segmentation_s, mission.elapsed_s());
    w = planner.next();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    out.all.push_back(ms);
    (step.waypoint.level == 0 ? out.top : out.descent).push_back(ms);
    if (step.decision) {
      ++out.decisions;
      out.descents += step.decision->decision.descend ? 1 : 0;
    }
    mission.charge_planning(planner.take_planning_s());
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  CLI::App app{"The planner's own time per waypoint over adaptive missions (segmentation given).", "bench_planner"};
  fs::path model_path;
  std::vector<std::string> fields;
  int threads = 1, repeat = 3;
  std::string strategy = "adaptive", label;
  adaptseg::examples::SegmenterOptions segmenter;
  app.add_option("--decision-model", model_path, "decision model (adaptseg_calibrate)")->required();
  app.add_option("--field", fields, "field to fly (repeatable)")->required();
  app.add_option("--planner-threads", threads,
                 "OpenCV threads of the planner (cv::setNumThreads; --threads: the network's)")
      ->capture_default_str();
  app.add_option("--repeat", repeat, "missions per field (the steps of all are pooled)")->capture_default_str();
  app.add_option("--strategy", strategy, "decision strategy")
      ->check(CLI::IsMember(adaptseg::strategy_names(true)))
      ->capture_default_str();
  app.add_option("--label", label, "first column of the rows (default: the segmenter)");
  segmenter.add_to(app);
  if (const auto code = adaptseg::examples::parse_command_line(app, argc, argv)) return *code;
  try {
    const adaptseg::DecisionModel model = adaptseg::DecisionModel::load(model_path);
    const auto& info = adaptseg::strategy_info(strategy);
    if (info.policy != adaptseg::StrategyPolicy::decision_function)
      throw std::invalid_argument("--strategy must fly the decision function");
    if (label.empty()) label = segmenter.name;
    Steps everything;  // every field's steps pooled: the row "all" when there are several
    const auto row = [&](const std::string& name, const Steps& pooled) {
      double total = 0.0;
      for (double v : pooled.all) total += v;
      std::printf("| %s | %s | %d | %zu | %d / %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f | %.1f |\n", label.c_str(),
                  name.c_str(), threads, pooled.all.size() / static_cast<std::size_t>(repeat), pooled.descents,
                  pooled.decisions, percentile(pooled.all, 0.5), percentile(pooled.all, 0.95),
                  percentile(pooled.all, 1.0), percentile(pooled.top, 0.5), percentile(pooled.descent, 0.5),
                  total / repeat, percentile(pooled.setup, 0.5));
      std::fflush(stdout);
    };
    for (const std::string& spec : fields) {
      const adaptseg::Field field = adaptseg::examples::load_field_spec(spec);
      Steps pooled;
      segmenter.with_backend(field, model.camera, [&](auto& backend) {
        for (int r = 0; r < repeat; ++r) {
          cv::setNumThreads(threads);
          auto s = fly(field, backend, model, info);
          pooled.all.insert(pooled.all.end(), s.all.begin(), s.all.end());
          pooled.top.insert(pooled.top.end(), s.top.begin(), s.top.end());
          pooled.descent.insert(pooled.descent.end(), s.descent.begin(), s.descent.end());
          pooled.setup.insert(pooled.setup.end(), s.setup.begin(), s.setup.end());
          pooled.decisions = s.decisions, pooled.descents = s.descents;
        }
        return 0;
      });
      row(field.name(), pooled);
      for (auto part : {&Steps::all, &Steps::top, &Steps::descent, &Steps::setup})
        (everything.*part).insert((everything.*part).end(), (pooled.*part).begin(), (pooled.*part).end());
      everything.decisions += pooled.decisions, everything.descents += pooled.descents;
    }
    if (fields.size() > 1) row("all " + std::to_string(fields.size()) + " fields", everything);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_planner: error: %s\n", e.what());
    return 2;
  }
}
