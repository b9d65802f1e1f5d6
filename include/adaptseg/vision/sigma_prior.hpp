#pragma once
/// @file
/// σ̂'s prior for the front-aware rule (FrontAwarePolicy `sigma_prior_weight` k and
/// `sigma_prior_sd` τ) estimated from the training fields' top-level images as the UAV meets
/// them (CalibrationOptions::sigma_prior; the search that uses it: front_aware_search.hpp).

#include <adaptseg/core/decision.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace adaptseg {

/// The prior of a new field's σ the front-aware rule's σ̂ shrinks towards
/// (FrontAwarePolicy::Params `sigma_prior_weight` k and `sigma_prior_sd` τ).
struct SigmaPrior {
  double weight = 0.25;  ///< k = v / τ² [fields]
  double sd = 0.0;       ///< τ
};

/// The top-level images of one training field as the UAV sees them, in flight order: each
/// image's σ and its region's share of the field (DecisionContext::sigma, region_share).
struct TopLevelTrace {
  double field_sigma = 0.0;  ///< σ of the field's top-level map (ReferenceCurve::field_sigma)
  std::vector<double> sigma;
  std::vector<double> share;
};

/// k and τ of σ̂'s hierarchical model (FrontAwarePolicy) estimated on training fields:
/// τ² the sample variance of the fields' σ; v, the spread of the mean σ of a seen share S
/// (variance v / S about the field's, hence v·(1 − S) / S about the whole field's mean m), is
/// the mean over the fields and over the prefixes of each flight (0 < S <= 0.9) of
/// (m_S − m)²·S / (1 − S), so that it holds the fields' spatial correlation along the flight
/// as the UAV meets it; k = v / τ², kept in [0.01, 100]. std::nullopt for fewer than two
/// fields or a field without a top-level image.
[[nodiscard]] inline std::optional<SigmaPrior> estimate_sigma_prior(std::span<const TopLevelTrace> fields) {
  if (fields.size() < 2) return std::nullopt;
  double mean = 0.0;
  for (const auto& f : fields) mean += f.field_sigma / static_cast<double>(fields.size());
  double tau2 = 0.0, v = 0.0;
  std::size_t prefixes = 0;
  for (const auto& f : fields) {
    tau2 += (f.field_sigma - mean) * (f.field_sigma - mean) / static_cast<double>(fields.size() - 1);
    double total = 0.0, total_interest = 0.0;
    for (std::size_t i = 0; i < f.share.size(); ++i) total += f.share[i], total_interest += f.share[i] * f.sigma[i];
    if (!(total > 0.0)) return std::nullopt;
    const double m = total_interest / total;
    double seen = 0.0, seen_interest = 0.0;
    for (std::size_t i = 0; i + 1 < f.share.size(); ++i) {
      seen += f.share[i] / total;
      seen_interest += f.share[i] / total * f.sigma[i];
      if (seen <= 0.0 || seen > 0.9) continue;  // near the end (m_S − m)² / (1 − S) is all noise
      const double d = seen_interest / seen - m;
      v += d * d * seen / (1.0 - seen);
      ++prefixes;
    }
  }
  if (prefixes > 0) v /= static_cast<double>(prefixes);
  const double k = tau2 > 0.0 ? std::clamp(v / tau2, 0.01, 100.0) : 100.0;
  return SigmaPrior{k, std::sqrt(tau2)};
}

namespace detail {

/// Records what each top-level image shows (σ, region share) and never descends.
struct TopLevelRecorder {
  TopLevelTrace trace;
  void begin_mission() {
    trace.sigma.clear();
    trace.share.clear();
  }
  Decision decide(const DecisionContext& c) {
    trace.sigma.push_back(c.sigma);
    trace.share.push_back(c.region_share);
    return {};
  }
  void observe(const DescentOutcome&) {}
  [[nodiscard]] std::string name() const { return "top-level"; }
};

}  // namespace detail

}  // namespace adaptseg
