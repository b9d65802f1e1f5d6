#pragma once
/// @file
/// decisions.csv, one row per decision of a mission (docs/data_format.md): what was forecast for
/// the candidate the row describes, what the descent changed, and, in simulation, what it
/// gained. Written from one table of columns (kDecisionColumns: each column's name beside how a
/// row writes it), so that the header and the rows cannot drift apart. Numbers are written in
/// fixed notation, whatever the C locale (std::to_chars).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/sim/csv.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/detail/number_text.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace adaptseg {

/// One row of decisions.csv: a decision of a mission and what is known about it.
struct DecisionRow {
  std::string_view field;     ///< the field flown (quoted in the CSV where it holds a comma)
  std::string_view strategy;  ///< the strategy flown (kStrategyTable's name)
  std::size_t index = 0;      ///< the decision's index in the mission
  const DecisionRecord* record = nullptr;
  /// The candidate the row describes: the one chosen, else the one of best forecast (field gain
  /// where the rule makes one, else ΔmIoU); none where there was no candidate.
  std::optional<std::size_t> candidate;
  const RealisedDescent* realised = nullptr;  ///< in simulation, after a descent

  [[nodiscard]] const Candidate* chosen() const { return candidate ? &record->candidates[*candidate] : nullptr; }
  [[nodiscard]] const CandidateScore* score() const {
    return candidate && *candidate < record->decision.scores.size() ? &record->decision.scores[*candidate] : nullptr;
  }
};

namespace detail {
/// `v` with 6 decimals; empty where it is not finite (a forecast the rule does not make).
[[nodiscard]] inline std::string finite6(double v) { return std::isfinite(v) ? format_fixed(v, 6) : std::string(); }
}  // namespace detail

/// A column of decisions.csv: its name and how a row writes it (empty: no value).
struct DecisionColumn {
  const char* name;
  std::string (*value)(const DecisionRow&);
};

/// Every column of decisions.csv, in order (docs/data_format.md says what each holds).
inline const std::array<DecisionColumn, 29> kDecisionColumns{{
    {"field", [](const DecisionRow& r) { return csv_field(r.field); }},
    {"strategy", [](const DecisionRow& r) { return std::string(r.strategy); }},
    {"decision", [](const DecisionRow& r) { return std::to_string(r.index); }},
    {"image", [](const DecisionRow& r) { return std::to_string(r.record->waypoint_index); }},
    {"sigma", [](const DecisionRow& r) { return detail::format_fixed(r.record->sigma, 6); }},
    {"action", [](const DecisionRow& r) { return std::string(r.record->decision.descend ? "descend" : "continue"); }},
    {"gsd_cm",
     [](const DecisionRow& r) { return r.chosen() ? detail::format_fixed(r.chosen()->gsd_cm, 3) : std::string(); }},
    {"images", [](const DecisionRow& r) { return r.chosen() ? std::to_string(r.chosen()->images) : std::string(); }},
    {"extra_time_s",
     [](const DecisionRow& r) {
       return r.chosen() ? detail::format_fixed(r.chosen()->extra_time_s, 3) : std::string();
     }},
    {"forecast_delta_sigma",
     [](const DecisionRow& r) {
       return r.score() ? detail::format_fixed(r.score()->predicted_delta_sigma, 6) : std::string();
     }},
    {"forecast_delta_miou",
     [](const DecisionRow& r) {
       return r.score() ? detail::format_fixed(r.score()->predicted_delta_miou, 6) : std::string();
     }},
    {"forecast_delta_miou_std",
     [](const DecisionRow& r) {
       return r.score() ? detail::format_fixed(r.score()->predicted_delta_miou_std, 6) : std::string();
     }},
    {"forecast_relabelled_interest",
     [](const DecisionRow& r) { return r.score() ? detail::finite6(r.score()->predicted_relabelled) : std::string(); }},
    {"forecast_field_gain",
     [](const DecisionRow& r) { return r.score() ? detail::finite6(r.score()->predicted_field_gain) : std::string(); }},
    {"forecast_front_margin",
     [](const DecisionRow& r) {
       return r.score() ? detail::finite6(r.score()->predicted_front_margin) : std::string();
     }},
    {"observed_sigma_sub",
     [](const DecisionRow& r) {
       return r.record->outcome ? detail::format_fixed(r.record->outcome->sigma_sub, 6) : std::string();
     }},
    {"observed_relabelled",
     [](const DecisionRow& r) {
       return r.record->outcome ? detail::format_fixed(r.record->outcome->relabelled.share, 6) : std::string();
     }},
    {"observed_relabelled_interest",
     [](const DecisionRow& r) {
       return r.record->outcome ? detail::format_fixed(r.record->outcome->relabelled.interest_share, 6) : std::string();
     }},
    {"realised_region_delta_miou",
     [](const DecisionRow& r) {
       return r.realised ? detail::format_fixed(r.realised->region_delta_miou(), 6) : std::string();
     }},
    {"realised_field_gain",
     [](const DecisionRow& r) { return r.realised ? detail::format_fixed(r.realised->field_gain, 6) : std::string(); }},
    {"flown",
     [](const DecisionRow& r) {
       return r.chosen() ? std::string(r.chosen()->deferred ? "tour" : "now") : std::string();
     }},
    {"observed_top_input",
     [](const DecisionRow& r) {
       return r.record->outcome ? detail::finite6(r.record->outcome->top_input) : std::string();
     }},
    {"observed_fine_input",
     [](const DecisionRow& r) {
       return r.record->outcome ? detail::finite6(r.record->outcome->fine_input) : std::string();
     }},
    {"realised_delta_tp",
     [](const DecisionRow& r) { return r.realised ? std::to_string(r.realised->delta_tp) : std::string(); }},
    {"realised_delta_fp",
     [](const DecisionRow& r) { return r.realised ? std::to_string(r.realised->delta_fp) : std::string(); }},
    {"realised_delta_fn",
     [](const DecisionRow& r) { return r.realised ? std::to_string(r.realised->delta_fn) : std::string(); }},
    {"forecast_curve_rise",
     [](const DecisionRow& r) { return r.score() ? detail::finite6(r.score()->predicted_curve_rise) : std::string(); }},
    {"forecast_end_s",
     [](const DecisionRow& r) { return r.score() ? detail::finite6(r.score()->predicted_end_s) : std::string(); }},
    {"realised_field_gain_region",
     [](const DecisionRow& r) {
       return r.realised ? detail::format_fixed(r.realised->field_gain_region, 6) : std::string();
     }},
}};

/// The header line of decisions.csv (with its line break).
[[nodiscard]] inline std::string decisions_csv_header() {
  std::string line;
  for (const DecisionColumn& c : kDecisionColumns) {
    if (!line.empty()) line += ',';
    line += c.name;
  }
  line += '\n';
  return line;
}

/// The rows of a mission's decisions: per decision, the candidate it describes (the one chosen
/// by chosen_candidate(), `strategy` naming the rule in its message; else the best forecast) and
/// its realised descent where `realised` (one per descent, in decision order) has one.
/// @throws std::logic_error as chosen_candidate() for a descent its candidates cannot name.
[[nodiscard]] inline std::vector<DecisionRow> decision_rows(std::string_view field, std::string_view strategy,
                                                            std::span<const DecisionRecord> decisions,
                                                            std::span<const RealisedDescent> realised) {
  std::vector<DecisionRow> rows;
  std::size_t next_realised = 0;
  for (std::size_t k = 0; k < decisions.size(); ++k) {
    const DecisionRecord& d = decisions[k];
    DecisionRow row{field, strategy, k, &d, std::nullopt, nullptr};
    if (d.decision.descend) row.candidate = chosen_candidate(d.decision, d.candidates, std::string(strategy));
    for (std::size_t i = 0; !d.decision.descend && i < d.candidates.size() && i < d.decision.scores.size(); ++i) {
      const CandidateScore& s = d.decision.scores[i];
      const bool by_gain = std::isfinite(s.predicted_field_gain);
      if (!row.candidate || (by_gain ? s.predicted_field_gain > d.decision.scores[*row.candidate].predicted_field_gain
                                     : s.predicted_delta_miou < d.decision.scores[*row.candidate].predicted_delta_miou))
        row.candidate = i;
    }
    if (next_realised < realised.size() && realised[next_realised].decision == k)
      row.realised = &realised[next_realised++];
    rows.push_back(row);
  }
  return rows;
}

/// Writes the rows of a mission's decisions (decision_rows()) to `os`, one line each.
inline void write_decisions_csv(std::ostream& os, std::string_view field, std::string_view strategy,
                                std::span<const DecisionRecord> decisions, std::span<const RealisedDescent> realised) {
  for (const DecisionRow& row : decision_rows(field, strategy, decisions, realised)) {
    for (std::size_t c = 0; c < kDecisionColumns.size(); ++c) os << (c ? "," : "") << kDecisionColumns[c].value(row);
    os << '\n';
  }
}

}  // namespace adaptseg
