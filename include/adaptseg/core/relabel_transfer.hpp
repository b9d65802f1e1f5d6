#pragma once
/// @file
/// How far a field's gain factor moves with its relabelled factor (beyond the paper;
/// docs/method.md, "The field factor from what a descent relabelled"). In flight the relabelled
/// share χ of each descent is observable and tells the field factor s of what descents relabel
/// (FieldFactorSource::relabelled); whether the gain follows is a property of the class and the
/// network that calibration can measure on its training fields' cells: a field whose cells
/// relabel more than the pooled fit per unit of input may gain more too (a class whose descents
/// correct the map) or not (one whose finer looks write the class where it is absent).

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/gsd.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <utility>
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
  struct Sums {
    double xx = 0.0, xg = 0.0, xr = 0.0;
  };
  struct Pair {
    double top = 0.0, sub = 0.0;
    std::vector<std::pair<std::size_t, Sums>> fields;
  };
  std::vector<Pair> pairs;
  std::vector<std::size_t> fields_seen;
  for (const CellSample& c : cells) {
    const double x = c.top.value(input), w = c.top.field_px;
    if (!std::isfinite(x) || !(x > 0.0) || !(w > 0.0)) continue;
    auto p = std::find_if(pairs.begin(), pairs.end(), [&](const Pair& q) {
      return detail::same_gsd(q.top, c.top_gsd_cm) && detail::same_gsd(q.sub, c.sub_gsd_cm);
    });
    if (p == pairs.end()) p = pairs.insert(pairs.end(), Pair{c.top_gsd_cm, c.sub_gsd_cm, {}});
    auto f = std::find_if(p->fields.begin(), p->fields.end(), [&](const auto& e) { return e.first == c.field; });
    if (f == p->fields.end()) f = p->fields.insert(p->fields.end(), {c.field, Sums{}});
    f->second.xx += w * x * x;
    f->second.xg += w * x * c.normalized_gain();
    f->second.xr += w * x * c.relabelled;
    if (std::find(fields_seen.begin(), fields_seen.end(), c.field) == fields_seen.end()) fields_seen.push_back(c.field);
  }
  if (fields_seen.size() < 3) return 1.0;
  double num = 0.0, den = 0.0;
  for (const Pair& p : pairs) {
    Sums all;
    for (const auto& [field, s] : p.fields) all.xx += s.xx, all.xg += s.xg, all.xr += s.xr;
    const double beta = all.xg / all.xx, alpha = all.xr / all.xx;
    if (!(beta > 0.0) || !(alpha > 0.0)) continue;
    for (const auto& [field, s] : p.fields) {
      const double rb = s.xg / s.xx / beta - 1.0, ra = s.xr / s.xx / alpha - 1.0;
      num += ra * rb;
      den += ra * ra;
    }
  }
  if (!(den > 0.0)) return 1.0;
  return std::clamp(num / den, 0.0, 1.0);
}

}  // namespace adaptseg
