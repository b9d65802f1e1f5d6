// The decision layer: the gain model (gain_model.hpp), the paper's rule (utility_policy.hpp),
// the front-aware rule (front_aware_policy.hpp), the model-file wrapper (decision_function.hpp),
// the linear baseline, and the conformance suite on each policy.

#include "policy_conformance.hpp"

#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/gain_model.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/core/utility_policy.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

using namespace adaptseg;

namespace {
// Synthetic initialisation data: descending further (larger Δh) loses more σ and gains more
// accuracy; a descent relabels ρ = 0.125 of σ(1 − σ); its field gain per relabelled share is Δh / 11.
std::vector<RegionSample> samples() {
  std::vector<RegionSample> out;
  for (double dh : {2.75, 5.5, 8.25, 11.0})
    for (double sigma : {0.02, 0.05, 0.1, 0.2, 0.3}) {
      RegionSample s;
      s.top_gsd_cm = 3.0;
      s.delta_h_m = dh;
      s.sigma_top = sigma;
      s.sigma_sub = sigma + 0.02 * dh * sigma;
      s.miou_top = 0.7;
      s.miou_sub = 0.7 + 0.025 * dh;
      s.relabelled = {0.15 * sigma * (1.0 - sigma), 0.125 * sigma * (1.0 - sigma)};
      s.region_share = 0.1;
      s.field_sigma = 0.1;
      s.field_gain = (dh / 11.0) * s.relabelled.interest_share * s.region_share / s.field_sigma;
      out.push_back(s);
    }
  return out;
}

std::vector<Candidate> candidates() {
  // 1.0, 1.5, 2.0, 2.5 cm/px below 3.0 cm/px with the default camera (h = 5.5 * gsd).
  return {{1.0, 5.5, 9, 40.0}, {1.5, 8.25, 4, 20.0}, {2.0, 11.0, 4, 20.0}, {2.5, 13.75, 4, 20.0}};
}

const GainModel& fitted() {
  static const GainModel m = GainModel::fit(samples());
  return m;
}

DecisionContext context(std::span<const Candidate> c, double sigma = 0.2) {
  return {.sigma = sigma, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
}
}  // namespace

static_assert(DecisionPolicy<UtilityPolicy>);
static_assert(DecisionPolicy<FrontAwarePolicy>);
static_assert(DecisionPolicy<DecisionFunction>);
static_assert(DecisionPolicy<LinearDecision>);
static_assert(!DecisionPolicy<int>);

// ---------------------------------------------------------------------------------------------
// GainModel
// ---------------------------------------------------------------------------------------------
TEST_CASE("gain model: initialised GPs reproduce the training trends") {
  const GainModel& m = fitted();
  CHECK(m.o_model().size() == 20);
  CHECK(m.i_model().size() == 20);
  CHECK(m.gain_inputs() == GainModel::GainInputs::delta_sigma_and_height);
  const GainForecast far = m.forecast(11.0, 0.2);
  const GainForecast near = m.forecast(2.75, 0.2);
  CHECK(far.delta_sigma < near.delta_sigma);  // more σ recovered lower down
  CHECK(far.delta_miou == doctest::Approx(-0.275).epsilon(0.1));
  CHECK(near.delta_miou == doctest::Approx(-0.069).epsilon(0.2));
  CHECK(far.delta_miou_std >= 0.0);
  // C: χ = σ(1 − σ) · ρ with ρ = 0.125, and 0 where nothing of L, or nothing else, is seen.
  CHECK(far.relabelled == doctest::Approx(0.02).epsilon(0.02));
  CHECK(m.forecast(5.5, 0.05).relabelled == doctest::Approx(0.125 * 0.05 * 0.95).epsilon(0.02));
  CHECK(m.forecast(5.5, 0.0).relabelled == 0.0);
  CHECK(m.forecast(5.5, 1.0).relabelled == 0.0);
  CHECK(far.relabelled_noisy_std >= far.relabelled_std);
  // η: the field gain per relabelled share at each descent height, linear in between.
  REQUIRE(m.efficiency_points().size() == 4);
  CHECK(m.efficiency(11.0) == doctest::Approx(1.0));
  CHECK(m.efficiency(2.75) == doctest::Approx(0.25));
  CHECK(m.efficiency(6.875) == doctest::Approx(0.625));
  CHECK(m.efficiency(20.0) == doctest::Approx(1.0));  // constant beyond the ends
  CHECK(m.efficiency(1.0) == doctest::Approx(0.25));
  CHECK_THROWS_AS((void)GainModel::fit({}), std::invalid_argument);
}

TEST_CASE(
    "gain model: the paper's I on delta sigma alone cannot tell candidate altitudes apart where (delta sigma, delta h) "
    "can") {
  // What an oracle backend gives: σ does not change with altitude (Δσ = 0), while the
  // accuracy gain grows with the descent.
  std::vector<RegionSample> flat;
  for (double dh : {2.75, 5.5, 8.25, 11.0})
    for (double sigma : {0.05, 0.1, 0.2, 0.3}) {
      RegionSample s;
      s.top_gsd_cm = 3.0;
      s.delta_h_m = dh;
      s.sigma_top = sigma;
      s.sigma_sub = sigma;
      s.miou_top = 0.8;
      s.miou_sub = 0.8 + 0.015 * dh;
      flat.push_back(s);
    }
  const auto paper = GainModel::fit(flat, {.gain_inputs = GainModel::GainInputs::delta_sigma});
  CHECK(paper.gain_inputs() == GainModel::GainInputs::delta_sigma);
  CHECK(paper.forecast(11.0, 0.2).delta_miou == doctest::Approx(paper.forecast(2.75, 0.2).delta_miou).epsilon(1e-9));
  const auto by_height = GainModel::fit(flat);
  CHECK(by_height.i_model().dimension() == 2);
  CHECK(by_height.forecast(11.0, 0.2).delta_miou == doctest::Approx(-0.165).epsilon(0.05));
  CHECK(by_height.forecast(2.75, 0.2).delta_miou == doctest::Approx(-0.041).epsilon(0.1));
}

TEST_CASE("gain model: the online update extends O") {
  GainModel m = fitted();
  GainModel refitting = fitted();
  refitting.set_refit_every(1);
  const DescentOutcome out{.top_altitude_m = 16.5, .sub_altitude_m = 5.5, .sigma_top = 0.1, .sigma_sub = 0.3};
  const double before = m.forecast(11.0, 0.1).delta_sigma;
  m.update(out);
  m.update(out);
  refitting.update(out);
  CHECK(m.o_model().size() == 22);
  CHECK(m.updates() == 2);
  CHECK(refitting.o_model().size() == 21);
  CHECK(m.i_model().size() == 20);  // I needs ground truth: fixed
  // The observed, much larger σ recovery (Δσ = -0.2) pulls O's prediction towards it.
  CHECK(std::abs(m.forecast(11.0, 0.1).delta_sigma + 0.2) < 0.5 * std::abs(before + 0.2));
  CHECK_THROWS_AS(m.set_refit_every(-1), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// UtilityPolicy (the paper's rule)
// ---------------------------------------------------------------------------------------------
TEST_CASE("utility policy: thresholds, σ weighting and the best utility") {
  UtilityPolicy policy(fitted(), {});
  const auto c = candidates();
  const DecisionContext ctx = context(c);
  Decision d = policy.decide(ctx);
  REQUIRE(d.scores.size() == 4);
  REQUIRE(d.descend);
  double best = 0.0;
  for (const auto& s : d.scores) best = std::max(best, s.utility);
  for (std::size_t k = 0; k < c.size(); ++k)
    if (d.scores[k].utility == best) CHECK(d.gsd_cm == c[k].gsd_cm);
  // σ weighting: half the valid fraction, half the utility.
  DecisionContext half_valid = ctx;
  half_valid.valid_fraction = 0.5;
  CHECK(policy.decide(half_valid).scores[0].utility == doctest::Approx(d.scores[0].utility * 0.5));
  // Thresholds.
  auto p = policy.params();
  p.min_sigma = 0.25;
  policy.set_params(p);
  CHECK_FALSE(policy.decide(ctx).descend);
  p.min_sigma = 0.0;
  p.min_utility = best * 1.01;
  policy.set_params(p);
  CHECK_FALSE(policy.decide(ctx).descend);
  p.min_utility = best * 0.99;
  policy.set_params(p);
  CHECK(policy.decide(ctx).descend);
  // No affordable candidate: continue.
  CHECK_FALSE(policy.decide(context({})).descend);
  CHECK_THROWS_AS(policy.set_params({.min_sigma = 2.0}), std::invalid_argument);
  CHECK_THROWS_AS(policy.set_params({.exploration = -1.0}), std::invalid_argument);
}

TEST_CASE("utility policy: relative utility compares with the mission's running mean") {
  UtilityPolicy policy(fitted(), {.min_utility = 1.2, .relative_utility = true});
  const auto c = candidates();
  const DecisionContext low = context(c, 0.05);
  const DecisionContext high = context(c, 0.3);
  CHECK_FALSE(policy.decide(low).descend);  // first image: ratio 1 < 1.2
  CHECK_FALSE(policy.decide(low).descend);
  CHECK(policy.decide(high).descend);  // well above the running mean
  policy.begin_mission();
  CHECK_FALSE(policy.decide(high).descend);  // alone again: ratio 1
}

TEST_CASE(
    "utility policy: online updates extend O only when adaptive, and a new mission starts from the initial model") {
  UtilityPolicy adaptive(fitted(), {.online = true});
  UtilityPolicy fixed(fitted(), {.online = false});
  CHECK(adaptive.name() == "adaptive");
  CHECK(fixed.name() == "nonadaptive");
  const DescentOutcome out{.top_altitude_m = 16.5, .sub_altitude_m = 5.5, .sigma_top = 0.1, .sigma_sub = 0.3};
  adaptive.observe(out);
  fixed.observe(out);
  CHECK(adaptive.model().o_model().size() == 21);
  CHECK(fixed.model().o_model().size() == 20);
  adaptive.begin_mission();
  CHECK(adaptive.model().o_model().size() == 20);
  CHECK(adaptive.initial_model().o_model().size() == 20);
}

// ---------------------------------------------------------------------------------------------
// FrontAwarePolicy
// ---------------------------------------------------------------------------------------------
namespace {
// One candidate 1.0 cm/px (Δh = 11 m, η = 1) for 40 s; the field's lawnmowers at 3.0 cm/px
// (40 s) and 1.0 cm/px (185 s); regions of 1/7 of the field; the training fields' σ 0.2. With
// C's ρ = 0.125 a region of σ = 0.2 is forecast to relabel 0.02 of its pixels, a field gain of
// 0.02 · (1/7) / 0.2 = 0.0143.
struct Scenario {
  std::vector<Candidate> one{{1.0, 5.5, 9, 40.0}};
  std::vector<Candidate> cheap{{1.0, 5.5, 2, 10.0}};  // the same descent over a few cells
  std::vector<LawnmowerForecast> lawnmowers{{1.0, 185.0}, {3.0, 40.0}};

  /// Reference curves whose rise over 40 s (linear from 40 to 185 s) is `rise`, and a second
  /// one rising by `rise2` (the spread of the training fields).
  std::vector<ReferenceCurve> reference(double rise, std::optional<double> rise2 = std::nullopt) const {
    std::vector<ReferenceCurve> r{{"a", {{1.0, 0.75 + rise * 145.0 / 40.0}, {3.0, 0.75}}, 0.2}};
    if (rise2) r.push_back({"b", {{1.0, 0.75 + *rise2 * 145.0 / 40.0}, {3.0, 0.75}}, 0.2});
    return r;
  }
  /// The k-th region (k = 0, 1, ...), after k descents.
  DecisionContext region(int k, double sigma = 0.2, bool is_cheap = false) const {
    DecisionContext c{.sigma = sigma,
                      .valid_fraction = 1.0,
                      .top_gsd_cm = 3.0,
                      .top_altitude_m = 16.5,
                      .candidates = is_cheap ? cheap : one};
    c.elapsed_s = 5.7 * (k + 1) + 40.0 * k;
    c.rest_s = 40.0 - 5.7 * (k + 1);
    c.region_share = 1.0 / 7.0;
    c.lawnmowers = lawnmowers;
    return c;
  }
  /// A descent at region 0 that relabelled `factor` times what C forecast.
  static DescentOutcome outcome(double factor) {
    return {.top_altitude_m = 16.5,
            .sub_altitude_m = 5.5,
            .sigma_top = 0.2,
            .sigma_sub = 0.2,
            .relabelled = {0.024 * factor, 0.02 * factor}};
  }
};
}  // namespace

TEST_CASE(
    "front-aware policy: a descent's forecast margin is against the curve at its end, and a new mission forgets") {
  const Scenario s;
  // The curve rises 0.01 per 40 s from the top level (40 s, 0.75); a descent of 40 s from
  // region 0 (T0 = 40 s) is forecast to gain about 0.0143: it ends above the curve.
  const std::vector<CurvePoint> curve{{40.0, 0.75}, {185.0, 0.75 + 0.01 * 145.0 / 40.0}};
  FrontAwarePolicy policy(fitted(), s.reference(0.01), {.confidence = 0.0});
  const Decision first = policy.decide(s.region(0));
  REQUIRE(first.scores.size() == 1);
  const CandidateScore& sc = first.scores[0];
  CHECK(
      sc.predicted_front_margin ==
      doctest::Approx(front_margin(curve, 40.0 + s.one[0].extra_time_s, 0.75 + sc.predicted_field_gain)).epsilon(1e-9));
  CHECK(sc.predicted_front_margin > 0.0);
  CHECK(first.descend);
  // A new mission forgets what the last one chose and saw.
  (void)policy.decide(s.region(1));
  policy.begin_mission();
  const Decision again = policy.decide(s.region(0));
  CHECK(again.scores[0].predicted_front_margin == doctest::Approx(sc.predicted_front_margin).epsilon(1e-12));
  // The rule needs the forecasts, a valid reference and a model that forecasts relabelling.
  DecisionContext blind = s.region(0);
  blind.lawnmowers = {};
  CHECK_THROWS_WITH_AS((void)policy.decide(blind), doctest::Contains("lawnmower forecasts"), std::invalid_argument);
  CHECK_THROWS_AS(FrontAwarePolicy(fitted(), {}, {}), std::invalid_argument);
  CHECK_THROWS_AS(FrontAwarePolicy(fitted(), {{"x", {{0.0, 0.5}}, 0.1}}, {}), std::invalid_argument);
  CHECK_THROWS_AS(FrontAwarePolicy(fitted(), s.reference(0.0), {.confidence = -1.0}), std::invalid_argument);
  CHECK_THROWS_WITH_AS(FrontAwarePolicy(GainModel(fitted().o_model(), fitted().i_model()), s.reference(0.0), {}),
                       doctest::Contains("needs C or a cell gain model"), std::invalid_argument);
}

TEST_CASE("front-aware policy: the field gain comes from C's relabelling, η and the field's estimated σ") {
  const Scenario s;
  FrontAwarePolicy policy(fitted(), s.reference(0.0), {.confidence = 0.0});
  const Decision d = policy.decide(s.region(0));
  REQUIRE(d.scores.size() == 1);
  CHECK(d.scores[0].predicted_relabelled == doctest::Approx(0.02).epsilon(0.02));
  CHECK(d.scores[0].predicted_field_gain == doctest::Approx(0.02 / 7.0 / 0.2).epsilon(0.02));
  CHECK(d.descend);  // a flat curve: any gain beats it
  // A field that shows less of L than the training fields so far: σ̂ is pulled towards what
  // it shows, so the same relabelled share is worth more of the field's mIoU.
  FrontAwarePolicy sparse(fitted(), s.reference(0.0), {});
  (void)sparse.decide(s.region(0, 0.02));
  const Decision d2 = sparse.decide(s.region(1, 0.2));
  CHECK(d2.scores[0].predicted_field_gain > d.scores[0].predicted_field_gain);
}

TEST_CASE("front-aware policy: beyond the finest lawnmower's time a descent must still beat the curve's last slope") {
  const Scenario s;
  // The mission already ends after the finest lawnmower (185 s): T0 = 205 s. The curve rises
  // 0.02 per 40 s up to 185 s; a descent of 40 s is forecast to gain 0.0143.
  DecisionContext late = s.region(0);
  late.elapsed_s = 200.0;
  late.rest_s = 5.0;
  FrontAwarePolicy steep(fitted(), s.reference(0.02), {.confidence = 0.0});
  const Decision d = steep.decide(late);
  CHECK_FALSE(d.descend);  // read flat beyond 185 s, any positive gain would have descended
  REQUIRE(d.scores.size() == 1);
  CHECK(d.scores[0].predicted_field_gain == doctest::Approx(0.0143).epsilon(0.03));
  FrontAwarePolicy gentle(fitted(), s.reference(0.01), {.confidence = 0.0});
  CHECK(gentle.decide(late).descend);  // 0.0143 beats 0.01 per 40 s
  // The extension itself: the last segment goes on; flat before the first point.
  const std::vector<CurvePoint> curve{{40.0, 0.75}, {185.0, 0.8}};
  CHECK(detail::interpolate_extend(curve, 330.0, &CurvePoint::time_s, &CurvePoint::miou) == doctest::Approx(0.85));
  CHECK(detail::interpolate_extend(curve, 100.0, &CurvePoint::time_s, &CurvePoint::miou) ==
        detail::interpolate_flat(curve, 100.0, &CurvePoint::time_s, &CurvePoint::miou));
  CHECK(detail::interpolate_extend(curve, 0.0, &CurvePoint::time_s, &CurvePoint::miou) == 0.75);
  const std::vector<CurvePoint> falling{{40.0, 0.8}, {185.0, 0.75}};  // never extended downwards
  CHECK(detail::interpolate_extend(falling, 330.0, &CurvePoint::time_s, &CurvePoint::miou) == 0.75);
}

TEST_CASE("front-aware policy: what a descent relabelled changes a later decision when online, not otherwise") {
  const Scenario s;
  const double gain = 0.02 / 7.0 / 0.2;
  SUBCASE("a descent that changes less than forecast stops the descents") {
    // The curve rises by 0.6 of the forecast gain over a descent's time: worth descending.
    const auto reference = s.reference(0.6 * gain);
    FrontAwarePolicy adaptive(fitted(), reference, {.online = true});
    FrontAwarePolicy fixed(fitted(), reference, {.online = false});
    for (FrontAwarePolicy* p : {&adaptive, &fixed}) {
      REQUIRE(p->decide(s.region(0)).descend);
      p->observe(Scenario::outcome(0.25));
    }
    CHECK(adaptive.field_scale() < 0.5);
    CHECK(fixed.field_scale() == 1.0);
    CHECK_FALSE(adaptive.decide(s.region(1)).descend);
    CHECK(fixed.decide(s.region(1)).descend);
  }
  SUBCASE("learning that may only stop descents still stops them") {
    FrontAwarePolicy stop_only(fitted(), s.reference(0.6 * gain), {.online = true, .learn_stop_only = true});
    REQUIRE(stop_only.decide(s.region(0)).descend);
    stop_only.observe(Scenario::outcome(0.25));
    CHECK(stop_only.field_scale() < 0.5);
    CHECK_FALSE(stop_only.decide(s.region(1)).descend);
  }
  SUBCASE("a descent that changes more than forecast makes a later, costlier one worth it") {
    const auto reference = s.reference(1.5 * gain);
    FrontAwarePolicy adaptive(fitted(), reference, {.online = true});
    FrontAwarePolicy fixed(fitted(), reference, {.online = false});
    // A dense first region, cheap to re-map: worth descending for both.
    for (FrontAwarePolicy* p : {&adaptive, &fixed}) {
      REQUIRE(p->decide(s.region(0, 0.6, true)).descend);
      p->observe(Scenario::outcome(4.0 * 1.2));  // four times the relabelling C forecast at σ 0.6
    }
    CHECK(adaptive.field_scale() > 3.0);
    const Decision learnt = adaptive.decide(s.region(1));
    CHECK(learnt.descend);
    CHECK_FALSE(fixed.decide(s.region(1)).descend);
    // Learning that may only stop descents learns as much, forecasts as much, and adds no descent
    // that the frozen rule does not take.
    FrontAwarePolicy stop_only(fitted(), reference, {.online = true, .learn_stop_only = true});
    REQUIRE(stop_only.decide(s.region(0, 0.6, true)).descend);
    stop_only.observe(Scenario::outcome(4.0 * 1.2));
    CHECK(stop_only.field_scale() == doctest::Approx(adaptive.field_scale()));
    const Decision capped = stop_only.decide(s.region(1));
    CHECK_FALSE(capped.descend);
    CHECK(capped.scores[0].predicted_field_gain == doctest::Approx(learnt.scores[0].predicted_field_gain));
    // The non-adaptive rule ignores the setting: nothing it learns to cap.
    FrontAwarePolicy fixed_stop_only(fitted(), reference, {.online = false, .learn_stop_only = true});
    REQUIRE(fixed_stop_only.decide(s.region(0, 0.6, true)).descend);
    fixed_stop_only.observe(Scenario::outcome(4.0 * 1.2));
    CHECK(fixed_stop_only.field_scale() == 1.0);
  }
  SUBCASE("outcomes reported after all the decisions (a tour) are weighed against their own forecast") {
    FrontAwarePolicy adaptive(fitted(), s.reference(0.0), {.online = true});
    const Decision dense = adaptive.decide(s.region(0, 0.6));
    const Decision sparse = adaptive.decide(s.region(1, 0.2));
    REQUIRE(dense.descend);
    REQUIRE(sparse.descend);
    REQUIRE(dense.scores[0].predicted_relabelled > 1.4 * sparse.scores[0].predicted_relabelled);
    // The second descent, flown first, relabels exactly what was forecast for it: s stays 1.
    DescentOutcome second = Scenario::outcome(1.0);
    second.descent = 1;
    second.relabelled.interest_share = sparse.scores[0].predicted_relabelled;
    adaptive.observe(second);
    CHECK(adaptive.field_scale() == doctest::Approx(1.0));
    CHECK(adaptive.field_scale_sd() < 0.5);
    // The first, the same share where far more was forecast: s falls.
    DescentOutcome first = second;
    first.descent = 0;
    adaptive.observe(first);
    CHECK(adaptive.field_scale() < 0.9);
  }
  SUBCASE("a new mission forgets what the last one learnt") {
    FrontAwarePolicy adaptive(fitted(), s.reference(0.6 * gain), {.online = true});
    (void)adaptive.decide(s.region(0));
    adaptive.observe(Scenario::outcome(0.25));
    adaptive.begin_mission();
    CHECK(adaptive.field_scale() == 1.0);
    CHECK(adaptive.field_scale_sd() == doctest::Approx(0.5));
    CHECK(adaptive.model().o_model().size() == fitted().o_model().size());
  }
}

namespace {
/// The synthetic gain model with a cell gain model of input expected_error: from 3 cm/px (and from
/// 2 cm/px) re-mapped at 1 cm/px a cell gains `beta` of its input; the scene check reads the
/// finer look's input with γ = beta.
GainModel with_cells(double beta) {
  GainModel m = fitted();
  m.set_cells(
      CellGainModel(DecisionInput::expected_error, {{2.0, 1.0, beta, 1e-4, 1.0, 1e-4, beta, 4e-3 * beta * beta},
                                                    {3.0, 1.0, beta, 1e-4, 1.0, 1e-4, beta, 4e-3 * beta * beta}}));
  return m;
}

/// `n` cells of 1000 field pixels with expected error `x` (of a 4000-pixel region).
std::vector<CellInputs> cells(int n, double x) {
  CellInputs c;
  c.values.fill(NAN);
  c.values[index_of(DecisionInput::expected_error)] = x;
  c.field_px = 1000.0;
  return std::vector<CellInputs>(static_cast<std::size_t>(n), c);
}

/// The Scenario's region k offering the 2 best cells (k = 1) or all 4 (k = 2) of its region at
/// 1 cm/px, each cell costing 20 s, and the mission's mean input so far `x`.
struct CellScenario {
  std::vector<Candidate> offers;
  std::vector<LawnmowerForecast> lawnmowers{{1.0, 185.0}, {3.0, 40.0}};
  explicit CellScenario(double x) {
    for (int n : {2, 4}) {
      Candidate c{1.0, 5.5, n, 10.0 + 20.0 * n};
      c.cells = cells(n, x);
      offers.push_back(c);
    }
  }
  DecisionContext region(int k, double x) const {
    DecisionContext c{
        .sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = offers};
    c.elapsed_s = 5.7 * (k + 1) + 40.0 * k;
    c.rest_s = 40.0 - 5.7 * (k + 1);
    c.region_share = 1.0 / 7.0;
    c.region_px = 4000.0;
    c.region_input = x;
    c.lawnmowers = lawnmowers;
    return c;
  }
};

DescentOutcome cell_outcome(double top_input, double fine_input) {
  DescentOutcome o{.top_altitude_m = 16.5, .sub_altitude_m = 5.5, .sigma_top = 0.2, .sigma_sub = 0.2};
  o.relabelled = {0.05, 0.05};
  o.top_input = top_input;
  o.fine_input = fine_input;
  return o;
}
}  // namespace

TEST_CASE("front-aware policy with cells: gain from the cells' input, the field's own curve, the scene check") {
  const CellScenario s(0.1);
  const std::vector<ReferenceCurve> reference{{"a", {{1.0, 0.95}, {3.0, 0.75}}, 0.2, 0.05}};
  // The decision at the first region of `s` of a policy with cells of slope β against `curves`.
  const auto decided = [&s](double beta, const std::vector<ReferenceCurve>& curves, FrontAwarePolicy::Params p) {
    return FrontAwarePolicy(with_cells(beta), curves, p).decide(s.region(0, 0.1));
  };
  SUBCASE("the forecast is β·Σ w·x over the cells, as a share of the field's L") {
    FrontAwarePolicy p(with_cells(1.0), reference, {});
    const Decision d = p.decide(s.region(0, 0.1));
    REQUIRE(d.scores.size() == 2);
    // 2 cells of a quarter of the region with x = 0.1: 0.05 of the region, a = 1/7, σ̂ = 0.2.
    CHECK(d.scores[0].predicted_field_gain == doctest::Approx(0.05 / 7.0 / 0.2));
    CHECK(d.scores[1].predicted_field_gain == doctest::Approx(0.10 / 7.0 / 0.2));
  }
  SUBCASE("gain ratios measured on the folds scale every forecast of a descent to their GSD") {
    // β = 4: the four cells forecast 0.29 against the training curve's 0.12 over their 90 s.
    FrontAwarePolicy plain(with_cells(4.0), reference, {});
    const Decision d = plain.decide(s.region(0, 0.1));
    REQUIRE(d.descend);
    REQUIRE(d.scores.size() == 2);
    // A ratio of another GSD than the candidates', or of 1, changes nothing.
    for (const GainRatio r : {GainRatio{2.0, 0.0}, GainRatio{1.0, 1.0}}) {
      FrontAwarePolicy p(with_cells(4.0), reference, {.gain_ratios = {r}});
      const Decision e = p.decide(s.region(0, 0.1));
      CHECK(e.descend);
      CHECK(e.candidate == d.candidate);
      for (std::size_t k = 0; k < 2; ++k)
        CHECK(e.scores[k].predicted_field_gain == doctest::Approx(d.scores[k].predicted_field_gain));
    }
    FrontAwarePolicy doubled(with_cells(4.0), reference, {.gain_ratios = {{1.0, 2.0}}});
    const Decision twice = doubled.decide(s.region(0, 0.1));
    for (std::size_t k = 0; k < 2; ++k)
      CHECK(twice.scores[k].predicted_field_gain == doctest::Approx(2.0 * d.scores[k].predicted_field_gain));
    // A quarter of the forecast no longer beats the curve: what β = 1 forecasts.
    FrontAwarePolicy quarter(with_cells(4.0), reference, {.gain_ratios = {{1.0, 0.25}}});
    FrontAwarePolicy beta_one(with_cells(1.0), reference, {});
    const Decision q = quarter.decide(s.region(0, 0.1));
    CHECK_FALSE(q.descend);
    CHECK(q.scores[1].predicted_field_gain ==
          doctest::Approx(beta_one.decide(s.region(0, 0.1)).scores[1].predicted_field_gain));
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.gain_ratios = {{1.0, -0.5}}}),
                         doctest::Contains("gain_ratios: a ratio must be finite and >= 0"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.gain_ratios = {{0.0, 1.0}}}),
                         doctest::Contains("gain_ratios: a GSD must be finite and > 0"), std::invalid_argument);
  }
  SUBCASE("margin biases measured on the folds add b·T to a descent's margin, its gain unchanged") {
    // β = 1: the four cells forecast 0.071 against the curve's 0.124 over their 90 s, the two
    // cells 0.036 against 0.069 over 50 s; neither descends.
    FrontAwarePolicy plain(with_cells(1.0), reference, {});
    const Decision d = plain.decide(s.region(0, 0.1));
    REQUIRE_FALSE(d.descend);
    // A bias of another GSD changes nothing.
    FrontAwarePolicy other(with_cells(1.0), reference, {.margin_biases = {{2.0, 0.001}}});
    CHECK_FALSE(other.decide(s.region(0, 0.1)).descend);
    // +0.001 per second: +0.09 for the four cells (lower bound 0.037), +0.05 for the two (0.017).
    FrontAwarePolicy raised(with_cells(1.0), reference, {.margin_biases = {{1.0, 0.001}}});
    const Decision r = raised.decide(s.region(0, 0.1));
    CHECK(r.descend);
    CHECK(r.candidate == 1);
    for (std::size_t k = 0; k < 2; ++k)
      CHECK(r.scores[k].predicted_field_gain == doctest::Approx(d.scores[k].predicted_field_gain));
    // β = 4 descends (0.29 against 0.124); −0.002 per second takes 0.18 and 0.10 off: no descent.
    FrontAwarePolicy four(with_cells(4.0), reference, {});
    REQUIRE(four.decide(s.region(0, 0.1)).descend);
    FrontAwarePolicy lowered(with_cells(4.0), reference, {.margin_biases = {{1.0, -0.002}}});
    CHECK_FALSE(lowered.decide(s.region(0, 0.1)).descend);
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.margin_biases = {{1.0, NAN}}}),
                         doctest::Contains("margin_biases: a bias must be finite"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.margin_biases = {{-1.0, 0.0}}}),
                         doctest::Contains("margin_biases: a GSD must be finite and > 0"), std::invalid_argument);
  }
  SUBCASE("the slope read at the field's entropy (field-entropy): a field the network is sure of loses") {
    // β = 4 at entropy 0.5, +10 per unit over the training fields' range 0.2 to 0.8: β = 1 on a
    // field of entropy 0.2 (no descent, as with_cells(1.0)), 7 at 0.8, 4 while it is unknown.
    const auto by_entropy = [] {
      GainModel m = with_cells(4.0);
      std::vector<CellGainModel::Point> points = m.cells()->points();
      for (CellGainModel::Point& q : points) q.entropy_slope = 10.0, q.entropy_reference = 0.5, q.entropy_high = 0.8;
      for (CellGainModel::Point& q : points) q.entropy_low = 0.2;
      m.set_cells(CellGainModel(DecisionInput::expected_error, points, SlopePooling::field_entropy));
      return m;
    };
    // Hardly any prior weight: the field's entropy is what its first image shows.
    const FrontAwarePolicy::Params params{.sigma_prior_weight = 1e-6};
    FrontAwarePolicy p(by_entropy(), reference, params);
    CHECK(p.reads_field_entropy());
    CHECK_FALSE(FrontAwarePolicy(with_cells(4.0), reference, params).reads_field_entropy());
    CHECK(DecisionFunction(FrontAwarePolicy(by_entropy(), reference, params)).reads_field_entropy());
    const Decision unknown = p.decide(s.region(0, 0.1));
    FrontAwarePolicy four(with_cells(4.0), reference, params);
    CHECK(unknown.descend);
    CHECK(unknown.scores[1].predicted_field_gain ==
          doctest::Approx(four.decide(s.region(0, 0.1)).scores[1].predicted_field_gain));
    DecisionContext sure = s.region(0, 0.1);
    sure.region_entropy = 0.2;
    p.begin_mission();
    const Decision d = p.decide(sure);
    CHECK_FALSE(d.descend);
    FrontAwarePolicy one(with_cells(1.0), reference, params);
    CHECK(d.scores[1].predicted_field_gain ==
          doctest::Approx(one.decide(s.region(0, 0.1)).scores[1].predicted_field_gain).epsilon(1e-4));
    DecisionContext unsure = s.region(0, 0.1);
    unsure.region_entropy = 0.95;  // beyond the training fields' range: read at its end, 0.8
    p.begin_mission();
    const Decision e = p.decide(unsure);
    CHECK(e.descend);
    CHECK(e.scores[1].predicted_field_gain == doctest::Approx(1.75 * unknown.scores[1].predicted_field_gain));
  }
  SUBCASE("the curve agreement: no descent to a GSD whose lawnmower lost on too many training fields") {
    // β = 4 descends to 1 cm/px against field a, whose lawnmower at 1 cm/px beat its 3 cm/px one.
    CHECK(finer_lawnmower_share(reference, 3.0, 1.0) == 1.0);
    FrontAwarePolicy sure(with_cells(4.0), reference, {.curve_agreement = 1.0});
    CHECK(sure.decide(s.region(0, 0.1)).descend);
    // Field b lost at 1 cm/px (its curve flat after the top level: the same forecast still beats
    // the mean rise); half the fields gained.
    std::vector<ReferenceCurve> two = reference;
    two.push_back({"b", {{1.0, 0.70}, {3.0, 0.75}}, 0.2, 0.05});
    CHECK(finer_lawnmower_share(two, 3.0, 1.0) == 0.5);
    CHECK(finer_lawnmower_share({}, 3.0, 1.0) == 0.0);
    for (const double q : {0.0, 0.5}) {
      FrontAwarePolicy p(with_cells(4.0), two, {.curve_agreement = q});
      CHECK(p.decide(s.region(0, 0.1)).descend);
    }
    FrontAwarePolicy strict(with_cells(4.0), two, {.curve_agreement = 0.75});
    const Decision d = strict.decide(s.region(0, 0.1));
    CHECK_FALSE(d.descend);
    CHECK(d.scores.size() == 2);  // still assessed, and reported
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.curve_agreement = 1.5}),
                         doctest::Contains("curve_agreement must be in [0, 1]"), std::invalid_argument);
  }
  SUBCASE("the finest descent GSD: no descent to a finer candidate, which is still assessed") {
    // β = 4 descends to 1 cm/px (both offers are 1 cm/px); a limit at 1 cm/px (up to rounding)
    // or none keeps it, one at 2 cm/px takes none and still reports both.
    for (const double g : {0.0, 1.0, 1.0 + 1e-12}) {
      FrontAwarePolicy p(with_cells(4.0), reference, {.finest_descent_gsd_cm = g});
      CHECK(p.decide(s.region(0, 0.1)).descend);
    }
    FrontAwarePolicy coarse(with_cells(4.0), reference, {.finest_descent_gsd_cm = 2.0});
    const Decision d = coarse.decide(s.region(0, 0.1));
    CHECK_FALSE(d.descend);
    CHECK(d.scores.size() == 2);
    CHECK(d.scores[1].predicted_field_gain > 0.0);
    CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.finest_descent_gsd_cm = -1.0}),
                         doctest::Contains("finest_descent_gsd_cm must be finite and >= 0"), std::invalid_argument);
  }
  SUBCASE("the longest descent: no descent that costs more extra seconds, which is still assessed") {
    // The offers cost 50 s and 90 s. A limit at the chosen one's seconds (up to rounding) or
    // none keeps it; one below both takes none and still reports both.
    const Decision unlimited = decided(4.0, reference, {});
    REQUIRE(unlimited.descend);
    const double t = s.offers[unlimited.candidate].extra_time_s;
    for (const double cap : {0.0, t, t * (1.0 - 1e-12)}) {
      const Decision d = decided(4.0, reference, {.longest_descent_s = cap});
      CHECK(d.descend);
      CHECK(d.candidate == unlimited.candidate);
    }
    const Decision shorter = decided(4.0, reference, {.longest_descent_s = 50.0});
    CHECK((!shorter.descend || s.offers[shorter.candidate].extra_time_s == 50.0));
    const Decision none = decided(4.0, reference, {.longest_descent_s = 40.0});
    CHECK_FALSE(none.descend);
    REQUIRE(none.scores.size() == 2);
    CHECK(none.scores[unlimited.candidate].predicted_field_gain > 0.0);
    for (const double wrong : {-1.0, std::numeric_limits<double>::quiet_NaN()})
      CHECK_THROWS_WITH_AS(FrontAwarePolicy(with_cells(1.0), reference, {.longest_descent_s = wrong}),
                           doctest::Contains("longest_descent_s must be finite and >= 0"), std::invalid_argument);
  }
  SUBCASE("against the field's own predicted curve, the forecasts' scale cancels") {
    // The training curve rises by 0.2 mIoU over 145 s: against it, a descent of twice the cells'
    // gain looks better than one of half of it. Against the curve the same model predicts for
    // this field (what flying everything at 1 cm/px would gain from the field's input), only the
    // gain per second of the descent against that of the lawnmower counts: the same decision
    // whatever the scale.
    std::vector<Decision> training, field;
    for (double beta : {0.5, 2.0}) {
      FrontAwarePolicy t(with_cells(beta), reference, {});
      FrontAwarePolicy f(with_cells(beta), reference, {.curve = CurveSource::field});
      training.push_back(t.decide(s.region(0, 0.1)));
      field.push_back(f.decide(s.region(0, 0.1)));
    }
    CHECK(training[0].descend != training[1].descend);
    CHECK(field[0].descend == field[1].descend);
    CHECK(field[0].candidate == field[1].candidate);
    // The predicted curve rises with the field's input: after five regions that hold little of
    // it, the same cells are worth a descent; after five that hold as much, flying lower is.
    for (const double elsewhere : {0.001, 0.1}) {
      FrontAwarePolicy p(with_cells(1.0), reference, {.curve = CurveSource::field});
      for (int k = 0; k < 5; ++k) {
        DecisionContext seen = s.region(0, elsewhere);
        seen.candidates = {};
        REQUIRE_FALSE(p.decide(seen).descend);
      }
      DecisionContext here = s.region(0, 0.1);
      here.elapsed_s = 5.7 * 6;
      here.rest_s = 40.0 - here.elapsed_s;
      CHECK(p.decide(here).descend == (elsewhere < 0.01));
    }
  }
  SUBCASE("the field curve corrected by the training fields' real rise") {
    // A training field that looks like this one (σ 0.2, input 0.1): its real curve rises 0.2 to
    // 1 cm/px, the cell model predicts β·0.1/0.2. Corrected, the predicted curve is that field's
    // real one whatever β: the descent is weighed as against the training curve, while the
    // uncorrected field curve weighs it as if flying lower gained β/2.
    const std::vector<ReferenceCurve> alike{{"a", {{1.0, 0.95}, {3.0, 0.75}}, 0.2, 0.1}};
    for (double beta : {0.5, 1.0}) {
      const Decision t = decided(beta, alike, {});
      const Decision c = decided(beta, alike, {.curve = CurveSource::corrected});
      const Decision f = decided(beta, alike, {.curve = CurveSource::field});
      REQUIRE(t.scores.size() == 2);
      for (std::size_t k = 0; k < 2; ++k) {
        CHECK(c.scores[k].predicted_front_margin == doctest::Approx(t.scores[k].predicted_front_margin));
        CHECK(f.scores[k].predicted_front_margin != doctest::Approx(t.scores[k].predicted_front_margin));
      }
      CHECK(c.descend == t.descend);
      // The training field's input at this top level is what counts: a file that gives it per
      // top level (here 0.1 at 3 cm/px, another nominal top's 0.3) reads the same.
      ReferenceCurve by_top = alike.front();
      by_top.field_input = 0.3;
      by_top.top_inputs = {{1.5, 0.3}, {3.0, 0.1}};
      FrontAwarePolicy per_top(with_cells(beta), {by_top}, {.curve = CurveSource::corrected});
      const Decision pt = per_top.decide(s.region(0, 0.1));
      for (std::size_t k = 0; k < 2; ++k)
        CHECK(pt.scores[k].predicted_front_margin == doctest::Approx(t.scores[k].predicted_front_margin));
    }
    // Two training fields whose real rise differs (a quarter and three quarters of the
    // prediction) weigh a descent as one field of their mean ratio does, but their spread makes
    // the lower bound more cautious. Cells of input 0.4 in a field of 0.1.
    const CellScenario rich(0.4);
    const std::vector<ReferenceCurve> two{{"a", {{1.0, 0.875}, {3.0, 0.75}}, 0.2, 0.1},
                                          {"b", {{1.0, 1.125}, {3.0, 0.75}}, 0.2, 0.1}};
    const std::vector<ReferenceCurve> mean{{"m", {{1.0, 1.0}, {3.0, 0.75}}, 0.2, 0.1}};
    const FrontAwarePolicy::Params p{.confidence = 1.5, .scale_prior_sd = 0.01, .curve = CurveSource::corrected};
    FrontAwarePolicy spread(with_cells(1.0), two, p);
    FrontAwarePolicy single(with_cells(1.0), mean, p);
    FrontAwarePolicy uncorrected(with_cells(1.0), mean,
                                 {.confidence = 1.5, .scale_prior_sd = 0.01, .curve = CurveSource::field});
    const Decision a = spread.decide(rich.region(0, 0.1));
    const Decision b = single.decide(rich.region(0, 0.1));
    CHECK(a.scores[1].predicted_front_margin == doctest::Approx(b.scores[1].predicted_front_margin));
    CHECK(b.descend);
    CHECK_FALSE(a.descend);
    CHECK_FALSE(uncorrected.decide(rich.region(0, 0.1)).descend);  // the prediction: flying lower pays
  }
  SUBCASE("the mixture: the corrected curves and the training fields' own, as one set") {
    // Field a's real curve rises 0.2 to 1 cm/px; its input 0.05 against this field's 0.1 (X̂
    // shrunk towards 0.05 after one region) makes the corrected curve rise about half as much
    // again. The mixture weighs a descent against the mean of the two rises (its margin the mean
    // of theirs), with their disagreement as spread: at z = 0 it decides as that mean does, at
    // z > 0 it is more cautious than the training curve alone where the gain lies between them.
    for (double beta : {0.5, 1.0, 2.0}) {
      const Decision dt = decided(beta, reference, {});
      const Decision dc = decided(beta, reference, {.curve = CurveSource::corrected});
      const Decision dm = decided(beta, reference, {.curve = CurveSource::mixture});
      REQUIRE(dm.scores.size() == 2);
      for (std::size_t k = 0; k < 2; ++k) {
        const double rt = dt.scores[k].predicted_curve_rise, rc = dc.scores[k].predicted_curve_rise;
        CHECK(rc > 1.2 * rt);
        CHECK(dm.scores[k].predicted_curve_rise == doctest::Approx((rt + rc) / 2.0));
        CHECK(dm.scores[k].predicted_front_margin ==
              doctest::Approx((dt.scores[k].predicted_front_margin + dc.scores[k].predicted_front_margin) / 2.0));
        CHECK(dm.scores[k].predicted_field_gain == doctest::Approx(dt.scores[k].predicted_field_gain));
      }
    }
    // With β = 2.25 the 4-cell offer's gain beats the training rise but not the corrected one,
    // and their mean: at z = 0 the mixture takes it as the training curve does; at z = 1 their
    // disagreement (sd_D = |r_c − r_t| / √2) refuses it, where the training curve alone still
    // takes it.
    const auto at = [&](double z, CurveSource curve) {
      return decided(2.25, reference, {.confidence = z, .scale_prior_sd = 0.01, .curve = curve});
    };
    const Decision a = at(0.0, CurveSource::training), b = at(0.0, CurveSource::corrected);
    const Decision mm = at(0.0, CurveSource::mixture);
    const double gain = mm.scores[1].predicted_field_gain;
    CHECK(gain > a.scores[1].predicted_curve_rise);
    CHECK(gain < b.scores[1].predicted_curve_rise);
    CHECK(a.descend);
    CHECK_FALSE(b.descend);
    CHECK(gain > mm.scores[1].predicted_curve_rise);
    CHECK(mm.descend);
    CHECK(mm.candidate == 1);
    CHECK(at(1.0, CurveSource::training).descend);
    CHECK_FALSE(at(1.0, CurveSource::mixture).descend);
  }
  // A flatter training curve (0.05 over 145 s): the cells' descents are worth their time.
  const std::vector<ReferenceCurve> flat{{"a", {{1.0, 0.80}, {3.0, 0.75}}, 0.2, 0.05}};
  SUBCASE("the scene check: a finer look less sure than the coarse one stops the descents") {
    FrontAwarePolicy adaptive(with_cells(1.0), flat, {.online = true});
    FrontAwarePolicy fixed(with_cells(1.0), flat, {.online = false});
    for (FrontAwarePolicy* p : {&adaptive, &fixed}) {
      const Decision d = p->decide(s.region(0, 0.1));
      REQUIRE(d.descend);
      // The chosen cells held 0.05 (or 0.1) of the region's input at the top; the finer
      // images are less sure: 0.08 (0.16).
      const double top = d.candidate == 0 ? 0.05 : 0.1;
      p->observe(cell_outcome(top, 1.6 * top));
    }
    CHECK(adaptive.field_scale() < 0.0);
    CHECK(fixed.field_scale() == 1.0);
    CHECK_FALSE(adaptive.decide(s.region(1, 0.1)).descend);
    CHECK(fixed.decide(s.region(1, 0.1)).descend);
  }
  SUBCASE("the scene check: trusted no further than the training fields agree on its slope") {
    // The same finer look, less sure than the coarse one, read through a proxy whose slope the
    // training fields disagree on (τ_γ twice γ): one such look is weak evidence, s stays
    // positive and the next region is still worth a descent.
    GainModel doubted = fitted();
    doubted.set_cells(CellGainModel(DecisionInput::expected_error, {{2.0, 1.0, 1.0, 1e-4, 1.0, 1e-4, 1.0, 4e-3, 2.0},
                                                                    {3.0, 1.0, 1.0, 1e-4, 1.0, 1e-4, 1.0, 4e-3, 2.0}}));
    FrontAwarePolicy trusting(with_cells(1.0), flat, {.online = true});
    FrontAwarePolicy doubting(doubted, flat, {.online = true});
    for (FrontAwarePolicy* p : {&trusting, &doubting}) {
      const Decision d = p->decide(s.region(0, 0.1));
      REQUIRE(d.descend);
      const double top = d.candidate == 0 ? 0.05 : 0.1;
      p->observe(cell_outcome(top, 1.6 * top));
    }
    CHECK(trusting.field_scale() < 0.0);
    CHECK(doubting.field_scale() > 0.5);
    CHECK(doubting.field_scale() < 1.0);
    CHECK(doubting.decide(s.region(1, 0.1)).descend);
  }
  SUBCASE("the scene check: where descending loses, a descent the training fields saw lose is no gain") {
    // From 3 cm/px the training fields gained at 1 cm/px (β = 1) and lost at 2 cm/px (β < 0).
    // Once the scene check finds the finer look worse on this field (s < 0), no descent may be
    // forecast to gain: a loss on the training fields times a field that loses is not a gain,
    // and the predicted curve of this field does not rise to 2 cm/px by it either.
    GainModel m = fitted();
    m.set_cells(CellGainModel(DecisionInput::expected_error, {{3.0, 1.0, 1.0, 1e-4, 1.0, 1e-4, 1.0, 4e-3},
                                                              {3.0, 2.0, -0.5, 1e-4, 1.0, 1e-4, 0.0, 0.0}}));
    CellScenario two_gsds(0.1);
    Candidate coarser{2.0, 11.0, 1, 15.0};
    coarser.cells = cells(2, 0.1);
    two_gsds.offers.push_back(coarser);
    two_gsds.lawnmowers = {{1.0, 185.0}, {2.0, 90.0}, {3.0, 40.0}};
    for (const CurveSource curve : {CurveSource::training, CurveSource::field}) {
      FrontAwarePolicy adaptive(m, flat, {.online = true, .curve = curve});
      const Decision d = adaptive.decide(two_gsds.region(0, 0.1));
      REQUIRE(d.descend);
      REQUIRE(d.gsd_cm == 1.0);
      const double top = d.candidate == 0 ? 0.05 : 0.1;
      adaptive.observe(cell_outcome(top, 1.6 * top));
      REQUIRE(adaptive.field_scale() < 0.0);
      const Decision next = adaptive.decide(two_gsds.region(1, 0.1));
      for (const CandidateScore& c : next.scores) CHECK(c.predicted_field_gain <= 0.0);
      CHECK_FALSE(next.descend);
    }
  }
  SUBCASE("the scene check: a finer look that clears what the top doubted keeps descending") {
    FrontAwarePolicy adaptive(with_cells(1.0), flat, {.online = true});
    const Decision d = adaptive.decide(s.region(0, 0.1));
    REQUIRE(d.descend);
    const double top = d.candidate == 0 ? 0.05 : 0.1;
    adaptive.observe(cell_outcome(top, 0.0));  // the finer images are sure everywhere
    CHECK(adaptive.field_scale() == doctest::Approx(1.0).epsilon(0.05));
    CHECK(adaptive.field_scale_sd() < 0.5);
    CHECK(adaptive.decide(s.region(1, 0.1)).descend);
    // Without the finer images' input (a labels-only backend) nothing is learnt.
    FrontAwarePolicy blind(with_cells(1.0), flat, {.online = true});
    REQUIRE(blind.decide(s.region(0, 0.1)).descend);
    blind.observe(cell_outcome(top, NAN));
    CHECK(blind.field_scale() == 1.0);
  }
  SUBCASE("the relabelled share as the field factor: it scales the descent's gain, not the field's curve") {
    // Against the field's own curve, after five regions that hold little input, the cells of the
    // sixth are worth a descent (as above). They were forecast to relabel μ = α·Σ w·x of the
    // region (α = 1: 0.05 or 0.1); they relabel twice that, and the finer images are as unsure as
    // the top (a scene check that finds nothing).
    const FrontAwarePolicy::Params relabelled{
        .online = true, .curve = CurveSource::field, .field_factor = FieldFactorSource::relabelled};
    FrontAwarePolicy adaptive(with_cells(1.0), reference, relabelled);
    FrontAwarePolicy frozen(
        with_cells(1.0), reference,
        {.online = false, .curve = CurveSource::field, .field_factor = FieldFactorSource::relabelled});
    FrontAwarePolicy scene(with_cells(1.0), reference, {.online = true, .curve = CurveSource::field});
    const auto at = [&](int k) {
      DecisionContext here = s.region(k, 0.1);
      here.elapsed_s = 5.7 * (k + 1);
      here.rest_s = 40.0 - here.elapsed_s;
      return here;
    };
    for (FrontAwarePolicy* p : {&adaptive, &frozen, &scene}) {
      for (int k = 0; k < 5; ++k) {
        DecisionContext seen = s.region(0, 0.001);
        seen.candidates = {};
        REQUIRE_FALSE(p->decide(seen).descend);
      }
      const Decision d = p->decide(at(5));
      REQUIRE(d.descend);
      const double top = d.candidate == 0 ? 0.05 : 0.1;
      DescentOutcome o = cell_outcome(top, top);
      o.relabelled = {2.0 * top, 2.0 * top};
      p->observe(o);
    }
    CHECK(adaptive.field_scale() == doctest::Approx(2.0).epsilon(0.01));
    CHECK(frozen.field_scale() == 1.0);
    CHECK(scene.field_scale() < 0.1);  // the scene check saw no change: no gain
    const Decision twice = adaptive.decide(at(6));
    const Decision once = frozen.decide(at(6));
    const Decision none = scene.decide(at(6));
    CHECK(twice.descend);
    for (std::size_t k = 0; k < 2; ++k) {
      CHECK(twice.scores[k].predicted_field_gain ==
            doctest::Approx(adaptive.field_scale() * once.scores[k].predicted_field_gain));
      // The field's curve as the model predicts it, whatever s: the same rise as the frozen twin's.
      CHECK(twice.scores[k].predicted_curve_rise == doctest::Approx(once.scores[k].predicted_curve_rise));
      CHECK(once.scores[k].predicted_curve_rise > 0.0);
      // With the scene check s scales the curve's rise too.
      CHECK(none.scores[k].predicted_curve_rise < 0.1 * once.scores[k].predicted_curve_rise);
    }
    CHECK(parse_field_factor_source(to_string(FieldFactorSource::relabelled)) == FieldFactorSource::relabelled);
    CHECK_THROWS_AS((void)parse_field_factor_source("relabeled"), std::invalid_argument);
  }
  SUBCASE("the relabelled share carried to the gain by b: 1 + b·(s − 1), s itself at b = 1, nothing at b = 0") {
    // As above: a descent relabels twice its forecast share, s → 2; the gain follows by b.
    const auto run = [&](double b, double region_sd = 0.0, double field_sd = 0.0) {
      FrontAwarePolicy p(with_cells(1.0), reference,
                         {.online = true,
                          .curve = CurveSource::field,
                          .field_factor = FieldFactorSource::relabelled,
                          .relabel_transfer = b,
                          .relabel_region_sd = region_sd,
                          .relabel_field_sd = field_sd});
      for (int k = 0; k < 5; ++k) {
        DecisionContext seen = s.region(0, 0.001);
        seen.candidates = {};
        REQUIRE_FALSE(p.decide(seen).descend);
      }
      DecisionContext first = s.region(5, 0.1);
      first.elapsed_s = 5.7 * 6;
      first.rest_s = 40.0 - first.elapsed_s;
      const Decision d = p.decide(first);
      REQUIRE(d.descend);
      const double top = d.candidate == 0 ? 0.05 : 0.1;
      DescentOutcome o = cell_outcome(top, top);
      o.relabelled = {2.0 * top, 2.0 * top};
      p.observe(o);
      DecisionContext next = s.region(6, 0.1);
      next.elapsed_s = 5.7 * 7;
      next.rest_s = 40.0 - next.elapsed_s;
      return std::pair{p.field_scale(), p.decide(next)};
    };
    const auto [s1, whole] = run(1.0);
    const auto [s0, none] = run(0.0);
    const auto [sh, half] = run(0.5);
    // s learns from the relabelled share alike whatever b: b says only how far the gain follows.
    CHECK(s1 == doctest::Approx(2.0).epsilon(0.01));
    CHECK(s0 == s1);
    CHECK(sh == s1);
    for (std::size_t k = 0; k < 2; ++k) {
      const double base = none.scores[k].predicted_field_gain;  // b = 0: the gain as forecast
      REQUIRE(base > 0.0);
      CHECK(whole.scores[k].predicted_field_gain == doctest::Approx(s1 * base));
      CHECK(half.scores[k].predicted_field_gain == doctest::Approx((1.0 + 0.5 * (s1 - 1.0)) * base));
      // The relabelled share is forecast with s itself, whatever b.
      CHECK(none.scores[k].predicted_relabelled == doctest::Approx(whole.scores[k].predicted_relabelled));
    }
    // The factor on the gain: b·(what s learnt) and, for the rest of its spread between fields,
    // the prior ω² (b = 0: nothing learnt, the prior whole, not a certainty).
    FieldScale learnt(0.5);
    learnt.observe(1.0, 2.0, 0.01, true);
    const FactorEstimate own = learnt.transferred(1.0), half_way = learnt.transferred(0.5),
                         prior = learnt.transferred(0.0);
    CHECK(own.mean == learnt.mean());
    CHECK(own.var == learnt.var());
    CHECK(half_way.mean == doctest::Approx(1.0 + 0.5 * (learnt.mean() - 1.0)));
    CHECK(half_way.var == doctest::Approx(0.25 * learnt.var() + 0.75 * 0.25));
    CHECK(prior.mean == 1.0);
    CHECK(prior.var == doctest::Approx(0.25));
    FrontAwarePolicy::Params bad{.field_factor = FieldFactorSource::relabelled, .relabel_transfer = 1.5};
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("relabel_transfer must be in [0, 1]"),
                         std::invalid_argument);
    // A region's own spread τ_r = 1 beside the cells' (nearly none): one descent that relabels
    // twice its forecast says s ≈ (1/ω² + 2) / (1/ω² + 1) = 6 / 5 with ω = 0.5, not 2.
    const auto [s_region, region_decision] = run(1.0, 1.0);
    CHECK(s_region == doctest::Approx(1.2).epsilon(0.01));
    CHECK(region_decision.scores[0].predicted_field_gain ==
          doctest::Approx(s_region * none.scores[0].predicted_field_gain));
    bad = {.field_factor = FieldFactorSource::relabelled, .relabel_region_sd = -0.1};
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("relabel_region_sd must be finite and >= 0"),
                         std::invalid_argument);
    // s's own prior spread ω_χ = 0.25 (the fields' relabelled shares strayed less than their gains,
    // ω = 0.5): the same descent says s ≈ (1/ω_χ² + 2) / (1/ω_χ² + 1) = 18 / 17; the gain's factor
    // is s with the rest of ω's spread beside it (FieldScale::transferred).
    const auto [s_field, field_decision] = run(1.0, 1.0, 0.25);
    CHECK(s_field == doctest::Approx(18.0 / 17.0).epsilon(0.01));
    CHECK(field_decision.scores[0].predicted_field_gain ==
          doctest::Approx(s_field * none.scores[0].predicted_field_gain));
    FieldScale narrow(0.25);
    CHECK(narrow.transferred(0.5, 0.5).var == doctest::Approx(0.25));  // before any descent: ω², whatever ω_χ
    narrow.observe(1.0, 2.0, 0.01, true);
    const FactorEstimate gain = narrow.transferred(1.0, 0.5);
    CHECK(gain.mean == narrow.mean());
    CHECK(gain.var == doctest::Approx(narrow.var() + 0.25 - 0.0625));
    // s cannot explain more of the gain's spread than there is: b capped at ω / ω_χ = 0.4.
    const FactorEstimate capped = narrow.transferred(1.0, 0.1);
    CHECK(capped.mean == doctest::Approx(1.0 + 0.4 * (narrow.mean() - 1.0)));
    CHECK(capped.var == doctest::Approx(0.16 * narrow.var()));
    bad = {.field_factor = FieldFactorSource::relabelled, .relabel_field_sd = -0.1};
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("relabel_field_sd must be finite and >= 0"),
                         std::invalid_argument);
  }
  SUBCASE("the top level: the coarsest calibrated GSD whose lawnmower nothing faster beats") {
    FrontAwarePolicy p(with_cells(1.0), {{"a", {{1.0, 0.95}, {2.0, 0.85}, {3.0, 0.75}}, 0.2, 0.05}}, {});
    // 2 cm/px is faster than 3 over this area (its grid fits it better) and maps better.
    const std::vector<LawnmowerForecast> fits{{1.0, 185.0}, {2.0, 35.0}, {3.0, 40.0}};
    CHECK(p.top_gsd(fits, 3.0) == 2.0);
    const std::vector<LawnmowerForecast> usual{{1.0, 185.0}, {2.0, 60.0}, {3.0, 40.0}};
    CHECK(p.top_gsd(usual, 3.0) == 3.0);
    // A model calibrated for its nominal top level alone keeps it.
    FrontAwarePolicy nominal(fitted(), {{"a", {{1.0, 0.95}, {2.0, 0.85}, {3.0, 0.75}}, 0.2}}, {});
    CHECK(nominal.top_gsd(fits, 3.0) == 3.0);
    // Curves that cross: on field a 2 cm/px maps worse than 3, on b better. Their mean says 3 by
    // 0.01, but where 2 cm/px is also faster, flying 3 falls short on b (by 0.03, 0.015 on
    // average) and 2 on neither: the finer, faster top level.
    const std::vector<ReferenceCurve> crossing{{"a", {{1.0, 0.95}, {2.0, 0.70}, {3.0, 0.75}}, 0.2, 0.05},
                                               {"b", {{1.0, 0.95}, {2.0, 0.78}, {3.0, 0.75}}, 0.2, 0.05}};
    const FrontAwarePolicy crossed(with_cells(1.0), crossing, {});
    CHECK(crossed.top_gsd(fits, 3.0) == 2.0);
    // Where 3 cm/px is the faster one, nothing faster beats it on either field: the nominal.
    CHECK(crossed.top_gsd(usual, 3.0) == 3.0);
    // Curves on which 3 cm/px maps at least as well as 2 on every field: neither falls short on
    // them, but where 2 cm/px is faster, 3 could on this field and 2 could not: the faster.
    const std::vector<ReferenceCurve> coarse_as_good{{"a", {{1.0, 0.95}, {2.0, 0.70}, {3.0, 0.75}}, 0.2, 0.05},
                                                     {"b", {{1.0, 0.95}, {2.0, 0.75}, {3.0, 0.75}}, 0.2, 0.05}};
    const FrontAwarePolicy tied(with_cells(1.0), coarse_as_good, {});
    CHECK(tied.top_gsd(fits, 3.0) == 2.0);
    CHECK(tied.top_gsd(usual, 3.0) == 3.0);
  }
  SUBCASE("the top level at the predicted curve's first corner: hull") {
    // 3 -> 2 cm/px rises 0.10 in 20 s, 2 -> 1 as much in 125 s: the curve bends at 2.
    const std::vector<LawnmowerForecast> usual{{1.0, 185.0}, {2.0, 60.0}, {3.0, 40.0}};
    const ReferenceCurve bends{"a", {{1.0, 0.95}, {2.0, 0.85}, {3.0, 0.75}}, 0.2, 0.05};
    CHECK(FrontAwarePolicy(with_cells(1.0), {bends}, {}).top_gsd(usual, 3.0) == 3.0);
    const FrontAwarePolicy hull(with_cells(1.0), {bends}, {.top_level = TopLevelChoice::hull});
    CHECK(hull.top_gsd(usual, 3.0) == 2.0);
    // Where 2 cm/px gains little and 1 cm/px much, the curve is steeper beyond: the nominal top.
    const ReferenceCurve late{"a", {{1.0, 0.99}, {2.0, 0.76}, {3.0, 0.75}}, 0.2, 0.05};
    CHECK(FrontAwarePolicy(with_cells(1.0), {late}, {.top_level = TopLevelChoice::hull}).top_gsd(usual, 3.0) == 3.0);
    // The rates are the field's: the same curves over an area where 2 cm/px takes 100 s more stay at 3.
    const std::vector<LawnmowerForecast> slow{{1.0, 185.0}, {2.0, 140.0}, {3.0, 40.0}};
    CHECK(hull.top_gsd(slow, 3.0) == 3.0);
    CHECK(parse_top_level_choice(to_string(TopLevelChoice::hull)) == TopLevelChoice::hull);
    CHECK_THROWS_AS((void)parse_top_level_choice("convex"), std::invalid_argument);
  }
}

TEST_CASE("front-aware policy: pessimistic when unsure, from the field factor and the spread of the training curves") {
  const Scenario s;
  const double gain = 0.02 / 7.0 / 0.2;
  // Two training curves rising by 0.2 and 0.6 of the gain over a descent: mean 0.4.
  const auto reference = s.reference(0.2 * gain, 0.6 * gain);
  FrontAwarePolicy bold(fitted(), reference, {.confidence = 0.0});
  FrontAwarePolicy careful(fitted(), reference, {.confidence = 3.0});
  CHECK(bold.decide(s.region(0)).descend);
  CHECK_FALSE(careful.decide(s.region(0)).descend);
  // After a descent whose relabelling matched the forecast, the field factor is surer: the
  // lower bound rises.
  FrontAwarePolicy moderate(fitted(), s.reference(0.3 * gain), {.confidence = 1.2});
  FrontAwarePolicy moderate_fixed(fitted(), s.reference(0.3 * gain), {.online = false, .confidence = 1.2});
  for (FrontAwarePolicy* p : {&moderate, &moderate_fixed}) {
    (void)p->decide(s.region(0, 0.6));
    p->observe(Scenario::outcome(3.0));
  }
  CHECK(moderate.field_scale_sd() < 0.5 * moderate_fixed.field_scale_sd());
  CHECK(moderate.decide(s.region(1)).descend);
  CHECK_FALSE(moderate_fixed.decide(s.region(1)).descend);
}

TEST_CASE("front-aware policy: unsure of the field's σ while little of it is seen, sure once all of it is") {
  const Scenario s;
  const double gain = 0.02 / 7.0 / 0.2;
  // The curve rises by half the forecast gain over a descent; z = 1; the field factor is
  // nearly certain (ω = 0.05), so only σ̂'s spread can hold a descent back.
  const auto reference = s.reference(0.5 * gain);
  const FrontAwarePolicy::Params sure{.confidence = 1.0, .scale_prior_sd = 0.05, .sigma_prior_weight = 0.25};
  FrontAwarePolicy::Params unsure = sure;
  unsure.sigma_prior_sd = 0.15;  // fields' σ spread 0.15 about the training fields' 0.2
  FrontAwarePolicy a(fitted(), reference, sure), b(fitted(), reference, unsure);
  // First region: 1/7 of the field seen. Var σ̂ = (6/7)²·τ²·k/(k + 1/7) + (6/7)·k·τ² = 0.0153,
  // σ̂ = 0.2: ĝ's relative spread 0.62 > the 0.5 margin.
  const Decision da = a.decide(s.region(0)), db = b.decide(s.region(0));
  CHECK(da.descend);
  CHECK_FALSE(db.descend);
  CHECK(db.scores[0].predicted_field_gain == da.scores[0].predicted_field_gain);  // the mean is the same
  // The other six regions (no descent): at the last one the field is seen, Var σ̂ = 0.
  for (int k = 1; k < 6; ++k) (void)a.decide(s.region(k)), (void)b.decide(s.region(k));
  const Decision la = a.decide(s.region(0)), lb = b.decide(s.region(0));
  CHECK(la.descend);
  CHECK(lb.descend);
  CHECK(lb.scores[0].predicted_field_gain == doctest::Approx(la.scores[0].predicted_field_gain));
}

// ---------------------------------------------------------------------------------------------
// DecisionFunction, LinearDecision, conformance
// ---------------------------------------------------------------------------------------------
TEST_CASE("decision function: forwards to its rule, online on and off") {
  const Scenario s;
  DecisionFunction df(FrontAwarePolicy(fitted(), s.reference(0.0), {}));
  CHECK(df.front_aware());
  CHECK(df.name() == "adaptive");
  df.set_online(false);
  CHECK_FALSE(df.online());
  CHECK(df.name() == "nonadaptive");
  CHECK(df.model().o_model().size() == 20);
  df.begin_mission();
  CHECK(df.decide(s.region(0)).descend);
  DecisionFunction paper(UtilityPolicy(fitted(), {.min_utility = 1e9}));
  CHECK_FALSE(paper.front_aware());
  const auto c = candidates();
  CHECK_FALSE(paper.decide(context(c)).descend);
}

TEST_CASE("linear decision: altitude falls linearly with σ to the nearest candidate") {
  const LinearDecision lin({.sigma_low = 0.1, .sigma_high = 0.3});
  const auto c = candidates();
  DecisionContext ctx = context(c, 0.05);
  CHECK_FALSE(lin.decide(ctx).descend);  // below sigma_low: stay at h_max
  ctx.sigma = 0.3;
  CHECK(lin.decide(ctx).gsd_cm == 1.0);  // at sigma_high: the lowest altitude
  ctx.sigma = 0.2;                       // halfway: 16.5 - 11/2 = 11.0 m -> 2.0 cm/px
  CHECK(lin.decide(ctx).gsd_cm == 2.0);
  ctx.sigma = 0.11;  // 16.5 - 0.55 m: nearer h_max than any candidate
  CHECK_FALSE(lin.decide(ctx).descend);
  CHECK_THROWS_AS(LinearDecision({.sigma_low = 0.3, .sigma_high = 0.3}), std::invalid_argument);
}

TEST_CASE("decision policies: every policy passes the conformance suite") {
  const Scenario s;
  const auto c = candidates();
  // A mission of five regions: varied σ, all candidates, then none affordable.
  std::vector<DecisionContext> mission;
  for (int k = 0; k < 5; ++k) {
    DecisionContext ctx = s.region(k, 0.05 + 0.1 * k);
    ctx.candidates = k == 4 ? std::span<const Candidate>() : std::span<const Candidate>(c);
    mission.push_back(ctx);
  }
  const DescentOutcome outcome = Scenario::outcome(0.5);
  SUBCASE("utility") { test::check_policy_conformance(UtilityPolicy(fitted(), {}), mission, outcome); }
  SUBCASE("utility, relative") {
    test::check_policy_conformance(UtilityPolicy(fitted(), {.min_utility = 1.1, .relative_utility = true}), mission,
                                   outcome);
  }
  SUBCASE("front-aware") {
    test::check_policy_conformance(FrontAwarePolicy(fitted(), s.reference(0.001, 0.002), {.confidence = 0.5}), mission,
                                   outcome);
  }
  SUBCASE("decision function") {
    test::check_policy_conformance(DecisionFunction(FrontAwarePolicy(fitted(), s.reference(0.0), {})), mission,
                                   outcome);
  }
  SUBCASE("linear") {
    test::check_policy_conformance(LinearDecision({.sigma_low = 0.1, .sigma_high = 0.4}), mission, outcome);
  }
}
