#include "test_support.hpp"

#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/jump_guard.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/adaptive_planner.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/region_samples.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
#include <random>
#include <thread>
#include <utility>

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
  std::vector<std::size_t> outcomes{};  // DescentOutcome::descent, in the order observed
  void begin_mission() { seen = 0; }
  void observe(const DescentOutcome& o) {
    ++observed;
    outcomes.push_back(o.descent);
  }
};
static_assert(DecisionPolicy<Scripted>);

// Keeps the candidates each decision was offered, and descends to the one at index `pick`
// (clamped) wherever there is one, unless `descend` is false.
struct Pick {
  std::size_t pick = 0;
  bool descend = true;
  std::vector<std::vector<Candidate>> offered{};
  std::string name() const { return "pick"; }
  void begin_mission() { offered.clear(); }
  Decision decide(const DecisionContext& c) {
    offered.emplace_back(c.candidates.begin(), c.candidates.end());
    Decision d;
    if (!descend || c.candidates.empty()) return d;
    d.descend = true;
    d.candidate = std::min(pick, c.candidates.size() - 1);
    d.gsd_cm = c.candidates[d.candidate].gsd_cm;
    d.scores.resize(c.candidates.size());
    return d;
  }
  void observe(const DescentOutcome&) {}
};
static_assert(DecisionPolicy<Pick>);

AdaptiveOptions options() {
  AdaptiveOptions o;
  o.mission.fixed_segmentation_time_s = 0.1;
  o.mission.fixed_planning_time_s = 0.01;
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0, 1.5, 2.0, 2.5};
  return o;
}

/// Every name of a table of named values (`rows`) parses back to its value and prints as itself.
template <class Rows, class Parse>
void check_names_round_trip(const Rows& rows, Parse&& parse) {
  for (const auto& row : rows) {
    CHECK(parse(row.name) == row.value);
    CHECK(std::string(to_string(row.value)) == row.name);
  }
}
}  // namespace

namespace {
// Descends everywhere to `gsd` until its jump guard trips (bound: see JumpGuard).
struct Guarded : Scripted {
  JumpGuard guard;
  Decision decide(const DecisionContext& c) { return guard.tripped() ? Decision{} : Scripted::decide(c); }
  bool trusts_descent_image(double sigma_top, double sigma_image) { return guard.trusts(sigma_top, sigma_image); }
  void begin_mission() {
    Scripted::begin_mission();
    guard.reset();
  }
};
static_assert(GuardsDescentImages<Guarded>);
}  // namespace

TEST_CASE("adaptive planner: an image the policy's jump guard refuses is not fused and ends the descents") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  // No bound: every descent as without a guard.
  Guarded open{{.gsd = 1.0}, JumpGuard()};
  const AdaptiveResult a = run_adaptive_mission(f, oracle, open, options(), "open");
  CHECK(a.descents() == static_cast<int>(a.decisions.size()));
  CHECK_FALSE(open.guard.tripped());
  // A bound below any jump: the first descent image is refused, the descent ends there, no other
  // follows, and the map is the top-level lawnmower's.
  Guarded shut{{.gsd = 1.0}, JumpGuard(-2.0)};
  AdaptiveOptions o = options();
  o.mission.interest = f.interest();
  AdaptivePlanner<Guarded> planner(SurveyArea::of(f), shut, o);
  const SimulatedSensor sensor(f, planner.camera());
  int level1 = 0, refused = 0, outcomes = 0;
  while (const auto w = planner.next()) {
    const PlannerStep step = segment_and_report(planner, oracle, sensor.capture(w->waypoint));
    level1 += w->level;
    refused += step.trusted ? 0 : 1;
    if (step.outcome) {
      ++outcomes;
      CHECK(step.outcome->cut_short);
      CHECK(step.outcome->relabelled.share == 0.0);  // nothing of the refused image was fused
    }
    CHECK(step.trusted == (w->level == 0));
  }
  CHECK(shut.guard.tripped());
  CHECK(level1 == 1);
  CHECK(refused == 1);
  CHECK(outcomes == 1);
  const MissionResult lawnmower = run_lawnmower_mission(f, 3.0, oracle, options().mission);
  CHECK(cv::countNonZero(planner.map().labels() != lawnmower.fused_labels) == 0);
}

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
    // What each descent relabelled, seen in flight: the oracle's coarse errors it corrected.
    CHECK(d.outcome->relabelled.interest_share <= d.outcome->relabelled.share);
  }
  // In simulation, what each descent gained: every region corrected to the truth, and the
  // gains add up to the mission's gain over the top-level lawnmower (but for IoU's ratio).
  REQUIRE(a.realised.size() == a.decisions.size());
  const MissionResult top = run_lawnmower_mission(f, 3.0, oracle, options().mission);
  double sum = 0.0;
  for (std::size_t k = 0; k < a.realised.size(); ++k) {
    const RealisedDescent& r = a.realised[k];
    CHECK(r.decision == k);
    CHECK(r.region_miou_after == doctest::Approx(1.0));
    CHECK(r.region_miou_before <= r.region_miou_after);
    CHECK(r.field_gain >= 0.0);
    if (r.region_delta_miou() < 0.0) CHECK(a.decisions[k].outcome->relabelled.interest_share > 0.0);
    sum += r.field_gain;
  }
  CHECK(sum == doctest::Approx(1.0 - top.miou_interest().value()).epsilon(0.15));
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
      const auto it =
          std::find_if(d.candidates.begin(), d.candidates.end(), [&](const Candidate& c) { return c.gsd_cm == g; });
      REQUIRE(it != d.candidates.end());
      CAPTURE(region);
      CAPTURE(g);
      CHECK(r.mission.total_s() - base.mission.total_s() == doctest::Approx(it->extra_time_s).epsilon(1e-9));
      CHECK(static_cast<int>(r.mission.waypoints.size() - base.mission.waypoints.size()) == it->images);
    }
  }
}

TEST_CASE("adaptive planner: coverage 'interest' re-maps only the sub-cells that show a label of interest") {
  const Field f = t::patch_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {1.0};
  Scripted all{.gsd = 1.0};
  const AdaptiveResult region = run_adaptive_mission(f, oracle, all, o, "region");
  o.coverage = DescentCoverage::interest;
  Scripted all_focused{.gsd = 1.0};
  const AdaptiveResult focused = run_adaptive_mission(f, oracle, all_focused, o, "interest");
  REQUIRE(region.decisions.size() == 2);
  REQUIRE(focused.decisions.size() == 2);
  CHECK(region.descents() == 2);
  CHECK(focused.descents() == 1);  // the region without crop offers no descent at all
  int offered = 0;
  for (const auto& d : focused.decisions)
    for (const auto& c : d.candidates) {
      CHECK(c.images == 1);  // the patch's sub-cell only (a region needs 9)
      ++offered;
    }
  CHECK(offered == 1);
  // The patch is mapped exactly either way; the focused mission is shorter.
  CHECK(region.mission.miou_interest().value() == 1.0);
  CHECK(focused.mission.miou_interest().value() == 1.0);
  CHECK(focused.mission.total_s() < region.mission.total_s());
  CHECK(focused.mission.waypoints.size() == 2 + 1);
}

TEST_CASE("descent coverages: each rule says which cells it flies and whether it ranks them, their names parse back") {
  const cv::Mat labels(30, 30, CV_8UC1, cv::Scalar(0));
  cv::Mat crop = labels.clone();
  crop(cv::Rect(12, 12, 2, 2)).setTo(1);
  const std::vector<int> interest{1};
  const auto& interest_row = descent_coverage_info(DescentCoverage::interest);
  REQUIRE(static_cast<bool>(interest_row.flies));
  // One top-level pixel (3 px of the 1 cm/px grid) around the cell: the patch 2 px off is seen.
  CHECK(interest_row.flies(crop, cv::Rect(0, 0, 10, 10), 3.0, 1.0, interest));
  CHECK_FALSE(interest_row.flies(crop, cv::Rect(20, 20, 10, 10), 3.0, 1.0, interest));
  CHECK_FALSE(interest_row.flies(labels, cv::Rect(0, 0, 10, 10), 3.0, 1.0, interest));
  CHECK_FALSE(static_cast<bool>(descent_coverage_info(DescentCoverage::region).flies));  // every cell with field
  CHECK_FALSE(static_cast<bool>(descent_coverage_info(DescentCoverage::ranked).flies));
  CHECK(descent_coverage_info(DescentCoverage::ranked).ranks_cells);
  CHECK_FALSE(interest_row.ranks_cells);
  for (const auto& rule : kDescentCoverages) {
    CHECK(parse_descent_coverage(rule.name) == rule.coverage);
    CHECK(std::string(to_string(rule.coverage)) == rule.name);
  }
  CHECK_THROWS_WITH_AS(static_cast<void>(parse_descent_coverage("everywhere")),
                       "descent coverage must be 'region', 'interest' or 'ranked', not 'everywhere'",
                       std::invalid_argument);
}

TEST_CASE("adaptive planner: grid anchors by name, as the programs' --grid reads them") {
  check_names_round_trip(kGridAnchors, [](const char* n) { return parse_grid_anchor(n); });
  CHECK(parse_grid_anchor("centred") == GridAnchor::centred);
  CHECK(std::string(to_string(GridAnchor::corner)) == "corner");
  CHECK_THROWS_WITH_AS(static_cast<void>(parse_grid_anchor("centered")),
                       "grid anchor must be 'corner' or 'centred', not 'centered'", std::invalid_argument);
}

TEST_CASE("adaptive planner: descent grids by name, as the programs' --descent-grid and model files read them") {
  check_names_round_trip(kDescentGrids, [](const char* n) { return parse_descent_grid(n); });
  CHECK_THROWS_WITH_AS(static_cast<void>(parse_descent_grid("shared")),
                       "descent grid must be 'region' or 'field', not 'shared'", std::invalid_argument);
}

TEST_CASE("adaptive planner: coverage 'ranked' offers the best k cells by their expected error, for every k") {
  // Two top-level regions of 3 x 3 sub-cells at 1 cm/px; in the first, a small crop patch in
  // the top-left cell and a larger one in the bottom-right cell, both with edges off the 3 cm/px
  // grid, so that the oracle's top-level pixels on their edges are mixed (its expected error);
  // the second region is all soil.
  cv::Mat labels(1080, 2880, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(50, 50, 100, 100)).setTo(1);
  labels(cv::Rect(1000, 751, 301, 250)).setTo(1);
  const Field f("patches", 1.0, labels, t::soil_crop_weed(), {1});
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {1.0};
  o.coverage = DescentCoverage::ranked;
  o.cell_input = DecisionInput::expected_error;
  Pick best_one{.pick = 0};
  const AdaptiveResult one = run_adaptive_mission(f, oracle, best_one, o, "one");
  REQUIRE(best_one.offered.size() == 2);
  REQUIRE(best_one.offered[0].size() == 2);  // k = 1 and k = 2: the two cells with mixed pixels
  CHECK(best_one.offered[1].empty());        // all soil: no error to correct, nothing offered
  const Candidate& k1 = best_one.offered[0][0];
  const Candidate& k2 = best_one.offered[0][1];
  CHECK(k1.images == 1);
  CHECK(k2.images == 2);
  REQUIRE(k1.cells.size() == 1);
  REQUIRE(k2.cells.size() == 2);
  CHECK(k1.extra_time_s < k2.extra_time_s);
  // The best cell is the larger patch's (more boundary, more expected error) ...
  const double big = k1.cells[0].mass(DecisionInput::expected_error);
  CHECK(big > 0.0);
  for (const auto& c : k2.cells) CHECK(c.mass(DecisionInput::expected_error) <= big);
  // ... and the descent of k = 1 flies over it alone. What it showed, for the scene check: the
  // cell's expected error at the top, and none in the image at the field's GSD (the oracle is
  // sure there).
  REQUIRE(one.descents() == 1);
  const DescentOutcome& out = *one.decisions[0].outcome;
  CHECK(out.top_input == doctest::Approx(big / static_cast<double>(1440 * 1080)));
  CHECK(out.fine_input == 0.0);
  std::vector<Waypoint> low;
  for (const auto& w : one.mission.waypoints)
    if (w.level == 1) low.push_back(w.waypoint);
  REQUIRE(low.size() == 1);
  const cv::Rect cell = f.pixel_rect(low.front().footprint);
  CHECK((cell & cv::Rect(1000, 751, 301, 250)) == cv::Rect(1000, 751, 301, 250));
  // Both cells re-mapped at the field's GSD: the map is exact.
  Pick both{.pick = 1};
  const AdaptiveResult two = run_adaptive_mission(f, oracle, both, o, "two");
  CHECK(two.mission.miou_interest().value() == 1.0);
  CHECK(one.mission.miou_interest().value() < 1.0);
  CHECK(two.mission.waypoints.size() == 2 + 2);
}

namespace {
/// The oracle from the top level; from lower down a backend that hesitates everywhere: the
/// oracle's labels with half their probability on crop (what a network worse lower down shows).
struct WorseLower {
  OracleSegmenter oracle{3};
  double top_gsd_cm = 3.0;
  std::string name() const { return "worse-lower"; }
  cv::Mat segment(const Image& image) { return segment_with_probabilities(image).labels; }
  Segmentation segment_with_probabilities(const Image& image) {
    Segmentation s = oracle.segment_with_probabilities(image);
    if (image.gsd_cm >= top_gsd_cm * (1.0 - 1e-9)) return s;
    const cv::Mat valid = s.labels != image.ignore_label;
    for (auto& p : s.probabilities) p *= 0.5;
    cv::add(s.probabilities[1], 0.5, s.probabilities[1], valid);
    return s;
  }
};
static_assert(SegmentsWithProbabilities<WorseLower>);
}  // namespace

TEST_CASE("adaptive planner (ranked): the scene check stops descending where the finer look is worse") {
  // 2 x 2 regions at 3 cm/px, each with a crop patch whose edges are off the 3 cm/px grid.
  cv::Mat labels(2160, 2880, CV_8UC1, cv::Scalar(0));
  for (const cv::Point at : {cv::Point(50, 50), cv::Point(1490, 50), cv::Point(50, 1130), cv::Point(1490, 1130)})
    labels(cv::Rect(at, cv::Size(301, 250))).setTo(1);
  const Field f("patches", 1.0, labels, t::soil_crop_weed(), {1});
  // A model that expects a descent to 1 cm/px to gain what the top-level image's expected error
  // says (β = γ = 1), against a flat curve: every region with a patch is worth a descent.
  std::vector<RegionSample> samples;
  for (double dh : {5.5, 11.0})
    for (double sigma : {0.05, 0.2}) {
      RegionSample r;
      r.top_gsd_cm = 3.0;
      r.delta_h_m = dh;
      r.sigma_top = r.sigma_sub = sigma;
      r.miou_top = 0.8;
      r.miou_sub = 0.9;
      r.relabelled = {0.01, 0.01};
      r.region_share = 0.25;
      r.field_sigma = 0.05;
      r.field_gain = 0.01;
      samples.push_back(r);
    }
  GainModel model = GainModel::fit(samples, {.restarts = 0});
  model.set_cells(CellGainModel(DecisionInput::expected_error, {{3.0, 1.0, 1.0, 1e-6, 1.0, 1e-6, 1.0, 1e-4}}));
  const std::vector<ReferenceCurve> flat{{"flat", {{1.0, 0.8}, {3.0, 0.8}}, 0.05, 0.01}};
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {1.0};
  o.coverage = DescentCoverage::ranked;
  WorseLower backend;
  FrontAwarePolicy adaptive(model, flat, {.online = true});
  FrontAwarePolicy fixed(model, flat, {.online = false});
  const AdaptiveResult learns = run_adaptive_mission(f, backend, adaptive, o, "adaptive");
  const AdaptiveResult frozen = run_adaptive_mission(f, backend, fixed, o, "nonadaptive");
  // Without the check every region is re-mapped; with it the first descent shows a finer look
  // far less sure than the top (its expected error about crop 0.5 everywhere) and the UAV stops.
  CHECK(frozen.descents() == 4);
  CHECK(learns.descents() == 1);
  const DescentOutcome& first = *learns.decisions[0].outcome;
  CHECK(first.fine_input > first.top_input);
  CHECK(adaptive.field_scale() < 0.0);
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

TEST_CASE("adaptive planner (tour): each descent flown at once or after the survey, as costed") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  for (double top : {3.0, 6.0}) {
    AdaptiveOptions o = options();
    o.top_gsd_cm = top;
    o.candidate_gsd_cm = {1.0};
    Scripted never{.gsd = 0.5};
    const double coverage = run_adaptive_mission(f, oracle, never, o, "never").mission.total_s();
    Scripted at_once{.gsd = 1.0};
    const AdaptiveResult immediate = run_adaptive_mission(f, oracle, at_once, o, "immediate");
    o.schedule = DescentSchedule::tour;
    Scripted all{.gsd = 1.0};
    const AdaptiveResult tour = run_adaptive_mission(f, oracle, all, o, "tour");
    CAPTURE(top);
    REQUIRE(tour.descents() == static_cast<int>(tour.decisions.size()));
    CHECK(tour.mission.miou_all().value() == 1.0);
    // Each descent's cost is the cheaper of the two ways; the tour is never longer than charged.
    double charged = 0.0;
    std::size_t deferred = 0;
    for (std::size_t k = 0; k < tour.decisions.size(); ++k) {
      const Candidate& c = tour.decisions[k].candidates.at(0);
      const Candidate& now = immediate.decisions[k].candidates.at(0);
      CHECK(!now.deferred);
      if (k + 1 < tour.decisions.size() || deferred == 0) {
        CHECK(c.extra_time_s <= now.extra_time_s + 1e-9);
        CHECK(c.deferred == (c.extra_time_s < now.extra_time_s));
      } else {
        CHECK(c.deferred);  // where a chosen tour starts, it prices even "at once"
      }
      charged += c.extra_time_s;
      deferred += c.deferred ? 1 : 0;
    }
    CHECK(tour.mission.total_s() <= coverage + charged + 1e-9);
    CHECK(tour.mission.total_s() <= immediate.mission.total_s() + 1e-9);
    if (top == 6.0) {  // Δh = 27.5 m: climbing back costs more than flying on to the next region
      CHECK(deferred >= 2);
      CHECK(tour.mission.total_s() < immediate.mission.total_s() - 5.0);
    }
    // Path: the top level, with the at-once descents after their waypoint, then the tour.
    const auto& w = tour.mission.waypoints;
    const auto last_top = std::find_if(w.rbegin(), w.rend(), [](const WaypointRecord& r) { return r.level == 0; });
    const std::size_t tour_start = static_cast<std::size_t>(w.rend() - last_top);
    std::size_t after = 0;
    for (std::size_t k = tour_start; k < w.size(); ++k) after += w[k].level == 1 ? 1 : 0;
    std::size_t deferred_images = 0;
    for (const auto& d : tour.decisions)
      if (d.candidates.at(0).deferred) deferred_images += static_cast<std::size_t>(d.candidates[0].images);
    const auto& last_decision = tour.decisions.back();
    CHECK(after == deferred_images + (last_decision.candidates[0].deferred
                                          ? 0
                                          : static_cast<std::size_t>(last_decision.candidates[0].images)));
    // Outcomes name their descent; the simulation's realised gains come in decision order.
    CHECK(all.outcomes.size() == tour.decisions.size());
    for (std::size_t k = 0; k < tour.decisions.size(); ++k) {
      REQUIRE(tour.decisions[k].outcome.has_value());
      CHECK(tour.decisions[k].outcome->descent == k);
      CHECK(tour.realised.at(k).decision == k);
    }
  }
}

TEST_CASE("adaptive planner (row): a row's neighbouring descents share one descent and one climb, as costed") {
  // 30 x 22 m, 2 rows of 3 regions at 3 cm/px, descents to 1 cm/px (11 m lower) with a climb
  // rate of 0.25 m/s (44 s for 11 m): climbing back between two neighbouring regions costs more
  // than flying back along the row at low altitude, so staying low pays.
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {1.0};
  o.mission.timing.max_vertical_speed_mps = 0.25;
  Scripted never{.gsd = 0.5};
  const AdaptiveResult base = run_adaptive_mission(f, oracle, never, o, "never");
  const double coverage = base.mission.total_s();
  const auto fly = [&](DescentSchedule schedule) {
    AdaptiveOptions a = o;
    a.schedule = schedule;
    Scripted all{.gsd = 1.0};
    return run_adaptive_mission(f, oracle, all, a, "all");
  };
  const AdaptiveResult now = fly(DescentSchedule::immediate);
  const AdaptiveResult row = fly(DescentSchedule::row);
  REQUIRE(row.descents() == static_cast<int>(row.decisions.size()));
  CHECK(row.mission.miou_all().value() == 1.0);

  // The rows of the top level (rows run along x) and where each ends.
  std::vector<Eigen::Vector3d> top;
  for (const auto& w : base.mission.waypoints) top.push_back(w.waypoint.position);
  const auto row_ends = [&](std::size_t i) { return i + 1 == top.size() || top[i + 1].y() != top[i].y(); };
  REQUIRE(top.size() >= 4);
  std::size_t rows = 0;
  for (std::size_t i = 0; i < top.size(); ++i) rows += row_ends(i) ? 1 : 0;
  REQUIRE(rows >= 2);
  REQUIRE(rows < top.size());  // some row holds two regions or more

  // Each descent costs the cheaper of at once and deferred to its row's tour (at a row's last
  // waypoint, once a tour is chosen, always the tour); the mission costs what was charged.
  double charged = 0.0;
  std::size_t deferred = 0, in_row = 0;
  for (std::size_t k = 0; k < row.decisions.size(); ++k) {
    const Candidate& c = row.decisions[k].candidates.at(0);
    const Candidate& at_once = now.decisions[k].candidates.at(0);
    CAPTURE(k);
    if (!row_ends(k) || in_row == 0) {
      CHECK(c.extra_time_s <= at_once.extra_time_s + 1e-9);
      CHECK(c.deferred == (c.extra_time_s < at_once.extra_time_s));
    } else {
      CHECK(c.deferred);
    }
    charged += c.extra_time_s;
    deferred += c.deferred ? 1 : 0;
    in_row = row_ends(k) ? 0 : in_row + (c.deferred ? 1 : 0);
  }
  CAPTURE(deferred);
  CHECK(deferred >= 2);
  CHECK(row.mission.total_s() <= coverage + charged + 1e-9);
  CHECK(row.mission.total_s() < now.mission.total_s() - 5.0);
  // Fewer altitude changes: a row's deferred inspections are entered and left once.
  const auto changes = [](const MissionResult& m) {
    int n = 0;
    for (std::size_t k = 1; k < m.waypoints.size(); ++k)
      n += m.waypoints[k].waypoint.position.z() != m.waypoints[k - 1].waypoint.position.z() ? 1 : 0;
    return n;
  };
  CHECK(changes(row.mission) < changes(now.mission));
  MESSAGE(top.size(), " regions in ", rows, " rows, every one inspected: at once ", now.mission.total_s(), " s, ",
          changes(now.mission), " altitude changes; after each row ", row.mission.total_s(), " s, ",
          changes(row.mission));

  // Path: every sub-lawnmower image is flown before the next row's first top-level image and
  // lies in a region of the row flown last.
  std::size_t top_seen = 0, row_first = 0;
  for (const auto& w : row.mission.waypoints) {
    if (w.level == 0) {
      if (top_seen > 0 && row_ends(top_seen - 1)) row_first = top_seen;
      ++top_seen;
      continue;
    }
    const Eigen::Vector3d& p = w.waypoint.position;
    bool in_this_row = false;
    for (std::size_t i = row_first; i < top_seen; ++i) {
      const Area& a = base.mission.waypoints[i].waypoint.footprint;
      in_this_row |= p.x() >= a.x_min_m && p.x() <= a.x_max_m && p.y() >= a.y_min_m && p.y() <= a.y_max_m;
    }
    CHECK(in_this_row);
  }
  // Every descent's outcome reaches the policy (after its row's tour, for the deferred ones).
  for (std::size_t k = 0; k < row.decisions.size(); ++k) CHECK(row.decisions[k].outcome.has_value());
}

TEST_CASE("adaptive planner: a climb rate limit is charged exactly, and makes the survey-first tour pay") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {1.0};  // 3 -> 1 cm/px: a descent of 11 m over 30 x 22 m regions
  const auto fly = [&](double vz, DescentSchedule schedule, std::vector<int> which = {}) {
    AdaptiveOptions a = o;
    a.mission.timing.max_vertical_speed_mps = vz;
    a.schedule = schedule;
    Scripted policy{.gsd = 1.0, .which = std::move(which)};
    return run_adaptive_mission(f, oracle, policy, a, "scripted");
  };
  const auto deferred = [](const AdaptiveResult& r) {
    return std::count_if(r.decisions.begin(), r.decisions.end(), [](const DecisionRecord& d) {
      return d.decision.descend && !d.candidates.empty() && d.candidates.at(0).deferred;
    });
  };
  // A candidate's extra time is what the descent adds, under the limit too.
  Scripted never{.gsd = 0.5};
  AdaptiveOptions slow = o;
  slow.mission.timing.max_vertical_speed_mps = 0.25;
  const double base = run_adaptive_mission(f, oracle, never, slow, "never").mission.total_s();
  const AdaptiveResult one = fly(0.25, DescentSchedule::immediate, {2});
  REQUIRE(one.descents() == 1);
  CHECK(one.mission.total_s() - base == doctest::Approx(one.decisions[2].candidates.at(0).extra_time_s).epsilon(1e-9));
  // Every region descends: the paper's time model defers less than a slow climb does, and the
  // slow climb makes the tour's saving larger.
  const AdaptiveResult iso_now = fly(0.0, DescentSchedule::immediate);
  const AdaptiveResult iso_tour = fly(0.0, DescentSchedule::tour);
  const AdaptiveResult slow_now = fly(0.25, DescentSchedule::immediate);
  const AdaptiveResult slow_tour = fly(0.25, DescentSchedule::tour);
  for (const AdaptiveResult* r : {&iso_now, &iso_tour, &slow_now, &slow_tour}) {
    CHECK(r->descents() == static_cast<int>(r->decisions.size()));
    CHECK(r->mission.miou_all().value() == 1.0);
  }
  CAPTURE(deferred(iso_tour));
  CAPTURE(deferred(slow_tour));
  CHECK(deferred(slow_tour) > deferred(iso_tour));
  CHECK(slow_now.mission.total_s() > iso_now.mission.total_s() + 10.0);  // every descent climbs slower
  const double saved_iso = iso_now.mission.total_s() - iso_tour.mission.total_s();
  const double saved_slow = slow_now.mission.total_s() - slow_tour.mission.total_s();
  CAPTURE(saved_iso);
  CAPTURE(saved_slow);
  CHECK(saved_iso >= -1e-9);
  CHECK(saved_slow > saved_iso + 5.0);
}

TEST_CASE("adaptive planner (tour, row): the budget is never exceeded") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  for (const DescentSchedule schedule : {DescentSchedule::tour, DescentSchedule::row}) {
    CAPTURE(to_string(schedule));
    AdaptiveOptions o = options();
    o.top_gsd_cm = 6.0;
    o.schedule = schedule;
    Scripted never{.gsd = 0.5};
    const double coverage = run_adaptive_mission(f, oracle, never, o, "never").mission.total_s();
    Scripted all{.gsd = 1.0};
    const double everything = run_adaptive_mission(f, oracle, all, o, "all").mission.total_s();
    REQUIRE(everything > coverage + 100.0);
    for (double budget : {coverage + 1.0, coverage + 60.0, 0.5 * (coverage + everything), everything - 1.0}) {
      o.budget_s = budget;
      Scripted greedy{.gsd = 1.0};
      const AdaptiveResult r = run_adaptive_mission(f, oracle, greedy, o, "greedy");
      CAPTURE(budget);
      CHECK(r.mission.total_s() <= budget + 1e-9);
      CHECK(greedy.observed == r.descents());
    }
  }
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

// --- AdaptivePlanner driven step by step, as a UAV's companion computer would ---

namespace {
using Planner = AdaptivePlanner<Scripted>;

AdaptiveOptions weedmap_options(const Field& f) {
  AdaptiveOptions o = options();
  o.mission.interest = f.interest();
  return o;
}

// Flies `planner` with a simulated camera: next() -> capture -> segment_and_report() with the
// oracle, as a caller would.
// With `report_elapsed`, the caller keeps the mission time itself (flight by the timing model,
// the fixed per-image and per-waypoint times) and reports it with each image.
std::vector<PlannerStep> fly(Planner& planner, const Field& f, bool report_elapsed = false) {
  const SimulatedSensor sensor(f, planner.camera());
  OracleSegmenter oracle(f.num_classes());
  const auto& mo = planner.options().mission;
  std::vector<PlannerStep> steps;
  std::optional<Eigen::Vector3d> at;
  double clock = 0.0;
  while (const auto w = planner.next()) {
    if (at) clock += planner.timing().segment_time_s(*at, w->waypoint.position);
    at = w->waypoint.position;
    clock += *mo.fixed_segmentation_time_s + *mo.fixed_planning_time_s;
    steps.push_back(report_elapsed ? segment_and_report(planner, oracle, sensor.capture(w->waypoint), clock)
                                   : segment_and_report(planner, oracle, sensor.capture(w->waypoint)));
  }
  return steps;
}
}  // namespace

TEST_CASE("AdaptivePlanner: stepping by hand over WeedMap gives run_adaptive_mission's path, decisions and map") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  double unlimited_s = 0.0;
  // Each flag both ways, in two missions: without a budget the caller reports the elapsed time,
  // with one the planner keeps its own clock (a budget driven by the reported time: "the elapsed
  // time the caller reports drives the budget" below).
  for (const auto& flags : {std::pair{false, true}, std::pair{true, false}}) {
    const bool budget = flags.first, report_elapsed = flags.second;  // named: CAPTURE's lambda captures them
    CAPTURE(budget);
    CAPTURE(report_elapsed);
    AdaptiveOptions o = weedmap_options(f);
    if (budget) o.budget_s = unlimited_s - 1.0;  // at least one descent less
    Scripted sim_policy{.gsd = 1.5, .which = {0, 2, 3, 5, 8, 9, 11}};
    const AdaptiveResult sim = run_adaptive_mission(f, oracle, sim_policy, o, "scripted");
    Scripted live_policy = Scripted{.gsd = 1.5, .which = {0, 2, 3, 5, 8, 9, 11}};
    Planner planner(SurveyArea::of(f), live_policy, o);
    const auto steps = fly(planner, f, report_elapsed);

    REQUIRE(sim.descents() >= 2);
    if (!budget) unlimited_s = sim.mission.total_s();
    if (budget) CHECK(sim.descents() < 7);
    REQUIRE(steps.size() == sim.mission.waypoints.size());
    REQUIRE(planner.path().size() == steps.size());
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const auto& w = sim.mission.waypoints[k];
      CHECK(steps[k].waypoint.index == k);
      CHECK(steps[k].waypoint.level == w.level);
      CHECK(steps[k].waypoint.waypoint.position == w.waypoint.position);
      CHECK(steps[k].sigma == w.semantic_ratio);
    }
    REQUIRE(planner.decisions().size() == sim.decisions.size());
    for (std::size_t k = 0; k < sim.decisions.size(); ++k) {
      const auto& a = planner.decisions()[k];
      const auto& b = sim.decisions[k];
      CHECK(a.waypoint_index == b.waypoint_index);
      CHECK(a.sigma == b.sigma);
      CHECK(a.decision.descend == b.decision.descend);
      CHECK(a.decision.gsd_cm == b.decision.gsd_cm);
      CHECK(a.budget_limited == b.budget_limited);
      REQUIRE(a.candidates.size() == b.candidates.size());
      for (std::size_t c = 0; c < a.candidates.size(); ++c)
        CHECK(a.candidates[c].extra_time_s == b.candidates[c].extra_time_s);
      REQUIRE(a.outcome.has_value() == b.outcome.has_value());
      if (a.outcome) CHECK(a.outcome->sigma_sub == b.outcome->sigma_sub);
    }
    CHECK(live_policy.observed == sim_policy.observed);
    CHECK(cv::countNonZero(planner.map().labels() != sim.mission.fused_labels) == 0);
    CHECK(planner.elapsed_s() == doctest::Approx(sim.mission.total_s()).epsilon(1e-12));
    if (budget) CHECK(planner.elapsed_s() <= *o.budget_s + 1e-9);
    // The step results carry the decisions and outcomes as they happen.
    int decided = 0, outcomes = 0;
    for (const auto& s : steps) {
      decided += s.decision ? 1 : 0;
      outcomes += s.outcome ? 1 : 0;
      CHECK(s.decision.has_value() == (s.waypoint.level == 0));
    }
    CHECK(decided == static_cast<int>(sim.decisions.size()));
    CHECK(outcomes == sim.descents());
  }
}

TEST_CASE(
    "AdaptivePlanner (pooled map): stepping by hand gives run_adaptive_mission's map, and labels alone are refused") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = weedmap_options(f);
  o.mission.map_fusion = MapFusion::pooled;
  Scripted sim_policy{.gsd = 1.5, .which = {0, 2, 3, 5}};
  const AdaptiveResult sim = run_adaptive_mission(f, oracle, sim_policy, o, "scripted");
  REQUIRE(sim.descents() >= 2);
  Scripted live_policy{.gsd = 1.5, .which = {0, 2, 3, 5}};
  Planner planner(SurveyArea::of(f), live_policy, o);
  CHECK(planner.map().fusion() == MapFusion::pooled);
  (void)fly(planner, f);
  CHECK(cv::countNonZero(planner.map().labels() != sim.mission.fused_labels) == 0);
  // The oracle's looks are sure where they are finest: the map is the paper's.
  o.mission.map_fusion = MapFusion::finest;
  Scripted finest_policy{.gsd = 1.5, .which = {0, 2, 3, 5}};
  const AdaptiveResult finest = run_adaptive_mission(f, oracle, finest_policy, o, "scripted");
  CHECK(sim.mission.miou_interest().value() == doctest::Approx(finest.mission.miou_interest().value()).epsilon(1e-3));
  // Labels without probabilities cannot be pooled: refused, the waypoint still pending.
  o.mission.map_fusion = MapFusion::pooled;
  Scripted never{.gsd = 0.5};
  Planner live(SurveyArea::of(f), never, o);
  const auto w = live.next();
  REQUIRE(w.has_value());
  const Image img = SimulatedSensor(f, live.camera()).capture(w->waypoint);
  CHECK_THROWS_WITH_AS((void)live.report(img, oracle.segment(img), 0.1),
                       doctest::Contains("map fusion 'pooled' needs the class probabilities behind the labels"),
                       std::invalid_argument);
  CHECK(live.pending().has_value());
  CHECK(live.report(img, oracle.segment_with_probabilities(img), 0.1).waypoint.index == 0);
}

TEST_CASE("AdaptivePlanner: next() repeats the pending waypoint and is nullopt once done") {
  const Field f = t::blob_field(1500, 1100, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted one{.gsd = 2.0, .which = {0}};
  Planner planner(SurveyArea::of(f), one, weedmap_options(f));
  CHECK_FALSE(planner.done());
  const auto a = planner.next();
  const auto b = planner.next();
  REQUIRE(a.has_value());
  REQUIRE(b.has_value());
  CHECK(a->index == b->index);
  CHECK(planner.path().size() == 1);
  CHECK(planner.pending().has_value());
  const auto steps = fly(planner, f);
  CHECK(planner.done());
  CHECK_FALSE(planner.pending().has_value());
  CHECK_FALSE(planner.next().has_value());
  CHECK_FALSE(planner.next().has_value());
  // The first region was re-mapped at 2 cm/px right after its top-level image.
  REQUIRE(steps.size() > planner.top_level().size());
  CHECK(steps[1].waypoint.level == 1);
  CHECK(steps[1].waypoint.top_index == 0);
  CHECK(steps[1].waypoint.waypoint.gsd_cm == 2.0);
  CHECK(one.observed == 1);
  // Every waypoint flown is one the planner announced as reachable.
  const auto reachable = planner.reachable_waypoints();
  for (const auto& p : planner.path())
    CHECK(std::any_of(reachable.begin(), reachable.end(),
                      [&](const Waypoint& r) { return r.position == p.waypoint.position; }));
}

TEST_CASE("AdaptivePlanner: report() refuses a missing, repeated or malformed image") {
  const Field f = t::blob_field(1500, 1100, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  Planner planner(SurveyArea::of(f), never, weedmap_options(f));
  const SimulatedSensor sensor(f, planner.camera());
  const Image first = sensor.capture(planner.top_level().front());
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, oracle, first),
                       doctest::Contains("no waypoint is waiting for an image"), std::invalid_argument);
  const auto w = planner.next();
  REQUIRE(w.has_value());
  Image small = first;
  small.width_px = 320;
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, oracle, small),
                       doctest::Contains("the image must have the camera's size 480x360"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.report(first, cv::Mat(10, 10, CV_8UC1), 0.1),
                       doctest::Contains("labels must have the image's size 480x360"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, oracle, first, -1.0), doctest::Contains("elapsed_s"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.image_at(w->waypoint.position, cv::Mat(10, 10, CV_8UC3)),
                       doctest::Contains("bgr must be CV_8UC3 of the camera's size"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.image_at(w->waypoint.position, {}, std::numeric_limits<double>::quiet_NaN()),
                       doctest::Contains("yaw_deg must be finite"), std::invalid_argument);
  Image lost = first;
  lost.yaw_deg = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, oracle, lost), doctest::Contains("yaw_deg must be finite"),
                       std::invalid_argument);
  // A refused report changes nothing: the waypoint is still pending.
  CHECK(planner.pending().has_value());
  const PlannerStep step = segment_and_report(planner, oracle, first);
  CHECK(step.waypoint.index == 0);
  REQUIRE(step.decision.has_value());
  CHECK_FALSE(step.decision->decision.descend);
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, oracle, first),
                       doctest::Contains("each waypoint takes one image"), std::invalid_argument);
}

namespace {
/// The oracle, counting its calls.
struct CountingOracle {
  OracleSegmenter oracle;
  int calls = 0;
  std::string name() const { return "counting"; }
  cv::Mat segment(const Image& image) {
    ++calls;
    return oracle.segment(image);
  }
};
}  // namespace

TEST_CASE("AdaptivePlanner: a segmentation crosses once, checked where it was made") {
  const Field f = t::blob_field(1500, 1100, 1.0, 5, 40);
  Scripted never{.gsd = 0.5};
  Planner planner(SurveyArea::of(f), never, weedmap_options(f));
  const SimulatedSensor sensor(f, planner.camera());
  const Image first = sensor.capture(planner.top_level().front());
  CountingOracle backend{OracleSegmenter(f.num_classes())};
  // Refused before the backend runs: nothing is pending.
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, backend, first),
                       doctest::Contains("no waypoint is waiting for an image"), std::invalid_argument);
  CHECK(backend.calls == 0);
  REQUIRE(planner.next().has_value());
  // A segmentation checked for another class set, or for an image of another size: refused.
  const CheckedSegmentation other_classes = segment_and_check(backend, first, f.num_classes() + 1, false);
  CHECK_THROWS_WITH_AS((void)planner.report(first, other_classes, 0.1),
                       doctest::Contains("the segmentation was checked for another image size, ignore label or class "
                                         "set"),
                       std::invalid_argument);
  Image half = first;
  half.width_px /= 2;
  half.height_px /= 2;
  const CheckedSegmentation smaller =
      CheckedSegmentation::check(Segmentation{cv::Mat(half.height_px, half.width_px, CV_8UC1, cv::Scalar(0)), {}}, half,
                                 f.num_classes(), SegmentationSource::backend("test"));
  CHECK_THROWS_WITH_AS((void)planner.report(first, smaller, 0.1), doctest::Contains("checked for another image size"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.report(first, segment_and_check(backend, first, f.num_classes(), false), -0.1),
                       doctest::Contains("segmentation_s must be finite and >= 0"), std::invalid_argument);
  CHECK(planner.pending().has_value());
  // The backend's, checked once by segment_and_report: fused, the waypoint flown.
  const int before = backend.calls;
  CHECK(segment_and_report(planner, backend, first).waypoint.index == 0);
  CHECK(backend.calls == before + 1);
  CHECK_FALSE(planner.pending().has_value());
}

TEST_CASE("AdaptivePlanner: the elapsed time the caller reports drives the budget") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  const double coverage = run_adaptive_mission(f, oracle, never, options(), "never").mission.total_s();
  AdaptiveOptions o = weedmap_options(f);
  o.budget_s = coverage + 200.0;
  // Reporting the same mission time as the simulation gives the same budget-limited mission.
  Scripted greedy{.gsd = 1.0};
  const AdaptiveResult sim = run_adaptive_mission(f, oracle, greedy, o, "greedy");
  Scripted greedy_live{.gsd = 1.0};
  Planner planner(SurveyArea::of(f), greedy_live, o);
  (void)fly(planner, f, true);
  CHECK(planner.elapsed_s() == doctest::Approx(sim.mission.total_s()).epsilon(1e-12));
  CHECK(planner.elapsed_s() <= *o.budget_s + 1e-9);
  CHECK(planner.path().size() == sim.mission.waypoints.size());
  CHECK(sim.descents() > 0);
  // A caller whose clock says the budget is spent gets no descent, whatever the policy wants.
  Scripted late{.gsd = 1.0};
  Planner spent(SurveyArea::of(f), late, o);
  const SimulatedSensor sensor(f, spent.camera());
  while (const auto w = spent.next()) (void)segment_and_report(spent, oracle, sensor.capture(w->waypoint), *o.budget_s);
  CHECK(spent.elapsed_s() == *o.budget_s);
  CHECK(spent.path().size() == spent.top_level().size());
  for (const auto& d : spent.decisions()) {
    CHECK(d.budget_limited);
    CHECK(d.candidates.empty());
    CHECK_FALSE(d.decision.descend);
  }
}

TEST_CASE("AdaptivePlanner: live images made from poses land where the simulator puts them") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  Planner planner(SurveyArea::of(f), never, weedmap_options(f));
  const SimulatedSensor sensor(f, planner.camera());
  const auto reachable = planner.reachable_waypoints();
  CHECK(reachable.size() > planner.top_level().size() * 4);
  for (const auto& w : reachable) {
    const Image live = planner.image_at(w.position);
    const Image sim = sensor.capture(w);
    CHECK(live.footprint_px == sim.footprint_px);
    CHECK(live.gsd_cm == doctest::Approx(sim.gsd_cm));
  }
}

TEST_CASE(
    "AdaptivePlanner: DescentGrid::field shares the field's finer lawnmower out among the regions, as calibration "
    "flies it") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  Scripted never{.gsd = 0.5};
  AdaptiveOptions o = weedmap_options(f);
  const Planner by_region(SurveyArea::of(f), never, o);
  o.descent_grid = DescentGrid::field;
  const Planner by_field(SurveyArea::of(f), never, o);
  const LawnmowerPlanner lawnmower(by_field.camera());
  const auto has_field = [&](const Area& a) { return f.has_valid(a); };
  for (double g : o.candidate_gsd_cm) {
    CAPTURE(g);
    const auto whole = lawnmower.plan(f.area(), g, Eigen::Vector2d(f.area().x_min_m, f.area().y_min_m), has_field);
    std::vector<int> taken(whole.size(), 0);
    std::size_t regions = 0, fields = 0;
    for (std::size_t i = 0; i < by_field.top_level().size(); ++i) {
      regions += by_region.sub_plan(i, g).size();
      for (const Waypoint& w : by_field.sub_plan(i, g)) {
        ++fields;
        for (std::size_t k = 0; k < whole.size(); ++k)
          if ((whole[k].position - w.position).norm() < 1e-9) ++taken[k];
      }
    }
    // Each image of the field's own lawnmower at g is flown by exactly one region's descent.
    CHECK(fields == whole.size());
    for (int n : taken) CHECK(n == 1);
    // Where the finer footprint does not divide the top level's (3 cm/px over 2 and 2.5), the
    // regions' own grids fly more images than the field needs.
    if (g == 2.0 || g == 2.5) CHECK(regions > fields);
    // Calibration lays the same sub-lawnmowers: one cell sample per image.
    OracleSegmenter oracle(f.num_classes());
    const auto samples = collect_samples(f, oracle, by_field.camera(), o.top_gsd_cm, {g}, f.interest(),
                                         DescentCoverage::ranked, 0, MapFusion::finest, false, DescentGrid::field);
    CHECK(samples.cells.size() == fields);
  }
}

TEST_CASE("calibration: GainExtent::images counts a descent's field gain as the flight realises it") {
  check_names_round_trip(kGainExtents, [](const char* n) { return parse_gain_extent(n); });
  CHECK_THROWS_WITH_AS(static_cast<void>(parse_gain_extent("footprint")),
                       "gain extent must be 'region' or 'images', not 'footprint'", std::invalid_argument);
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  for (MapFusion fusion : {MapFusion::finest, MapFusion::pooled}) {
    AdaptiveOptions o = options();
    o.mission.map_fusion = fusion;
    const CameraModel camera(o.mission.camera);
    const auto samples = [&](double g, GainExtent extent, DescentCoverage coverage = DescentCoverage::region) {
      return collect_samples(f, oracle, camera, o.top_gsd_cm, {g}, f.interest(), coverage, 0, fusion, false,
                             DescentGrid::region, extent);
    };
    // 2 cm/px from 3: a 2 x 2 grid of footprints 1.33 regions a side overhangs each region into
    // its neighbours'; 1 cm/px tiles it exactly.
    const CalibrationSamples images = samples(2.0, GainExtent::images), region = samples(2.0, GainExtent::region),
                             tiled = samples(1.0, GainExtent::images), tiled_region = samples(1.0, GainExtent::region),
                             cells = samples(2.0, GainExtent::images, DescentCoverage::ranked);
    REQUIRE(images.regions.size() == region.regions.size());
    REQUIRE(tiled.regions.size() == tiled_region.regions.size());
    for (std::size_t i = 0; i < tiled.regions.size(); ++i)
      CHECK(tiled.regions[i].field_gain == tiled_region.regions[i].field_gain);
    int differ = 0;
    for (int i : {0, 1, 3, 5}) {
      CAPTURE(std::string(to_string(fusion)));
      CAPTURE(i);
      const auto k = static_cast<std::size_t>(i);
      REQUIRE(k < images.regions.size());
      Scripted one{.gsd = 2.0, .which = {i}};
      const AdaptiveResult flown = run_adaptive_mission(f, oracle, one, o, "one");
      REQUIRE(flown.realised.size() == 1);
      const RealisedDescent& d = flown.realised.front();
      REQUIRE(d.decision == k);
      // Every pixel the images cover, the neighbours' top-level labels beside them: exactly
      // what the flight realises, where the region's count misses the overhang.
      CHECK(images.regions[k].field_gain == doctest::Approx(d.field_gain).epsilon(1e-12));
      differ += region.regions[k].field_gain != images.regions[k].field_gain ? 1 : 0;
      // Each cell alone over its whole footprint: the cells (which do not overlap) add up to
      // the descent's pixels.
      std::int64_t tp = 0, fp = 0;
      for (const CellSample& c : cells.cells)
        if (c.region == k) tp += c.delta_tp, fp += c.delta_fp;
      CHECK(tp == d.delta_tp);
      CHECK(fp == d.delta_fp);
    }
    CHECK(differ > 0);
  }
}

TEST_CASE(
    "AdaptivePlanner: with GainExtent::images each ranked cell is forecast for the field pixels its calibration "
    "sample counts") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = options();
  o.candidate_gsd_cm = {2.0};
  o.coverage = DescentCoverage::ranked;
  o.cell_input = DecisionInput::expected_error;
  const CameraModel camera(o.mission.camera);
  const CalibrationSamples samples =
      collect_samples(f, oracle, camera, o.top_gsd_cm, {2.0}, f.interest(), o.coverage, 0, MapFusion::finest, false,
                      DescentGrid::region, GainExtent::images);
  const double field_px = f.valid_pixels();
  for (GainExtent extent : {GainExtent::region, GainExtent::images}) {
    CAPTURE(std::string(to_string(extent)));
    o.gain_extent = extent;
    Pick policy{.descend = false};
    (void)run_adaptive_mission(f, oracle, policy, o, "offered");
    std::size_t compared = 0, overhang = 0;
    for (std::size_t k = 0; k < policy.offered.size(); ++k) {
      if (policy.offered[k].empty()) continue;
      // The option with the most cells holds every ranked cell of the region.
      const Candidate& all = policy.offered[k].back();
      for (const CellInputs& c : all.cells) {
        CAPTURE(k);
        if (extent == GainExtent::region) {
          CHECK(c.footprint_px == 0.0);
          CHECK(c.gain_px() == c.field_px);
          continue;
        }
        // The same cell in calibration: its pixels in the region, those of its whole footprint,
        // and the field share its gain was normalised by.
        const auto same = std::find_if(samples.cells.begin(), samples.cells.end(), [&](const CellSample& s) {
          return s.region == k && s.top.field_px == c.field_px && s.top.footprint_px == c.footprint_px;
        });
        REQUIRE(same != samples.cells.end());
        CHECK(same->field_share == doctest::Approx(c.footprint_px / field_px).epsilon(1e-12));
        CHECK(c.gain_px() == c.footprint_px);
        ++compared;
        overhang += c.footprint_px > c.field_px ? 1 : 0;
      }
    }
    // 2 cm/px from 3: the footprints overhang their regions, and the flight weighs them so.
    if (extent == GainExtent::images) {
      CHECK(compared > 4);
      CHECK(overhang > 0);
    }
  }
}

TEST_CASE("AdaptivePlanner: GridAnchor::centred lays the top-level grid centred on the area, every waypoint inside") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  AdaptiveOptions o = weedmap_options(f);
  const Planner corner(SurveyArea::of(f), never, o);
  o.grid_anchor = GridAnchor::centred;
  const Planner centred(SurveyArea::of(f), never, o);
  REQUIRE(centred.top_level().size() == corner.top_level().size());
  const Area& a = f.area();
  double lo_x = a.x_max_m, hi_x = a.x_min_m, lo_y = a.y_max_m, hi_y = a.y_min_m;
  bool moved = false;
  for (std::size_t i = 0; i < centred.top_level().size(); ++i) {
    const Eigen::Vector3d& p = centred.top_level()[i].position;
    CHECK((p.x() > a.x_min_m && p.x() < a.x_max_m && p.y() > a.y_min_m && p.y() < a.y_max_m));
    lo_x = std::min(lo_x, centred.top_level()[i].footprint.x_min_m),
    hi_x = std::max(hi_x, centred.top_level()[i].footprint.x_max_m);
    lo_y = std::min(lo_y, centred.top_level()[i].footprint.y_min_m),
    hi_y = std::max(hi_y, centred.top_level()[i].footprint.y_max_m);
    moved = moved || (p - corner.top_level()[i].position).norm() > 1e-6;
  }
  CHECK(moved);
  // The footprints' overhang is split evenly between opposite sides.
  CHECK(a.x_min_m - lo_x == doctest::Approx(hi_x - a.x_max_m));
  CHECK(a.y_min_m - lo_y == doctest::Approx(hi_y - a.y_max_m));
}

TEST_CASE("AdaptivePlanner: a camera that does not hold the plan's heading is fused at its yaw") {
  const Field f = Field::load(t::example_field("weedmap-000")).sub_field({0.0, 0.0, 0.6, 0.6});
  OracleSegmenter oracle(f.num_classes());
  const Scripted twice{.gsd = 2.0, .which = {0, 2}};
  // upright: images at yaw 0; turned: the same waypoints, each image taken at yaw 180 (its
  // labels upside down); askew: at 25 deg.
  std::map<double, cv::Mat> maps;
  for (double yaw : {0.0, 180.0, 25.0}) {
    CAPTURE(yaw);
    Scripted policy = twice;
    Planner planner(SurveyArea::of(f), policy, weedmap_options(f));
    const SimulatedSensor sensor(f, planner.camera());
    while (const auto w = planner.next()) {
      const Image sim = sensor.capture(w->waypoint, yaw);
      Image live = planner.image_at(w->waypoint.position, sim.bgr, yaw);
      CHECK(live.yaw_deg == yaw);
      CHECK(live.footprint_px == sim.footprint_px);
      live.ground_truth = sim.ground_truth;
      (void)segment_and_report(planner, oracle, live);
    }
    CHECK(policy.observed == 2);
    maps[yaw] = planner.map().labels().clone();
  }
  CHECK(cv::countNonZero(maps[180.0] != maps[0.0]) == 0);
  // Askew, the turned landscape footprints leave gaps and overlap elsewhere; where both maps
  // are observed they agree but for nearest-neighbour edges.
  const cv::Mat both = (maps[0.0] != f.ignore_label()) & (maps[25.0] != f.ignore_label());
  const int agree = cv::countNonZero((maps[0.0] == maps[25.0]) & both);
  CHECK(cv::countNonZero(both) > 0.8 * cv::countNonZero(maps[0.0] != f.ignore_label()));
  CHECK(agree > 0.9 * cv::countNonZero(both));
}

TEST_CASE("AdaptivePlanner: a survey area without a mask covers the rectangle") {
  const Field f = t::blob_field(1500, 1100, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  Scripted never{.gsd = 0.5};
  SurveyArea area{.area = {0.0, 0.0, 15.0, 11.0}, .map_gsd_cm = 1.0, .num_classes = f.num_classes()};
  Planner planner(area, never, weedmap_options(f));
  CHECK(planner.map().labels().size() == cv::Size(1500, 1100));
  CHECK(planner.valid_fraction(planner.top_level().front().footprint) == 1.0);
  CHECK(planner.top_level().size() == LawnmowerPlanner(CameraModel{}).plan(area.area, 3.0).size());
  AdaptiveOptions no_interest = options();
  CHECK_THROWS_WITH_AS(Planner(area, never, no_interest), doctest::Contains("no labels of interest"),
                       std::invalid_argument);
  area.area.x_min_m = -1.0;
  CHECK_THROWS_WITH_AS(Planner(area, never, weedmap_options(f)), doctest::Contains("SurveyArea: area"),
                       std::invalid_argument);
}

/// A mission on the caller's clock (as a UAV's companion computer keeps it): each leg at the
/// timing model's time, then `step(waypoint, clock)` takes the image, reports it and advances the
/// clock by what the step cost. Returns the clock at the end.
template <typename Planner, typename Step>
double fly_on_callers_clock(Planner& planner, Step&& step) {
  double clock = 0.0;
  std::optional<Eigen::Vector3d> at;
  while (const auto w = planner.next()) {
    if (at) clock += planner.timing().segment_time_s(*at, w->waypoint.position);
    at = w->waypoint.position;
    step(*w, clock);
  }
  return clock;
}

/// The options of the tests on a clock below: `options()` over blob field `f` at a 6 cm/px top
/// level, with the segmentation and planning times fixed at `segmentation_s` and `planning_s`
/// (nullopt: measured).
AdaptiveOptions clocked_options(const Field& f, std::optional<double> segmentation_s,
                                std::optional<double> planning_s) {
  AdaptiveOptions o = options();
  o.top_gsd_cm = 6.0;
  o.mission.fixed_segmentation_time_s = segmentation_s;
  o.mission.fixed_planning_time_s = planning_s;
  o.mission.interest = f.interest();
  return o;
}

TEST_CASE("AdaptivePlanner: the budget holds on a slow computer, images and decisions slowed at random") {
  // A caller that keeps the mission clock itself (as a UAV's companion computer does): the flight
  // model's legs, then per image a segmentation of a random 0-300 ms and the planner slowed by
  // another random 0-300 ms (a busy computer). The planner learns a bound of a step's cost from
  // its clock and reserves it for every step still to come: no mission ends over its budget, and
  // the budgets that leave room still buy descents.
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = clocked_options(f, std::nullopt, std::nullopt);
  const SimulatedSensor sensor(f, CameraModel(o.mission.camera));
  // The top level alone at the worst step (0.6 s per image), and with every descent at none.
  double coverage_worst = 0.0, everything = 0.0;
  {
    Scripted never{.gsd = 0.5}, all{.gsd = 1.0};
    AdaptiveOptions fixed = options();
    fixed.top_gsd_cm = 6.0;
    fixed.mission.fixed_segmentation_time_s = 0.6;
    fixed.mission.fixed_planning_time_s = 0.0;
    coverage_worst = run_adaptive_mission(f, oracle, never, fixed, "never").mission.total_s();
    fixed.mission.fixed_segmentation_time_s = 0.0;
    everything = run_adaptive_mission(f, oracle, all, fixed, "all").mission.total_s();
  }
  REQUIRE(everything > coverage_worst + 60.0);
  int over = 0, descended = 0, runs = 0;
  double worst_slack = 1e9;
  for (unsigned seed = 0; seed < 50; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> slow(0.0, 0.3);
    const double budget = coverage_worst + (0.05 + 0.9 * (seed % 10) / 10.0) * (everything - coverage_worst);
    o.budget_s = budget;
    Scripted greedy{.gsd = 1.0};
    AdaptivePlanner<Scripted> planner(SurveyArea::of(f), greedy, o);
    const double clock = fly_on_callers_clock(planner, [&](const PlannedWaypoint& w, double& now) {
      const Image image = sensor.capture(w.waypoint);
      const double segmentation_s = slow(rng);
      now += segmentation_s;
      (void)planner.report(image, oracle.segment(image), segmentation_s, now);
      now += slow(rng) + planner.take_planning_s();
    });
    CAPTURE(seed);
    CAPTURE(budget);
    CHECK(clock <= budget);
    over += clock > budget ? 1 : 0;
    worst_slack = std::min(worst_slack, budget - clock);
    const auto n = std::count_if(planner.decisions().begin(), planner.decisions().end(),
                                 [](const DecisionRecord& d) { return d.decision.descend; });
    descended += n > 0 ? 1 : 0;
    ++runs;
  }
  MESSAGE("runs over budget: " << over << " of " << runs << "; runs with descents: " << descended << "; least slack "
                               << worst_slack << " s");
  CHECK(over == 0);
  CHECK(descended >= 40);  // every budget beyond the tightest buys descents
}

TEST_CASE("AdaptivePlanner: the budget holds on a vehicle's clock, whatever times are fixed") {
  // A vehicle's mission (adaptseg_live --mavlink) with the segmentation and planning times fixed
  // as a simulation's: each step costs, beyond the flight model's leg and the fixed 0.1 s, a
  // random 1-2 s of settling, acknowledgements and wind that no fixed time knows. The clock the
  // caller reports is the one that counts: every decision and every step of a descent is checked
  // against it (a descent is cut short where the rest no longer fits), each step still to come
  // reserved at the bound learned from it, not at the fixed times, and no mission ends over its
  // budget. Shallow descents (3 -> 2.5 cm/px, two images each) spend a budget to its last seconds:
  // with the fixed 0.1 s reserved per step, 11 of these 20 missions ended over it (by up to 6.2 s).
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = clocked_options(f, 0.1, 0.0);
  o.top_gsd_cm = 3.0;
  const SimulatedSensor sensor(f, CameraModel(o.mission.camera));
  double coverage_worst = 0.0, everything = 0.0;
  {
    Scripted never{.gsd = 0.5}, all{.gsd = 2.5};
    AdaptiveOptions worst = o;
    worst.mission.fixed_segmentation_time_s = 2.1;
    coverage_worst = run_adaptive_mission(f, oracle, never, worst, "never").mission.total_s();
    everything = run_adaptive_mission(f, oracle, all, o, "all").mission.total_s();
  }
  REQUIRE(everything > coverage_worst + 60.0);
  int over = 0, descended = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> settle(1.0, 2.0);
    const double budget = coverage_worst + (0.05 + 0.9 * (seed % 10) / 10.0) * (everything - coverage_worst);
    o.budget_s = budget;
    Scripted greedy{.gsd = 2.5};
    AdaptivePlanner<Scripted> planner(SurveyArea::of(f), greedy, o);
    const double clock = fly_on_callers_clock(planner, [&](const PlannedWaypoint& w, double& now) {
      now += settle(rng) + 0.1;
      const Image image = sensor.capture(w.waypoint);
      (void)planner.report(image, oracle.segment(image), 0.1, now);
    });
    CAPTURE(seed);
    CAPTURE(budget);
    CHECK(clock <= budget);
    over += clock > budget ? 1 : 0;
    descended += std::any_of(planner.decisions().begin(), planner.decisions().end(),
                             [](const DecisionRecord& d) { return d.decision.descend; });
  }
  CHECK(over == 0);
  CHECK(descended >= 12);  // the tightest budgets leave none
}

TEST_CASE("run_adaptive_mission: a backend and a policy that sleep keep the budget, measured time") {
  // The simulation measures the segmentation and the planner's time with the clock, as a mission
  // flown without fixed times does: both slowed by real sleeps, up to 40 ms each.
  struct SleepyOracle {
    OracleSegmenter oracle;
    std::mt19937 rng{3};
    std::string name() const { return "sleepy-oracle"; }
    cv::Mat segment(const Image& image) {
      std::this_thread::sleep_for(std::chrono::microseconds(std::uniform_int_distribution<int>(0, 40000)(rng)));
      return oracle.segment(image);
    }
  };
  struct SleepyScripted : Scripted {
    std::mt19937 rng{4};
    Decision decide(const DecisionContext& c) {
      std::this_thread::sleep_for(std::chrono::microseconds(std::uniform_int_distribution<int>(0, 40000)(rng)));
      return Scripted::decide(c);
    }
  };
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  AdaptiveOptions o = clocked_options(f, std::nullopt, std::nullopt);
  SleepyOracle backend{OracleSegmenter(f.num_classes())};
  SleepyScripted never;
  never.gsd = 0.5;
  const double coverage = run_adaptive_mission(f, backend, never, o, "never").mission.total_s();
  // Room for one descent (about 31 s of flight over this field) with its images and the rest
  // reserved at the bound of a step the clock learns: 70 s leaves that bound up to about 4.9 s,
  // so a loaded machine (CTest's parallel jobs beside the sleeps) still affords it. With 40 s a
  // first step of 0.6 s, the bound then 1.2 s, ruled the descent out (CI, 2026-12-02).
  o.budget_s = coverage + 70.0;
  SleepyScripted greedy;
  const AdaptiveResult r = run_adaptive_mission(f, backend, greedy, o, "greedy");
  CHECK(r.mission.total_s() <= *o.budget_s);
  CHECK(r.descents() >= 1);
}

TEST_CASE("AdaptivePlanner: a shared time account is charged the planner's planning and is the time it reads") {
  // A caller that keeps the account (run_adaptive_mission: the Mission's) charges flight and
  // segmentation; the planner charges its planning into it, per waypoint where the options fix
  // it, and reads the mission time from it: nothing is handed from one account to another.
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o = clocked_options(f, 0.1, 0.25);
  const SimulatedSensor sensor(f, CameraModel(o.mission.camera));
  Scripted greedy{.gsd = 1.0};
  TimeAccount shared;
  AdaptivePlanner<Scripted> planner(SurveyArea::of(f), greedy, o, &shared);
  std::size_t handed_out = 0;
  (void)fly_on_callers_clock(planner, [&](const PlannedWaypoint& w, double& legs) {
    ++handed_out;
    CHECK(shared.planning_s == doctest::Approx(0.25 * static_cast<double>(handed_out)));
    shared.flight_s = 7.0 + legs;  // the owner's: a take-off the planner knows nothing of, and the legs
    shared.segmentation_s += 0.1;
    const Image image = sensor.capture(w.waypoint);
    (void)planner.report(image, oracle.segment(image), 0.1);
    CHECK(planner.elapsed_s() == shared.total_s());
  });
  CHECK(std::any_of(planner.decisions().begin(), planner.decisions().end(),
                    [](const DecisionRecord& d) { return d.decision.descend; }));
  CHECK(shared.segmentation_s == doctest::Approx(0.1 * static_cast<double>(handed_out)));
  CHECK(shared.planning_s == doctest::Approx(0.25 * static_cast<double>(handed_out)));

  // Measured planning: what the planner charges is what it hands a caller with its own account.
  o.mission.fixed_planning_time_s.reset();
  TimeAccount measured;
  Scripted again{.gsd = 1.0};
  AdaptivePlanner<Scripted> second(SurveyArea::of(f), again, o, &measured);
  double taken = second.take_planning_s();
  while (const auto w = second.next()) {
    const Image image = sensor.capture(w->waypoint);
    (void)second.report(image, oracle.segment(image), 0.1);
    taken += second.take_planning_s();
  }
  CHECK(measured.planning_s > 0.0);
  CHECK(measured.planning_s == doctest::Approx(taken));
  CHECK(measured.flight_s == 0.0);  // the owner's to charge
  CHECK(second.elapsed_s() == measured.total_s());
}

TEST_CASE("run_adaptive_mission: one time account, flight by the ramp model plus fixed times per image and waypoint") {
  const Field f = t::blob_field(3000, 2200, 1.0, 5, 40);
  OracleSegmenter oracle(f.num_classes());
  const AdaptiveOptions o = clocked_options(f, 0.1, 0.25);
  Scripted greedy{.gsd = 1.0};
  const AdaptiveResult r = run_adaptive_mission(f, oracle, greedy, o, "greedy");
  REQUIRE(r.descents() >= 1);
  std::vector<Eigen::Vector3d> path;
  for (const auto& w : r.mission.waypoints) path.push_back(w.waypoint.position);
  const auto n = static_cast<double>(path.size());
  CHECK(r.mission.time.flight_s == doctest::Approx(TimingModel(o.mission.timing).path_time_s(path)));
  CHECK(r.mission.time.segmentation_s == doctest::Approx(0.1 * n));
  CHECK(r.mission.time.planning_s == doctest::Approx(0.25 * n));  // once per waypoint, never twice
}
