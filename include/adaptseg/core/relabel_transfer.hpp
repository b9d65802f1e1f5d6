#pragma once
/// @file
/// What one descent's relabelled share says about the field (beyond the paper; docs/method.md,
/// "The field factor from what a descent relabelled"): how far a field's gain factor moves with
/// its relabelled factor, and how far one region's relabelled share strays from its field's
/// factor, and how far the fields' relabelled factors stray from 1. In flight the relabelled
/// share χ of each descent is observable and tells the field factor s of what descents relabel
/// (FieldFactorSource::relabelled); whether the gain follows is a property of the class and the
/// network that calibration can measure on its training fields' cells: a field whose cells
/// relabel more than the pooled fit per unit of input may gain more too (a class whose descents
/// correct the map) or not (one whose finer looks write the class where it is absent).

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/field_slopes.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace adaptseg {

/// b in [0, 1] (FrontAwarePolicy::Params::relabel_transfer) from calibration's cell samples
/// `cells`, their input `input` (the cell gain model's): per pair of top-level and descent GSDs,
/// each field's own slopes through the origin of the normalised gain and of the relabelled share
/// on the input (Σ w·x·y / Σ w·x², w the cell's field pixels, as CellGainModel fits them) as
/// ratios to the slopes of every field's cells together, r_β and r_α; b is the slope through
/// (1, 1) of r_β on r_α over every field and pair where both pooled slopes are positive,
/// Σ (r_α − 1)(r_β − 1) / Σ (r_α − 1)², clamped to [0, 1]. Fewer than three fields with cells
/// that hold the input, or no spread of r_α: 1 (s scales the gain whole, nothing measured).
[[nodiscard]] inline double relabel_transfer(std::span<const CellSample> cells, DecisionInput input) {
  // Per pair of GSDs, each field's sums of the gain's and the relabelled share's fits.
  struct Pair {
    detail::PerField gain, relabel;
  };
  std::vector<Pair> pairs;
  std::vector<std::size_t> fields_seen;
  for (const detail::GsdGroup& g : detail::group_by_gsds(cells)) {
    Pair& p = pairs.emplace_back();
    for (const CellSample* c : g.cells) {
      const double x = c->top.value(input), w = c->top.field_px;
      if (!std::isfinite(x) || !(x > 0.0) || !(w > 0.0)) continue;
      detail::sums_of(p.gain, c->field).add(w, x, c->normalized_gain());
      detail::sums_of(p.relabel, c->field).add(w, x, c->relabelled);
      if (std::find(fields_seen.begin(), fields_seen.end(), c->field) == fields_seen.end())
        fields_seen.push_back(c->field);
    }
  }
  if (fields_seen.size() < 3) return 1.0;
  double num = 0.0, den = 0.0;
  for (const Pair& p : pairs) {
    double xx = 0.0, xg = 0.0, xr = 0.0;
    for (std::size_t k = 0; k < p.gain.size(); ++k)
      xx += p.gain[k].second.xx, xg += p.gain[k].second.xy, xr += p.relabel[k].second.xy;
    const double beta = xg / xx, alpha = xr / xx;
    if (!(beta > 0.0) || !(alpha > 0.0)) continue;
    for (std::size_t k = 0; k < p.gain.size(); ++k) {
      const detail::FieldSlopeSums &g = p.gain[k].second, &r = p.relabel[k].second;
      const double rb = g.xy / g.xx / beta - 1.0, ra = r.xy / r.xx / alpha - 1.0;
      num += ra * rb;
      den += ra * ra;
    }
  }
  if (!(den > 0.0)) return 1.0;
  return std::clamp(num / den, 0.0, 1.0);
}

namespace detail {
/// One field's regions at one pair of GSDs, as relabel_region_sd() reads them: Σ ρ, Σ ρ², n.
struct RegionRatios {
  double top = 0.0, sub = 0.0;
  std::size_t field = 0;
  double sum = 0.0, sum_sq = 0.0;
  std::size_t n = 0;
};

/// Per pair of GSDs and field, the ratios ρ of its regions' relabelled shares to their forecast
/// (relabel_region_sd()).
inline std::vector<RegionRatios> region_ratios(std::span<const CellSample> cells, DecisionInput input) {
  struct Region {
    std::size_t field = 0, region = 0;
    double px = 0.0, px_x = 0.0, px_chi = 0.0;
  };
  std::vector<RegionRatios> groups;
  for (const GsdGroup& g : group_by_gsds(cells)) {
    double xx = 0.0, xchi = 0.0;  // the pair's slope of χ on x through the origin, over every field
    std::vector<Region> regions;
    for (const CellSample* c : g.cells) {
      const double x = c->top.value(input), w = c->top.field_px;
      if (!std::isfinite(x) || !(x >= 0.0) || !(w > 0.0)) continue;
      xx += w * x * x, xchi += w * x * c->relabelled;
      auto r = std::find_if(regions.begin(), regions.end(),
                            [&](const Region& q) { return q.field == c->field && q.region == c->region; });
      if (r == regions.end()) r = regions.insert(regions.end(), Region{c->field, c->region});
      r->px += w, r->px_x += w * x, r->px_chi += w * c->relabelled;
    }
    const double alpha = xx > 0.0 ? xchi / xx : 0.0;
    std::vector<RegionRatios> of_pair;  // this pair's fields
    for (const Region& r : regions) {
      const double forecast = alpha * r.px_x / r.px;
      if (!(forecast > 0.0)) continue;
      const double rho = (r.px_chi / r.px) / forecast;
      auto f = std::find_if(of_pair.begin(), of_pair.end(), [&](const RegionRatios& q) { return q.field == r.field; });
      if (f == of_pair.end()) f = of_pair.insert(of_pair.end(), RegionRatios{g.top, g.sub, r.field});
      f->sum += rho, f->sum_sq += rho * rho, ++f->n;
    }
    groups.insert(groups.end(), of_pair.begin(), of_pair.end());
  }
  return groups;
}
}  // namespace detail

/// τ_r >= 0 (FrontAwarePolicy::Params::relabel_region_sd) from calibration's cell samples
/// `cells`, their input `input`: how far one region's relabelled share strays from what its
/// field's factor says, relative to the forecast. Per pair of GSDs, α the slope through the
/// origin of the relabelled share on the input over every field's cells (as relabel_transfer());
/// per field and region, the ratio ρ of its cells' relabelled share (Σ px·χ / Σ px) to the
/// forecast α·Σ px·x / Σ px; τ_r² the variance of ρ about its field's mean, pooled over the fields
/// and pairs with n − 1 degrees of freedom each. The cells' own spread (what the cell gain model's
/// κ_χ gives one descent) is not taken out: a region's cells share its ground. No field with two
/// regions that forecast a share: 0.
[[nodiscard]] inline double relabel_region_sd(std::span<const CellSample> cells, DecisionInput input) {
  double ss = 0.0, dof = 0.0;
  for (const detail::RegionRatios& g : detail::region_ratios(cells, input)) {
    if (g.n < 2) continue;
    ss += std::max(0.0, g.sum_sq - g.sum * g.sum / static_cast<double>(g.n));
    dof += static_cast<double>(g.n - 1);
  }
  return dof > 0.0 ? std::sqrt(ss / dof) : 0.0;
}

/// ω_χ (FrontAwarePolicy::Params::relabel_field_sd) from calibration's cell samples `cells`,
/// their input `input`: how far a field's relabelled factor strays from 1 between the training
/// fields, measured as the field factor's prior spread ω is (pooled_fold_models()). Per field f,
/// its factor s_f is the least-squares scale of the forecast relabelled shares onto its cells'
/// own, Σ (μ·w)(χ·w) / Σ (μ·w)² over its cells at every pair of GSDs, μ = α₋f·x with α₋f the
/// pair's slope through the origin of χ on the input over the other fields' cells (Σ w·x·χ /
/// Σ w·x², w the cell's field pixels), so that no field is forecast by a slope it made; ω_χ² is
/// the mean of (s_f − 1)² over the fields, ω_χ at least 0.1 (ω's floor). Fewer than two fields
/// with cells that hold the input: 0 (s keeps ω).
[[nodiscard]] inline double relabel_field_sd(std::span<const CellSample> cells, DecisionInput input) {
  detail::PerField scales;  // per field over every pair: xy = Σ (μ·w)(χ·w), xx = Σ (μ·w)²
  for (const detail::GsdGroup& g : detail::group_by_gsds(cells)) {
    // This pair's sums per field, weighted by w (the slope's) and by w² (the scale's).
    detail::PerField slope, scale;
    for (const CellSample* c : g.cells) {
      const double x = c->top.value(input), w = c->top.field_px;
      if (!std::isfinite(x) || !(x >= 0.0) || !(w > 0.0) || !std::isfinite(c->relabelled)) continue;
      detail::sums_of(slope, c->field).add(w, x, c->relabelled);
      detail::sums_of(scale, c->field).add(w * w, x, c->relabelled);
    }
    double xx = 0.0, xchi = 0.0;
    for (const auto& f : slope) xx += f.second.xx, xchi += f.second.xy;
    for (std::size_t k = 0; k < slope.size(); ++k) {  // `scale` holds the same fields in the same order
      const detail::FieldSlopeSums &own = slope[k].second, &sq = scale[k].second;
      if (!(xx - own.xx > 0.0)) continue;
      const double alpha = (xchi - own.xy) / (xx - own.xx);  // the other fields' slope
      detail::FieldSlopeSums& f = detail::sums_of(scales, slope[k].first);
      f.xy += alpha * sq.xy, f.xx += alpha * alpha * sq.xx;
    }
  }
  double ss = 0.0;
  std::size_t n = 0;
  for (const auto& f : scales) {
    if (!(f.second.xx > 0.0)) continue;
    ss += std::pow(f.second.xy / f.second.xx - 1.0, 2);
    ++n;
  }
  return n >= 2 ? std::max(0.1, std::sqrt(ss / static_cast<double>(n))) : 0.0;
}

}  // namespace adaptseg
