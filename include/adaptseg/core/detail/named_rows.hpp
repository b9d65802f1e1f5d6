#pragma once
/// @file
/// Every enum the library reads or writes by name maps to its names through one table (a
/// std::array of rows with the enum value and a `const char* name`): kDescentSchedules and
/// kDescentCoverages hold more per row; an enum with nothing but a name uses NamedValue rows.
/// Looking up a row by its value, a row by its name, and the refusal of an unknown name are
/// written here once.

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace adaptseg::detail {

/// A row of a table whose rows hold nothing but the value's name.
template <typename Enum>
struct NamedValue {
  Enum value;
  const char* name;
};

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
[[nodiscard]] const Row& row_named(const std::array<Row, N>& table, std::string_view name, const char* what) {
  std::string names;
  for (std::size_t k = 0; k < N; ++k) {
    if (name == table[k].name) return table[k];
    names += std::string(k == 0 ? "'" : k + 1 == N ? " or '" : ", '") + std::string(table[k].name) + "'";
  }
  throw std::invalid_argument(std::string(what) + " must be " + names + ", not '" + std::string(name) + "'");
}

/// Every row's name, in the table's order (a program's choices for a setting).
template <typename Row, std::size_t N>
[[nodiscard]] std::vector<std::string> names_of(const std::array<Row, N>& table) {
  std::vector<std::string> names;
  names.reserve(N);
  for (const Row& r : table) names.emplace_back(r.name);
  return names;
}

/// The name of `value` in a table of NamedValue rows.
/// @throws std::invalid_argument naming `what` for a value out of range.
template <typename Enum, std::size_t N>
[[nodiscard]] const char* name_of(const std::array<NamedValue<Enum>, N>& table, Enum value, const char* what) {
  return row_of(table, &NamedValue<Enum>::value, value, what).name;
}

/// The name of `value` in a table of NamedValue rows, or `fallback` where the table has none (an
/// enum that also holds values without a name of their own, e.g. a firmware the library does
/// not know).
template <typename Enum, std::size_t N>
[[nodiscard]] const char* name_or(const std::array<NamedValue<Enum>, N>& table, Enum value,
                                  const char* fallback) noexcept {
  for (const NamedValue<Enum>& r : table)
    if (r.value == value) return r.name;
  return fallback;
}

/// The value named `name` in a table of NamedValue rows.
/// @throws std::invalid_argument "<what> must be 'a', 'b' or 'c', not '<name>'" for another name.
template <typename Enum, std::size_t N>
[[nodiscard]] Enum value_named(const std::array<NamedValue<Enum>, N>& table, std::string_view name, const char* what) {
  return row_named(table, name, what).value;
}

}  // namespace adaptseg::detail
