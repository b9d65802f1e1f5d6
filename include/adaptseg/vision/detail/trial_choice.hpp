#pragma once
/// @file
/// The front-aware search's trials (front_aware_search.hpp): the grid and the settings it
/// tries, a trial's name, and which of several settings flown over the same folds to keep, by
/// the one-standard-error rule.

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

/// A trial's name: its z, its slope pooling, its top-level choice, its finest descent GSD
/// (`finest=G` in cm/px, `finest=any` for no limit) and its longest descent (`longest=S` in s,
/// `longest=any`) where the search tried several.
inline std::string z_text(double z, const SlopePooling* pooling = nullptr, const TopLevelChoice* top_level = nullptr,
                          const double* finest_descent_gsd_cm = nullptr, const double* longest_descent_s = nullptr) {
  std::string s = "front-aware z=" + format_number(z);
  if (pooling) s += " slopes=" + to_string(*pooling);
  if (top_level) s += " top=" + to_string(*top_level);
  if (finest_descent_gsd_cm)
    s += " finest=" + (*finest_descent_gsd_cm > 0.0 ? format_number(*finest_descent_gsd_cm) : std::string("any"));
  if (longest_descent_s)
    s += " longest=" + (*longest_descent_s > 0.0 ? format_number(*longest_descent_s) : std::string("any"));
  return s;
}

/// What the search tries beyond z: the slope poolings (several only where the cell gain model
/// pools several fields) and the top-level choices (several only with ranked cells, which
/// predict each field's curve at every top level).
struct FrontAwareGrid {
  std::vector<SlopePooling> poolings;
  std::vector<TopLevelChoice> top_levels;
  bool ranked = false;  ///< DescentCoverage::ranked
  bool pools = false;   ///< ranked with several training fields
};

/// One setting tried: its pooling and top level (indices into FrontAwareGrid), z, the
/// parameters flown.
struct FrontAwareSetting {
  std::size_t pooling = 0;
  std::size_t top_level = 0;
  double z = 0.0;
  FrontAwareParams params;
};

/// Whether trial `k` is kept over trial `b` among the z of one pooling, top level and limits
/// (indices into `trials` and `settings`, in the same order): a larger mean front margin, ties to
/// the larger z, the more cautious of settings that fly the training fields alike.
[[nodiscard]] inline bool keeps_z_over(std::span<const RuleTrial> trials, std::span<const FrontAwareSetting> settings,
                                       std::size_t k, std::size_t b) {
  return trials[k].front_margin > trials[b].front_margin ||
         (trials[k].front_margin == trials[b].front_margin && settings[k].z > settings[b].z);
}

/// The setting kept (an index into `trials` and `settings`, in the same order): per pooling and
/// top level, its z of best mean front margin (keeps_z_over); per top level, the first
/// pooling's unless another beats it by more than the folds' noise (select_pooling); of the
/// top levels' so kept, the first's unless another beats it by more than the folds' noise
/// (select_pooling again, the same grounds). Until 2026-12-05 any larger mean front margin took
/// another top level, and `hull` was kept for building on tile 1 for a gain on one training
/// field alone (docs/journal/2026-12-loto.md, forty-second session).
inline std::size_t choose_setting(std::span<const RuleTrial> trials, std::span<const FrontAwareSetting> settings,
                                  const FrontAwareGrid& grid, std::span<const std::size_t> grounds = {}) {
  const std::size_t none = trials.size();
  std::vector<std::vector<std::size_t>> best(grid.top_levels.size(),
                                             std::vector<std::size_t>(grid.poolings.size(), none));
  for (std::size_t k = 0; k < trials.size(); ++k) {
    std::size_t& b = best[settings[k].top_level][settings[k].pooling];
    if (b == none || keeps_z_over(trials, settings, k, b)) b = k;
  }
  std::vector<std::size_t> of_levels;
  std::vector<const RuleTrial*> levels;
  for (const std::vector<std::size_t>& of_level : best) {
    std::vector<const RuleTrial*> candidates;
    for (std::size_t b : of_level) candidates.push_back(&trials[b]);
    of_levels.push_back(of_level[select_pooling(candidates, grounds)]);
    levels.push_back(&trials[of_levels.back()]);
  }
  return of_levels[select_pooling(levels, grounds)];
}

/// Setting `s`'s trial name (z_text): its pooling, top level, finest descent GSD and longest
/// descent named where the search tries several of them.
[[nodiscard]] inline std::string setting_text(const RuleSearchInputs& in, const FrontAwareGrid& grid,
                                              const FrontAwareSetting& s) {
  return z_text(s.z, grid.poolings.size() > 1 ? &grid.poolings[s.pooling] : nullptr,
                grid.top_levels.size() > 1 ? &grid.top_levels[s.top_level] : nullptr,
                in.options.finest_descent_gsd_cm.size() > 1 ? &s.params.finest_descent_gsd_cm : nullptr,
                in.options.longest_descent_s.size() > 1 ? &s.params.longest_descent_s : nullptr);
}

}  // namespace adaptseg::detail
