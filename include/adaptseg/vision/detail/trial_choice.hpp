#pragma once
/// @file
/// The front-aware search's trials (front_aware_search.hpp): a trial's name, and which of
/// several settings flown over the same folds to keep, by the one-standard-error rule.

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/front_aware_settings.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/detail/number_text.hpp>

#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace adaptseg::detail {

/// Which of several settings of the same folds to keep (`trials`, the best of each slope
/// pooling, CalibrationOptions::slope_poolings' order): the first, unless another beats it on
/// the folds by more than one standard error of their paired differences, m̄ − m̄₁ >
/// sd(m − m₁) / sqrt(n) over the n folds (the one-standard-error rule of cross-validation,
/// Breiman et al. 1984, towards the first, the default); of those that do, the best mean.
/// Five training fields tell two poolings apart poorly, and a setting the folds prefer by less
/// than their own scatter is as likely to lose on a new field (docs/results.md, "Slopes pooled
/// over the cells or over the fields, chosen by the folds").
///
/// A difference on one fold alone is never beyond the noise: there the mean difference d/n
/// equals the standard error d/n exactly, and rounding would decide, so the mean must exceed the
/// standard error by a relative 1e-9 (a tie keeps the first). The pooling's choice has had the
/// tolerance since 2026-12-04 (the finest descent's from the start): of 240 pooling comparisons
/// in five leave-one-tile-out rows, 13 were such ties and each had kept the first, and the bundled
/// decision models calibrate to the same files, so no choice moved (docs/journal/2026-12-loto.md).
///
/// `ground`, where given, names each fold's ground (the index of its ground's first fold, at most
/// its own, as CalibrationOptions::field_grounds; equal for the folds of one field segmented by
/// several networks, --calibration-network-each): the paired differences of one
/// ground are averaged first and n counts the grounds, so that two looks at one field are not
/// taken for two fields' worth of evidence. Empty: every fold its own ground.
inline std::size_t select_pooling(std::span<const RuleTrial* const> trials, std::span<const std::size_t> ground = {}) {
  constexpr double tie_tolerance = 1e-9;
  std::size_t best = 0;
  const std::vector<double>& first = trials.front()->margins;
  for (std::size_t k = 1; k < trials.size(); ++k) {
    const std::vector<double>& m = trials[k]->margins;
    if (m.size() != first.size() || m.size() < 2) continue;
    // The paired differences, one per ground (its folds' mean), in the grounds' order.
    std::vector<double> sum(m.size(), 0.0), count(m.size(), 0.0);
    for (std::size_t f = 0; f < m.size(); ++f) {
      const std::size_t g = ground.size() == m.size() ? ground[f] : f;
      sum[g] += m[f] - first[f];
      count[g] += 1.0;
    }
    std::vector<double> d;
    for (std::size_t g = 0; g < sum.size(); ++g)
      if (count[g] > 0.0) d.push_back(sum[g] / count[g]);
    if (d.size() < 2) continue;
    const double n = static_cast<double>(d.size());
    double mean = 0.0;
    for (double x : d) mean += x / n;
    double ss = 0.0;
    for (double x : d) ss += std::pow(x - mean, 2);
    if (mean > std::sqrt(ss / (n - 1.0) / n) * (1.0 + tie_tolerance) &&
        trials[k]->front_margin > trials[best]->front_margin)
      best = k;
  }
  return best;
}

/// Each fold's ground (select_pooling; CalibrationOptions::field_grounds): empty where every
/// fold is its own (no grounds given, or one field's layouts).
[[nodiscard]] inline std::vector<std::size_t> fold_grounds(const RuleSearchInputs& in) {
  if (in.fields.size() < 2) return {};
  return in.options.field_grounds;
}

/// A trial's name: its z, its slope pooling, its top-level choice and its finest descent GSD
/// (`finest=G` in cm/px, `finest=any` for no limit) where the search tried several.
inline std::string z_text(double z, const SlopePooling* pooling = nullptr, const TopLevelChoice* top_level = nullptr,
                          const double* finest_descent_gsd_cm = nullptr) {
  std::string s = "front-aware z=" + format_number(z);
  if (pooling) s += " slopes=" + to_string(*pooling);
  if (top_level) s += " top=" + to_string(*top_level);
  if (finest_descent_gsd_cm)
    s += " finest=" + (*finest_descent_gsd_cm > 0.0 ? format_number(*finest_descent_gsd_cm) : std::string("any"));
  return s;
}

}  // namespace adaptseg::detail
