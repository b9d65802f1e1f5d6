#pragma once
/// @file
/// The paper's utility rule (UtilityPolicy, core/utility_policy.hpp) beyond deciding: its name,
/// its keys in the model file's `rule` mapping and its calibration search (the threshold,
/// absolute or relative, with σ weighting on and off, scored by the worst front margin over the
/// training layouts). One entry of DecisionRules (decision_rules.hpp).

#include <adaptseg/core/utility_policy.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

namespace detail {

/// A utility threshold for people: 4 significant digits; the lowest and highest doubles,
/// which stand for "descend whenever the rule can" and "never descend", by name.
inline std::string threshold_text(double t) {
  if (t <= std::numeric_limits<double>::lowest()) return "-inf (always)";
  if (t >= std::numeric_limits<double>::max()) return "+inf (never)";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", t);
  return buf;
}

}  // namespace detail

/// The paper's utility rule in the model file and in calibration.
struct UtilityRule {
  using Policy = UtilityPolicy;
  /// Its name: `kind` in the model file, `--rule` of the programs, CalibrationOptions::rule.
  static constexpr std::string_view kName = "utility";

  /// Writes the rule's own keys into the open `rule` mapping (after `kind`, `online` and
  /// `min_sigma`, which every rule has).
  static void write_keys(YAML::Emitter& e, const UtilityPolicy& rule) {
    const auto num = [](double v) { return detail::format_number(v); };
    const UtilityPolicy::Params& p = rule.params();
    e << YAML::Key << "weight_by_sigma" << YAML::Value << detail::flag_text(p.weight_by_sigma);
    e << YAML::Key << "min_utility" << YAML::Value << num(p.min_utility);
    e << YAML::Key << "exploration" << YAML::Value << num(p.exploration);
    e << YAML::Key << "relative_utility" << YAML::Value << detail::flag_text(p.relative_utility);
  }

  /// Reads what write_keys wrote: the rule over `model` with the keys every rule has.
  /// @throws std::invalid_argument naming the file and the key.
  [[nodiscard]] static UtilityPolicy read_keys(const detail::YamlReader& rule, GainModel model, double min_sigma,
                                               bool online) {
    return UtilityPolicy(std::move(model), {.min_sigma = min_sigma,
                                            .min_utility = rule.number("min_utility"),
                                            .exploration = rule.number("exploration"),
                                            .weight_by_sigma = rule.flag("weight_by_sigma"),
                                            .online = online,
                                            .relative_utility = rule.flag("relative_utility")});
  }

  /// Refuses options its search cannot use (before calibrate() samples anything).
  /// @throws std::invalid_argument if `threshold_steps` < 1, or for the front-aware rule's
  ///         `gain_ratios`, `margin_biases`, `finest_descent_gsd_cm`, `longest_descent_s` or
  ///         `frozen_folds`.
  static void check_options(const CalibrationOptions& options) {
    detail::require(options.threshold_steps >= 1, "calibrate: threshold_steps must be >= 1", options.threshold_steps);
    detail::require(!options.gain_ratios && !options.margin_biases,
                    "calibrate: gain_ratios and margin_biases belong to the front-aware rule; rule", kName);
    detail::require(options.finest_descent_gsd_cm.empty(),
                    "calibrate: finest_descent_gsd_cm belongs to the front-aware rule; rule", kName);
    detail::require(options.longest_descent_s.empty(),
                    "calibrate: longest_descent_s belongs to the front-aware rule; rule", kName);
    detail::require(!options.frozen_folds, "calibrate: frozen_folds belongs to the front-aware rule; rule", kName);
  }

  /// The calibration search (CalibrationOptions: `utility`, `threshold_steps`): `exploration`
  /// and `min_sigma` as given; thresholds searched (quantiles of the utilities seen, absolute
  /// and relative, σ weighting on and off, "never descend"), each flown over every layout (the
  /// fields; one field: the field and its halves) and scored by its worst front margin (ties:
  /// larger mean margin, then the relative rule, then shorter time). `fly` as in
  /// FrontAwareRule::search.
  /// @throws std::invalid_argument if `threshold_steps` < 1.
  template <class Fly>
  [[nodiscard]] static RuleSearchResult search(const RuleSearchInputs& in, Fly&& fly) {
    const CalibrationOptions& options = in.options;
    check_options(options);
    std::vector<RuleTrial> trials;
    std::vector<const Field*> layouts;
    std::vector<const std::vector<CurvePoint>*> layout_curves;
    for (std::size_t k = 0; k < in.fields.size(); ++k)
      layouts.push_back(&in.fields[k]), layout_curves.push_back(&in.curves[k]);
    for (std::size_t k = 0; k < in.halves.size(); ++k)
      layouts.push_back(&in.halves[k]), layout_curves.push_back(&in.half_curves[k]);
    struct Tried {
      RuleTrial trial;
      UtilityPolicy::Params params;
    };
    std::vector<Tried> tried;
    const auto try_params = [&](const UtilityPolicy::Params& p, std::vector<double>* utilities) {
      Tried c{{}, p};
      c.trial.description = "utility weight=" + std::to_string(p.weight_by_sigma ? 1 : 0) +
                            " relative=" + std::to_string(p.relative_utility ? 1 : 0) +
                            " min_utility=" + detail::threshold_text(p.min_utility);
      for (std::size_t k = 0; k < layouts.size(); ++k) {
        UtilityPolicy policy(in.model, p);
        double margin = 0.0;
        const AdaptiveResult r = fly(*layouts[k], policy, *layout_curves[k], margin);
        if (utilities && k == 0)
          for (const auto& d : r.decisions)
            for (const auto& s : d.decision.scores)
              if (std::isfinite(s.utility) && s.utility > 0.0) utilities->push_back(s.utility);
        detail::add_to_trial(c.trial, r, margin);
      }
      tried.push_back(std::move(c));
    };
    UtilityPolicy::Params probe = options.utility;
    probe.online = true;
    probe.min_utility = -std::numeric_limits<double>::max();
    for (bool weight : {true, false}) {
      probe.weight_by_sigma = weight;
      probe.relative_utility = false;
      std::vector<double> utilities;
      try_params(probe, &utilities);  // descends wherever the predicted gain is positive
      std::sort(utilities.begin(), utilities.end());
      for (const UtilityPolicy::Params& p : thresholds(probe, utilities, options.threshold_steps))
        try_params(p, nullptr);
    }
    std::stable_sort(tried.begin(), tried.end(), [](const Tried& a, const Tried& b) {
      if (a.trial.worst_margin != b.trial.worst_margin) return a.trial.worst_margin > b.trial.worst_margin;
      if (a.trial.front_margin != b.trial.front_margin) return a.trial.front_margin > b.trial.front_margin;
      // Equal on the training fields: prefer the scale-free rule, which transfers to fields
      // whose σ levels differ.
      if (a.params.relative_utility != b.params.relative_utility) return a.params.relative_utility;
      return a.trial.time_s < b.trial.time_s;
    });
    const UtilityPolicy::Params best = tried.front().params;
    for (auto& c : tried) trials.push_back(std::move(c.trial));
    return {DecisionFunction(UtilityPolicy(in.model, best)), std::move(trials)};
  }

 private:
  /// What search() tries after the probe `probe` (σ weighting on or off) saw `utilities`
  /// (sorted): absolute thresholds, quantiles spread evenly plus the top tail where only the
  /// best regions qualify (none without a utility); relative ones, a region's best utility over
  /// the mission's running mean; "never descend", the top-level lawnmower alone.
  [[nodiscard]] static std::vector<UtilityPolicy::Params> thresholds(const UtilityPolicy::Params& probe,
                                                                     const std::vector<double>& utilities, int steps) {
    std::vector<UtilityPolicy::Params> out;
    std::vector<double> quantiles;
    for (int k = 0; k < steps; ++k) quantiles.push_back(static_cast<double>(k) / steps);
    for (double q : {0.93, 0.96, 0.99}) quantiles.push_back(q);
    for (double q : quantiles) {
      if (utilities.empty()) break;
      UtilityPolicy::Params p = probe;
      p.min_utility = utilities[static_cast<std::size_t>(q * static_cast<double>(utilities.size() - 1))];
      out.push_back(p);
    }
    for (int k = 0; k < steps; ++k) {
      UtilityPolicy::Params p = probe;
      p.relative_utility = true;
      p.min_utility = 1.0 + 2.0 * static_cast<double>(k) / steps;
      out.push_back(p);
    }
    UtilityPolicy::Params never = probe;
    never.min_utility = std::numeric_limits<double>::max();
    out.push_back(never);
    return out;
  }
};

}  // namespace adaptseg
