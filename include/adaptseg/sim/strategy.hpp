#pragma once
/// @file
/// The strategies a mission can fly, one row each (kStrategyTable), and run_strategy(), which
/// flies one of them over a field in simulation: the experiment layer every program and study
/// shares (the paper's comparison of §5: lawnmowers at fixed altitudes against the adaptive
/// planner and its variants).

#include <adaptseg/core/descent_schedule.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/mission.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// What a strategy flies.
enum class StrategyPolicy {
  lawnmower,          ///< one fixed GSD, no decision
  decision_function,  ///< the calibrated decision function of a decision model (paper §3.2)
  linear,             ///< the conference version's linear rule, from the model's σ range
};

/// Every StrategyPolicy by name (the `policy` column of strategies_csv()).
inline constexpr std::array<detail::NamedValue<StrategyPolicy>, 3> kStrategyPolicies{{
    {StrategyPolicy::lawnmower, "lawnmower"},
    {StrategyPolicy::decision_function, "decision_function"},
    {StrategyPolicy::linear, "linear"},
}};

/// One row of the table of strategies: everything a program or a figure needs to know about a
/// strategy. A new strategy is a new row of kStrategyTable; the programs, the benchmarks and the
/// figures (through strategies_csv()) read it.
struct StrategyInfo {
  const char* name;          ///< on the command line and in results.csv
  StrategyPolicy policy;     ///< what it flies
  DescentSchedule schedule;  ///< when the chosen descents are flown (not lawnmower)
  bool online;               ///< decision_function: learns in flight (DecisionFunction::set_online)
  const char* label;         ///< in the figures' legends

  /// Flies a decision model (every strategy but the lawnmower), which it needs.
  [[nodiscard]] constexpr bool flies_model() const noexcept { return policy != StrategyPolicy::lawnmower; }
};

/// Every strategy, in the order a comparison flies them on a test field (the lawnmowers first).
/// adaptive / nonadaptive: the decision model with online updates on / off, descents flown at
/// once (the paper); tour: adaptive, but the whole top level first and the chosen descents after
/// it as one low-altitude tour where that is cheaper; row: the same per lawnmower row, staying low
/// between a row's inspections; linear: the conference version's rule.
inline constexpr std::array<StrategyInfo, 6> kStrategyTable{{
    {"lawnmower", StrategyPolicy::lawnmower, DescentSchedule::immediate, false, "lawnmower (fixed altitude)"},
    {"nonadaptive", StrategyPolicy::decision_function, DescentSchedule::immediate, false, "non-adaptive"},
    {"adaptive", StrategyPolicy::decision_function, DescentSchedule::immediate, true, "adaptive"},
    {"tour", StrategyPolicy::decision_function, DescentSchedule::tour, true, "tour (at once or after the survey)"},
    {"row", StrategyPolicy::decision_function, DescentSchedule::row, true, "row (at once or after each row)"},
    {"linear", StrategyPolicy::linear, DescentSchedule::immediate, false, "linear (ECMR 2021)"},
}};

/// The name of the fixed-altitude lawnmower (the yardstick, flown at several GSDs).
inline constexpr const char* kLawnmowerStrategy = kStrategyTable[0].name;
static_assert(kStrategyTable[0].policy == StrategyPolicy::lawnmower, "the lawnmower is the table's first row");

/// The names of the strategies (all of them, or only those that fly a decision model), in the
/// table's order.
[[nodiscard]] inline std::vector<std::string> strategy_names(bool model_based_only = false) {
  std::vector<std::string> names;
  for (const auto& s : kStrategyTable)
    if (!model_based_only || s.flies_model()) names.emplace_back(s.name);
  return names;
}

/// The row of strategy `name`.
/// @throws std::invalid_argument naming every strategy for an unknown name.
[[nodiscard]] inline const StrategyInfo& strategy_info(std::string_view name) {
  return detail::row_named(kStrategyTable, name, "strategy");
}

/// The table as CSV (`name,policy,schedule,online,label`), which a comparison writes beside its
/// results for the figures (python/adaptseg_tools/plot_evaluation.py).
[[nodiscard]] inline std::string strategies_csv() {
  std::string out = "name,policy,schedule,online,label\n";
  for (const auto& s : kStrategyTable)
    out += std::string(s.name) + ',' + detail::name_of(kStrategyPolicies, s.policy, "strategy policy") + ',' +
           to_string(s.schedule) + ',' + (s.online ? "true" : "false") + ",\"" + s.label + "\"\n";
  return out;
}

/// Throws unless `model` was calibrated with the backend named `segmenter` (a network's name
/// holds its weights' identity, so another network, or the same at another temperature, is
/// refused whatever its folder is called).
/// @throws std::invalid_argument naming both.
inline void check_segmenter(const DecisionModel& model, const std::string& segmenter) {
  if (model.segmenter != segmenter)
    throw std::invalid_argument("the decision model was calibrated with segmenter '" + model.segmenter +
                                "' but the mission uses '" + segmenter +
                                "': calibrate with the backend the mission flies (adaptseg_calibrate --segmenter, "
                                "--network)");
}

/// One flown strategy: the mission, and for those that fly a decision model its decisions.
struct StrategyRun {
  MissionResult mission;
  std::optional<std::vector<DecisionRecord>> decisions;
  std::vector<RealisedDescent> realised{};  ///< simulation: what each descent gained
};

/// Flies `strategy` (a name of kStrategyTable) over `field` in simulation. The lawnmower: at
/// `gsd_cm`, with `overlap`. The others: from `model`'s top GSD with its candidates, camera and
/// timing (those of `options` are replaced by the model's), within `budget_s` if set; without
/// labels of interest in `options`, the model's. The error messages name the example programs'
/// flags (`--gsd`, `--overlap`, `--decision-model`), which pass these values on unchanged.
/// @throws std::invalid_argument for an unknown strategy, a lawnmower without a finite positive
///         GSD or finer than the field's, an overlap with another strategy, a model-based
///         strategy without a model or with a model calibrated for another backend or another
///         field's classes, and the reasons of the missions.
template <SegmentationBackend Backend>
[[nodiscard]] StrategyRun run_strategy(const Field& field, Backend& backend, const std::string& strategy, double gsd_cm,
                                       const DecisionModel* model, MissionOptions options,
                                       std::optional<double> budget_s, LawnmowerOverlap overlap = {}) {
  const StrategyInfo& info = strategy_info(strategy);
  if (!info.flies_model()) {
    if (gsd_cm == 0.0) throw std::invalid_argument("--strategy lawnmower needs --gsd (a positive GSD in cm/px)");
    if (!(gsd_cm > 0.0) || !std::isfinite(gsd_cm))
      throw std::invalid_argument("--gsd must be a finite positive GSD in cm/px (got " + detail::format_number(gsd_cm) +
                                  ")");
    if (gsd_cm < field.gsd_cm() * (1.0 - 1e-9))
      throw std::invalid_argument("--gsd " + std::to_string(gsd_cm) + " cm/px is finer than field '" + field.name() +
                                  "' (" + std::to_string(field.gsd_cm()) + " cm/px)");
    return {run_lawnmower_mission(field, gsd_cm, backend, options, overlap), std::nullopt};
  }
  if (overlap != LawnmowerOverlap{})
    throw std::invalid_argument(
        "--overlap applies to --strategy lawnmower only (the decision function's regions "
        "are the paper's non-overlapping top-level footprints)");
  if (model == nullptr)
    throw std::invalid_argument("--strategy " + strategy + " needs --decision-model (from adaptseg_calibrate)");
  check_segmenter(*model, backend.name());
  // Without labels of interest, the model's (its GPs were fitted for them).
  model->check_classes(field);
  if (options.interest.empty()) options.interest = field.class_indices(model->interest);
  model->check_compatible(field, options.interest);
  AdaptiveOptions ao = model->adaptive_options(std::move(options), budget_s);
  if (info.policy == StrategyPolicy::linear) {
    LinearDecision policy(model->linear);
    auto r = run_adaptive_mission(field, backend, policy, ao, policy.name());
    return {std::move(r.mission), std::move(r.decisions), std::move(r.realised)};
  }
  DecisionFunction df = model->decision_function;
  df.set_online(info.online);
  ao.schedule = info.schedule;
  auto r = run_adaptive_mission(field, backend, df, ao, strategy);
  return {std::move(r.mission), std::move(r.decisions), std::move(r.realised)};
}

}  // namespace adaptseg
