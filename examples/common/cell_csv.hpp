#pragma once
// CSV helpers of the programs: a text as one field (csv_field), and the decision-input columns
// of the cell CSVs (adaptseg_calibrate --cell-samples-csv,
// adaptseg_cell_study --csv; docs/data_format.md): `top_NAME` for every input of
// kDecisionInputs as the top-level image gives it over the cell, then `fine_NAME` as the finer
// image gives it (`nan` where the backend cannot give it). Not part of the library.

#include <adaptseg/core/decision_inputs.hpp>

#include <ostream>
#include <string>

namespace adaptseg::examples {

/// A text as one CSV field: quoted (inner quotes doubled) where it holds a comma, a quote or a
/// line break, as a region's field name does ("weedmap-rededge-000[0,0,0.5,1]"); as is otherwise.
[[nodiscard]] inline std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// Appends the input columns' names to a CSV header line (each after a comma).
inline void write_input_columns_header(std::ostream& os) {
  for (const auto& in : kDecisionInputs) os << ",top_" << in.name;
  for (const auto& in : kDecisionInputs) os << ",fine_" << in.name;
}

/// Appends a cell's input values to its CSV row (each after a comma), in the header's order.
inline void write_input_columns(std::ostream& os, const CellInputs& top, const CellInputs& fine) {
  for (double v : top.values) os << ',' << v;
  for (double v : fine.values) os << ',' << v;
}

}  // namespace adaptseg::examples
