#pragma once
/// @file
/// Comparing GSDs (leaf helper): GSDs computed as multiples of a field's, or read back from a
/// model file, differ in their last bits from the same level given on the command line.

#include <algorithm>
#include <cmath>

namespace adaptseg::detail {

/// True if GSDs `a` and `b` are the same level: equal to 1e-9 relative.
[[nodiscard]] inline bool same_gsd(double a, double b) noexcept {
  return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
}

}  // namespace adaptseg::detail
