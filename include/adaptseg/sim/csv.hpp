#pragma once
/// @file
/// The one CSV quoting rule of adaptseg's tables (decisions.csv, results.csv, the cell samples):
/// a text as one field (RFC 4180).

#include <string>
#include <string_view>

namespace adaptseg {

/// A text as one CSV field: quoted (inner quotes doubled) where it holds a comma, a quote or a
/// line break, as a region's field name does ("weedmap-rededge-000[0,0,0.5,1]"); as is otherwise.
[[nodiscard]] inline std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\n") == std::string_view::npos) return std::string(s);
  std::string q(1, '"');
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  q += '"';
  return q;
}

}  // namespace adaptseg
