#include <adaptseg/decision_function.hpp>
#include <adaptseg/lawnmower_curve.hpp>
#include <adaptseg/linear_decision.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <vector>

using namespace adaptseg;

namespace {
// Synthetic initialisation data: descending further (larger Δh) loses more σ and gains more
// accuracy; denser regions (larger σ) gain more.
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
      out.push_back(s);
    }
  return out;
}

std::vector<Candidate> candidates() {
  // 1.0, 1.5, 2.0, 2.5 cm/px below 3.0 cm/px with the default camera (h = 5.5 * gsd).
  return {{1.0, 5.5, 9, 40.0}, {1.5, 8.25, 4, 20.0}, {2.0, 11.0, 4, 20.0}, {2.5, 13.75, 4, 20.0}};
}
}  // namespace

static_assert(DecisionPolicy<DecisionFunction>);
static_assert(DecisionPolicy<LinearDecision>);
static_assert(!DecisionPolicy<int>);

TEST_CASE("decision function: initialised GPs reproduce the training trends") {
  const auto df = DecisionFunction::initialize(samples(), {});
  CHECK(df.o_model().size() == 20);
  CHECK(df.i_model().size() == 20);
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  const auto far = df.score(ctx, c[0]);   // Δh = 11 m
  const auto near = df.score(ctx, c[3]);  // Δh = 2.75 m
  CHECK(far.predicted_delta_sigma < near.predicted_delta_sigma);  // more σ recovered lower down
  CHECK(far.predicted_delta_miou == doctest::Approx(-0.275).epsilon(0.1));
  CHECK(near.predicted_delta_miou == doctest::Approx(-0.069).epsilon(0.2));
  CHECK(far.predicted_delta_miou_std >= 0.0);
}

TEST_CASE("decision function: thresholds, σ weighting and the best utility") {
  auto df = DecisionFunction::initialize(samples(), {});
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  Decision d = df.decide(ctx);
  REQUIRE(d.scores.size() == 4);
  REQUIRE(d.descend);
  double best = 0.0;
  for (const auto& s : d.scores) best = std::max(best, s.utility);
  for (std::size_t k = 0; k < c.size(); ++k)
    if (d.scores[k].utility == best) CHECK(d.gsd_cm == c[k].gsd_cm);
  // σ weighting: half the σ, half the utility (same predictions up to the σ input of O).
  DecisionContext half_valid = ctx;
  half_valid.valid_fraction = 0.5;
  CHECK(df.decide(half_valid).scores[0].utility == doctest::Approx(d.scores[0].utility * 0.5));
  // Thresholds.
  auto p = df.params();
  p.min_sigma = 0.25;
  df.set_params(p);
  CHECK_FALSE(df.decide(ctx).descend);
  p.min_sigma = 0.0;
  p.min_utility = best * 1.01;
  df.set_params(p);
  CHECK_FALSE(df.decide(ctx).descend);
  p.min_utility = best * 0.99;
  df.set_params(p);
  CHECK(df.decide(ctx).descend);
  // No affordable candidate: continue.
  DecisionContext none = ctx;
  none.candidates = {};
  CHECK_FALSE(df.decide(none).descend);
  CHECK_THROWS_AS(df.set_params({.min_sigma = 2.0}), std::invalid_argument);
  CHECK_THROWS_AS(df.set_params({.exploration = -1.0}), std::invalid_argument);
}

TEST_CASE("decision function: relative utility compares with the mission's running mean") {
  auto df = DecisionFunction::initialize(samples(), {.min_utility = 1.2, .relative_utility = true});
  const auto c = candidates();
  DecisionContext low{.sigma = 0.05, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  DecisionContext high = low;
  high.sigma = 0.3;
  CHECK_FALSE(df.decide(low).descend);  // first image: ratio 1 < 1.2
  CHECK_FALSE(df.decide(low).descend);
  CHECK(df.decide(high).descend);       // well above the running mean
  df.reset_mission();
  CHECK_FALSE(df.decide(high).descend);  // alone again: ratio 1
}

TEST_CASE("decision function: online updates extend O only when adaptive") {
  auto adaptive = DecisionFunction::initialize(samples(), {.online = true});
  auto refitting = DecisionFunction::initialize(samples(), {.online = true, .refit_every = 1});
  auto fixed = DecisionFunction::initialize(samples(), {.online = false});
  CHECK(adaptive.name() == "adaptive");
  CHECK(fixed.name() == "nonadaptive");
  const DescentOutcome out{.top_altitude_m = 16.5, .sub_altitude_m = 5.5, .sigma_top = 0.1, .sigma_sub = 0.3};
  adaptive.observe(out);
  adaptive.observe(out);
  fixed.observe(out);
  refitting.observe(out);
  CHECK(refitting.o_model().size() == 21);
  CHECK(adaptive.o_model().size() == 22);
  CHECK(adaptive.online_updates() == 2);
  CHECK(fixed.o_model().size() == 20);
  // The observed, much larger σ recovery (Δσ = -0.2) pulls O's prediction towards it.
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.1, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  const double before = fixed.score(ctx, c[0]).predicted_delta_sigma;
  const double after = adaptive.score(ctx, c[0]).predicted_delta_sigma;
  CHECK(std::abs(after - (-0.2)) < 0.5 * std::abs(before - (-0.2)));
}

TEST_CASE("decision function: save and load give the same decisions and broken files are refused") {
  auto df = DecisionFunction::initialize(samples(), {.min_sigma = 0.01, .min_utility = 1e-4, .exploration = 0.5});
  std::stringstream ss;
  df.save(ss);
  const std::string text = ss.str();
  auto back = DecisionFunction::load(ss);
  CHECK(back.params().min_sigma == df.params().min_sigma);
  CHECK(back.params().exploration == df.params().exploration);
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.17, .valid_fraction = 0.9, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  const Decision a = df.decide(ctx), b = back.decide(ctx);
  CHECK(a.descend == b.descend);
  for (std::size_t k = 0; k < c.size(); ++k)
    CHECK(a.scores[k].utility == doctest::Approx(b.scores[k].utility).epsilon(1e-9));
  std::istringstream truncated(text.substr(0, text.size() / 2));
  CHECK_THROWS_AS((void)DecisionFunction::load(truncated), std::invalid_argument);
  std::istringstream wrong("adaptseg.decision_function 7\n");
  CHECK_THROWS_WITH_AS((void)DecisionFunction::load(wrong), doctest::Contains("version"), std::invalid_argument);
  std::istringstream empty("");
  CHECK_THROWS_AS((void)DecisionFunction::load(empty), std::invalid_argument);
  CHECK_THROWS_AS((void)DecisionFunction::initialize({}, {}), std::invalid_argument);
}

TEST_CASE("decision function: the front-aware rule descends while descents beat the lawnmower curve") {
  auto df = DecisionFunction::initialize(samples(), {.weight_by_sigma = false, .front_aware = true});
  // Training lawnmower by GSD, and this field's lawnmower times at the same GSDs.
  df.set_reference_lawnmower({{1.0, 1.0}, {1.5, 0.85}, {2.0, 0.82}, {2.5, 0.77}, {3.0, 0.75}});
  const std::vector<LawnmowerForecast> lawnmowers{{1.0, 185.0}, {1.5, 107.0}, {2.0, 101.0}, {2.5, 96.0}, {3.0, 40.0}};
  const std::vector<CurvePoint> curve{{185.0, 1.0}, {107.0, 0.85}, {101.0, 0.82}, {96.0, 0.77}, {40.0, 0.75}};
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5,
                      .candidates = c, .elapsed_s = 5.7, .rest_s = 34.3, .region_share = 1.0 / 7.0,
                      .lawnmowers = lawnmowers};
  // First region: the mission's end point is the top-level lawnmower's (40 s, 0.75), margin 0.
  // Re-mapping the region (1/7 of the field) from 1.0 cm/px gains about 0.275 / 7 = 0.039 for
  // 40 s: (80 s, 0.789) lies above the curve (0.764 there).
  const Decision first = df.decide(ctx);
  REQUIRE(first.descend);
  double best = -1.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const auto& s = first.scores[k];
    // The predicted margin is the forecast end point against the curve, from the region's gain.
    const double expected = front_margin(curve, 40.0 + c[k].extra_time_s, 0.75 - s.predicted_delta_miou / 7.0);
    CHECK(s.predicted_front_margin == doctest::Approx(expected).epsilon(1e-9));
    best = std::max(best, s.predicted_front_margin);
  }
  CHECK(best > 0.015);
  for (std::size_t k = 0; k < c.size(); ++k)
    if (first.scores[k].predicted_front_margin == best) CHECK(first.gsd_cm == c[k].gsd_cm);
  // A later region, after that descent (end point now about 85 s): another descent would end
  // in the curve's steep part (2.5 -> 1.5 cm/px costs only 11 s there), below it: continue.
  DecisionContext next = ctx;
  next.elapsed_s = 5.7 + 40.0 + 5.7;
  next.rest_s = 33.6;
  const Decision second = df.decide(next);
  CHECK_FALSE(second.descend);
  for (const auto& s : second.scores) CHECK(s.predicted_front_margin < 0.0);
  // A new mission forgets the forecast: the first region descends again.
  df.reset_mission();
  CHECK(df.decide(ctx).descend);
  // The rule needs the forecasts and the reference; it excludes the relative threshold.
  df.reset_mission();
  DecisionContext blind = ctx;
  blind.lawnmowers = {};
  CHECK_THROWS_WITH_AS((void)df.decide(blind), doctest::Contains("lawnmower forecasts"), std::invalid_argument);
  auto no_reference = DecisionFunction::initialize(samples(), {.front_aware = true});
  CHECK_THROWS_WITH_AS((void)no_reference.decide(ctx), doctest::Contains("reference lawnmower"),
                       std::invalid_argument);
  CHECK_THROWS_AS(df.set_params({.relative_utility = true, .front_aware = true}), std::invalid_argument);
  CHECK_THROWS_AS(df.set_reference_lawnmower({{0.0, 0.5}}), std::invalid_argument);
  // Saved and loaded with its reference.
  std::stringstream ss;
  df.save(ss);
  auto back = DecisionFunction::load(ss);
  CHECK(back.params().front_aware);
  REQUIRE(back.reference_lawnmower().size() == 5);
  CHECK(back.reference_lawnmower()[3].miou == 0.77);
  CHECK(back.decide(ctx).gsd_cm == first.gsd_cm);
}

namespace {
// The text a version 1 or 2 file had for `df` (saved as version 3): the old version number,
// and I's kernel under its old name (those versions had the isotropic kernel type for I).
std::string old_format_text(const DecisionFunction& df, int version) {
  std::stringstream ss;
  df.save(ss);
  std::string text = ss.str();
  text.replace(text.find("adaptseg.decision_function 3\n"), 29, "adaptseg.decision_function " + std::to_string(version) + "\n");
  const std::string ard = "kernel squared_exponential_ard\n";
  const auto i_kernel = text.find(ard, text.find(ard) + 1);  // the second GP is I
  REQUIRE(i_kernel != std::string::npos);
  text.replace(i_kernel, ard.size(), "kernel squared_exponential_isotropic\n");
  if (version == 1) {  // version 1 had no front_aware and no reference_lawnmower lines
    const auto a = text.find("front_aware");
    const std::string ref = "reference_lawnmower 0\n";
    text.erase(a, text.find(ref) + ref.size() - a);
  }
  return text;
}
}  // namespace

TEST_CASE("decision function: files of format versions 1 and 2 still load, with the same predictions") {
  const auto df = DecisionFunction::initialize(samples(), {.min_utility = 1e-4});
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  for (int version : {1, 2}) {
    CAPTURE(version);
    std::istringstream old(old_format_text(df, version));
    const auto back = DecisionFunction::load(old);
    CHECK_FALSE(back.params().front_aware);
    CHECK(back.params().min_utility == 1e-4);
    CHECK(back.reference_lawnmower().empty());
    CHECK(back.gain_inputs() == DecisionFunction::GainInputs::delta_sigma);
    for (const auto& cand : c)
      CHECK(back.score(ctx, cand).predicted_delta_miou == doctest::Approx(df.score(ctx, cand).predicted_delta_miou).epsilon(1e-12));
  }
  // An old file whose I block is cut off says so.
  std::string cut = old_format_text(df, 2);
  cut.erase(cut.rfind("end adaptseg.gaussian_process"));
  std::istringstream truncated(cut);
  CHECK_THROWS_AS((void)DecisionFunction::load(truncated), std::invalid_argument);
}

TEST_CASE("decision function: I on (delta sigma, delta h) tells candidate altitudes apart where delta sigma cannot") {
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
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  const auto paper = DecisionFunction::initialize(flat, {});
  CHECK(paper.gain_inputs() == DecisionFunction::GainInputs::delta_sigma);
  CHECK(paper.score(ctx, c[0]).predicted_delta_miou ==
        doctest::Approx(paper.score(ctx, c[3]).predicted_delta_miou).epsilon(1e-9));  // blind to Δh
  const auto by_height =
      DecisionFunction::initialize(flat, {}, 3, 0, DecisionFunction::GainInputs::delta_sigma_and_height);
  CHECK(by_height.gain_inputs() == DecisionFunction::GainInputs::delta_sigma_and_height);
  CHECK(by_height.i_model().dimension() == 2);
  CHECK(by_height.score(ctx, c[0]).predicted_delta_miou == doctest::Approx(-0.165).epsilon(0.05));  // Δh = 11 m
  CHECK(by_height.score(ctx, c[3]).predicted_delta_miou == doctest::Approx(-0.041).epsilon(0.1));   // Δh = 2.75 m
  // Saved as version 3 and read back: the same predictions.
  std::stringstream ss;
  by_height.save(ss);
  CHECK(ss.str().rfind("adaptseg.decision_function 3\n", 0) == 0);
  const auto back = DecisionFunction::load(ss);
  CHECK(back.i_model().dimension() == 2);
  CHECK(back.score(ctx, c[1]).predicted_delta_miou ==
        doctest::Approx(by_height.score(ctx, c[1]).predicted_delta_miou).epsilon(1e-12));
}

TEST_CASE("linear decision: altitude falls linearly with σ to the nearest candidate") {
  const LinearDecision lin({.sigma_low = 0.1, .sigma_high = 0.3});
  const auto c = candidates();
  DecisionContext ctx{.sigma = 0.05, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = c};
  CHECK_FALSE(lin.decide(ctx).descend);  // below sigma_low: stay at h_max
  ctx.sigma = 0.3;
  CHECK(lin.decide(ctx).gsd_cm == 1.0);  // at sigma_high: the lowest altitude
  ctx.sigma = 0.2;                        // halfway: 16.5 - 11/2 = 11.0 m -> 2.0 cm/px
  CHECK(lin.decide(ctx).gsd_cm == 2.0);
  ctx.sigma = 0.11;                       // 16.5 - 0.55 m: nearer h_max than any candidate
  CHECK_FALSE(lin.decide(ctx).descend);
  CHECK_THROWS_AS(LinearDecision({.sigma_low = 0.3, .sigma_high = 0.3}), std::invalid_argument);
}
