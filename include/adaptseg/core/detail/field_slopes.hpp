#pragma once
/// @file
/// Slopes through the origin fitted on each training field alone and pooled over the fields
/// (CellGainModel::fit, SlopePooling): random effects (DerSimonian and Laird 1986), and random
/// effects with a field-level covariate (a meta-regression: the slope a linear function of the
/// field's mean top-level entropy). docs/method.md, "Cells that pay".

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// One training field's sums for the slope through the origin of y on x (weights w), and the
/// field-level covariate u (its pixel-weighted mean: Σ px·u / Σ px).
struct FieldSlopeSums {
  double xy = 0.0, xx = 0.0, yy = 0.0;
  double pu = 0.0, px = 0.0;  ///< Σ px·u and Σ px of the covariate
  std::size_t n = 0;
  void add(double w, double x, double y) {
    xy += w * x * y;
    xx += w * x * x;
    yy += w * y * y;
    ++n;
  }
  /// One cell's covariate value `u` (skipped where not finite) over `px` pixels.
  void add_covariate(double px_cell, double u) {
    if (!std::isfinite(u) || !(px_cell > 0.0)) return;
    pu += px_cell * u;
    px += px_cell;
  }
  [[nodiscard]] double covariate() const noexcept {
    return px > 0.0 ? pu / px : std::numeric_limits<double>::quiet_NaN();
  }
};

/// Each training field's sums (field index, sums), in the order the fields first occur.
using PerField = std::vector<std::pair<std::size_t, FieldSlopeSums>>;

/// The sums of `field` in `fields`, added (zero) if it has none yet.
inline FieldSlopeSums& sums_of(PerField& fields, std::size_t field) {
  auto it = std::find_if(fields.begin(), fields.end(), [&](const auto& f) { return f.first == field; });
  if (it == fields.end()) it = fields.insert(fields.end(), {field, FieldSlopeSums{}});
  return it->second;
}

/// One field's own slope b_f = Σ w·x·y / Σ w·x², its variance v_f = s_f² / Σ w·x² (s_f² the
/// field's residual variance) and its covariate u_f.
struct OwnSlope {
  double b = 0.0, v = 0.0, u = 0.0;
};

/// The fields that count (at least two cells holding some input), each with its own slope.
inline std::vector<OwnSlope> own_slopes(const PerField& fields) {
  std::vector<OwnSlope> out;
  for (const auto& [field, f] : fields) {
    if (!(f.xx > 0.0) || f.n < 2) continue;
    const double b = f.xy / f.xx;
    const double rss = std::max(0.0, f.yy - b * f.xy);
    // A field whose line fits its cells exactly (the oracle at the field's GSD) still has a
    // finite weight.
    out.push_back({b, std::max(rss / static_cast<double>(f.n - 1), 1e-12) / f.xx, f.covariate()});
  }
  return out;
}

/// A slope pooled over the fields: its value at the covariate `reference` and its change per
/// unit of covariate `per_unit` (0 without a covariate), the covariate's range over the fields
/// that count [`low`, `high`] (0, 0 without one).
struct PooledSlope {
  double at_reference = 0.0;
  double per_unit = 0.0;
  double reference = 0.0;
  double low = 0.0, high = 0.0;
};

/// β or α of one pair of GSDs from each training field's sums (CellGainModel, SlopePooling::
/// fields): the b_f pooled as random effects (DerSimonian and Laird 1986): τ², the spread of the
/// true slopes between fields, by the method of moments from Cochran's Q about the
/// precision-weighted mean; then the mean of the b_f weighted by 1 / (v_f + τ²). Fields that
/// agree within their cells' scatter weigh by their precision (near the fit pooled over the
/// cells); fields that disagree weigh alike (near the mean of their slopes). A field of fewer
/// than two cells, or whose cells hold no input, does not count; without any field that counts,
/// the fit pooled over the cells (also the result for one field's sums: its own fit).
inline double field_slope(const PerField& fields) {
  if (fields.size() == 1) {  // one field's (or SlopePooling::cells: all cells') own fit
    const FieldSlopeSums& f = fields.front().second;
    return f.xx > 0.0 ? f.xy / f.xx : 0.0;
  }
  double xy = 0.0, xx = 0.0;
  for (const auto& [field, f] : fields) xy += f.xy, xx += f.xx;
  const std::vector<OwnSlope> slopes = own_slopes(fields);
  if (slopes.empty()) return xx > 0.0 ? xy / xx : 0.0;
  double sw = 0.0, sww = 0.0, swb = 0.0;
  for (const OwnSlope& s : slopes) {
    sw += 1.0 / s.v;
    sww += 1.0 / (s.v * s.v);
    swb += s.b / s.v;
  }
  const double fixed = swb / sw;
  double q = 0.0;
  for (const OwnSlope& s : slopes) q += (s.b - fixed) * (s.b - fixed) / s.v;
  const double c = sw - sww / sw;
  const double tau2 = c > 0.0 ? std::max(0.0, (q - static_cast<double>(slopes.size() - 1)) / c) : 0.0;
  double num = 0.0, den = 0.0;
  for (const OwnSlope& s : slopes) {
    num += s.b / (s.v + tau2);
    den += 1.0 / (s.v + tau2);
  }
  return num / den;
}

/// The weighted least-squares line of the b_f on the u_f, weights 1 / (v_f + `tau2`), centred
/// at the weighted mean covariate; with the residual Q about it and tr P (P the projection's
/// residual operator: Σ w − Σ w² / Σ w − Σ w²·(u − ū)² / S_uu), what τ²'s moment estimate needs.
struct CovariateLine {
  PooledSlope slope;
  double q = 0.0, trace = 0.0;
};
inline CovariateLine covariate_line(const std::vector<OwnSlope>& slopes, double tau2) {
  double sw = 0.0, swu = 0.0, swb = 0.0;
  for (const OwnSlope& s : slopes) {
    const double w = 1.0 / (s.v + tau2);
    sw += w, swu += w * s.u, swb += w * s.b;
  }
  const double u0 = swu / sw, b0 = swb / sw;
  double suu = 0.0, sub = 0.0, sww = 0.0, swwuu = 0.0;
  for (const OwnSlope& s : slopes) {
    const double w = 1.0 / (s.v + tau2);
    suu += w * (s.u - u0) * (s.u - u0);
    sub += w * (s.u - u0) * (s.b - b0);
    sww += w * w;
    swwuu += w * w * (s.u - u0) * (s.u - u0);
  }
  CovariateLine out;
  out.slope.at_reference = b0;
  out.slope.reference = u0;
  out.slope.per_unit = suu > 0.0 ? sub / suu : 0.0;
  for (const OwnSlope& s : slopes) {
    const double r = s.b - b0 - out.slope.per_unit * (s.u - u0);
    out.q += r * r / (s.v + tau2);
  }
  out.trace = sw - sww / sw - (suu > 0.0 ? swwuu / suu : 0.0);
  return out;
}

/// β of one pair of GSDs from each training field's sums and covariate (CellGainModel,
/// SlopePooling::field_entropy): a random-effects meta-regression, b_f = a + c·(u_f − ū) + e_f,
/// e_f ~ N(0, v_f + τ²), τ² by the method of moments from the residual Q of the fixed-effects
/// line (the DerSimonian and Laird estimate with two parameters: (Q − (k − 2)) / tr P), then the
/// line weighted by 1 / (v_f + τ²). Needs three fields that count with a covariate and a spread
/// in it; else field_slope() with no change per unit.
inline PooledSlope field_slope_by_covariate(const PerField& fields) {
  std::vector<OwnSlope> slopes = own_slopes(fields);
  std::erase_if(slopes, [](const OwnSlope& s) { return !std::isfinite(s.u); });
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const OwnSlope& s : slopes) lo = std::min(lo, s.u), hi = std::max(hi, s.u);
  if (slopes.size() < 3 || !(hi > lo)) {
    PooledSlope flat;
    flat.at_reference = field_slope(fields);
    return flat;
  }
  const CovariateLine fixed = covariate_line(slopes, 0.0);
  const double k = static_cast<double>(slopes.size());
  const double tau2 = fixed.trace > 0.0 ? std::max(0.0, (fixed.q - (k - 2.0)) / fixed.trace) : 0.0;
  PooledSlope out = covariate_line(slopes, tau2).slope;
  out.low = lo;
  out.high = hi;
  return out;
}

/// τ_γ of one pair of GSDs (CellGainModel): the proxy's slope fitted on each training field's
/// cells alone, γ_f = Σ w·d·ν / Σ w·d² (from `fields`, the sums fit() collects of ν on
/// d = x − x'), and their spread about the pooled `slope`, Σ_f (γ_f − γ)² / (n − 1) over the n
/// fields whose finer looks changed the input; |γ| where n < 2.
inline double field_slope_spread(const PerField& fields, double slope) {
  double sq = 0.0;
  std::size_t n = 0;
  for (const auto& [field, sums] : fields)
    if (sums.xx > 0.0) {
      sq += std::pow(sums.xy / sums.xx - slope, 2);
      ++n;
    }
  return n >= 2 ? std::sqrt(sq / static_cast<double>(n - 1)) : std::abs(slope);
}

}  // namespace adaptseg::detail
