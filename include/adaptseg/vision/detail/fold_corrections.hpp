#pragma once
/// @file
/// What descents realised against their forecast on the calibration folds, per descent GSD
/// (the front-aware search, front_aware_search.hpp): the gain ratios and the margin biases of
/// CalibrationOptions::gain_ratios and margin_biases (docs/method.md, "Gain ratios measured on
/// the folds", "Margin biases measured on the folds"), and what else a fold's trials fly with
/// beyond the setting tried (FoldCorrection: those, the jump bound, b, τ_r and ω_χ).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/front_aware_settings.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace adaptseg::detail {

/// Every fold's flight but `skip`'s (none skipped: `kAllFolds`).
inline constexpr std::size_t kAllFolds = static_cast<std::size_t>(-1);

/// Calls `visit(descent, record, k, j)` for each realised descent of `flights` but those of flight
/// `skip` whose rule forecast a finite field gain: its RealisedDescent, its DecisionRecord, the
/// candidate chosen and the flight's index.
template <class Visit>
void for_each_forecast_descent(std::span<const AdaptiveResult> flights, std::size_t skip, Visit&& visit) {
  for (std::size_t j = 0; j < flights.size(); ++j) {
    if (j == skip) continue;
    for (const RealisedDescent& d : flights[j].realised) {
      const DecisionRecord& rec = flights[j].decisions[d.decision];
      const std::size_t k = chosen_candidate(rec.decision, rec.candidates, "front-aware");
      if (k >= rec.decision.scores.size() || !std::isfinite(rec.decision.scores[k].predicted_field_gain)) continue;
      visit(d, rec, k, j);
    }
  }
}

/// Per descent GSD, realised / forecast field gain over the descents of `flights` (each an
/// AdaptiveResult of a fold, simulated so that its descents' realised field gains are known),
/// those of flight `skip` left out: (Σ realised + 2·f̄) / (Σ forecast + 2·f̄), f̄ the mean
/// forecast gain of the GSD's descents (two descents' worth of prior at ratio 1), kept in [0, 4];
/// in increasing GSD order. A GSD whose descents were forecast nothing positive in all is left
/// out (ratio 1).
inline std::vector<GainRatio> fold_gain_ratios(std::span<const AdaptiveResult> flights, std::size_t skip = kAllFolds) {
  struct Sums {
    double gsd_cm, forecast, realised;
    int n;
  };
  std::vector<Sums> sums;
  for_each_forecast_descent(
      flights, skip, [&](const RealisedDescent& d, const DecisionRecord& rec, std::size_t k, std::size_t) {
        const double g = rec.candidates[k].gsd_cm;
        auto it = std::find_if(sums.begin(), sums.end(), [&](const Sums& s) { return s.gsd_cm == g; });
        if (it == sums.end()) it = sums.insert(sums.end(), {g, 0.0, 0.0, 0});
        it->forecast += rec.decision.scores[k].predicted_field_gain;
        it->realised += d.field_gain;
        ++it->n;
      });
  std::sort(sums.begin(), sums.end(), [](const Sums& a, const Sums& b) { return a.gsd_cm < b.gsd_cm; });
  std::vector<GainRatio> out;
  for (const Sums& s : sums) {
    if (!(s.forecast > 0.0)) continue;
    const double prior = 2.0 * s.forecast / s.n;
    out.push_back({s.gsd_cm, std::clamp((s.realised + prior) / (s.forecast + prior), 0.0, 4.0)});
  }
  return out;
}

/// Per descent GSD, how far the descents of `flights` ended above their forecast margin per
/// second of descent, those of flight `skip` left out. A descent's forecast margin is its
/// forecast field gain less the predicted lawnmower curve's rise over its extra time
/// (CandidateScore::predicted_field_gain − predicted_curve_rise); its realised margin, its
/// realised field gain (RealisedDescent::field_gain) less the rise of its field's real curve
/// (`curves[j]` of flight j: the upper envelope of its lawnmowers, as front_margin reads it)
/// over the same seconds, ending at CandidateScore::predicted_end_s. Per GSD Σ(realised −
/// forecast margin) / (Σ T + 2·T̄), T the descents' extra times (two descents' worth of prior at
/// bias 0); in increasing GSD order. Descents without a predicted rise or end are left out.
inline std::vector<MarginBias> fold_margin_biases(std::span<const AdaptiveResult> flights,
                                                  std::span<const std::vector<CurvePoint>* const> curves,
                                                  std::size_t skip = kAllFolds) {
  struct Sums {
    double gsd_cm, error, seconds;
    int n;
  };
  std::vector<std::vector<CurvePoint>> envelopes;
  for (const std::vector<CurvePoint>* c : curves) envelopes.push_back(upper_envelope(*c));
  const auto real_miou = [&](std::size_t j, double t) { return miou_at_time(envelopes[j], t); };
  std::vector<Sums> sums;
  for_each_forecast_descent(
      flights, skip, [&](const RealisedDescent& d, const DecisionRecord& rec, std::size_t k, std::size_t j) {
        const CandidateScore& s = rec.decision.scores[k];
        const double seconds = rec.candidates[k].extra_time_s;
        if (!std::isfinite(s.predicted_curve_rise) || !std::isfinite(s.predicted_end_s) || !(seconds > 0.0)) return;
        const double forecast = s.predicted_field_gain - s.predicted_curve_rise;
        const double realised =
            d.field_gain - (real_miou(j, s.predicted_end_s) - real_miou(j, s.predicted_end_s - seconds));
        const double g = rec.candidates[k].gsd_cm;
        auto it = std::find_if(sums.begin(), sums.end(), [&](const Sums& x) { return x.gsd_cm == g; });
        if (it == sums.end()) it = sums.insert(sums.end(), {g, 0.0, 0.0, 0});
        it->error += realised - forecast;
        it->seconds += seconds;
        ++it->n;
      });
  std::sort(sums.begin(), sums.end(), [](const Sums& a, const Sums& b) { return a.gsd_cm < b.gsd_cm; });
  std::vector<MarginBias> out;
  for (const Sums& s : sums) out.push_back({s.gsd_cm, s.error / (s.seconds + 2.0 * s.seconds / s.n)});
  return out;
}

/// What one fold's trials fly with beyond the setting tried (FrontAwareParams' own
/// fields of the same names): the gain ratios and margin biases measured on the other folds'
/// flights, the jump guard's bound and the relabelled factor's b, τ_r and ω_χ measured on the other
/// fields' cells; each the search's base parameters' where its option is off.
struct FoldCorrection {
  std::vector<GainRatio> gain_ratios;
  std::vector<MarginBias> margin_biases;
  double jump_bound = std::numeric_limits<double>::infinity();  ///< the jump guard's (CalibrationOptions::jump_guard)
  double relabel_transfer = 1.0;                                ///< b (CalibrationOptions::relabel_transfer)
  double relabel_region_sd = 0.0;                               ///< τ_r (CalibrationOptions::relabel_region_spread)
  double relabel_field_sd = 0.0;                                ///< ω_χ (CalibrationOptions::relabel_field_spread)

  /// `p`'s own: the correction that changes nothing (a default one: that of default Params).
  [[nodiscard]] static FoldCorrection of(const FrontAwareParams& p) {
    return {p.gain_ratios, p.margin_biases, p.jump_bound, p.relabel_transfer, p.relabel_region_sd, p.relabel_field_sd};
  }
  void apply_to(FrontAwareParams& p) const {
    p.gain_ratios = gain_ratios;
    p.margin_biases = margin_biases;
    p.jump_bound = jump_bound;
    p.relabel_transfer = relabel_transfer;
    p.relabel_region_sd = relabel_region_sd;
    p.relabel_field_sd = relabel_field_sd;
  }
};

}  // namespace adaptseg::detail
