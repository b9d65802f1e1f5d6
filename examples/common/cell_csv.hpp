#pragma once
// CSV helpers of the programs: a text as one field (csv_field, the library's), and the
// decision-input columns of the cell CSVs (adaptseg_calibrate --cell-samples-csv,
// adaptseg_cell_study --csv; docs/data_format.md): `top_NAME` for every input of
// kDecisionInputs as the top-level image gives it over the cell, then `fine_NAME` as the finer
// image gives it (`nan` where the backend cannot give it). Not part of the library.

#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/sim/csv.hpp>

#include <ostream>
#include <string>

namespace adaptseg::examples {

/// The library's quoting of a CSV field (<adaptseg/sim/csv.hpp>).
using adaptseg::csv_field;

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
