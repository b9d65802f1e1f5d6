#pragma once
/// @file
/// The conference version's linear decision function (Stache et al., ECMR 2021, the
/// "linear" baseline of the journal's Fig. waypoints): the altitude falls linearly with σ.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace adaptseg {

/// Target altitude `h(σ) = h_max − (h_max − h_min) · clamp((σ − σ_lo) / (σ_hi − σ_lo), 0, 1)`,
/// continuous in σ (hence the "sudden jumps" the paper remarks on). The UAV descends to the
/// candidate whose altitude is nearest `h(σ)` if that lies below h_max; candidates are the
/// only altitudes a sub-lawnmower is planned for, so `h_min` is the lowest candidate's.
/// `σ_lo` and `σ_hi` come from the training field (e.g. the range of σ seen there).
class LinearDecision {
 public:
  struct Params {
    double sigma_low = 0.0;   ///< σ at and below which the UAV stays at h_max
    double sigma_high = 1.0;  ///< σ at and above which it goes to the lowest altitude
  };

  /// @throws std::invalid_argument unless 0 <= sigma_low < sigma_high <= 1.
  explicit LinearDecision(Params params) : params_(params) {
    detail::require(std::isfinite(params_.sigma_low) && params_.sigma_low >= 0.0,
                    "LinearDecision: sigma_low must be in [0, 1)", params_.sigma_low);
    detail::require(
        std::isfinite(params_.sigma_high) && params_.sigma_high > params_.sigma_low && params_.sigma_high <= 1.0,
        "LinearDecision: sigma_high must be in (sigma_low, 1]", params_.sigma_high);
  }

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] std::string name() const { return "linear"; }

  [[nodiscard]] Decision decide(const DecisionContext& c) const {
    Decision d;
    if (c.candidates.empty()) return d;
    double h_min = c.top_altitude_m;
    for (const auto& k : c.candidates) h_min = std::min(h_min, k.altitude_m);
    const double t = std::clamp((c.sigma - params_.sigma_low) / (params_.sigma_high - params_.sigma_low), 0.0, 1.0);
    const double target = c.top_altitude_m - (c.top_altitude_m - h_min) * t;
    double best = std::abs(c.top_altitude_m - target);  // staying is a candidate too
    for (const auto& k : c.candidates) {
      CandidateScore s;
      s.gsd_cm = k.gsd_cm;
      s.utility = -std::abs(k.altitude_m - target);
      d.scores.push_back(s);
      if (std::abs(k.altitude_m - target) < best) {
        best = std::abs(k.altitude_m - target);
        d.descend = true;
        d.gsd_cm = k.gsd_cm;
      }
    }
    return d;
  }

  void begin_mission() const noexcept {}  ///< nothing to forget: the rule has no state
  void observe(const DescentOutcome&) const noexcept {}

 private:
  Params params_;
};

static_assert(DecisionPolicy<LinearDecision>);

}  // namespace adaptseg
