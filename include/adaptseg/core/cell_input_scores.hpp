#pragma once
/// @file
/// The scores a decision input is chosen by on the training fields, to rank cells by and
/// forecast them from (beyond the paper; docs/method.md, "Cells that pay"): how much of each
/// field's achievable gain the input's best cells capture (`ranking`), and the same counted only
/// where the cell gain model fitted on the other fields forecasts a gain (`transfer`).

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/detail/named_rows.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

namespace adaptseg {

/// Which score chooses the input (CalibrationOptions::cell_input_score):
/// - `ranking`: cell_ranking_capture(), how well the input ranks each field's cells by what
///   re-mapping them gains, each field on its own. Blind to the slope: an input whose cells rank
///   well but whose slope, pooled over the fields, is negative never makes a descent pay.
/// - `transfer`: cell_transfer_capture(), the same counted only for the pairs of GSDs where the
///   model fitted without the field forecasts a gain (β > 0): what the input's best cells would
///   gain on a field the model never saw, descending only where its slope says so.
enum class CellInputScore { ranking, transfer };

/// Every score by name (`--cell-input-score` of the programs).
inline constexpr std::array<detail::NamedValue<CellInputScore>, 2> kCellInputScores{{
    {CellInputScore::ranking, "ranking"},
    {CellInputScore::transfer, "transfer"},
}};

/// The name of a score.
[[nodiscard]] inline std::string to_string(CellInputScore s) {
  return detail::name_of(kCellInputScores, s, "cell input score");
}

/// Parses a score's name.
/// @throws std::invalid_argument for anything but `ranking` or `transfer`.
[[nodiscard]] inline CellInputScore parse_cell_input_score(std::string_view name) {
  return detail::value_named(kCellInputScores, name, "cell input score");
}

namespace detail {

/// The share of the achievable positive field gain (Σ max(gain, 0)) of one field and pair of
/// GSDs that re-mapping the `share` of its `cells` with the most `input` mass captures; nullopt
/// where nothing is achievable.
[[nodiscard]] inline std::optional<double> captured_share(std::vector<const CellSample*> cells, DecisionInput input,
                                                          double share) {
  double positive = 0.0;
  for (const CellSample* s : cells) positive += std::max(0.0, s->field_gain);
  if (!(positive > 0.0)) return std::nullopt;
  std::stable_sort(cells.begin(), cells.end(),
                   [&](const CellSample* a, const CellSample* b) { return a->top.mass(input) > b->top.mass(input); });
  const auto n = static_cast<std::size_t>(std::lround(share * static_cast<double>(cells.size())));
  double captured = 0.0;
  for (std::size_t k = 0; k < n; ++k) captured += cells[k]->field_gain;
  return captured / positive;
}

/// The (field, top GSD, descent GSD) groups of `samples`, in order of first appearance, each
/// with its cells.
[[nodiscard]] inline std::vector<std::pair<std::tuple<std::size_t, double, double>, std::vector<const CellSample*>>>
cell_groups(std::span<const CellSample> samples) {
  std::vector<std::pair<std::tuple<std::size_t, double, double>, std::vector<const CellSample*>>> groups;
  for (const CellSample& s : samples) {
    const std::tuple key{s.field, s.top_gsd_cm, s.sub_gsd_cm};
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
    if (it == groups.end()) it = groups.insert(groups.end(), {key, {}});
    it->second.push_back(&s);
  }
  return groups;
}

}  // namespace detail

/// How well an input ranks the cells of the training fields by what re-mapping them gains:
/// on each field and pair of top-level and candidate GSD in turn, the share of the achievable
/// positive field gain (Σ max(gain, 0)) that re-mapping the `share` of cells with the most input
/// mass (CellInputs::mass) captures; the mean over the (field, GSD) pairs with a positive
/// achievable gain. No fitting is involved (the cell gain model only rescales the ranking), so
/// each field is scored without the others: a leave-one-field-out score. NaN without such a pair.
[[nodiscard]] inline double cell_ranking_capture(std::span<const CellSample> samples, DecisionInput input,
                                                 double share = 0.2) {
  double sum = 0.0;
  int count = 0;
  for (const auto& [key, cells] : detail::cell_groups(samples))
    if (const auto captured = detail::captured_share(cells, input, share)) {
      sum += *captured;
      ++count;
    }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

/// cell_ranking_capture() as a decision would realise it on a field the model never saw: each
/// training field's (field, GSD pair) share captured counts where the cell gain model of `input`
/// fitted on the other fields' cells (CellGainModel::fit, `pooling`) has a positive slope β for
/// the pair, and as 0 where it has not (that model forecasts every descent of the pair a loss,
/// or knows no such pair, and would not descend). The mean over the (field, GSD) pairs with a
/// positive achievable gain, as cell_ranking_capture(). With one field there is no other to fit
/// on: cell_ranking_capture(). NaN without such a pair.
[[nodiscard]] inline double cell_transfer_capture(std::span<const CellSample> samples, DecisionInput input,
                                                  SlopePooling pooling = SlopePooling::cells, double share = 0.2) {
  // Each (field, GSD pair) group and its captured share once; each field's model once.
  const auto groups = detail::cell_groups(samples);
  std::vector<std::size_t> fields;
  std::vector<std::optional<double>> captured;
  for (const auto& [key, cells] : groups) {
    if (std::find(fields.begin(), fields.end(), std::get<0>(key)) == fields.end()) fields.push_back(std::get<0>(key));
    captured.push_back(detail::captured_share(cells, input, share));
  }
  if (fields.size() < 2) return cell_ranking_capture(samples, input, share);
  double sum = 0.0;
  int count = 0;
  for (const std::size_t held_out : fields) {
    std::vector<CellSample> others;
    for (const CellSample& s : samples)
      if (s.field != held_out) others.push_back(s);
    const CellGainModel model = CellGainModel::fit(others, input, pooling);
    const auto slope = [&](double top, double sub) {
      for (const auto& p : model.points())
        if (detail::same_gsd(p.top_gsd_cm, top) && detail::same_gsd(p.sub_gsd_cm, sub)) return p.gain_slope;
      return 0.0;
    };
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const auto& [field, top, sub] = groups[g].first;
      if (field != held_out || !captured[g]) continue;
      if (slope(top, sub) > 0.0) sum += *captured[g];
      ++count;
    }
  }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

/// The score `score` names.
[[nodiscard]] inline double cell_input_score(CellInputScore score, std::span<const CellSample> samples,
                                             DecisionInput input) {
  return score == CellInputScore::transfer ? cell_transfer_capture(samples, input)
                                           : cell_ranking_capture(samples, input);
}

}  // namespace adaptseg
