#pragma once
// The conformance suite every DecisionPolicy model runs (the concept's laws are written beside
// it in include/adaptseg/core/decision.hpp).

#include <adaptseg/core/decision.hpp>

#include <doctest/doctest.h>

#include <span>
#include <string>
#include <vector>

namespace adaptseg::test {

namespace detail {

struct Flown {
  std::vector<Decision> decisions;
};

/// One mission: begin_mission, then decide at every context and observe `outcome` after every
/// descent; checks the per-decision laws on the way.
template <DecisionPolicy Policy>
Flown fly_mission(Policy& policy, std::span<const DecisionContext> mission, const DescentOutcome& outcome) {
  Flown out;
  policy.begin_mission();
  for (const DecisionContext& c : mission) {
    const Decision d = policy.decide(c);
    CHECK(d.scores.size() == c.candidates.size());
    if (c.candidates.empty()) CHECK_FALSE(d.descend);
    if (d.descend) {
      CHECK_NOTHROW((void)chosen_candidate(d, c.candidates, policy.name()));
      policy.observe(outcome);
    }
    out.decisions.push_back(d);
  }
  return out;
}

inline void check_same(const Flown& a, const Flown& b) {
  REQUIRE(a.decisions.size() == b.decisions.size());
  for (std::size_t k = 0; k < a.decisions.size(); ++k) {
    CAPTURE(k);
    const Decision& x = a.decisions[k];
    const Decision& y = b.decisions[k];
    CHECK(x.descend == y.descend);
    if (x.descend) CHECK(x.gsd_cm == y.gsd_cm);
    REQUIRE(x.scores.size() == y.scores.size());
    for (std::size_t i = 0; i < x.scores.size(); ++i) {
      CHECK(x.scores[i].gsd_cm == y.scores[i].gsd_cm);
      CHECK(x.scores[i].utility == y.scores[i].utility);
      CHECK(x.scores[i].predicted_delta_miou == y.scores[i].predicted_delta_miou);
    }
  }
}

}  // namespace detail

/// Flies `mission` (top-level contexts in flight order; `outcome` is reported after every
/// descent) and checks the DecisionPolicy laws: a non-empty name; one score per candidate;
/// no descent without candidates; a descent names a candidate; begin_mission forgets the
/// previous mission (the same mission flown again takes the same decisions, also after the
/// policy learnt from another one); a copy decides as the original.
template <DecisionPolicy Policy>
void check_policy_conformance(const Policy& prototype, std::span<const DecisionContext> mission,
                              const DescentOutcome& outcome) {
  Policy policy = prototype;
  CHECK_FALSE(std::string(policy.name()).empty());
  const detail::Flown first = detail::fly_mission(policy, mission, outcome);
  // Something else in between: a mission whose descents all saw nothing relabelled.
  DescentOutcome nothing = outcome;
  nothing.relabelled = {};
  nothing.sigma_sub = outcome.sigma_top;
  (void)detail::fly_mission(policy, mission, nothing);
  detail::check_same(first, detail::fly_mission(policy, mission, outcome));
  Policy copy = prototype;
  detail::check_same(first, detail::fly_mission(copy, mission, outcome));
}

}  // namespace adaptseg::test
