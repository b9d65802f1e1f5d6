#pragma once
/// @file
/// The paper's decision rule (§3.2.2; docs/method.md, "The decision function"): descend where the
/// forecast accuracy gain
/// per second of extra flight beats a threshold chosen on the training field.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gain_model.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace adaptseg {

/// The paper's utility rule over a GainModel; a DecisionPolicy.
///
/// For each candidate h' with exact extra time T(h'): ΔmIoU(h') = μ_I(μ_O(Δh', σ)) (GainModel),
/// gain `G = −ΔmIoU + κ·sd_I` (κ = `exploration`: optimism under uncertainty), weighted if
/// `weight_by_sigma` by the image's share of labels of interest σ · (valid fraction of the
/// image) (field mIoU counts pixels: a region's errors scale with its pixels of interest),
/// utility `U = G / T`. Descend to the candidate of largest U if σ >= `min_sigma`, G > 0 and
/// U >= `min_utility`. With `relative_utility` the threshold applies to U divided by the mean
/// best utility of the top-level images seen so far in this mission (current one included): a
/// scale-free rule that transfers between fields whose σ levels differ (a departure from the
/// paper). Online (`online`, §3.2.3) each descent's outcome updates O (GainModel::update);
/// `online = false` is the paper's "non-adaptive" baseline. `begin_mission` restores the model
/// as it was given and forgets the running mean.
///
/// @code
/// adaptseg::UtilityPolicy policy(adaptseg::GainModel::fit(samples), {.min_utility = 1e-4});
/// adaptseg::AdaptivePlanner planner(area, policy, options);
/// @endcode
class UtilityPolicy {
 public:
  /// Thresholds and behaviour; validated by the constructor.
  struct Params {
    double min_sigma = 0.0;         ///< σ below which the UAV never descends
    double min_utility = 0.0;       ///< utility threshold [gain per second]
    double exploration = 0.0;       ///< κ >= 0, weight of I's predictive standard deviation
    bool weight_by_sigma = true;    ///< gain weighted by σ (see class comment)
    bool online = true;             ///< update O after each descent (false: non-adaptive)
    bool relative_utility = false;  ///< threshold on U / mean best U so far (see class comment)

    /// @throws std::invalid_argument naming the field.
    void validate() const {
      detail::require(std::isfinite(min_sigma) && min_sigma >= 0.0 && min_sigma <= 1.0,
                      "UtilityPolicy::Params::min_sigma must be in [0, 1]", min_sigma);
      detail::require(!std::isnan(min_utility), "UtilityPolicy::Params::min_utility must not be NaN", min_utility);
      detail::require(std::isfinite(exploration) && exploration >= 0.0,
                      "UtilityPolicy::Params::exploration must be finite and >= 0", exploration);
    }
  };

  /// @throws std::invalid_argument for invalid params.
  UtilityPolicy(GainModel model, Params params) : initial_(std::move(model)), model_(initial_), params_(params) {
    params_.validate();
  }

  [[nodiscard]] std::string name() const { return params_.online ? "adaptive" : "nonadaptive"; }
  [[nodiscard]] const Params& params() const noexcept { return params_; }
  /// @throws std::invalid_argument for invalid params.
  void set_params(const Params& p) {
    p.validate();
    params_ = p;
  }
  /// The model as updated during the current mission.
  [[nodiscard]] const GainModel& model() const noexcept { return model_; }
  /// The model as given (what begin_mission restores).
  [[nodiscard]] const GainModel& initial_model() const noexcept { return initial_; }

  void begin_mission() {
    model_ = initial_;
    utility_sum_ = 0.0;
    utility_count_ = 0;
  }

  /// Predicted Δσ, ΔmIoU and its standard deviation, and utility of one candidate.
  [[nodiscard]] CandidateScore score(const DecisionContext& ctx, const Candidate& c) const {
    CandidateScore s = scored(c, model_.forecast(ctx.top_altitude_m - c.altitude_m, ctx.sigma));
    s.utility = utility(gain_of(s, ctx), c.extra_time_s);
    return s;
  }

  [[nodiscard]] Decision decide(const DecisionContext& c) {
    Decision d;
    double best = -std::numeric_limits<double>::infinity();
    std::size_t best_index = 0;
    for (std::size_t k = 0; k < c.candidates.size(); ++k) {
      d.scores.push_back(score(c, c.candidates[k]));
      const CandidateScore& s = d.scores.back();
      if (gain_of(s, c) > 0.0 && s.utility > best) {
        best = s.utility;
        best_index = k;
      }
    }
    if (!std::isfinite(best)) return d;
    double u = best;
    if (params_.relative_utility) {
      utility_sum_ += best;
      ++utility_count_;
      const double mean = utility_sum_ / static_cast<double>(utility_count_);
      u = mean > 0.0 ? best / mean : 0.0;
    }
    if (c.sigma >= params_.min_sigma && u >= params_.min_utility) {
      d.descend = true;
      d.gsd_cm = c.candidates[best_index].gsd_cm;
    }
    return d;
  }

  /// Online update of O after a descent (no-op unless `online`).
  void observe(const DescentOutcome& out) {
    if (params_.online) model_.update(out);
  }

 private:
  /// G = −ΔmIoU + κ·sd_I, weighted by σ · valid fraction if `weight_by_sigma`.
  [[nodiscard]] double gain_of(const CandidateScore& s, const DecisionContext& c) const {
    const double g = -s.predicted_delta_miou + params_.exploration * s.predicted_delta_miou_std;
    return params_.weight_by_sigma ? g * c.sigma * c.valid_fraction : g;
  }

  GainModel initial_;
  GainModel model_;
  Params params_;
  double utility_sum_ = 0.0;
  std::size_t utility_count_ = 0;
};

static_assert(DecisionPolicy<UtilityPolicy>);

}  // namespace adaptseg
