#pragma once
/// @file
/// The decision rules a model file may hold and calibration may choose, one entry each: a rule
/// is its policy (core/, what decides in flight) and one struct beside it here in vision/ with
/// its name, its model-file keys and its calibration search (front_aware_rule.hpp,
/// utility_rule.hpp). The model file (decision_model.hpp), calibrate() (calibration.hpp) and
/// the programs' `--rule` handle the rules through this list alone. A new rule: its policy
/// (added to DecisionFunction's variant) and its struct, listed here.

#include <adaptseg/vision/front_aware_rule.hpp>
#include <adaptseg/vision/utility_rule.hpp>

#include <cstddef>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace adaptseg {

/// Every rule, the default (CalibrationOptions::rule) first.
using DecisionRules = std::tuple<FrontAwareRule, UtilityRule>;

/// Calls `f.template operator()<Rule>()` for every rule of DecisionRules, in order.
template <class F>
void for_each_rule(F&& f) {
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (f.template operator()<std::tuple_element_t<I, DecisionRules>>(), ...);
  }
  (std::make_index_sequence<std::tuple_size_v<DecisionRules>>{});
}

/// The rules' names, in order (`--rule`'s choices).
[[nodiscard]] inline std::vector<std::string> rule_names() {
  std::vector<std::string> out;
  for_each_rule([&]<class Rule>() { out.emplace_back(Rule::kName); });
  return out;
}

/// "front-aware or utility": the names for a message.
[[nodiscard]] inline std::string rule_names_text() {
  const std::vector<std::string> names = rule_names();
  std::string s;
  for (std::size_t k = 0; k < names.size(); ++k) s += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + names[k];
  return s;
}

/// True if `name` names a rule of DecisionRules.
[[nodiscard]] inline bool is_rule_name(std::string_view name) {
  bool found = false;
  for_each_rule([&]<class Rule>() { found = found || name == Rule::kName; });
  return found;
}

namespace detail {
template <class Policy, class Rules>
struct RuleForImpl;
template <class Policy>
struct RuleForImpl<Policy, std::tuple<>> {
  static_assert(!std::is_same_v<Policy, Policy>, "no entry of DecisionRules has this policy");
};
template <class Policy, class First, class... Rest>
struct RuleForImpl<Policy, std::tuple<First, Rest...>>
    : std::conditional_t<std::is_same_v<typename First::Policy, Policy>, std::type_identity<First>,
                         RuleForImpl<Policy, std::tuple<Rest...>>> {};
}  // namespace detail

/// The entry of DecisionRules whose policy is `Policy`.
template <class Policy>
using RuleFor = typename detail::RuleForImpl<Policy, DecisionRules>::type;

}  // namespace adaptseg
