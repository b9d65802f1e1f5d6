#include "test_support.hpp"

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/oracle_segmenter.hpp>

#include <doctest/doctest.h>

using namespace adaptseg;
namespace t = adaptseg::test;

namespace {
// Descends to `gsd` at the top-level waypoints whose index is in `which` (all if empty).
struct Scripted {
  double gsd = 1.0;
  std::vector<int> which{};
  int seen = 0;
  int observed = 0;
  std::string name() const { return "scripted"; }
  Decision decide(const DecisionContext& c) {
    Decision d;
    const bool pick = which.empty() || std::find(which.begin(), which.end(), seen) != which.end();
    ++seen;
    for (const auto& k : c.candidates)
      if (pick && k.gsd_cm == gsd) {
        d.descend = true;
        d.gsd_cm = gsd;
      }
    return d;
  }
  void observe(const DescentOutcome&) { ++observed; }
};
static_assert(DecisionPolicy<Scripted>);

AdaptiveOptions options() {
  AdaptiveOptions o;
  o.mission.fixed_segmentation_time_s = 0.1;
  o.mission.fixed_planning_time_s = 0.01;
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0, 1.5, 2.0, 2.5};
  return o;
}
}  // namespace

TEST_CASE("adaptive planner: never descending is the top-level lawnmower") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};  // no such candidate: never descends
  const AdaptiveResult a = run_adaptive_mission(f, oracle, never, options(), "never");
  const MissionResult l = run_lawnmower_mission(f, 3.0, oracle, options().mission);
  CHECK(a.descents() == 0);
  CHECK(a.mission.waypoints.size() == l.waypoints.size());
  CHECK(a.mission.total_s() == doctest::Approx(l.total_s()));
  CHECK(a.mission.miou_interest().value() == doctest::Approx(l.miou_interest().value()));
  CHECK(a.decisions.size() == l.waypoints.size());
}

TEST_CASE("adaptive planner: descending everywhere to the field's GSD maps it exactly") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted all{.gsd = 1.0};
  const AdaptiveResult a = run_adaptive_mission(f, oracle, all, options(), "all");
  CHECK(a.descents() == static_cast<int>(a.decisions.size()));
  CHECK(all.observed == a.descents());
  CHECK(a.mission.miou_all().value() == 1.0);
  int level1 = 0;
  for (const auto& w : a.mission.waypoints) level1 += w.level;
  CHECK(level1 > 0);
  for (const auto& d : a.decisions) {
    REQUIRE(d.outcome.has_value());
    CHECK(d.outcome->sub_altitude_m == doctest::Approx(5.5));
    CHECK(d.candidates.size() == 4);
  }
}

TEST_CASE("adaptive planner: a candidate's extra time is exactly what the descent adds") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  const AdaptiveResult base = run_adaptive_mission(f, oracle, never, options(), "never");
  for (int region : {0, 3}) {
    for (double g : {1.0, 2.0}) {
      Scripted one{.gsd = g, .which = {region}};
      const AdaptiveResult r = run_adaptive_mission(f, oracle, one, options(), "one");
      REQUIRE(r.descents() == 1);
      const auto& d = r.decisions[static_cast<std::size_t>(region)];
      const auto it = std::find_if(d.candidates.begin(), d.candidates.end(),
                                   [&](const Candidate& c) { return c.gsd_cm == g; });
      REQUIRE(it != d.candidates.end());
      CAPTURE(region);
      CAPTURE(g);
      CHECK(r.mission.total_s() - base.mission.total_s() == doctest::Approx(it->extra_time_s).epsilon(1e-9));
      CHECK(static_cast<int>(r.mission.waypoints.size() - base.mission.waypoints.size()) == it->images);
    }
  }
}

TEST_CASE("adaptive planner: the budget is never exceeded and the top level is always covered") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  const double coverage = run_adaptive_mission(f, oracle, never, options(), "never").mission.total_s();
  Scripted all{.gsd = 1.0};
  const double everything = run_adaptive_mission(f, oracle, all, options(), "all").mission.total_s();
  REQUIRE(everything > coverage + 100.0);
  for (double budget : {coverage + 1.0, coverage + 60.0, 0.5 * (coverage + everything), everything - 1.0}) {
    AdaptiveOptions o = options();
    o.budget_s = budget;
    Scripted greedy{.gsd = 1.0};
    const AdaptiveResult r = run_adaptive_mission(f, oracle, greedy, o, "greedy");
    CAPTURE(budget);
    CHECK(r.mission.total_s() <= budget + 1e-9);
    int top = 0;
    for (const auto& w : r.mission.waypoints) top += w.level == 0 ? 1 : 0;
    CHECK(top == static_cast<int>(r.decisions.size()));
    CHECK(top == static_cast<int>(run_lawnmower_mission(f, 3.0, oracle, o.mission).waypoints.size()));
    bool limited = false;
    for (const auto& d : r.decisions) limited |= d.budget_limited;
    CHECK(limited);
  }
  AdaptiveOptions tiny = options();
  tiny.budget_s = coverage - 1.0;
  Scripted greedy{.gsd = 1.0};
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, greedy, tiny, "greedy"),
                       doctest::Contains("too small for the top-level coverage"), std::invalid_argument);
}

TEST_CASE("adaptive planner: bad options are refused") {
  const Field f = t::blob_field(600, 600, 2.0);
  OracleSegmenter oracle(f.num_classes());
  Scripted s;
  AdaptiveOptions o = options();
  o.top_gsd_cm = 1.0;
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, s, o, "x"), doctest::Contains("top_gsd_cm"),
                       std::invalid_argument);
  o = options();
  o.candidate_gsd_cm = {4.0};
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, s, o, "x"), doctest::Contains("candidate"),
                       std::invalid_argument);
  o = options();
  o.budget_s = -5.0;
  CHECK_THROWS_AS((void)run_adaptive_mission(f, oracle, s, o, "x"), std::invalid_argument);
  // Candidates finer than the field (2 cm/px) are skipped, not flown.
  o = options();
  o.top_gsd_cm = 6.0;
  o.candidate_gsd_cm = {1.0, 3.0};
  Scripted fine{.gsd = 1.0};
  const auto r = run_adaptive_mission(f, oracle, fine, o, "x");
  CHECK(r.descents() == 0);
  for (const auto& d : r.decisions)
    for (const auto& c : d.candidates) CHECK(c.gsd_cm == 3.0);
}
