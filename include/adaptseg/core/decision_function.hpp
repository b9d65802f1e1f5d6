#pragma once
/// @file
/// The calibrated decision function (paper §3.2.2-3.2.3; docs/method.md, "The decision function"):
/// the gain model with the
/// decision rule chosen at calibration, as a decision-model file holds it.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/gain_model.hpp>
#include <adaptseg/core/utility_policy.hpp>

#include <span>
#include <string>
#include <utility>
#include <variant>

namespace adaptseg {

/// The gain model (GainModel: O, I, C) with the rule chosen at calibration: the paper's
/// UtilityPolicy or the FrontAwarePolicy. A DecisionPolicy that forwards to that rule, so a
/// model file's choice is made at run time; use the rule types directly to fix it at compile
/// time.
///
/// @code
/// adaptseg::DecisionFunction policy = adaptseg::DecisionModel::load("model.yaml").decision_function;
/// policy.set_online(false);  // the paper's "non-adaptive" baseline
/// @endcode
class DecisionFunction {
 public:
  using Rule = std::variant<UtilityPolicy, FrontAwarePolicy>;

  explicit DecisionFunction(UtilityPolicy rule) : rule_(std::move(rule)) {}
  explicit DecisionFunction(FrontAwarePolicy rule) : rule_(std::move(rule)) {}

  [[nodiscard]] std::string name() const {
    return std::visit([](const auto& r) { return r.name(); }, rule_);
  }
  void begin_mission() {
    std::visit([](auto& r) { r.begin_mission(); }, rule_);
  }
  [[nodiscard]] Decision decide(const DecisionContext& context) {
    return std::visit([&](auto& r) { return r.decide(context); }, rule_);
  }
  void observe(const DescentOutcome& outcome) {
    std::visit([&](auto& r) { r.observe(outcome); }, rule_);
  }

  /// The rule's top-level GSD (ChoosesTopLevel; `nominal` for a rule that does not choose).
  [[nodiscard]] double top_gsd(std::span<const LawnmowerForecast> lawnmowers, double nominal) const {
    return std::visit(
        [&](const auto& r) -> double {
          if constexpr (requires { r.top_gsd(lawnmowers, nominal); })
            return r.top_gsd(lawnmowers, nominal);
          else
            return nominal;
        },
        rule_);
  }

  /// Whether the rule reads the field's mean top-level entropy (ReadsFieldEntropy).
  [[nodiscard]] bool reads_field_entropy() const {
    return std::visit(
        [](const auto& r) {
          if constexpr (requires { r.reads_field_entropy(); })
            return r.reads_field_entropy();
          else
            return false;
        },
        rule_);
  }

  /// Whether the rule trusts a descent image (GuardsDescentImages; a rule without a guard: true).
  bool trusts_descent_image(double sigma_top, double sigma_image) {
    return std::visit(
        [&](auto& r) {
          if constexpr (requires { r.trusts_descent_image(sigma_top, sigma_image); })
            return r.trusts_descent_image(sigma_top, sigma_image);
          else
            return true;
        },
        rule_);
  }

  /// Whether the rule learns in flight ("adaptive") or not ("non-adaptive").
  [[nodiscard]] bool online() const {
    return std::visit([](const auto& r) { return r.params().online; }, rule_);
  }
  void set_online(bool online) {
    std::visit(
        [&](auto& r) {
          auto p = r.params();
          p.online = online;
          r.set_params(p);
        },
        rule_);
  }

  [[nodiscard]] bool front_aware() const noexcept { return std::holds_alternative<FrontAwarePolicy>(rule_); }
  /// The gain model as calibrated (before any online update).
  [[nodiscard]] const GainModel& model() const {
    return std::visit([](const auto& r) -> const GainModel& { return r.initial_model(); }, rule_);
  }
  [[nodiscard]] const Rule& rule() const noexcept { return rule_; }
  [[nodiscard]] Rule& rule() noexcept { return rule_; }

 private:
  Rule rule_;
};

static_assert(DecisionPolicy<DecisionFunction>);
static_assert(ChoosesTopLevel<DecisionFunction>);
static_assert(ReadsFieldEntropy<DecisionFunction>);
static_assert(GuardsDescentImages<DecisionFunction>);

}  // namespace adaptseg
