#pragma once
/// @file
/// A lookup table of label values (leaf helper of metrics.hpp and descent_coverage.hpp).

#include <array>
#include <cstddef>
#include <span>

namespace adaptseg {

namespace detail {
/// lut[v] is true for the label values v in `labels` (values outside 0..255 are ignored).
[[nodiscard]] inline std::array<bool, 256> label_lut(std::span<const int> labels) {
  std::array<bool, 256> lut{};
  for (int c : labels)
    if (c >= 0 && c < 256) lut[static_cast<std::size_t>(c)] = true;
  return lut;
}
}  // namespace detail

}  // namespace adaptseg
