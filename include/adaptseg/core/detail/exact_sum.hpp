#pragma once
/// @file
/// Sums of floats that do not depend on the order of their terms: each value is taken in units
/// of 2^-32 (exactly for every float that is a multiple of 2^-32, which includes every float
/// of magnitude at least 2^-9; others are cut to a whole unit towards zero, an error below
/// 2.4e-10 per term) and the units are added as integers. A cell's mean decision input is then the same
/// to the bit whether its pixels are summed one map pixel at a time or one camera pixel at a
/// time with its weight (image_summary.hpp), and sums of values that double arithmetic adds
/// exactly (all multiples of 2^-32 below 2^20 in total, as the oracle's are) equal the double sum.

#include <cmath>
#include <cstdint>

namespace adaptseg::detail {

/// 2^32: the units per 1 of an ExactSum.
inline constexpr double kExactSumScale = 4294967296.0;

/// `v` in units of 2^-32, cut towards zero (the product is exact: a float times a power of two;
/// the cut is one instruction where rounding would be a library call). |v| must stay below 2^30.
[[nodiscard]] inline std::int64_t exact_units(float v) noexcept {
  return static_cast<std::int64_t>(static_cast<double>(v) * kExactSumScale);
}

/// A sum of units (exact_units()) in 128 bits: no overflow for any count of terms a map holds.
class ExactSum {
 public:
  /// Adds `units` (exact_units()) times `weight` (> 0; the map pixels a camera pixel covers).
  void add(std::int64_t units, std::int64_t weight = 1) noexcept {
    // |units| < 2^62 and weight < 2^31 in any use here; the product may not fit 64 bits, so it
    // is added as weight terms of one word each, split into two halves.
    const std::uint64_t u = static_cast<std::uint64_t>(units < 0 ? -units : units);
    const std::uint64_t w = static_cast<std::uint64_t>(weight);
    const std::uint64_t lo_lo = (u & 0xffffffffu) * w;
    const std::uint64_t hi_lo = (u >> 32) * w;  // < 2^61: shifted by 32 it spans both words
    std::uint64_t lo = lo_lo + (hi_lo << 32);
    std::uint64_t hi = (hi_lo >> 32) + (lo < lo_lo ? 1u : 0u);
    if (units < 0) {  // two's complement of the 128-bit product
      lo = ~lo + 1u;
      hi = ~hi + (lo == 0 ? 1u : 0u);
    }
    const std::uint64_t before = lo_;
    lo_ += lo;
    hi_ += hi + (lo_ < before ? 1u : 0u);
  }
  /// The sum as a double: exact while it is below 2^53 units (2^21 in value) in magnitude.
  [[nodiscard]] double value() const noexcept {
    const bool negative = static_cast<std::int64_t>(hi_) < 0;
    std::uint64_t lo = lo_, hi = hi_;
    if (negative) {
      lo = ~lo + 1u;
      hi = ~hi + (lo == 0 ? 1u : 0u);
    }
    const double magnitude = std::ldexp(static_cast<double>(hi), 64) + static_cast<double>(lo);
    return (negative ? -magnitude : magnitude) / kExactSumScale;
  }

 private:
  std::uint64_t lo_ = 0;
  std::uint64_t hi_ = 0;
};

}  // namespace adaptseg::detail
