// run_strategy, compiled once for every example program (the adaptseg_examples_common library):
// the planner and its policies are instantiated here for AnyBackend alone.

#include "strategies.hpp"

#include "segmenters.hpp"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace adaptseg::examples {

StrategyRun run_strategy(const Field& field, AnyBackend& backend, const std::string& strategy, double gsd_cm,
                         const DecisionModel* model, MissionOptions options, std::optional<double> budget_s,
                         LawnmowerOverlap overlap) {
  const StrategyInfo& info = strategy_info(strategy);
  if (info.policy == StrategyPolicy::lawnmower) {
    if (gsd_cm == 0.0) throw std::invalid_argument("--strategy lawnmower needs --gsd (a positive GSD in cm/px)");
    if (!(gsd_cm > 0.0) || !std::isfinite(gsd_cm))
      throw std::invalid_argument("--gsd must be a finite positive GSD in cm/px (got " + fmt(gsd_cm, 3) + ")");
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
  // Without --interest, the model's labels of interest (its GPs were fitted for them).
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

}  // namespace adaptseg::examples
