#pragma once
/// @file
/// Error reporting shared by every component.
///
/// - Bad input (a parameter out of range, a malformed file) throws `std::invalid_argument`
///   whose message names the parameter and the offending value.
/// - Numerical failure that survives recovery (e.g. jitter retries of a Cholesky
///   factorisation) throws `adaptseg::NumericalError`.
/// - Expected outcomes (no descent, budget exhausted) are values, never exceptions.
/// - Internal invariants use `ADAPTSEG_ASSERT`, compiled in when `ADAPTSEG_ENABLE_ASSERTS`
///   is defined (the project's tests and examples define it); a failed assertion throws
///   `std::logic_error`: the library never prints or aborts.

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg {

/// Numerical failure after the library's own recovery attempts.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {

/// Formats "<what>: <value>" messages for `std::invalid_argument`.
template <typename T>
[[nodiscard]] std::string describe(std::string_view what, const T& value) {
  std::ostringstream os;
  os << what << " (got " << value << ")";
  return os.str();
}

/// Throws `std::invalid_argument(describe(what, value))` unless `ok`.
template <typename T>
void require(bool ok, std::string_view what, const T& value) {
  if (!ok) throw std::invalid_argument(describe(what, value));
}

/// Throws unless `value` is finite and strictly positive; `name` names the parameter.
inline void require_positive(double value, std::string_view name) {
  require(std::isfinite(value) && value > 0.0, std::string(name) + " must be finite and > 0", value);
}

/// Throws unless `value` is finite; `name` names the parameter.
inline void require_finite(double value, std::string_view name) {
  require(std::isfinite(value), std::string(name) + " must be finite", value);
}

[[noreturn]] inline void assertion_failed(const char* expr, const char* file, int line) {
  std::ostringstream os;
  os << "adaptseg internal assertion failed: " << expr << " at " << file << ':' << line;
  throw std::logic_error(os.str());
}

}  // namespace detail
}  // namespace adaptseg

#if defined(ADAPTSEG_ENABLE_ASSERTS)
#define ADAPTSEG_ASSERT(expr) \
  ((expr) ? static_cast<void>(0) : ::adaptseg::detail::assertion_failed(#expr, __FILE__, __LINE__))
#else
#define ADAPTSEG_ASSERT(expr) static_cast<void>(0)
#endif
