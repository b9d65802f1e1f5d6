#pragma once
// Running any strategy by name, and parsing field specifications, for the example programs.

#include "cli.hpp"

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/decision_model.hpp>
#include <adaptseg/linear_decision.hpp>

#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace adaptseg::examples {

inline const std::vector<std::string> kStrategies{"lawnmower", "adaptive", "nonadaptive", "linear"};

/// "x0,y0,x1,y1" -> FieldRegion (fractions along the image axes).
/// @throws std::invalid_argument for anything else.
inline FieldRegion parse_region(const std::string& text) {
  std::istringstream is(text);
  double v[4];
  char comma = 0;
  bool ok = static_cast<bool>(is >> v[0]);
  for (int k = 1; k < 4 && ok; ++k) ok = (is >> comma) && comma == ',' && (is >> v[k]);
  ok = ok && (is >> std::ws).eof();
  if (!ok) throw std::invalid_argument("region '" + text + "' is not x0,y0,x1,y1 (fractions 0..1)");
  return {v[0], v[1], v[2], v[3]};
}

/// A field directory with an optional region: "DIR" or "DIR:x0,y0,x1,y1".
inline Field load_field_spec(const std::string& spec) {
  const auto colon = spec.rfind(':');
  if (colon != std::string::npos && colon + 1 < spec.size()) {
    const std::string tail = spec.substr(colon + 1);
    if (std::count(tail.begin(), tail.end(), ',') == 3 && tail.find('/') == std::string::npos)
      return Field::load(spec.substr(0, colon)).sub_field(parse_region(tail));
  }
  return Field::load(spec);
}

/// One flown strategy: the mission, and the decisions for the model-based ones.
struct StrategyRun {
  MissionResult mission;
  std::optional<std::vector<DecisionRecord>> decisions;
};

/// Flies `strategy` over `field`. Lawnmower: at `gsd_cm`. Others: from `model`'s top GSD
/// with its candidates, camera and timing (the mission options' camera and timing are
/// replaced by the model's), within `budget_s` if set.
template <SegmentationBackend Backend>
StrategyRun run_strategy(const Field& field, Backend& backend, const std::string& strategy, double gsd_cm,
                         const DecisionModel* model, MissionOptions options, std::optional<double> budget_s) {
  if (strategy == "lawnmower") {
    if (!(gsd_cm > 0.0)) throw std::invalid_argument("--strategy lawnmower needs --gsd (a positive GSD in cm/px)");
    if (gsd_cm < field.gsd_cm() * (1.0 - 1e-9))
      throw std::invalid_argument("--gsd " + std::to_string(gsd_cm) + " cm/px is finer than field '" +
                                  field.name() + "' (" + std::to_string(field.gsd_cm()) + " cm/px)");
    return {run_lawnmower_mission(field, gsd_cm, backend, options), std::nullopt};
  }
  if (model == nullptr) throw std::invalid_argument("--strategy " + strategy + " needs --model (from adaptseg_calibrate)");
  if (model->segmenter != backend.name())
    throw std::invalid_argument("the decision model was calibrated with segmenter '" + model->segmenter +
                                "' but the mission uses '" + backend.name() +
                                "': calibrate with the backend the mission flies (adaptseg_calibrate --segmenter)");
  // Without --interest, the model's labels of interest (its GPs were fitted for them).
  if (options.interest.empty()) options.interest = field.class_indices(model->interest);
  model->check_compatible(field, options.interest);
  options.camera = model->camera;
  options.timing = model->timing;
  AdaptiveOptions ao{options, model->top_gsd_cm, model->candidate_gsd_cm, budget_s};
  if (strategy == "linear") {
    LinearDecision policy(model->linear);
    auto r = run_adaptive_mission(field, backend, policy, ao, policy.name());
    return {std::move(r.mission), std::move(r.decisions)};
  }
  if (strategy != "adaptive" && strategy != "nonadaptive")
    throw std::invalid_argument("unknown strategy '" + strategy + "'");
  DecisionFunction df = model->decision_function;
  auto p = df.params();
  p.online = strategy == "adaptive";
  df.set_params(p);
  auto r = run_adaptive_mission(field, backend, df, ao, df.name());
  return {std::move(r.mission), std::move(r.decisions)};
}

}  // namespace adaptseg::examples
