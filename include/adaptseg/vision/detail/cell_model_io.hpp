#pragma once
/// @file
/// The cell gain model (cell_gain_model.hpp) in a decision-model file (decision_model.hpp,
/// `gain_model.cells`): its input, its slope pooling, and one list per quantity of its points.

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// The keys of the cell gain model's points in a model file (`gain_model.cells`), one list each.
/// The last, `proxy_slope_sd` (since 2026-11-27), may be missing: 0, the scene check as before it.
inline constexpr std::array<std::pair<const char*, double CellGainModel::Point::*>, 9> kCellPointKeys{{
    {"top_gsd_cm", &CellGainModel::Point::top_gsd_cm},
    {"sub_gsd_cm", &CellGainModel::Point::sub_gsd_cm},
    {"gain_slope", &CellGainModel::Point::gain_slope},
    {"gain_noise", &CellGainModel::Point::gain_noise},
    {"relabel_slope", &CellGainModel::Point::relabel_slope},
    {"relabel_noise", &CellGainModel::Point::relabel_noise},
    {"proxy_slope", &CellGainModel::Point::proxy_slope},
    {"proxy_noise", &CellGainModel::Point::proxy_noise},
    {"proxy_slope_sd", &CellGainModel::Point::proxy_slope_sd},
}};

/// The keys of β's dependence on the field's entropy (SlopePooling::field_entropy), written and
/// required with that pooling only.
inline constexpr std::array<std::pair<const char*, double CellGainModel::Point::*>, 4> kCellEntropyKeys{{
    {"entropy_slope", &CellGainModel::Point::entropy_slope},
    {"entropy_reference", &CellGainModel::Point::entropy_reference},
    {"entropy_low", &CellGainModel::Point::entropy_low},
    {"entropy_high", &CellGainModel::Point::entropy_high},
}};

namespace detail {

/// Writes `cells` as the value of the key just emitted (a mapping; read_cell_model).
inline void emit_cell_model(YAML::Emitter& e, const CellGainModel& cells) {
  e << YAML::BeginMap;
  e << YAML::Key << "input" << YAML::Value << to_string(cells.input());
  if (cells.pooling() != SlopePooling::cells)
    e << YAML::Key << "slope_pooling" << YAML::Value << to_string(cells.pooling());
  const auto emit_points = [&](const auto& keys) {
    for (const auto& [key, member] : keys) {
      std::vector<double> v;
      for (const auto& p : cells.points()) v.push_back(p.*member);
      e << YAML::Key << key << YAML::Value;
      emit_numbers(e, v);
    }
  };
  emit_points(kCellPointKeys);
  if (cells.pooling() == SlopePooling::field_entropy) emit_points(kCellEntropyKeys);
  e << YAML::EndMap;
}

/// The cell gain model of the mapping `c` (`gain_model.cells` of the file `where`).
/// @throws std::invalid_argument naming the file and the key for a missing or mistyped one.
[[nodiscard]] inline CellGainModel read_cell_model(const std::string& where, const YamlReader& c) {
  const DecisionInput input = parse_decision_input(c.text("input"));
  std::vector<CellGainModel::Point> points;
  for (const auto& [key, member] : kCellPointKeys) {
    if (member == &CellGainModel::Point::proxy_slope_sd && !c.has(key)) continue;
    const auto v = c.numbers(key);
    if (points.empty()) points.resize(v.size());
    if (v.empty() || v.size() != points.size())
      yaml_error(where,
                 "'gain_model.cells' needs one top_gsd_cm, sub_gsd_cm, gain_slope, gain_noise, "
                 "relabel_slope, relabel_noise, proxy_slope, proxy_noise and (optional) "
                 "proxy_slope_sd value per point (>= 1 point)");
    for (std::size_t j = 0; j < v.size(); ++j) points[j].*member = v[j];
  }
  // Absent (files of adaptseg before 2026-11-27, or pooled over the cells): cells.
  SlopePooling pooling = SlopePooling::cells;
  if (c.has("slope_pooling")) {
    const std::string name = c.text("slope_pooling");
    try {
      pooling = parse_slope_pooling(name);
    } catch (const std::invalid_argument&) {
      yaml_error(where, "'gain_model.cells.slope_pooling' must be cells, fields or field-entropy (got '" + name + "')");
    }
  }
  if (pooling == SlopePooling::field_entropy)
    for (const auto& [key, member] : kCellEntropyKeys) {
      const auto v = c.numbers(key);
      if (v.size() != points.size())
        yaml_error(where,
                   "'gain_model.cells' with slope_pooling field-entropy needs one entropy_slope, "
                   "entropy_reference, entropy_low and entropy_high value per point");
      for (std::size_t j = 0; j < v.size(); ++j) points[j].*member = v[j];
    }
  return CellGainModel(input, std::move(points), pooling);
}

}  // namespace detail
}  // namespace adaptseg
