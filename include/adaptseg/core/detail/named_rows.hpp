#pragma once
/// @file
/// Lookups in a table of named rules (a std::array of rows with a `const char* name`), the shape
/// of kDescentSchedules and kDescentCoverages: a row by its key, a row by its name.

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace adaptseg::detail {

/// The row of `table` whose member `key` equals `value`.
/// @throws std::invalid_argument naming `what` if there is none (an enum value out of range).
template <typename Row, std::size_t N, typename Key>
[[nodiscard]] const Row& row_of(const std::array<Row, N>& table, Key Row::*key, Key value, const char* what) {
  for (const Row& r : table)
    if (r.*key == value) return r;
  throw std::invalid_argument(std::string("unknown ") + what + " " + std::to_string(static_cast<long long>(value)));
}

/// The row of `table` named `name`.
/// @throws std::invalid_argument "<what> must be 'a', 'b' or 'c', not '<name>'" if there is none.
template <typename Row, std::size_t N>
[[nodiscard]] const Row& row_named(const std::array<Row, N>& table, const std::string& name, const char* what) {
  std::string names;
  for (std::size_t k = 0; k < N; ++k) {
    if (name == table[k].name) return table[k];
    names += std::string(k == 0 ? "'" : k + 1 == N ? " or '" : ", '") + table[k].name + "'";
  }
  throw std::invalid_argument(std::string(what) + " must be " + names + ", not '" + name + "'");
}

}  // namespace adaptseg::detail
