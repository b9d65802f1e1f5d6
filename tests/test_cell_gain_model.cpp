#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/cell_input_scores.hpp>
#include <adaptseg/core/jump_guard.hpp>
#include <adaptseg/core/relabel_transfer.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace adaptseg;

namespace {
/// A cell of `px` field pixels whose expected error is `x`, seen at `top` cm/px and re-mapped at
/// `sub` on field `field`, gaining `nu` (normalised) and relabelling `chi`.
CellSample cell(std::size_t field, double top, double sub, double x, double px, double nu, double chi) {
  CellSample c;
  c.field = field;
  c.top_gsd_cm = top;
  c.sub_gsd_cm = sub;
  c.top.values.fill(NAN);
  c.top.values[index_of(DecisionInput::expected_error)] = x;
  c.top.values[index_of(DecisionInput::sigma)] = 0.5;
  c.top.field_px = px;
  c.field_sigma = 0.1;
  c.field_share = px / 1e6;
  c.field_gain = nu * c.field_share / c.field_sigma;  // normalized_gain() == nu
  c.relabelled = chi;
  return c;
}
}  // namespace

TEST_CASE("cell gain model: slopes and noise per pair of GSDs, forecasts of a set of cells") {
  std::vector<CellSample> s;
  // From 15 cm/px: re-mapped at 5 the gain is 0.9 x exactly, relabelling 1.2 x; at 10 it
  // scatters about 0.2 x (±0.05 x). From 12.5 cm/px at 5: 0.8 x.
  for (double x : {0.01, 0.02, 0.05, 0.1}) {
    s.push_back(cell(0, 15.0, 5.0, x, 1000.0, 0.9 * x, 1.2 * x));
    s.push_back(cell(1, 15.0, 10.0, x, 1000.0, 0.25 * x, 0.5 * x));
    s.push_back(cell(1, 15.0, 10.0, x, 1000.0, 0.15 * x, 0.5 * x));
    s.push_back(cell(0, 12.5, 5.0, x, 1000.0, 0.8 * x, 1.0 * x));
  }
  CHECK(s.front().normalized_gain() == doctest::Approx(0.009));
  const CellGainModel m = CellGainModel::fit(s, DecisionInput::expected_error);
  CHECK(m.input() == DecisionInput::expected_error);
  REQUIRE(m.points().size() == 3);
  CHECK(m.top_gsds() == std::vector<double>{12.5, 15.0});
  CHECK(m.points()[0].top_gsd_cm == 12.5);  // sorted by (top, descent)
  CHECK(m.points()[1].sub_gsd_cm == 5.0);
  CHECK(m.at(15.0, 10.0).gain_slope == doctest::Approx(0.2));
  CHECK(m.at(15.0, 5.0).gain_slope == doctest::Approx(0.9));
  CHECK(m.at(15.0, 5.0).gain_noise == doctest::Approx(0.0).epsilon(1e-12));
  CHECK(m.at(15.0, 10.0).gain_noise > 0.0);
  CHECK(m.at(15.0, 5.0).relabel_slope == doctest::Approx(1.2));
  CHECK(m.at(12.5, 5.0).gain_slope == doctest::Approx(0.8));
  // Between the calibrated descent GSDs linear, beyond them constant; a top-level GSD that was
  // not calibrated reads the nearest that was.
  CHECK(m.at(15.0, 7.5).gain_slope == doctest::Approx(0.55));
  CHECK(m.at(15.0, 2.0).gain_slope == doctest::Approx(0.9));
  CHECK(m.at(20.0, 5.0).gain_slope == doctest::Approx(0.9));
  CHECK(m.at(12.0, 5.0).gain_slope == doctest::Approx(0.8));
  // Two cells of a region of 4000 field pixels: shares 1/4 and 1/8.
  CellInputs a, b;
  a.values.fill(NAN);
  b.values.fill(NAN);
  a.values[index_of(DecisionInput::expected_error)] = 0.2;
  a.field_px = 1000.0;
  b.values[index_of(DecisionInput::expected_error)] = 0.4;
  b.field_px = 500.0;
  const std::vector<CellInputs> cells{a, b};
  const auto f = m.forecast(15.0, 5.0, cells, 4000.0);
  CHECK(f.gain == doctest::Approx(0.9 * (0.25 * 0.2 + 0.125 * 0.4)));
  CHECK(f.relabelled == doctest::Approx(1.2 * (0.25 * 0.2 + 0.125 * 0.4)));
  const auto g = m.forecast(15.0, 10.0, cells, 4000.0);
  CHECK(g.gain_var == doctest::Approx(m.at(15.0, 10.0).gain_noise * (0.0625 * 0.2 + 0.015625 * 0.4)));
  CHECK(m.cell_gain(15.0, 5.0, a) == doctest::Approx(0.18));
  // GainExtent::images: a cell whose image overhangs the region is forecast a gain over its
  // whole footprint's field pixels (gain_px), and still relabels only its pixels in the region.
  CellInputs wide = a;
  wide.footprint_px = 1500.0;
  CHECK(a.gain_px() == 1000.0);
  CHECK(wide.gain_px() == 1500.0);
  const auto w = m.forecast(15.0, 10.0, std::vector<CellInputs>{wide, b}, 4000.0);
  CHECK(w.gain == doctest::Approx(m.at(15.0, 10.0).gain_slope * (0.375 * 0.2 + 0.125 * 0.4)));
  CHECK(w.gain_var == doctest::Approx(m.at(15.0, 10.0).gain_noise * (0.140625 * 0.2 + 0.015625 * 0.4)));
  CHECK(w.input == doctest::Approx(0.375 * 0.2 + 0.125 * 0.4));
  CHECK(w.relabelled == doctest::Approx(g.relabelled));
  CHECK(w.relabelled_var == doctest::Approx(g.relabelled_var));
  // An unknown input value (a labels-only backend) holds nothing.
  CellInputs unknown;
  unknown.values.fill(NAN);
  unknown.field_px = 1000.0;
  CHECK(m.forecast(15.0, 5.0, std::vector<CellInputs>{unknown}, 4000.0).gain == 0.0);
  CHECK_THROWS_AS((void)m.forecast(15.0, 5.0, cells, 0.0), std::invalid_argument);
  CHECK_THROWS_AS((void)CellGainModel::fit({}, DecisionInput::expected_error), std::invalid_argument);
  CHECK_THROWS_AS(CellGainModel(DecisionInput::sigma, {}), std::invalid_argument);
  CHECK_THROWS_AS(CellGainModel(DecisionInput::sigma, {{15.0, 5.0, 1.0, -1.0, 1.0, 0.0}}), std::invalid_argument);
  CHECK_THROWS_AS(CellGainModel(DecisionInput::sigma, {{15.0, 20.0, 1.0, 0.0, 1.0, 0.0}}), std::invalid_argument);
  CHECK_THROWS_AS(
      CellGainModel(DecisionInput::sigma, {{15.0, 10.0, 1.0, 0.0, 1.0, 0.0}, {15.0, 5.0, 1.0, 0.0, 1.0, 0.0}}),
      std::invalid_argument);
}

TEST_CASE("cell gain model: an input is scored by how much of each field's gain its best cells capture") {
  // Two fields, one pair of GSDs: expected error ranks the cells by their gain, sigma against it.
  std::vector<CellSample> s;
  for (std::size_t f = 0; f < 2; ++f)
    for (int k = 0; k < 10; ++k) {
      CellSample c = cell(f, 15.0, 5.0, 0.01 * (k + 1), 1000.0, 0.9 * 0.01 * (k + 1), 0.0);
      c.top.values[index_of(DecisionInput::sigma)] = 1.0 - 0.1 * k;
      s.push_back(c);
    }
  const double best = cell_ranking_capture(s, DecisionInput::expected_error);
  const double worst = cell_ranking_capture(s, DecisionInput::sigma);
  // The best 20 % of 10 cells: gains 10 and 9 of 55 parts.
  CHECK(best == doctest::Approx(19.0 / 55.0));
  CHECK(worst == doctest::Approx(3.0 / 55.0));
  CHECK(std::isnan(cell_ranking_capture({}, DecisionInput::sigma)));
}

TEST_CASE(
    "cell gain model: the transfer score counts a field's capture only where the others' slope forecasts a gain") {
  // Fields 0 and 1: the gain grows with the input (captured 19 / 55 each, as above). Field 2: the
  // input is ten times larger, its five largest cells lose 0.5 x, the others gain 0.05: its best
  // 20 % capture (-0.5 - 0.45) / (5 * 0.05) = -3.8 of its achievable gain, and with it among the
  // training fields the pooled slope is negative (it holds nearly all of Σ w x²).
  const auto fields = [](bool losing) {
    std::vector<CellSample> s;
    for (std::size_t f = 0; f < 3; ++f)
      for (int k = 0; k < 10; ++k) {
        const bool loses = losing && f == 2;
        const double x = (loses ? 0.1 : 0.01) * (k + 1);
        const double nu = !loses ? 0.9 * x : k < 5 ? 0.05 : -0.5 * x;
        s.push_back(cell(f, 15.0, 5.0, x, 1000.0, nu, 0.0));
      }
    return s;
  };
  const std::vector<CellSample> agree = fields(false), lose = fields(true);
  const DecisionInput e = DecisionInput::expected_error;
  // Where every field's slope is positive, the two scores are one.
  CHECK(cell_transfer_capture(agree, e) == doctest::Approx(19.0 / 55.0));
  CHECK(cell_transfer_capture(agree, e) == doctest::Approx(cell_ranking_capture(agree, e)));
  // Fields 0 and 1 left out: the model of the others (with field 2) forecasts a loss, they count 0;
  // field 2 left out: fields 0 and 1 forecast a gain, it counts its -3.8.
  CHECK(cell_ranking_capture(lose, e) == doctest::Approx((2.0 * 19.0 / 55.0 - 3.8) / 3.0));
  CHECK(cell_transfer_capture(lose, e) == doctest::Approx(-3.8 / 3.0));
  CHECK(cell_input_score(CellInputScore::transfer, lose, e) == cell_transfer_capture(lose, e));
  CHECK(cell_input_score(CellInputScore::ranking, lose, e) == cell_ranking_capture(lose, e));
  // One field: no other to fit on, the ranking score.
  const std::vector<CellSample> one(lose.begin() + 20, lose.end());
  CHECK(cell_transfer_capture(one, e) == doctest::Approx(-3.8));
  CHECK(std::isnan(cell_transfer_capture({}, e)));
  CHECK(parse_cell_input_score("transfer") == CellInputScore::transfer);
  CHECK(to_string(CellInputScore::ranking) == "ranking");
  CHECK_THROWS_AS((void)parse_cell_input_score("capture"), std::invalid_argument);
}

TEST_CASE("cell gain model: the scene check's proxy slope, and how far it differs between the training fields") {
  // Cells whose finer look removes a share `removed` of the top's expected error, on field f,
  // gaining `gain` per unit of what was removed (γ_f).
  const auto looked = [](std::size_t f, double x, double removed, double gamma_f) {
    CellSample c = cell(f, 15.0, 5.0, x, 1000.0, gamma_f * removed * x, 0.0);
    c.fine.values.fill(NAN);
    c.fine.values[index_of(DecisionInput::expected_error)] = (1.0 - removed) * x;
    return c;
  };
  std::vector<CellSample> agree, disagree, one;
  for (double x : {0.02, 0.05, 0.1})
    for (double removed : {0.3, 0.6}) {
      agree.push_back(looked(0, x, removed, 0.8));
      agree.push_back(looked(1, x, removed, 0.8));
      disagree.push_back(looked(0, x, removed, 0.8));
      disagree.push_back(looked(1, x, removed, -0.4));
      one.push_back(looked(0, x, removed, 0.8));
    }
  const CellGainModel::Point a = CellGainModel::fit(agree, DecisionInput::expected_error).at(15.0, 5.0);
  CHECK(a.proxy_slope == doctest::Approx(0.8));
  CHECK(a.proxy_slope_sd == doctest::Approx(0.0).epsilon(1e-12));
  // Two fields of slopes 0.8 and -0.4: pooled 0.2, each 0.6 from it.
  const CellGainModel::Point d = CellGainModel::fit(disagree, DecisionInput::expected_error).at(15.0, 5.0);
  CHECK(d.proxy_slope == doctest::Approx(0.2));
  CHECK(d.proxy_slope_sd == doctest::Approx(std::sqrt(2.0 * 0.36)));
  // One field: how far its slope transfers is unknown, as far as the slope itself.
  const CellGainModel::Point o = CellGainModel::fit(one, DecisionInput::expected_error).at(15.0, 5.0);
  CHECK(o.proxy_slope_sd == doctest::Approx(o.proxy_slope));
  CHECK_THROWS_AS(CellGainModel(DecisionInput::sigma, {{15.0, 5.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, -0.1}}),
                  std::invalid_argument);
}

TEST_CASE(
    "cell gain model: slopes pooled over the training fields' cells, or the fields' own slopes as random effects") {
  // Field 0 holds much input (x up to 0.9) and loses by re-mapping (-0.4 x, relabelling 0.2 x);
  // field 1 holds little (x <= 0.05) and gains (0.8 x, relabelling 1.0 x).
  std::vector<CellSample> s;
  for (double x : {0.5, 0.7, 0.9}) s.push_back(cell(0, 15.0, 5.0, x, 1000.0, -0.4 * x, 0.2 * x));
  for (double x : {0.01, 0.03, 0.05}) s.push_back(cell(1, 15.0, 5.0, x, 1000.0, 0.8 * x, 1.0 * x));
  // Pooled over the cells (the default), field 0's x^2 outweighs field 1's by about 300 to 1.
  const CellGainModel by_cells = CellGainModel::fit(s, DecisionInput::expected_error);
  CHECK(by_cells.pooling() == SlopePooling::cells);
  double wxy = 0.0, wxx = 0.0;
  for (const CellSample& c : s) {
    const double x = c.top.value(DecisionInput::expected_error);
    wxy += x * c.normalized_gain();
    wxx += x * x;
  }
  CHECK(by_cells.at(15.0, 5.0).gain_slope == doctest::Approx(wxy / wxx));
  CHECK(by_cells.at(15.0, 5.0).gain_slope < -0.39);
  // Each field's own line is exact, so the two disagree far beyond their cells' scatter: as
  // random effects they weigh alike, and the slope is the mean of theirs.
  const CellGainModel by_fields = CellGainModel::fit(s, DecisionInput::expected_error, SlopePooling::fields);
  CHECK(by_fields.pooling() == SlopePooling::fields);
  const CellGainModel::Point p = by_fields.at(15.0, 5.0);
  CHECK(p.gain_slope == doctest::Approx(0.2));
  CHECK(p.relabel_slope == doctest::Approx(0.6));
  // The residuals about the pooled slope are the noise: each field is 0.6 or 0.4 off it.
  double ex = 0.0, e2 = 0.0;
  for (const CellSample& c : s) {
    const double x = c.top.value(DecisionInput::expected_error);
    ex += x;
    e2 += std::pow(c.normalized_gain() - 0.2 * x, 2);
  }
  CHECK(p.gain_noise == doctest::Approx(e2 / ex));
  // A field whose cells hold no input says nothing about the slope.
  s.push_back(cell(2, 15.0, 5.0, 0.0, 1000.0, 0.0, 0.0));
  s.push_back(cell(2, 15.0, 5.0, 0.0, 1000.0, 0.0, 0.0));
  CHECK(CellGainModel::fit(s, DecisionInput::expected_error, SlopePooling::fields).at(15.0, 5.0).gain_slope ==
        doctest::Approx(0.2));
  // One field: its own slope, whichever the pooling.
  const std::vector<CellSample> one(s.begin(), s.begin() + 3);
  CHECK(CellGainModel::fit(one, DecisionInput::expected_error, SlopePooling::fields).at(15.0, 5.0).gain_slope ==
        CellGainModel::fit(one, DecisionInput::expected_error).at(15.0, 5.0).gain_slope);

  // Fields that agree within their cells' scatter weigh by their precision: field 0's slope,
  // 0.5 from cells of much input and little scatter, against field 1's, about 0.56 from cells
  // of little input and scatter of half their gain, gives about 0.5 (their plain mean: 0.53).
  std::vector<CellSample> agree;
  int k = 0;
  for (double x : {0.5, 0.7, 0.9, 0.6})
    agree.push_back(cell(0, 15.0, 5.0, x, 1000.0, 0.5 * x * (k++ % 2 ? 1.01 : 0.99), 0.0));
  for (double x : {0.01, 0.03, 0.05, 0.02})
    agree.push_back(cell(1, 15.0, 5.0, x, 1000.0, 0.56 * x * (k++ % 2 ? 1.5 : 0.5), 0.0));
  CHECK(CellGainModel::fit(agree, DecisionInput::expected_error, SlopePooling::fields).at(15.0, 5.0).gain_slope ==
        doctest::Approx(0.5).epsilon(0.004));

  CHECK(parse_slope_pooling(to_string(SlopePooling::fields)) == SlopePooling::fields);
  CHECK(parse_slope_pooling(to_string(SlopePooling::cells)) == SlopePooling::cells);
  CHECK_THROWS_WITH_AS((void)parse_slope_pooling("field"),
                       doctest::Contains("slope pooling must be 'cells', 'fields' or 'field-entropy', not 'field'"),
                       std::invalid_argument);
}

TEST_CASE("cell gain model: the slope as a line in the field's mean top-level entropy (field-entropy)") {
  // Four fields whose own slopes lie on b = -0.3 + u, u their mean entropy: the two surest
  // fields lose by re-mapping (b = -0.1, 0), the two least sure gain (+0.2, +0.3).
  const std::vector<double> entropy{0.2, 0.3, 0.5, 0.6};
  std::vector<CellSample> s;
  for (std::size_t f = 0; f < entropy.size(); ++f)
    for (double x : {0.1, 0.2, 0.3}) {
      CellSample c = cell(f, 15.0, 5.0, x, 1000.0, (-0.3 + entropy[f]) * x, 0.5 * x);
      c.top.values[index_of(DecisionInput::entropy)] = entropy[f];
      s.push_back(c);
    }
  const CellGainModel m = CellGainModel::fit(s, DecisionInput::expected_error, SlopePooling::field_entropy);
  CHECK(m.pooling() == SlopePooling::field_entropy);
  CHECK(m.reads_field_entropy());
  const CellGainModel::Point& p = m.points().front();
  // Exact lines: the fields weigh alike, the reference is their mean entropy, the line exact.
  CHECK(p.entropy_reference == doctest::Approx(0.4));
  CHECK(p.gain_slope == doctest::Approx(0.1));
  CHECK(p.entropy_slope == doctest::Approx(1.0));
  CHECK(p.entropy_low == doctest::Approx(0.2));
  CHECK(p.entropy_high == doctest::Approx(0.6));
  CHECK(p.gain_noise == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(m.entropy_reference(15.0) == doctest::Approx(0.4));
  // What at() reads: β at the reference until the field's entropy is known; then on the line,
  // clamped to the training fields' range; the sign follows the field.
  CellGainModel flown = m;
  CHECK(flown.at(15.0, 5.0).gain_slope == doctest::Approx(0.1));
  flown.set_field_entropy(0.25);
  CHECK(flown.at(15.0, 5.0).gain_slope == doctest::Approx(-0.05));
  CellInputs one;
  one.values.fill(NAN);
  one.values[index_of(DecisionInput::expected_error)] = 0.2;
  one.field_px = 1000.0;
  CHECK(flown.cell_gain(15.0, 5.0, one) == doctest::Approx(-0.01));
  flown.set_field_entropy(0.9);
  CHECK(flown.at(15.0, 5.0).gain_slope == doctest::Approx(0.3));
  flown.set_field_entropy(0.0);
  CHECK(flown.at(15.0, 5.0).gain_slope == doctest::Approx(-0.1));
  // The same cells pooled without the covariate: one slope for every field, +0.1.
  CHECK(CellGainModel::fit(s, DecisionInput::expected_error, SlopePooling::fields).at(15.0, 5.0).gain_slope ==
        doctest::Approx(0.1));
  // Fewer than three fields with an entropy: no line, the fields' pooled slope.
  const std::vector<CellSample> two(s.begin(), s.begin() + 6);
  const CellGainModel flat = CellGainModel::fit(two, DecisionInput::expected_error, SlopePooling::field_entropy);
  CHECK_FALSE(flat.reads_field_entropy());
  CHECK(flat.at(15.0, 5.0).gain_slope ==
        CellGainModel::fit(two, DecisionInput::expected_error, SlopePooling::fields).at(15.0, 5.0).gain_slope);
  CHECK(parse_slope_pooling("field-entropy") == SlopePooling::field_entropy);
  // A range upside down is refused.
  CellGainModel::Point bad = p;
  bad.entropy_low = 0.7;
  CHECK_THROWS_AS(CellGainModel(DecisionInput::expected_error, {bad}, SlopePooling::field_entropy),
                  std::invalid_argument);
}

namespace {
// A re-mapped cell: its top-level σ, its finer image's σ and what re-mapping it gained the field.
CellSample sigma_cell(double top, double fine, double gain) {
  CellSample c;
  c.top.field_px = 100.0;
  c.top.values[index_of(DecisionInput::sigma)] = top;
  c.fine.values[index_of(DecisionInput::sigma)] = fine;
  c.field_gain = gain;
  return c;
}
}  // namespace

TEST_CASE("jump guard: the bound refuses the largest jumps that lost in total, and one beyond it trips") {
  // Jumps +0.6, +0.4, +0.3, +0.1, 0 (a cell without a finer σ counts for nothing); from the
  // largest down the gains sum to -0.02, -0.015, -0.025 (the lowest), +0.005: the three largest
  // are refused, the bound halfway between +0.3 and +0.1.
  const std::vector<CellSample> cells{sigma_cell(0.1, 0.7, -0.02), sigma_cell(0.0, 0.4, 0.005),
                                      sigma_cell(0.2, 0.5, -0.01), sigma_cell(0.3, 0.4, 0.03),
                                      sigma_cell(0.5, 0.5, 0.01),  sigma_cell(0.5, std::nan(""), -1.0)};
  CHECK(jump_bound(cells) == doctest::Approx(0.2));
  // Where re-mapping never lost in total from the largest jump down, or too few cells: no guard.
  CHECK(std::isinf(jump_bound(std::vector<CellSample>{sigma_cell(0.1, 0.7, 0.02), sigma_cell(0.0, 0.4, -0.01)})));
  CHECK(std::isinf(jump_bound(std::vector<CellSample>{sigma_cell(0.1, 0.7, -0.02)})));
  CHECK(std::isinf(jump_bound({})));
  JumpGuard guard(0.4);
  CHECK(guard.trusts(0.1, 0.45));
  CHECK_FALSE(guard.tripped());
  CHECK_FALSE(guard.trusts(0.1, 0.6));
  CHECK(guard.tripped());
  CHECK_FALSE(guard.trusts(0.1, 0.1));  // once tripped, for the rest of the mission
  guard.reset();
  CHECK(guard.trusts(0.1, 0.1));
  CHECK(JumpGuard().trusts(0.0, 1.0));  // no bound: no guard
  CHECK_THROWS_AS(JumpGuard(std::nan("")), std::invalid_argument);
}

TEST_CASE("relabel transfer: how far a field's gain factor moved with its relabelled factor on the training fields") {
  // Four fields at one pair of GSDs, two cells each; field f gains g_f·x and relabels r_f·x.
  const auto fields = [](std::vector<std::pair<double, double>> gr) {
    std::vector<CellSample> s;
    for (std::size_t f = 0; f < gr.size(); ++f)
      for (double x : {0.02, 0.05}) s.push_back(cell(f, 15.0, 5.0, x, 1000.0, gr[f].first * x, gr[f].second * x));
    return s;
  };
  const auto b = [](const std::vector<CellSample>& s) { return relabel_transfer(s, DecisionInput::expected_error); };
  // Gain and relabelled share in proportion on every field: the gain follows s whole.
  CHECK(b(fields({{0.1, 0.5}, {0.2, 1.0}, {0.3, 1.5}, {0.4, 2.0}})) == doctest::Approx(1.0));
  // The gain's ratios half as far from 1 as the relabelled share's (pooled slopes 0.25 and 1.25;
  // ratios 0.8/0.6, 0.9/0.8, 1.1/1.2, 1.2/1.4).
  CHECK(b(fields({{0.2, 0.75}, {0.225, 1.0}, {0.275, 1.5}, {0.3, 1.75}})) == doctest::Approx(0.5));
  // The field that relabels most gains least (a class whose closer looks write it where it is
  // absent): nothing carried over.
  CHECK(b(fields({{0.4, 0.5}, {0.3, 1.0}, {0.2, 1.5}, {0.1, 2.0}})) == 0.0);
  // More than in proportion: clamped to s itself.
  CHECK(b(fields({{0.05, 0.5}, {0.1, 1.0}, {0.4, 1.5}, {0.45, 2.0}})) == 1.0);
  // Too few fields, or no spread of the relabelled share: nothing measured, 1.
  CHECK(b(fields({{0.4, 0.5}, {0.1, 2.0}})) == 1.0);
  CHECK(b(fields({{0.4, 1.0}, {0.1, 1.0}, {0.2, 1.0}})) == 1.0);
  CHECK(b({}) == 1.0);
}

TEST_CASE("relabel region spread: how far a region's relabelled share strays from its field's, about the forecast") {
  // Two fields, two regions each, every cell x = 0.1: the pooled slope α = 1, each region forecast
  // 0.1. Field 0's regions relabel 0.05 and 0.15 (ρ 0.5 and 1.5), field 1's 0.1 and 0.1: within
  // the fields Σ (ρ − ρ̄)² = 0.5 over 2 degrees of freedom, τ_r = 0.5.
  std::vector<CellSample> s;
  const auto add = [&](std::size_t field, std::size_t region, double chi) {
    for (int k = 0; k < 3; ++k) {
      CellSample c = cell(field, 15.0, 5.0, 0.1, 1000.0, 0.01, chi);
      c.region = region;
      s.push_back(c);
    }
  };
  add(0, 0, 0.05);
  add(0, 1, 0.15);
  add(1, 0, 0.1);
  add(1, 1, 0.1);
  CHECK(relabel_region_sd(s, DecisionInput::expected_error) == doctest::Approx(0.5));
  // A field's own level is taken out, the ratios are to the pooled forecast: field 1 relabelling
  // 0.2 in both regions raises α to 1.5, field 0's ratios become 1/3 and 1, τ_r = 1/3.
  for (CellSample& c : s)
    if (c.field == 1) c.relabelled = 0.2;
  CHECK(relabel_region_sd(s, DecisionInput::expected_error) == doctest::Approx(1.0 / 3.0));
  // One region per field: nothing to measure.
  s.erase(std::remove_if(s.begin(), s.end(), [](const CellSample& c) { return c.region == 1; }), s.end());
  CHECK(relabel_region_sd(s, DecisionInput::expected_error) == 0.0);
}

TEST_CASE("relabel field spread: how far the fields' relabelled factors stray from 1, each against the others' slope") {
  // Fields relabelling r_f·x with the same cells (x 0.02 and 0.05, 1000 px): the others' slope is
  // the mean of their r, field f's factor r_f / that. r = 1, 2, 3: factors 1/2.5, 2/2, 3/1.5 =
  // 0.4, 1, 2; ω_χ² = (0.36 + 0 + 1) / 3.
  const auto fields = [](std::vector<double> r, double sub = 5.0) {
    std::vector<CellSample> s;
    for (std::size_t f = 0; f < r.size(); ++f)
      for (double x : {0.02, 0.05}) s.push_back(cell(f, 15.0, sub, x, 1000.0, 0.1 * x, r[f] * x));
    return s;
  };
  const auto omega = [](const std::vector<CellSample>& s) {
    return relabel_field_sd(s, DecisionInput::expected_error);
  };
  CHECK(omega(fields({1.0, 2.0, 3.0})) == doctest::Approx(std::sqrt(1.36 / 3.0)));
  // A field's factor is over every pair of GSDs it has cells at: the same fields at a second
  // pair, where they relabel alike, pull each factor halfway to 1 (Σ μ·χ / Σ μ² over both).
  std::vector<CellSample> two = fields({1.0, 2.0, 3.0});
  for (const CellSample& c : fields({2.0, 2.0, 2.0}, 10.0)) two.push_back(c);
  // Field 0: (2.5·1 + 2·2) / (2.5² + 2²) = 6.5 / 10.25; field 1: 1; field 2: (1.5·3 + 2·2) / (1.5² + 2²).
  const double s0 = 6.5 / 10.25, s2 = 8.5 / 6.25;
  CHECK(omega(two) == doctest::Approx(std::sqrt((std::pow(s0 - 1.0, 2) + std::pow(s2 - 1.0, 2)) / 3.0)));
  // Fields alike: at least ω's floor, 0.1. One field, or none: 0 (s keeps ω).
  CHECK(omega(fields({2.0, 2.0, 2.0})) == 0.1);
  CHECK(omega(fields({2.0})) == 0.0);
  CHECK(omega({}) == 0.0);
}
