#pragma once
/// @file
/// Offline initialisation on a training field (paper §3.2.2; method.md §4): collect the O and
/// I samples, fit the decision function, and choose its thresholds on the training field
/// only, by the front margin over the training field's own lawnmower curve.

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/decision_function.hpp>
#include <adaptseg/decision_model.hpp>
#include <adaptseg/linear_decision.hpp>
#include <adaptseg/metrics.hpp>
#include <adaptseg/mission.hpp>
#include <adaptseg/region_samples.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace adaptseg {

/// How to calibrate.
struct CalibrationOptions {
  AdaptiveOptions adaptive{};            ///< camera, timing, labels of interest, top and candidate GSDs
  std::vector<double> lawnmower_gsd_cm{};///< GSDs of the training field's lawnmower curve
  DecisionFunction::Params base{};       ///< exploration, refit schedule; thresholds are searched
  int threshold_steps = 10;              ///< utility thresholds tried (quantiles of observed utility)
  int restarts = 3;                      ///< GP hyperparameter restarts
  /// Score thresholds by their worst front margin over the training field and its two halves
  /// (split across the longer image axis) instead of the whole field's margin alone: a
  /// threshold must work on more than one layout to be chosen.
  bool robust = true;
  /// Choose the front-aware rule (DecisionFunction::Params::front_aware, which needs no
  /// threshold: it stops descending when descents no longer beat the training lawnmower
  /// curve mapped onto the field's geometry) instead of the best threshold trial of the
  /// paper's utility rule. The trials are flown and reported either way. `base.weight_by_sigma`
  /// selects its σ weighting.
  bool front_aware = true;
  /// What I predicts the accuracy gain from (DecisionFunction::GainInputs); (Δσ, Δh) by
  /// default, which reduces to the paper's chain where Δσ carries the information (see
  /// docs/method.md). What a descent covers is `adaptive.coverage` (region by default, as
  /// AdaptiveOptions; the example programs default to DescentCoverage::interest).
  DecisionFunction::GainInputs gain_inputs = DecisionFunction::GainInputs::delta_sigma_and_height;
};

/// One threshold setting tried on the training field.
struct ThresholdTrial {
  DecisionFunction::Params params;
  double time_s = 0.0;          ///< on the whole training field
  double miou_interest = 0.0;   ///< on the whole training field
  double front_margin = 0.0;    ///< on the whole training field
  double worst_margin = 0.0;    ///< smallest margin over the calibration layouts (the score)
  int descents = 0;             ///< on the whole training field
};

/// Everything calibration produced.
struct CalibrationResult {
  std::vector<RegionSample> samples;
  DecisionFunction decision_function;   ///< fitted, with the chosen thresholds
  LinearDecision::Params linear{};      ///< σ range of the training field's top-level images
  std::vector<CurvePoint> lawnmower_curve;  ///< on the training field
  std::vector<ThresholdTrial> trials;   ///< every setting tried, the chosen one first
};

/// Calibrates on `train` with `backend` (the backend the missions will use).
///
/// 1. Region samples at every top-level region × candidate GSD (collect_region_samples).
/// 2. O and I fitted (DecisionFunction::initialize).
/// 3. The training field's lawnmower curve at `lawnmower_gsd_cm`.
/// 4. One adaptive mission on `train` with no threshold gives the utilities the policy sees;
///    thresholds at their quantiles (absolute and relative, σ weighting on/off), the
///    front-aware rule (its reference lawnmower: the training curve by GSD) and "never
///    descend" are each flown on `train`. With `front_aware` (default) the front-aware rule is
///    chosen; otherwise the threshold setting with the largest worst-case front margin over
///    the layouts (ties: larger whole-field margin, then shorter time).
/// 5. The linear baseline's σ range: the 5th and 95th percentiles of σ at h_max.
/// @throws std::invalid_argument for invalid options (see run_adaptive_mission and
///         collect_region_samples).
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationResult calibrate(const Field& train, Backend& backend, const CalibrationOptions& options) {
  detail::require(!options.lawnmower_gsd_cm.empty(), "calibrate: lawnmower_gsd_cm must not be empty", 0);
  detail::require(options.threshold_steps >= 1, "calibrate: threshold_steps must be >= 1", options.threshold_steps);
  const std::vector<int> interest =
      options.adaptive.mission.interest.empty() ? train.interest() : options.adaptive.mission.interest;
  detail::require(!interest.empty(), "calibrate: no labels of interest", 0);
  const CameraModel camera(options.adaptive.mission.camera);
  auto samples = collect_region_samples(train, backend, camera, options.adaptive.top_gsd_cm,
                                        options.adaptive.candidate_gsd_cm, interest, options.adaptive.coverage);
  detail::require(!samples.empty(), "calibrate: the training field gave no region sample", train.name());

  // Calibration layouts: the field, and (robust) its halves across the longer axis.
  std::vector<Field> layouts{train};
  if (options.robust) {
    const bool wide = train.width_px() >= train.height_px();
    layouts.push_back(train.sub_field(wide ? FieldRegion{0, 0, 0.5, 1} : FieldRegion{0, 0, 1, 0.5}));
    layouts.push_back(train.sub_field(wide ? FieldRegion{0.5, 0, 1, 1} : FieldRegion{0, 0.5, 1, 1}));
  }
  std::vector<std::vector<CurvePoint>> curves;
  for (const Field& f : layouts) {
    curves.emplace_back();
    for (double g : options.lawnmower_gsd_cm) {
      const MissionResult r = run_lawnmower_mission(f, g, backend, options.adaptive.mission);
      curves.back().push_back({r.total_s(), r.miou_interest().value_or(0.0)});
    }
  }
  const std::vector<CurvePoint>& curve = curves.front();

  DecisionFunction::Params probe = options.base;
  probe.min_sigma = 0.0;
  probe.min_utility = -std::numeric_limits<double>::max();
  DecisionFunction fitted = DecisionFunction::initialize(samples, probe, options.restarts, 0, options.gain_inputs);
  std::vector<GsdPoint> reference;  // the training lawnmower by GSD, for the front-aware rule
  for (std::size_t k = 0; k < curve.size(); ++k) reference.push_back({options.lawnmower_gsd_cm[k], curve[k].miou});
  fitted.set_reference_lawnmower(reference);

  const auto fly = [&](const DecisionFunction::Params& p) {
    ThresholdTrial t;
    t.params = p;
    t.worst_margin = std::numeric_limits<double>::infinity();
    AdaptiveResult whole;
    for (std::size_t k = 0; k < layouts.size(); ++k) {
      DecisionFunction df = fitted;
      df.set_params(p);
      AdaptiveResult r = run_adaptive_mission(layouts[k], backend, df, options.adaptive, df.name());
      const double margin = front_margin(curves[k], r.mission.total_s(), r.mission.miou_interest().value_or(0.0));
      t.worst_margin = std::min(t.worst_margin, margin);
      if (k == 0) {
        t.time_s = r.mission.total_s();
        t.miou_interest = r.mission.miou_interest().value_or(0.0);
        t.front_margin = margin;
        t.descents = r.descents();
        whole = std::move(r);
      }
    }
    return std::make_pair(t, std::move(whole));
  };

  std::vector<ThresholdTrial> trials;
  for (bool weight : {true, false}) {
    probe.weight_by_sigma = weight;
    probe.relative_utility = false;
    auto [open, open_run] = fly(probe);  // descends wherever the predicted gain is positive
    std::vector<double> utilities;
    for (const auto& d : open_run.decisions)
      for (const auto& s : d.decision.scores)
        if (std::isfinite(s.utility) && s.utility > 0.0) utilities.push_back(s.utility);
    std::sort(utilities.begin(), utilities.end());
    trials.push_back(open);
    // Absolute thresholds: quantiles spread evenly, plus the top tail where only the best
    // regions qualify.
    std::vector<double> quantiles;
    for (int k = 0; k < options.threshold_steps; ++k) quantiles.push_back(static_cast<double>(k) / options.threshold_steps);
    for (double q : {0.93, 0.96, 0.99}) quantiles.push_back(q);
    for (double q : quantiles) {
      if (utilities.empty()) break;
      DecisionFunction::Params p = probe;
      p.min_utility = utilities[static_cast<std::size_t>(q * static_cast<double>(utilities.size() - 1))];
      trials.push_back(fly(p).first);
    }
    // The front-aware rule (descend while the forecast front margin rises; no threshold).
    DecisionFunction::Params front = probe;
    front.front_aware = true;
    trials.push_back(fly(front).first);
    // Relative thresholds: a region's best utility over the mission's running mean.
    for (int k = 0; k < options.threshold_steps; ++k) {
      DecisionFunction::Params p = probe;
      p.relative_utility = true;
      p.min_utility = 1.0 + 2.0 * static_cast<double>(k) / options.threshold_steps;
      trials.push_back(fly(p).first);
    }
    DecisionFunction::Params never = probe;  // the top-level lawnmower alone
    never.min_utility = std::numeric_limits<double>::max();
    trials.push_back(fly(never).first);
  }
  std::stable_sort(trials.begin(), trials.end(), [](const ThresholdTrial& a, const ThresholdTrial& b) {
    if (a.worst_margin != b.worst_margin) return a.worst_margin > b.worst_margin;
    if (a.front_margin != b.front_margin) return a.front_margin > b.front_margin;
    // Equal on the training field: prefer the scale-free rule, which transfers to fields
    // whose σ levels differ.
    if (a.params.relative_utility != b.params.relative_utility) return a.params.relative_utility;
    return a.time_s < b.time_s;
  });
  if (options.front_aware) {  // the rule is chosen, not its threshold: put it first
    const auto chosen = std::find_if(trials.begin(), trials.end(), [&](const ThresholdTrial& t) {
      return t.params.front_aware && t.params.weight_by_sigma == options.base.weight_by_sigma;
    });
    ADAPTSEG_ASSERT(chosen != trials.end());
    std::rotate(trials.begin(), chosen, chosen + 1);
  }
  fitted.set_params(trials.front().params);

  std::vector<double> sig;
  for (const auto& s : samples) sig.push_back(s.sigma_top);
  std::sort(sig.begin(), sig.end());
  const auto pct = [&](double q) { return sig[static_cast<std::size_t>(q * static_cast<double>(sig.size() - 1))]; };
  LinearDecision::Params linear{pct(0.05), pct(0.95)};
  if (!(linear.sigma_high > linear.sigma_low)) linear = {0.0, std::max(1e-6, sig.back())};
  linear.sigma_high = std::min(1.0, linear.sigma_high);
  return CalibrationResult{std::move(samples), std::move(fitted), linear, std::move(curve), std::move(trials)};
}

/// The model file's content for a calibration on `train` with the backend named `segmenter`:
/// the fitted decision function, the linear baseline, and what they were calibrated for.
[[nodiscard]] inline DecisionModel make_decision_model(const Field& train, const std::string& segmenter,
                                                       const CalibrationOptions& options,
                                                       const CalibrationResult& calibration) {
  DecisionModel m{.calibration_field = train.name(),
                  .segmenter = segmenter,
                  .classes = {},
                  .interest = {},
                  .camera = options.adaptive.mission.camera,
                  .timing = options.adaptive.mission.timing,
                  .top_gsd_cm = options.adaptive.top_gsd_cm,
                  .candidate_gsd_cm = options.adaptive.candidate_gsd_cm,
                  .coverage = options.adaptive.coverage,
                  .decision_function = calibration.decision_function,
                  .linear = calibration.linear,
                  .samples = calibration.samples.size(),
                  .train_front_margin = calibration.trials.empty() ? 0.0 : calibration.trials.front().front_margin};
  for (const auto& c : train.classes()) m.classes.push_back(c.name);
  const auto& interest = options.adaptive.mission.interest.empty() ? train.interest() : options.adaptive.mission.interest;
  for (int i : interest) m.interest.push_back(train.classes().at(static_cast<std::size_t>(i)).name);
  return m;
}

}  // namespace adaptseg
