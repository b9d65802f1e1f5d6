#pragma once
/// @file
/// One locale-independent text codec for the numbers of adaptseg's files: the shortest text
/// that reads back to the same double (std::to_chars), and a strict reader (std::from_chars)
/// that accepts exactly one finite number. Neither depends on the global locale, so a file
/// written under any locale reads back under any other.

#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace adaptseg::detail {

/// The shortest decimal text that reads back to exactly `v` ("C" format, '.' as decimal
/// separator); "nan", "inf" or "-inf" for non-finite values.
[[nodiscard]] inline std::string format_number(double v) {
  std::array<char, 32> buf{};
  const auto [end, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  if (ec != std::errc{}) return std::isnan(v) ? "nan" : (v < 0 ? "-inf" : "inf");  // unreachable for doubles
  return std::string(buf.data(), end);
}

/// `v` in fixed notation with `digits` digits after the point, as printf's "%.*f" writes it in
/// the C locale ("nan", "inf", "-inf" for non-finite values).
[[nodiscard]] inline std::string format_fixed(double v, int digits) {
  std::array<char, 400> buf{};  // the longest double in fixed notation (309 digits) and its decimals
  const auto [end, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::fixed, digits);
  if (ec != std::errc{}) return format_number(v);  // more than 80 decimals asked for: the shortest text
  return std::string(buf.data(), end);
}

/// `text` as a finite double if it is exactly one number (no surrounding characters); a
/// leading '+' is accepted. nullopt otherwise.
[[nodiscard]] inline std::optional<double> parse_number(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc{} || end != text.data() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

/// `text` as an integer in [lo, hi] if it is exactly one; nullopt otherwise.
[[nodiscard]] inline std::optional<long long> parse_integer(std::string_view text, long long lo, long long hi) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  long long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc{} || end != text.data() + text.size() || v < lo || v > hi) return std::nullopt;
  return v;
}

}  // namespace adaptseg::detail
