#include "comma_locale.hpp"
#include "test_support.hpp"

#include <adaptseg/vision/calibration.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;

namespace {
/// Half the default camera's image (same lens and sensor): with fields of half the size, the
/// calibrations below see the same 2 x 2 regions as with the default camera over twice the
/// field, at a quarter of the pixels (and of the time, which the sanitizer build multiplies).
const CameraParams kSmallCamera{.image_width_px = 240, .image_height_px = 180};

CalibrationOptions small_options() {
  CalibrationOptions o;
  o.adaptive.mission.camera = kSmallCamera;
  o.adaptive.mission.fixed_segmentation_time_s = 0.1;
  o.adaptive.mission.fixed_planning_time_s = 0.0;
  o.adaptive.top_gsd_cm = 3.0;
  o.adaptive.candidate_gsd_cm = {1.0, 2.0};
  o.lawnmower_gsd_cm = {1.0, 2.0, 3.0};
  o.threshold_steps = 3;
  o.fit.restarts = 1;
  return o;
}

/// Two blob fields of the same kind, and small_options() with ranked cells and z in {0, 1}.
std::vector<Field> two_blob_fields() {
  return {t::blob_field(1300, 1000, 1.0, 4, 15), t::blob_field(1000, 1300, 1.0, 11, 15)};
}
/// A trial of the folds' margins `margins`, its front margin their mean.
RuleTrial trial(std::vector<double> margins) {
  RuleTrial t;
  for (double m : margins) t.front_margin += m / static_cast<double>(margins.size());
  t.margins = std::move(margins);
  return t;
}
CalibrationOptions ranked_options() {
  CalibrationOptions o = small_options();
  o.adaptive.coverage = DescentCoverage::ranked;
  o.confidences = {0.0, 1.0};
  return o;
}
}  // namespace

TEST_CASE("calibration: region samples pair every region with every candidate") {
  const Field f = t::blob_field(2000, 1500, 1.0, 9, 30);
  OracleSegmenter oracle(f.num_classes());
  const auto samples = collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest());
  // 20 x 15 m field, 14.4 x 10.8 m regions: 2 x 2 regions, 2 candidates each.
  REQUIRE(samples.size() == 8);
  for (const auto& s : samples) {
    CHECK(s.delta_h_m == doctest::Approx(16.5 - 5.5 * s.sub_gsd_cm));
    if (s.sub_gsd_cm == 1.0) CHECK(s.miou_sub == doctest::Approx(1.0));  // the oracle is exact at g0
    CHECK(s.miou_top <= s.miou_sub + 1e-12);
    CHECK(s.sigma_top >= 0.0);
    CHECK(s.sigma_top <= 1.0);
  }
  CHECK_THROWS_AS((void)collect_region_samples(f, oracle, CameraModel{}, 3.0, {4.0}, f.interest()),
                  std::invalid_argument);
  CHECK_THROWS_AS((void)collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0}, {}), std::invalid_argument);
}

TEST_CASE("calibration: with coverage 'interest' a sample re-maps the cells that show a label of interest") {
  const Field f = t::patch_field();  // two regions, one crop patch in the first
  OracleSegmenter oracle(f.num_classes());
  const auto all = collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest());
  const auto focused =
      collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest(), DescentCoverage::interest);
  CHECK(all.size() == 4);
  REQUIRE(focused.size() == 2);  // the region without crop has no cell to re-map
  for (const auto& s : focused) {
    CHECK(s.sigma_top > 0.0);
    // The cells not re-mapped keep their (correct) top-level soil: only the patch's edges
    // could be wrong, and at the field's GSD they are not.
    if (s.sub_gsd_cm == 1.0) CHECK(s.miou_sub == 1.0);
    CHECK(s.miou_sub >= s.miou_top);
  }
}

TEST_CASE("calibration: region samples carry what the descent relabelled and what it adds to the field") {
  const Field f = t::blob_field(2000, 1500, 1.0, 9, 30);
  OracleSegmenter oracle(f.num_classes());
  const auto samples =
      collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest(), DescentCoverage::region, 3);
  REQUIRE(samples.size() == 8);
  double share = 0.0;
  for (const auto& s : samples) {
    CHECK(s.field == 3);
    CHECK(s.relabelled.interest_share >= 0.0);
    CHECK(s.relabelled.interest_share <= s.relabelled.share + 1e-12);
    CHECK(s.region_share > 0.0);
    CHECK(s.field_sigma == samples.front().field_sigma);
    // The oracle at the field's GSD relabels only to correct: never a loss.
    if (s.sub_gsd_cm == 1.0) {
      CHECK(s.field_gain >= -1e-12);
      share += s.region_share;
    }
    // A region that relabels nothing gains nothing.
    if (s.relabelled.share == 0.0) CHECK(s.field_gain == doctest::Approx(0.0));
  }
  CHECK(share == doctest::Approx(1.0));  // the regions tile the field
  // Descending everywhere to the field's GSD: the region gains add up to about the field's
  // lawnmower gain (exactly, but for IoU's ratio).
  MissionOptions mo;
  mo.fixed_segmentation_time_s = 0.1;
  const double lawnmower_gain = run_lawnmower_mission(f, 1.0, oracle, mo).miou_interest().value() -
                                run_lawnmower_mission(f, 3.0, oracle, mo).miou_interest().value();
  double sum = 0.0;
  for (const auto& s : samples)
    if (s.sub_gsd_cm == 1.0) sum += s.field_gain;
  CHECK(sum == doctest::Approx(lawnmower_gain).epsilon(0.1));
}

TEST_CASE("calibration: the rules by name, one entry each, an unknown name refused up front") {
  CHECK(rule_names() == std::vector<std::string>{"front-aware", "utility"});
  CHECK(rule_names_text() == "front-aware or utility");
  static_assert(std::is_same_v<RuleFor<FrontAwarePolicy>, FrontAwareRule>);
  static_assert(std::is_same_v<RuleFor<UtilityPolicy>, UtilityRule>);
  const Field f = t::blob_field(400, 300, 1.0, 4, 15);
  OracleSegmenter oracle(f.num_classes());
  CalibrationOptions options = small_options();
  options.rule = "threshold";  // the name of 0.1.0
  CHECK_THROWS_WITH_AS((void)calibrate(f, oracle, options),
                       doctest::Contains("calibrate: the rule must be front-aware or utility; rule (got threshold)"),
                       std::invalid_argument);
  options.rule = "front-aware";
  options.confidences.clear();
  CHECK_THROWS_WITH_AS((void)calibrate(f, oracle, options), doctest::Contains("confidences must not be empty"),
                       std::invalid_argument);
}

TEST_CASE("calibration: the paper's rule takes the threshold with the best worst-case training margin") {
  const Field f = t::blob_field(1300, 1000, 1.0, 4, 15);
  OracleSegmenter oracle(f.num_classes());
  CalibrationOptions options = small_options();
  options.rule = "utility";
  const CalibrationResult cal = calibrate(f, oracle, options);
  CHECK(cal.samples.size() == 2u * 2u * 2u);
  REQUIRE(cal.lawnmower_curves.size() == 1);
  CHECK(cal.lawnmower_curves.front().size() == 3);
  REQUIRE_FALSE(cal.trials.empty());
  REQUIRE_FALSE(cal.decision_function.front_aware());
  // "Never descend" is always tried, so the best worst-case margin is at least 0.
  CHECK(cal.trials.front().worst_margin >= 0.0);
  CHECK(cal.trials.front().margins.size() == 3);  // the field and its halves
  for (const auto& trial : cal.trials) CHECK(trial.worst_margin <= cal.trials.front().worst_margin);
  CHECK(cal.linear.sigma_high > cal.linear.sigma_low);
  const DecisionModel model = make_decision_model(f, oracle.name(), small_options(), cal);
  CHECK(model.classes == std::vector<std::string>{"soil", "crop", "weed"});
  CHECK(model.interest == std::vector<std::string>{"crop", "weed"});
  CHECK(model.candidate_gsd_cm == std::vector<double>{1.0, 2.0});
  CHECK(model.train_front_margin == cal.trials.front().front_margin);
  CHECK(model.calibration_segmentation_time_s == 0.1);
  model.check_compatible(f, f.interest());
}

TEST_CASE("calibration: by default the front-aware rule, its confidence chosen on the training field") {
  const Field f = t::blob_field(1300, 1000, 1.0, 4, 15);
  OracleSegmenter oracle(f.num_classes());
  const CalibrationOptions options = small_options();
  REQUIRE(options.rule == "front-aware");
  const CalibrationResult cal = calibrate(f, oracle, options);
  REQUIRE(cal.decision_function.front_aware());
  const auto& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  // One trial per confidence level; the chosen one first, with the best mean margin.
  REQUIRE(cal.trials.size() == options.confidences.size());
  for (const auto& trial : cal.trials) CHECK(trial.front_margin <= cal.trials.front().front_margin);
  CHECK(cal.trials.front().description ==
        "front-aware z=" + std::string(adaptseg::detail::format_number(rule.params().confidence)));
  // Its reference: the training lawnmower's mIoU at each lawnmower GSD, and the field's σ.
  REQUIRE(rule.reference().size() == 1);
  const auto& reference = rule.reference().front();
  REQUIRE(reference.points.size() == options.lawnmower_gsd_cm.size());
  for (std::size_t k = 0; k < reference.points.size(); ++k) {
    CHECK(reference.points[k].gsd_cm == options.lawnmower_gsd_cm[k]);
    CHECK(reference.points[k].miou == cal.lawnmower_curves.front()[k].miou);
  }
  CHECK(reference.field_sigma == cal.samples.front().field_sigma);
  CHECK(rule.model().c_model().has_value());
  // The model file keeps the rule, its settings and its reference, and predicts the same.
  t::TempDir tmp;
  make_decision_model(f, oracle.name(), options, cal).save(tmp.path() / "model.yaml");
  const DecisionModel back = DecisionModel::load(tmp.path() / "model.yaml");
  REQUIRE(back.decision_function.front_aware());
  const auto& back_rule = std::get<FrontAwarePolicy>(back.decision_function.rule());
  CHECK(back_rule.params().confidence == rule.params().confidence);
  CHECK(back_rule.params().scale_prior_sd == rule.params().scale_prior_sd);
  CHECK(back_rule.params().sigma_prior_weight == rule.params().sigma_prior_weight);
  CHECK(back_rule.params().sigma_prior_sd == rule.params().sigma_prior_sd);
  CHECK(rule.params().sigma_prior_sd == 0.0);  // one field: no spread of fields to estimate
  CHECK(back_rule.reference().front().points.size() == reference.points.size());
  CHECK(back_rule.reference().front().field_sigma == reference.field_sigma);
  for (double sigma : {0.0, 0.05, 0.2})
    for (double dh : {5.5, 11.0}) {
      const GainForecast a = rule.model().forecast(dh, sigma), b = back_rule.model().forecast(dh, sigma);
      CHECK(a.delta_miou == b.delta_miou);
      CHECK(a.relabelled == b.relabelled);
      CHECK(rule.model().efficiency(dh) == back_rule.model().efficiency(dh));
    }
}

TEST_CASE("calibration: with coverage 'ranked' every cell is a sample, and the input that ranks them best is chosen") {
  const std::vector<Field> fields = two_blob_fields();
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::field_entropy, SlopePooling::cells, SlopePooling::fields};
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  REQUIRE_FALSE(cal.cell_samples.empty());
  // Every input about L is known from the oracle (it gives probabilities) and scored; the
  // chosen one first, with the best capture.
  REQUIRE(cal.cell_input_scores.size() == 5);
  for (const auto& [input, score] : cal.cell_input_scores) CHECK(score <= cal.cell_input_scores.front().second);
  const auto& cells = cal.decision_function.model().cells();
  REQUIRE(cells.has_value());
  CHECK(cells->input() == cal.cell_input_scores.front().first);
  // Each z tried with each pooling asked for but the field's entropy, which two fields cannot
  // make a line of (it would be `fields`): the cells, the fields; the chosen one first, the best
  // mean margin of its pooling, and the model's cell gain model pooled as it says.
  REQUIRE(cal.trials.size() == 2 * options.confidences.size());
  const std::string chosen = " slopes=" + to_string(cells->pooling());
  CHECK(cal.trials.front().description.ends_with(chosen));
  for (const SlopePooling pooling : {SlopePooling::cells, SlopePooling::fields}) {
    int tried = 0;
    for (const auto& trial : cal.trials) tried += trial.description.ends_with(" slopes=" + to_string(pooling));
    CHECK(tried == static_cast<int>(options.confidences.size()));
  }
  for (const auto& trial : cal.trials)
    if (trial.description.ends_with(chosen)) CHECK(trial.front_margin <= cal.trials.front().front_margin);
  const CellGainModel refit = CellGainModel::fit(cal.cell_samples, cells->input(), cells->pooling());
  for (std::size_t k = 0; k < cells->points().size(); ++k)
    CHECK(refit.points()[k].gain_slope == cells->points()[k].gain_slope);
  // Cells of both fields at both candidate GSDs; each re-mapped alone.
  std::size_t at_g0 = 0;
  for (const CellSample& c : cal.cell_samples) {
    CHECK(c.field < 2);
    CHECK(c.top.field_px > 0.0);
    CHECK(c.relabelled >= 0.0);
    if (c.sub_gsd_cm == 1.0) ++at_g0;
  }
  CHECK(at_g0 > 0);
  CHECK(at_g0 < cal.cell_samples.size());
  // The oracle's expected error is the share of pixels its top-level map has wrong, and a cell
  // re-mapped at the field's own GSD is exact: nearly all of it is gained (β near 1, the field's
  // σ standing in for its union of L), and re-mapping the best fifth of the cells by it captures
  // a large part of the achievable gain.
  const CellGainModel by_error = CellGainModel::fit(cal.cell_samples, DecisionInput::expected_error);
  CHECK(by_error.at(3.0, 1.0).gain_slope > 0.7);
  CHECK(by_error.at(3.0, 1.0).gain_slope < 1.2);
  // At the field's GSD the oracle is sure everywhere (one-hot): its finer look removes all of
  // the top's expected error, and the scene check reads that as the gain it is.
  CHECK(by_error.at(3.0, 1.0).proxy_slope == doctest::Approx(by_error.at(3.0, 1.0).gain_slope).epsilon(1e-9));
  for (const CellSample& c : cal.cell_samples)
    if (c.sub_gsd_cm == 1.0) CHECK(c.fine.value(DecisionInput::expected_error) == 0.0);
  // In pixels: an exact re-mapping only corrects (misses found, false positives removed), and
  // a cell's field gain has the sign of what it corrected; the field's own counts are one per
  // field and top-level GSD.
  std::size_t corrected = 0;
  for (const CellSample& c : cal.cell_samples) {
    CHECK(c.field_tp + c.field_fp + c.field_fn > 0);
    CHECK(c.field_tp > 0);
    if (c.sub_gsd_cm != 1.0) continue;
    CHECK(c.delta_tp >= 0);
    CHECK(c.delta_fp <= 0);
    if (c.field_gain > 1e-12) CHECK((c.delta_tp > 0 || c.delta_fp < 0));
    if (c.delta_tp == 0 && c.delta_fp == 0) CHECK(c.field_gain == doctest::Approx(0.0).epsilon(1e-12));
    corrected += c.delta_tp > 0 || c.delta_fp < 0;
  }
  CHECK(corrected > 0);
  std::map<std::pair<std::size_t, double>, std::array<std::int64_t, 3>> field_counts;
  std::size_t same = 0;
  for (const CellSample& c : cal.cell_samples) {
    const std::array<std::int64_t, 3> k{c.field_tp, c.field_fp, c.field_fn};
    same += field_counts.emplace(std::pair{c.field, c.top_gsd_cm}, k).first->second == k;
  }
  CHECK(same == cal.cell_samples.size());
  // Cells seen from the coarsest candidate GSD too (the alternative top level), re-mapped below it.
  CHECK(cells->top_gsds() == std::vector<double>{2.0, 3.0});
  CHECK(std::any_of(cal.cell_samples.begin(), cal.cell_samples.end(),
                    [](const CellSample& c) { return c.top_gsd_cm == 2.0 && c.sub_gsd_cm == 1.0; }));
  CHECK(cell_ranking_capture(cal.cell_samples, DecisionInput::expected_error) > 0.3);
  // The model file keeps the cell model; a mission from it ranks by the same input.
  t::TempDir tmp;
  const DecisionModel model = make_decision_model(std::span<const Field>(fields), oracle.name(), options, cal);
  CHECK(model.coverage == DescentCoverage::ranked);
  model.save(tmp.path() / "model.yaml");
  const DecisionModel back = DecisionModel::load(tmp.path() / "model.yaml");
  REQUIRE(back.decision_function.model().cells().has_value());
  const auto& back_cells = *back.decision_function.model().cells();
  CHECK(back_cells.input() == cells->input());
  REQUIRE(back_cells.points().size() == cells->points().size());
  for (std::size_t k = 0; k < cells->points().size(); ++k) {
    CHECK(back_cells.points()[k].gain_slope == cells->points()[k].gain_slope);
    CHECK(back_cells.points()[k].relabel_noise == cells->points()[k].relabel_noise);
    CHECK(back_cells.points()[k].proxy_slope_sd == cells->points()[k].proxy_slope_sd);
  }
  // Two fields whose finer looks both change the input: the proxy slope's spread between them.
  CHECK(cells->at(3.0, 1.0).proxy_slope_sd >= 0.0);
  CHECK(cells->at(3.0, 1.0).proxy_slope_sd < cells->at(3.0, 1.0).proxy_slope);
  // A file written before proxy_slope_sd existed loads with 0 (the scene check as it was).
  {
    std::ifstream in(tmp.path() / "model.yaml");
    std::ofstream old(tmp.path() / "old.yaml");
    for (std::string line; std::getline(in, line);)
      if (line.find("proxy_slope_sd:") == std::string::npos) old << line << '\n';
  }
  const DecisionModel before = DecisionModel::load(tmp.path() / "old.yaml");
  for (const auto& p : before.decision_function.model().cells()->points()) CHECK(p.proxy_slope_sd == 0.0);
  // The pooling: kept where it is not `cells`, absent (cells, as files before it) otherwise;
  // any other value refused naming the key.
  CHECK(back_cells.pooling() == cells->pooling());
  {
    // The model without its pooling (whichever the folds chose) and the field-entropy lines.
    std::string text;
    {
      std::istringstream in(t::read_file(tmp.path() / "model.yaml"));
      for (std::string line; std::getline(in, line);)
        if (!line.starts_with("    slope_pooling: ") && !line.starts_with("    entropy_")) text += line + "\n";
    }
    const auto input = text.find("    input: ");
    REQUIRE(input != std::string::npos);
    const auto next = text.find('\n', input) + 1;
    t::write_file(tmp.path() / "cells.yaml", text);
    CHECK(DecisionModel::load(tmp.path() / "cells.yaml").decision_function.model().cells()->pooling() ==
          SlopePooling::cells);
    const auto with = [&](const std::string& value) {
      t::write_file(tmp.path() / "pooling.yaml",
                    text.substr(0, next) + "    slope_pooling: " + value + "\n" + text.substr(next));
      return tmp.path() / "pooling.yaml";
    };
    CHECK(DecisionModel::load(with("fields")).decision_function.model().cells()->pooling() == SlopePooling::fields);
    // field-entropy needs β's line per point, and keeps it.
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(with("field-entropy")),
                         doctest::Contains("missing key 'gain_model.cells.entropy_slope'"), std::invalid_argument);
    {
      std::string list = "[";
      for (std::size_t k = 0; k < cells->points().size(); ++k) list += k ? ", 0.5" : "0.5";
      list += "]";
      std::string entropy = "    slope_pooling: field-entropy\n";
      for (const char* key : {"entropy_slope", "entropy_reference", "entropy_low", "entropy_high"})
        entropy += std::string("    ") + key + ": " + list + "\n";
      t::write_file(tmp.path() / "entropy.yaml", text.substr(0, next) + entropy + text.substr(next));
      const DecisionModel e = DecisionModel::load(tmp.path() / "entropy.yaml");
      CHECK(e.decision_function.reads_field_entropy());
      e.save(tmp.path() / "entropy-again.yaml");
      const DecisionModel loaded = DecisionModel::load(tmp.path() / "entropy-again.yaml");
      const CellGainModel& again = *loaded.decision_function.model().cells();
      CHECK(again.pooling() == SlopePooling::field_entropy);
      for (const auto& q : again.points()) CHECK((q.entropy_slope == 0.5 && q.entropy_high == 0.5));
    }
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(with("both")),
                         doctest::Contains("slope_pooling' must be cells, fields or field-entropy"),
                         std::invalid_argument);
  }
  // Each training field's mean input at both top levels: the nominal one's is field_input, and
  // the finer top level's map has less wrong (the oracle's expected error is its share of
  // wrong pixels), so less of it. The file keeps both.
  const auto& reference = std::get<FrontAwarePolicy>(cal.decision_function.rule()).reference();
  const auto& back_reference = std::get<FrontAwarePolicy>(back.decision_function.rule()).reference();
  REQUIRE(back_reference.size() == reference.size());
  for (std::size_t f = 0; f < reference.size(); ++f) {
    const ReferenceCurve& r = reference[f];
    REQUIRE(r.top_inputs.size() == 2);
    CHECK(r.input_at(3.0) == r.field_input);
    CHECK(r.field_input > 0.0);
    CHECK(r.input_at(2.0) > 0.0);
    CHECK(r.input_at(2.0) < r.input_at(3.0));
    CHECK(back_reference[f].input_at(2.0) == doctest::Approx(r.input_at(2.0)));
    CHECK(back_reference[f].input_at(3.0) == doctest::Approx(r.input_at(3.0)));
  }
  const AdaptiveOptions ao = back.adaptive_options(MissionOptions{});
  CHECK(ao.coverage == DescentCoverage::ranked);
  CHECK(ao.cell_input == cells->input());
  // A labels-only choice: only the inputs the labels give are tried.
  options.cell_inputs = {DecisionInput::sigma, DecisionInput::boundary};
  options.slope_poolings = {SlopePooling::fields};  // and one pooling only: no name in the trials
  const CalibrationResult labels_only = calibrate(std::span<const Field>(fields), oracle, options);
  REQUIRE(labels_only.cell_input_scores.size() == 2);
  REQUIRE(labels_only.trials.size() == options.confidences.size());
  CHECK(labels_only.trials.front().description.find("slopes") == std::string::npos);
  CHECK(labels_only.decision_function.model().cells()->pooling() == SlopePooling::fields);
  // Poolings the search cannot use are refused before anything is sampled.
  for (const std::vector<SlopePooling>& bad :
       {std::vector<SlopePooling>{}, std::vector<SlopePooling>{SlopePooling::cells, SlopePooling::cells}}) {
    options.slope_poolings = bad;
    CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                         doctest::Contains("slope_poolings"), std::invalid_argument);
  }
  // A ranked model without its cell model is refused when read.
  std::string text = t::read_file(tmp.path() / "model.yaml");
  const auto at = text.find("  cells:");
  REQUIRE(at != std::string::npos);
  const auto end = text.find("\nrule:", at);
  t::write_file(tmp.path() / "no_cells.yaml", text.substr(0, at) + text.substr(end + 1));
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "no_cells.yaml"), doctest::Contains("cell gain model"),
                       std::invalid_argument);
  // A training field's inputs per top level: one per GSD, none negative.
  const auto inputs = text.find("top_input: [");
  REQUIRE(inputs != std::string::npos);
  const auto line_end = text.find('\n', inputs);
  for (const auto& [bad, message] : {std::pair{"top_input: [0.1]", "as many 'top_input' as 'top_input_gsd_cm'"},
                                     std::pair{"top_input: [-0.1, 0.1]", "top_inputs of GSD > 0 and input >= 0"}}) {
    t::write_file(tmp.path() / "bad_inputs.yaml", text.substr(0, inputs) + bad + text.substr(line_end));
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "bad_inputs.yaml"), doctest::Contains(message),
                         std::invalid_argument);
  }
}

TEST_CASE("calibration: field-entropy is tried only where the training fields' entropies make a line") {
  // Fields of one cell per x at 15 -> 5 cm/px each, gaining about b_f x with b_f on a line in
  // the field's mean entropy u_f.
  const auto fields_at = [](const std::vector<double>& entropy) {
    std::vector<std::vector<CellSample>> cells(entropy.size());
    for (std::size_t f = 0; f < entropy.size(); ++f)
      for (double x : {0.1, 0.2, 0.3}) {
        CellSample c;
        c.field = f;
        c.top_gsd_cm = 15.0;
        c.sub_gsd_cm = 5.0;
        c.top.values.fill(NAN);
        c.top.values[index_of(DecisionInput::expected_error)] = x;
        c.top.values[index_of(DecisionInput::entropy)] = entropy[f];
        c.top.field_px = 1000.0;
        c.field_sigma = 0.1;
        c.field_share = 1e-3;
        c.field_gain = (-0.3 + entropy[f] + 0.01 * x) * x * c.field_share / c.field_sigma;
        c.relabelled = 0.5 * x;
        cells[f].push_back(c);
      }
    return cells;
  };
  const std::vector<SlopePooling> all{SlopePooling::field_entropy, SlopePooling::cells, SlopePooling::fields};
  CHECK(detail::distinct_poolings(all, fields_at({0.2, 0.4, 0.6}), DecisionInput::expected_error) == all);
  // The same entropy on every field, or two fields: no line, left out.
  const std::vector<SlopePooling> rest{SlopePooling::cells, SlopePooling::fields};
  CHECK(detail::distinct_poolings(all, fields_at({0.0, 0.0, 0.0}), DecisionInput::expected_error) == rest);
  CHECK(detail::distinct_poolings(all, fields_at({0.2, 0.6}), DecisionInput::expected_error) == rest);
  // Asked for alone, it stays (it is the fields pooling there).
  CHECK(detail::distinct_poolings({SlopePooling::field_entropy}, fields_at({0.0, 0.0, 0.0}),
                                  DecisionInput::expected_error) ==
        std::vector<SlopePooling>{SlopePooling::field_entropy});
}
TEST_CASE("calibration: another slope pooling replaces the first only where the folds prefer it beyond their noise") {
  const auto select = [](const std::vector<RuleTrial>& trials) {
    std::vector<const RuleTrial*> p;
    for (const auto& t : trials) p.push_back(&t);
    return adaptseg::detail::select_pooling(p);
  };
  // Better on every fold by 0.002 to 0.004: mean difference 0.003, standard error 0.0003.
  CHECK(select({trial({0.0, 0.01, 0.0, 0.02, 0.0}), trial({0.002, 0.013, 0.004, 0.023, 0.003})}) == 1);
  // Better on average by 0.0008, from one fold of five (+0.005, another -0.001): standard error
  // 0.0011, not beyond it.
  CHECK(select({trial({0.0, 0.01, 0.0, 0.02, 0.0}), trial({0.0, 0.009, 0.0, 0.025, 0.0})}) == 0);
  // Just beyond it: +0.006 on one fold and +0.001 on another (mean 0.0014, standard error 0.0012).
  CHECK(select({trial({0.0, 0.01, 0.0, 0.02, 0.0}), trial({0.001, 0.01, 0.0, 0.026, 0.0})}) == 1);
  // Equal, or worse: the first.
  CHECK(select({trial({0.0, 0.01}), trial({0.0, 0.01})}) == 0);
  CHECK(select({trial({0.0, 0.01}), trial({-0.001, 0.005})}) == 0);
  // Of several beyond the noise, the best mean; one alone is the one.
  CHECK(select({trial({0.0, 0.0, 0.0}), trial({0.01, 0.011, 0.012}), trial({0.02, 0.021, 0.022})}) == 2);
  CHECK(select({trial({0.0, 0.01})}) == 0);
  // Better on one fold alone: the mean difference d/n equals the standard error d/n, a tie that
  // rounding would decide; the rule's tolerance keeps the first (the margins of building, tile 1,
  // whose finest descent rounding once chose).
  for (const double d : {0.0177, 0.0035, 0.02})
    CHECK(select({trial({0.0111, -0.0015, -0.0047, 0.0, 0.0065}),
                  trial({0.0111, -0.0015, -0.0047 + d, 0.0, 0.0065})}) == 0);
  // On two folds it is beyond the noise.
  CHECK(select({trial({0.0, 0.0, 0.0, 0.0, 0.0}), trial({0.0, 0.01, 0.01, 0.0, 0.0})}) == 1);
}
TEST_CASE("calibration: two looks at one ground count once in the one-standard-error rule") {
  const std::vector<RuleTrial> trials{trial({0.0, 0.0, 0.0, 0.0, 0.0, 0.0}), trial({0.01, 0.01, 0.0, 0.0, 0.0, 0.0})};
  const std::vector<const RuleTrial*> p{&trials[0], &trials[1]};
  // Six fields: better on two of them, beyond the noise.
  CHECK(adaptseg::detail::select_pooling(p) == 1);
  // Three grounds, each seen by two networks: better on one ground alone, never enough.
  const std::vector<std::size_t> grounds{0, 0, 2, 2, 4, 4};
  CHECK(adaptseg::detail::select_pooling(p, grounds) == 0);
  // Every fold its own ground: as without grounds.
  const std::vector<std::size_t> own{0, 1, 2, 3, 4, 5};
  CHECK(adaptseg::detail::select_pooling(p, own) == 1);
  // Better on two grounds of three (one look each): beyond the noise of the grounds' means.
  const std::vector<RuleTrial> two{trial({0.0, 0.0, 0.0, 0.0, 0.0, 0.0}), trial({0.01, 0.0, 0.01, 0.0, 0.0, 0.0})};
  CHECK(adaptseg::detail::select_pooling(std::vector<const RuleTrial*>{&two[0], &two[1]}, grounds) == 1);
}

TEST_CASE("calibration: a field seen by two networks leaves its fold with its every look") {
  const std::vector<Field> two = two_blob_fields();
  const std::vector<Field> fields{two[0], two[0], two[1]};  // field 0 looked at twice
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  options.field_grounds = {0, 0, 2};
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  // One fold per look; the two looks of field 0, each with a model of field 1 alone (the other
  // look left out with it), fly the same mission (one segmenter here).
  REQUIRE(!cal.trials.empty());
  for (const RuleTrial& t : cal.trials) {
    REQUIRE(t.margins.size() == 3);
    CHECK(t.margins[0] == t.margins[1]);
  }
  // ... the fold of field 0 given once, beside field 1 (the same model: fitted on field 1).
  CalibrationOptions once = options;
  once.field_grounds.clear();
  const CalibrationResult single = calibrate(std::span<const Field>(two), oracle, once);
  REQUIRE(single.trials.size() == cal.trials.size());
  for (std::size_t k = 0; k < cal.trials.size(); ++k) {
    REQUIRE(single.trials[k].margins.size() == 2);
    CHECK(single.trials[k].margins[0] == doctest::Approx(cal.trials[k].margins[0]).epsilon(1e-12));
  }
  // Had the fold of one look kept the other, one ground of two would be its own model: given
  // only looks of one ground, the folds have nothing to fit and the calibration says so.
  const std::vector<Field> one{two[0], two[0]};
  options.field_grounds = {0, 0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(one), oracle, options),
                       doctest::Contains("every training field is of one ground"), std::invalid_argument);
  // Grounds not one per field, or naming another than the first of their ground: refused.
  options.field_grounds = {0, 0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("one ground per training field"), std::invalid_argument);
  options.field_grounds = {0, 2, 2};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("must name the first field"), std::invalid_argument);
  // The gain ratios leave one flight out, not a ground: not with grounds.
  options.field_grounds = {0, 0, 2};
  options.gain_ratios = true;
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("not with field_grounds"), std::invalid_argument);
}

TEST_CASE(
    "calibration: several top-level choices, each with every setting, the first kept unless another's is beyond the "
    "noise") {
  const std::vector<Field> fields = two_blob_fields();
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  options.top_levels = {TopLevelChoice::hull, TopLevelChoice::undominated};
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  // Every z with each choice, named by it; the one kept first, and the model's rule flies it.
  REQUIRE(cal.trials.size() == 4);
  int hull = 0, undominated = 0;
  for (const auto& trial : cal.trials) {
    hull += trial.description.ends_with(" top=hull");
    undominated += trial.description.ends_with(" top=undominated");
  }
  CHECK(hull == 2);
  CHECK(undominated == 2);
  const FrontAwarePolicy& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  CHECK(cal.trials.front().description.ends_with(" top=" + to_string(rule.params().top_level)));
  // The first choice (hull) kept unless the other's best z beats its best by more than one
  // standard error of their paired fold margins (choose_setting's rule, tested on its own below).
  const RuleTrial* best_hull = nullptr;
  const RuleTrial* best_undominated = nullptr;
  for (const auto& trial : cal.trials) {
    const RuleTrial*& best = trial.description.ends_with(" top=hull") ? best_hull : best_undominated;
    if (!best || trial.front_margin > best->front_margin) best = &trial;
  }
  REQUIRE(best_hull != nullptr);
  REQUIRE(best_undominated != nullptr);
  REQUIRE(best_hull->margins.size() == 2);
  REQUIRE(best_undominated->margins.size() == 2);
  const std::vector<const RuleTrial*> levels{best_hull, best_undominated};
  const bool beyond = adaptseg::detail::select_pooling(levels) == 1;
  CHECK(rule.params().top_level == (beyond ? TopLevelChoice::undominated : TopLevelChoice::hull));
  // One choice: no name in the trials; none: the parameters' own (as before the list).
  options.top_levels = {TopLevelChoice::undominated};
  CHECK(calibrate(std::span<const Field>(fields), oracle, options).trials.front().description.find("top=") ==
        std::string::npos);
  options.top_levels.clear();
  options.front_aware.top_level = TopLevelChoice::hull;
  const CalibrationResult own = calibrate(std::span<const Field>(fields), oracle, options);
  CHECK(own.trials.size() == 2);
  CHECK(std::get<FrontAwarePolicy>(own.decision_function.rule()).params().top_level == TopLevelChoice::hull);
  // A choice named twice is refused up front.
  options.top_levels = {TopLevelChoice::hull, TopLevelChoice::hull};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("top_levels names a choice twice"), std::invalid_argument);
}

TEST_CASE("calibration: the finest descent GSD tried with the setting kept, the first kept unless another is better") {
  const std::vector<Field> fields = two_blob_fields();
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  const std::vector<double> candidates = options.adaptive.candidate_gsd_cm;
  REQUIRE(candidates.size() >= 2);
  const double coarsest = *std::max_element(candidates.begin(), candidates.end());
  options.finest_descent_gsd_cm = {0.0, coarsest};
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  // Every z with the first (no limit), then the setting kept with the other: one trial more.
  const std::size_t zs = options.confidences.size();
  REQUIRE(cal.trials.size() == zs + 1);
  int any = 0, limited = 0;
  for (const auto& trial : cal.trials) {
    any += trial.description.ends_with(" finest=any");
    limited += trial.description.ends_with(" finest=" + adaptseg::detail::format_number(coarsest));
  }
  CHECK(any == static_cast<int>(zs));
  CHECK(limited == 1);
  // The one kept is first, and the model's rule flies its limit; it is the limited trial only
  // where that beats the same setting without the limit beyond the folds' noise.
  const std::string suffix = " finest=" + adaptseg::detail::format_number(coarsest);
  const FrontAwarePolicy& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  const bool kept_limit = cal.trials.front().description.ends_with(suffix);
  CHECK(rule.params().finest_descent_gsd_cm == (kept_limit ? coarsest : 0.0));
  const auto limited_trial = std::find_if(cal.trials.begin(), cal.trials.end(),
                                          [&](const RuleTrial& t) { return t.description.ends_with(suffix); });
  REQUIRE(limited_trial != cal.trials.end());
  CHECK(limited_trial->margins.size() == fields.size());
  const std::string stem = limited_trial->description.substr(0, limited_trial->description.size() - suffix.size());
  const auto unlimited = std::find_if(cal.trials.begin(), cal.trials.end(),
                                      [&](const RuleTrial& t) { return t.description == stem + " finest=any"; });
  REQUIRE(unlimited != cal.trials.end());
  const std::vector<const RuleTrial*> pair{&*unlimited, &*limited_trial};
  CHECK(adaptseg::detail::select_pooling(pair) == (kept_limit ? 1u : 0u));
  CHECK(cal.trials.front().description == (kept_limit ? limited_trial : unlimited)->description);
  // One GSD: no name in the trials, and the rule flies it; none: no limit (as before the list).
  options.finest_descent_gsd_cm = {coarsest};
  const CalibrationResult one = calibrate(std::span<const Field>(fields), oracle, options);
  CHECK(one.trials.size() == zs);
  CHECK(one.trials.front().description.find("finest=") == std::string::npos);
  CHECK(std::get<FrontAwarePolicy>(one.decision_function.rule()).params().finest_descent_gsd_cm == coarsest);
  options.finest_descent_gsd_cm.clear();
  CHECK(std::get<FrontAwarePolicy>(calibrate(std::span<const Field>(fields), oracle, options).decision_function.rule())
            .params()
            .finest_descent_gsd_cm == 0.0);
  // A GSD named twice, or a negative one, is refused up front.
  options.finest_descent_gsd_cm = {0.0, 0.0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("finest_descent_gsd_cm names a limit twice"), std::invalid_argument);
  options.finest_descent_gsd_cm = {-1.0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("finest_descent_gsd_cm must hold finite GSDs >= 0"), std::invalid_argument);
  // It belongs to the front-aware rule: the utility rule refuses it rather than ignore it.
  options.finest_descent_gsd_cm = {0.0, coarsest};
  options.rule = "utility";
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("finest_descent_gsd_cm belongs to the front-aware rule"),
                       std::invalid_argument);
}

TEST_CASE(
    "calibration: the longest descent tried with every z and the setting kept, the first kept unless another "
    "is better") {
  const std::vector<Field> fields = two_blob_fields();
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  const std::size_t zs = options.confidences.size();
  // Every z with the first (no limit), then every z again with the other.
  const double cap = 1.0;  // shorter than any descent of these fields: none is taken
  options.longest_descent_s = {0.0, cap};
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  REQUIRE(cal.trials.size() == 2 * zs);
  std::vector<const RuleTrial*> unlimited, limited;
  for (const auto& trial : cal.trials) {
    if (trial.description.ends_with(" longest=any")) unlimited.push_back(&trial);
    if (trial.description.ends_with(" longest=1")) limited.push_back(&trial);
  }
  REQUIRE(unlimited.size() == zs);
  REQUIRE(limited.size() == zs);
  for (const RuleTrial* t : limited) CHECK(t->descents == 0);
  CHECK(std::any_of(unlimited.begin(), unlimited.end(), [](const RuleTrial* t) { return t->descents > 0; }));
  // Among the limited trials the largest z is kept (all tie: none descends); against the
  // unlimited one kept, the one-standard-error rule decides, and the model flies its limit.
  const FrontAwarePolicy& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  const bool kept_limit = cal.trials.front().description.ends_with(" longest=1");
  CHECK(rule.params().longest_descent_s == (kept_limit ? cap : 0.0));
  if (kept_limit) CHECK(rule.params().confidence == options.confidences.back());
  // One limit: no name in the trials, no second search, and the rule flies it.
  options.longest_descent_s = {cap};
  const CalibrationResult one = calibrate(std::span<const Field>(fields), oracle, options);
  CHECK(one.trials.size() == zs);
  CHECK(one.trials.front().description.find("longest=") == std::string::npos);
  CHECK(std::get<FrontAwarePolicy>(one.decision_function.rule()).params().longest_descent_s == cap);
  for (const auto& trial : one.trials) CHECK(trial.descents == 0);
  // A limit named twice, or a negative one, is refused up front; the utility rule refuses it.
  options.longest_descent_s = {30.0, 30.0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("longest_descent_s names a limit twice"), std::invalid_argument);
  options.longest_descent_s = {-1.0};
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("longest_descent_s must hold finite seconds >= 0"), std::invalid_argument);
  options.longest_descent_s = {0.0, 30.0};
  options.rule = "utility";
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("longest_descent_s belongs to the front-aware rule"), std::invalid_argument);
}

TEST_CASE(
    "calibration: the relabel transfer b, region spread τ_r and field spread ω_χ measured on the training fields' "
    "cells, with the relabelled factor") {
  std::vector<Field> fields = two_blob_fields();
  fields.push_back(t::blob_field(1200, 1100, 1.0, 7, 15));
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  options.relabel_transfer = true;
  // Refused up front without the relabelled factor, each.
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("relabel_transfer (how far the gain follows the relabelled share) needs the "
                                         "field factor 'relabelled'"),
                       std::invalid_argument);
  options.relabel_transfer = false;
  options.relabel_region_spread = true;
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("relabel_region_spread"), std::invalid_argument);
  options.relabel_region_spread = false;
  options.relabel_field_spread = true;
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, options),
                       doctest::Contains("relabel_field_spread"), std::invalid_argument);
  options.relabel_region_spread = true;
  options.relabel_transfer = true;
  options.front_aware.field_factor = FieldFactorSource::relabelled;
  const CalibrationResult cal = calibrate(std::span<const Field>(fields), oracle, options);
  const FrontAwarePolicy& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  // The model's b and τ_r: every field's cells, with the input the cells are ranked by (not
  // asked, each stays as given: 1 and 0, as every other calibration here shows).
  const DecisionInput input = rule.model().cells()->input();
  const double b = relabel_transfer(cal.cell_samples, input);
  CHECK(b < 1.0);  // measured (on these blob fields the oracle relabels most where it gains least: 0)
  CHECK(rule.params().relabel_transfer == b);
  const double tau = relabel_region_sd(cal.cell_samples, input);
  CHECK(tau > 0.0);
  CHECK(rule.params().relabel_region_sd == tau);
  const double omega_chi = relabel_field_sd(cal.cell_samples, input);
  CHECK(omega_chi >= 0.1);
  CHECK(rule.params().relabel_field_sd == omega_chi);
  CHECK(rule.params().field_factor == FieldFactorSource::relabelled);
}

TEST_CASE(
    "calibration: the setting kept, per top level its pooling's best z, then the first top level unless another is "
    "beyond the noise") {
  using adaptseg::detail::FrontAwareSetting;
  adaptseg::detail::FrontAwareGrid grid;
  grid.poolings = {SlopePooling::cells, SlopePooling::fields};
  grid.top_levels = {TopLevelChoice::undominated, TopLevelChoice::hull};
  // Settings in the search's order: pooling, then top level, then z.
  std::vector<FrontAwareSetting> settings;
  for (std::size_t p = 0; p < 2; ++p)
    for (std::size_t l = 0; l < 2; ++l)
      for (double z : {0.0, 1.0}) settings.push_back({.pooling = p, .top_level = l, .z = z, .params = {}});
  const auto choose = [&](const std::vector<RuleTrial>& trials) {
    return adaptseg::detail::choose_setting(trials, settings, grid);
  };
  const RuleTrial zero = trial({0.0, 0.0, 0.0}), small = trial({0.001, 0.0, 0.0});
  // All alike: the first level, the first pooling, the larger z.
  CHECK(choose({zero, zero, zero, zero, zero, zero, zero, zero}) == 1);
  // The second top level better (hull, cells, z = 0) on one fold alone: its mean is exactly
  // its standard error, not beyond the noise, and the first level stays (until 2026-12-05 any
  // larger mean took it).
  CHECK(choose({zero, zero, small, zero, zero, zero, zero, zero}) == 1);
  // Better on average but worse on a fold, by less than the noise: the first level stays.
  const RuleTrial noisy = trial({0.002, -0.001, 0.0});
  CHECK(choose({zero, zero, noisy, zero, zero, zero, zero, zero}) == 1);
  // Better on every fold: beyond the noise, kept.
  const RuleTrial clear = trial({0.002, 0.003, 0.002});
  CHECK(choose({zero, zero, clear, zero, zero, zero, zero, zero}) == 2);
  // The second pooling better than the first within its level on average, but not beyond the
  // folds' noise: that level's first pooling stays, and so the first level (equal means).
  CHECK(choose({zero, zero, zero, zero, noisy, zero, zero, zero}) == 1);
  // Beyond the noise (better on every fold): that pooling, and with it its level.
  CHECK(choose({zero, zero, zero, zero, zero, zero, clear, zero}) == 6);
  // The levels judged at the pooling each keeps: hull's noisy gain at its first pooling is no
  // reason to leave the first level, its clear gain at the second pooling (beyond its first
  // pooling's noise too) is.
  CHECK(choose({zero, zero, noisy, zero, zero, zero, clear, zero}) == 6);
}

TEST_CASE("calibration: confidence levels the training fields cannot tell apart go to the more cautious") {
  // At z = 20 and z = 40 no forecast's lower bound beats the curve: neither setting descends,
  // both fly the lawnmower and tie exactly. The tie goes to the larger z, in either order.
  const Field f = t::blob_field(1300, 1000, 1.0, 4, 15);
  OracleSegmenter oracle(f.num_classes());
  for (const std::vector<double>& levels : {std::vector<double>{20.0, 40.0}, std::vector<double>{40.0, 20.0}}) {
    CalibrationOptions options = small_options();
    options.confidences = levels;
    const CalibrationResult cal = calibrate(f, oracle, options);
    REQUIRE(cal.trials.size() == 2);
    CHECK(cal.trials[0].front_margin == cal.trials[1].front_margin);
    for (const auto& trial : cal.trials) CHECK(trial.descents == 0);
    CHECK(std::get<FrontAwarePolicy>(cal.decision_function.rule()).params().confidence == 40.0);
    CHECK(cal.trials.front().description == "front-aware z=40");
  }
}

TEST_CASE("calibration: gain ratios, realised over forecast field gain per descent GSD, shrunk towards 1") {
  // One fold's flight: descents to 1 cm/px forecast 0.01 and 0.03 that realised nothing, one to
  // 2 cm/px forecast 0.02 that realised 0.06, one to 3 cm/px forecast 0.001 that realised 1 (kept
  // at 4), one whose rule forecast no field gain (left out).
  AdaptiveResult flight;
  const auto descend = [&](double gsd, double forecast, double realised) {
    DecisionRecord rec;
    rec.candidates = {Candidate{gsd, 5.0, 1, 10.0}};
    rec.decision.descend = true;
    rec.decision.gsd_cm = gsd;
    CandidateScore score;
    score.predicted_field_gain = forecast;
    rec.decision.scores = {score};
    RealisedDescent r;
    r.decision = flight.decisions.size();
    r.field_gain = realised;
    flight.decisions.push_back(rec);
    flight.realised.push_back(r);
  };
  descend(2.0, 0.02, 0.06);
  descend(1.0, 0.01, 0.0);
  descend(1.0, 0.03, 0.0);
  descend(3.0, 0.001, 1.0);
  descend(4.0, std::numeric_limits<double>::quiet_NaN(), 0.5);
  const std::vector<AdaptiveResult> flights{flight};
  const std::vector<GainRatio> ratios = detail::fold_gain_ratios(flights);
  REQUIRE(ratios.size() == 3);
  CHECK(ratios[0].gsd_cm == 1.0);
  CHECK(ratios[0].ratio == doctest::Approx((0.0 + 0.04) / (0.04 + 0.04)));  // prior 2 x mean forecast 0.02
  CHECK(ratios[1].gsd_cm == 2.0);
  CHECK(ratios[1].ratio == doctest::Approx((0.06 + 0.04) / (0.02 + 0.04)));
  CHECK(ratios[2].gsd_cm == 3.0);
  CHECK(ratios[2].ratio == 4.0);
  CHECK(detail::fold_gain_ratios({}).empty());
}

TEST_CASE("calibration: margin biases, realised less forecast margin per second of descent, shrunk towards 0") {
  // Flight 0 over a field whose lawnmowers rise 0.5 -> 0.7 from 100 to 200 s: a descent to
  // 1 cm/px of 50 s ending at 150 s, forecast 0.02 - 0.05, realised 0.08 - 0.1 (error +0.01); one
  // to 2 cm/px of 10 s ending past the curve (flat there), forecast 0.01 - 0.002, realised 0
  // (-0.008). Flight 1, 0.3 -> 0.4 from 50 to 150 s: to 1 cm/px, 30 s ending at 100 s, forecast
  // 0.01 - 0.01, realised 0.05 - 0.03 (+0.02); one without a predicted rise (left out).
  std::vector<AdaptiveResult> flights(2);
  const auto descend = [&](std::size_t j, double gsd, double seconds, double end, double gain, double rise,
                           double realised) {
    DecisionRecord rec;
    rec.candidates = {Candidate{gsd, 5.0, 1, seconds}};
    rec.decision.descend = true;
    rec.decision.gsd_cm = gsd;
    CandidateScore score;
    score.predicted_field_gain = gain;
    score.predicted_curve_rise = rise;
    score.predicted_end_s = end;
    rec.decision.scores = {score};
    RealisedDescent r;
    r.decision = flights[j].decisions.size();
    r.field_gain = realised;
    flights[j].decisions.push_back(rec);
    flights[j].realised.push_back(r);
  };
  descend(0, 1.0, 50.0, 150.0, 0.02, 0.05, 0.08);
  descend(0, 2.0, 10.0, 250.0, 0.01, 0.002, 0.0);
  descend(1, 1.0, 30.0, 100.0, 0.01, 0.01, 0.05);
  descend(1, 1.0, 30.0, 100.0, 0.01, std::numeric_limits<double>::quiet_NaN(), 0.5);
  const std::vector<CurvePoint> c0{{100.0, 0.5}, {200.0, 0.7}}, c1{{150.0, 0.4}, {50.0, 0.3}};
  const std::vector<const std::vector<CurvePoint>*> curves{&c0, &c1};
  const std::vector<MarginBias> all = detail::fold_margin_biases(flights, curves);
  REQUIRE(all.size() == 2);
  CHECK(all[0].gsd_cm == 1.0);
  CHECK(all[0].per_s == doctest::Approx(0.03 / (80.0 + 80.0)));  // prior: 2 x mean 40 s at bias 0
  CHECK(all[1].gsd_cm == 2.0);
  CHECK(all[1].per_s == doctest::Approx(-0.008 / (10.0 + 20.0)));
  // Each fold by the other's flight only.
  const std::vector<MarginBias> without_1 = detail::fold_margin_biases(flights, curves, 1);
  REQUIRE(without_1.size() == 2);
  CHECK(without_1[0].per_s == doctest::Approx(0.01 / (50.0 + 100.0)));
  const std::vector<MarginBias> without_0 = detail::fold_margin_biases(flights, curves, 0);
  REQUIRE(without_0.size() == 1);
  CHECK(without_0[0].gsd_cm == 1.0);
  CHECK(without_0[0].per_s == doctest::Approx(0.02 / (30.0 + 60.0)));
  // The gain ratios skip a flight the same way (flight 0's: 0.08 of 0.02, 0 of 0.01).
  const std::vector<GainRatio> ratios_without_1 = detail::fold_gain_ratios(flights, 1);
  REQUIRE(ratios_without_1.size() == 2);
  CHECK(ratios_without_1[0].ratio == doctest::Approx((0.08 + 0.04) / (0.02 + 0.04)));
  CHECK(ratios_without_1[1].ratio == doctest::Approx((0.0 + 0.02) / (0.01 + 0.02)));
}

TEST_CASE("calibration: gain ratios and margin biases measured on the folds where asked for, and kept in the model") {
  const std::vector<Field> fields = two_blob_fields();
  OracleSegmenter oracle(fields.front().num_classes());
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  const auto params = [](const CalibrationResult& c) {
    return std::get<FrontAwarePolicy>(c.decision_function.rule()).params();
  };
  const CalibrationResult plain = calibrate(std::span<const Field>(fields), oracle, options);
  CHECK(params(plain).gain_ratios.empty());  // not asked for
  CHECK(params(plain).margin_biases.empty());
  // The folds descend at z = 0, as the measuring flights fly them.
  const auto z0 = std::find_if(plain.trials.begin(), plain.trials.end(),
                               [](const RuleTrial& t) { return t.description == "front-aware z=0"; });
  REQUIRE(z0 != plain.trials.end());
  REQUIRE(z0->descents > 0);
  options.gain_ratios = true;
  options.margin_biases = true;
  // Measured by flying each field with the model of the others: one field is refused, and so is
  // a rule without a forecast margin.
  CHECK_THROWS_WITH_AS((void)calibrate(fields.front(), oracle, options),
                       doctest::Contains("which needs at least two training fields; count (got 1)"),
                       std::invalid_argument);
  CalibrationOptions utility = options;
  utility.rule = "utility";
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), oracle, utility),
                       doctest::Contains("gain_ratios and margin_biases belong to the front-aware rule"),
                       std::invalid_argument);
  const CalibrationResult measured = calibrate(std::span<const Field>(fields), oracle, options);
  const std::vector<GainRatio> ratios = params(measured).gain_ratios;
  const std::vector<MarginBias> biases = params(measured).margin_biases;
  REQUIRE_FALSE(ratios.empty());
  REQUIRE_FALSE(biases.empty());
  for (const GainRatio& r : ratios) {
    CHECK((r.gsd_cm == 1.0 || r.gsd_cm == 2.0));
    CHECK(r.ratio >= 0.0);
    CHECK(r.ratio <= 4.0);
  }
  for (const MarginBias& b : biases) {
    CHECK((b.gsd_cm == 1.0 || b.gsd_cm == 2.0));
    CHECK(std::isfinite(b.per_s));
  }
  t::TempDir tmp;
  make_decision_model(fields, oracle.name(), options, measured).save(tmp.path() / "model.yaml");
  const FrontAwarePolicy::Params back =
      std::get<FrontAwarePolicy>(DecisionModel::load(tmp.path() / "model.yaml").decision_function.rule()).params();
  REQUIRE(back.gain_ratios.size() == ratios.size());
  for (std::size_t k = 0; k < ratios.size(); ++k) {
    CHECK(back.gain_ratios[k].gsd_cm == ratios[k].gsd_cm);
    CHECK(back.gain_ratios[k].ratio == doctest::Approx(ratios[k].ratio).epsilon(1e-9));
  }
  REQUIRE(back.margin_biases.size() == biases.size());
  for (std::size_t k = 0; k < biases.size(); ++k) {
    CHECK(back.margin_biases[k].gsd_cm == biases[k].gsd_cm);
    CHECK(back.margin_biases[k].per_s == doctest::Approx(biases[k].per_s).epsilon(1e-9));
  }
}

TEST_CASE("calibration: several training fields pool their samples and keep every field's curve") {
  const Field a = t::blob_field(1300, 1000, 1.0, 4, 15);
  const Field b = t::blob_field(1000, 1300, 1.0, 11, 15).sub_field({0, 0, 1, 0.8});
  OracleSegmenter oracle(a.num_classes());
  const std::vector<Field> fields{a, b};
  CalibrationOptions options = small_options();
  options.sigma_prior = CalibrationOptions::SigmaPriorSource::estimated;
  const CalibrationResult cal = calibrate(fields, oracle, options);
  const auto only_a = collect_region_samples(a, oracle, CameraModel(kSmallCamera), 3.0, {1.0, 2.0}, a.interest(),
                                             DescentCoverage::region, 0);
  const auto only_b = collect_region_samples(b, oracle, CameraModel(kSmallCamera), 3.0, {1.0, 2.0}, b.interest(),
                                             DescentCoverage::region, 1);
  CHECK(cal.samples.size() == only_a.size() + only_b.size());
  CHECK(std::count_if(cal.samples.begin(), cal.samples.end(), [](const RegionSample& s) { return s.field == 1; }) ==
        static_cast<long>(only_b.size()));
  REQUIRE(cal.lawnmower_curves.size() == 2);
  const auto& rule = std::get<FrontAwarePolicy>(cal.decision_function.rule());
  REQUIRE(rule.reference().size() == 2);
  CHECK(rule.reference()[1].field == b.name());
  // Each trial flew each field once, with a model fitted without it.
  for (const auto& trial : cal.trials) CHECK(trial.margins.size() == 2);
  // σ̂'s prior estimated on the two fields (asked for): τ their σ's spread (n − 1).
  const double sa = rule.reference()[0].field_sigma, sb = rule.reference()[1].field_sigma;
  CHECK(rule.params().sigma_prior_sd == doctest::Approx(std::abs(sa - sb) / std::sqrt(2.0)));
  CHECK(rule.params().sigma_prior_weight >= 0.01);
  CHECK(rule.params().sigma_prior_weight <= 100.0);
  // By default as given: k = 0.25, no spread.
  const CalibrationResult plain = calibrate(fields, oracle, small_options());
  CHECK(std::get<FrontAwarePolicy>(plain.decision_function.rule()).params().sigma_prior_sd == 0.0);
  CHECK(std::get<FrontAwarePolicy>(plain.decision_function.rule()).params().sigma_prior_weight == 0.25);
  const DecisionModel model = make_decision_model(fields, oracle.name(), options, cal);
  CHECK(model.calibration_fields == std::vector<std::string>{a.name(), b.name()});
  // The file keeps σ̂'s prior; a file written before it existed (no `sigma_prior_sd`) reads as
  // τ = 0, the rule as it was then.
  t::TempDir tmp;
  model.save(tmp.path() / "model.yaml");
  const auto rule_of = [](const DecisionModel& m) {
    return std::get<FrontAwarePolicy>(m.decision_function.rule()).params();
  };
  const DecisionModel back = DecisionModel::load(tmp.path() / "model.yaml");
  CHECK(rule_of(back).sigma_prior_sd == rule.params().sigma_prior_sd);
  CHECK(rule_of(back).sigma_prior_weight == rule.params().sigma_prior_weight);
  std::stringstream text;
  text << std::ifstream(tmp.path() / "model.yaml").rdbuf();
  std::string old = text.str();
  const auto at = old.find("  sigma_prior_sd:");
  REQUIRE(at != std::string::npos);
  old.erase(at, old.find('\n', at) + 1 - at);
  std::ofstream(tmp.path() / "old.yaml") << old;
  CHECK(rule_of(DecisionModel::load(tmp.path() / "old.yaml")).sigma_prior_sd == 0.0);
  CHECK(rule_of(back).curve == CurveSource::training);
  // The lawnmower curve's kind is kept (files without the keys: the training fields' curves).
  DecisionModel corrected = model;
  auto& policy = std::get<FrontAwarePolicy>(corrected.decision_function.rule());
  FrontAwarePolicy::Params p = policy.params();
  for (const CurveSource source : {CurveSource::field, CurveSource::corrected, CurveSource::mixture}) {
    p.curve = source;
    policy.set_params(p);
    corrected.save(tmp.path() / "corrected.yaml");
    CHECK(rule_of(DecisionModel::load(tmp.path() / "corrected.yaml")).curve == source);
  }
  p.curve = CurveSource::corrected;
  // A copy of model file `from` with the rest of the line from the first `marker` on replaced by
  // `replacement`, written to `to`.
  const auto edited = [&](const char* from, std::string_view marker, std::string_view replacement, const char* to) {
    std::stringstream in;
    in << std::ifstream(tmp.path() / from).rdbuf();
    std::string content = in.str();
    const auto pos = content.find(marker);
    REQUIRE(pos != std::string::npos);
    content.replace(pos, content.find('\n', pos) - pos, replacement);
    std::ofstream(tmp.path() / to) << content;
    return tmp.path() / to;
  };
  // So is the top-level rule (files without the key: undominated); a name it does not know is refused.
  CHECK(rule_of(back).top_level == TopLevelChoice::undominated);
  // So are the gain ratios (files without the keys: none); lists of two lengths are refused.
  CHECK(rule_of(back).gain_ratios.empty());
  p.gain_ratios = {{1.0, 0.5}, {2.0, 1.25}};
  policy.set_params(p);
  corrected.save(tmp.path() / "ratios.yaml");
  const std::vector<GainRatio> read_back = rule_of(DecisionModel::load(tmp.path() / "ratios.yaml")).gain_ratios;
  REQUIRE(read_back.size() == 2);
  CHECK(read_back[0].gsd_cm == 1.0);
  CHECK(read_back[0].ratio == 0.5);
  CHECK(read_back[1].gsd_cm == 2.0);
  CHECK(read_back[1].ratio == 1.25);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(
                           edited("ratios.yaml", "  gain_ratio: [0.5, 1.25]", "  gain_ratio: [0.5]", "uneven.yaml")),
                       doctest::Contains("'rule.gain_ratio' needs as many values as 'rule.gain_ratio_gsd_cm'"),
                       std::invalid_argument);
  p.gain_ratios.clear();
  // So are the margin biases (files without the keys: none); lists of two lengths are refused.
  CHECK(rule_of(back).margin_biases.empty());
  p.margin_biases = {{1.0, -0.0005}, {2.0, 0.00025}};
  policy.set_params(p);
  corrected.save(tmp.path() / "biases.yaml");
  const std::vector<MarginBias> biases_back = rule_of(DecisionModel::load(tmp.path() / "biases.yaml")).margin_biases;
  REQUIRE(biases_back.size() == 2);
  CHECK(biases_back[0].gsd_cm == 1.0);
  CHECK(biases_back[0].per_s == -0.0005);
  CHECK(biases_back[1].gsd_cm == 2.0);
  CHECK(biases_back[1].per_s == 0.00025);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("biases.yaml", "  margin_bias_per_s: [",
                                                        "  margin_bias_per_s: [-0.0005]", "uneven_biases.yaml")),
                       doctest::Contains("'rule.margin_bias_per_s' needs as many values as 'rule.margin_bias_gsd_cm'"),
                       std::invalid_argument);
  p.margin_biases.clear();
  // The curve agreement: kept (files without the key: 0, no check); outside [0, 1] refused.
  CHECK(rule_of(back).curve_agreement == 0.0);
  p.curve_agreement = 0.75;
  policy.set_params(p);
  corrected.save(tmp.path() / "agreement.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "agreement.yaml")).curve_agreement == 0.75);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("agreement.yaml", "curve_agreement: 0.75",
                                                        "curve_agreement: 1.5", "wrong_agreement.yaml")),
                       doctest::Contains("curve_agreement must be in [0, 1]"), std::invalid_argument);
  p.curve_agreement = 0.0;
  // The finest descent GSD: kept (files without the key: 0, no limit); a negative one refused.
  CHECK(rule_of(back).finest_descent_gsd_cm == 0.0);
  p.finest_descent_gsd_cm = 2.0;
  policy.set_params(p);
  corrected.save(tmp.path() / "finest.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "finest.yaml")).finest_descent_gsd_cm == 2.0);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("finest.yaml", "finest_descent_gsd_cm: 2",
                                                        "finest_descent_gsd_cm: -2", "wrong_finest.yaml")),
                       doctest::Contains("finest_descent_gsd_cm must be finite and >= 0"), std::invalid_argument);
  p.finest_descent_gsd_cm = 0.0;
  // The longest descent: kept (files without the key: 0, no limit); a negative one refused.
  CHECK(rule_of(back).longest_descent_s == 0.0);
  p.longest_descent_s = 45.0;
  policy.set_params(p);
  corrected.save(tmp.path() / "longest.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "longest.yaml")).longest_descent_s == 45.0);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("longest.yaml", "longest_descent_s: 45",
                                                        "longest_descent_s: -45", "wrong_longest.yaml")),
                       doctest::Contains("longest_descent_s must be finite and >= 0"), std::invalid_argument);
  p.longest_descent_s = 0.0;
  // The jump guard's bound: kept (files without the key: none, infinity).
  CHECK(std::isinf(rule_of(back).jump_bound));
  p.jump_bound = 0.25;
  policy.set_params(p);
  corrected.save(tmp.path() / "guard.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "guard.yaml")).jump_bound == 0.25);
  p.jump_bound = std::numeric_limits<double>::infinity();
  p.top_level = TopLevelChoice::hull;
  policy.set_params(p);
  corrected.save(tmp.path() / "hull.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "hull.yaml")).top_level == TopLevelChoice::hull);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("hull.yaml", "top_level: hull", "top_level: hul", "bad.yaml")),
                       doctest::Contains("'rule.top_level' must be undominated or hull (got 'hul')"),
                       std::invalid_argument);
  p.top_level = TopLevelChoice::undominated;
  // The field factor's source: kept (files without the key: the scene check); unknown refused.
  CHECK(rule_of(back).field_factor == FieldFactorSource::scene_check);
  p.field_factor = FieldFactorSource::relabelled;
  policy.set_params(p);
  corrected.save(tmp.path() / "relabelled.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "relabelled.yaml")).field_factor == FieldFactorSource::relabelled);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("relabelled.yaml", "field_factor: relabelled",
                                                        "field_factor: relabeled", "bad_factor.yaml")),
                       doctest::Contains("'rule.field_factor' must be scene-check or relabelled (got 'relabeled')"),
                       std::invalid_argument);
  // b, how far the gain follows the relabelled factor: kept where not 1 (absent: 1); out of
  // [0, 1] refused.
  CHECK(rule_of(back).relabel_transfer == 1.0);
  p.relabel_transfer = 0.375;
  policy.set_params(p);
  corrected.save(tmp.path() / "transfer.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "transfer.yaml")).relabel_transfer == 0.375);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(edited("transfer.yaml", "relabel_transfer: 0.375",
                                                        "relabel_transfer: 1.5", "bad_transfer.yaml")),
                       doctest::Contains("relabel_transfer must be in [0, 1]"), std::invalid_argument);
  p.relabel_transfer = 1.0;
  // τ_r and ω_χ likewise: kept where above 0 (absent: 0).
  for (double FrontAwarePolicy::Params::*spread :
       {&FrontAwarePolicy::Params::relabel_region_sd, &FrontAwarePolicy::Params::relabel_field_sd}) {
    CHECK(rule_of(back).*spread == 0.0);
    p.*spread = 0.25;
    policy.set_params(p);
    corrected.save(tmp.path() / "spread.yaml");
    CHECK(rule_of(DecisionModel::load(tmp.path() / "spread.yaml")).*spread == 0.25);
    p.*spread = 0.0;
  }
  // Learning that may only stop descents: kept where set (absent: false).
  CHECK_FALSE(rule_of(back).learn_stop_only);
  p.learn_stop_only = true;
  policy.set_params(p);
  corrected.save(tmp.path() / "stop_only.yaml");
  CHECK(rule_of(DecisionModel::load(tmp.path() / "stop_only.yaml")).learn_stop_only);
  p.learn_stop_only = false;
  // Fields of another class set are refused.
  const Field other("o", 1.0, a.labels(), {{"a", {0, 0, 0}}, {"b", {1, 1, 1}}, {"c", {2, 2, 2}}}, {1});
  const std::vector<Field> mixed{a, other};
  CHECK_THROWS_WITH_AS((void)calibrate(mixed, oracle, options), doctest::Contains("classes"), std::invalid_argument);
}

namespace {
/// The oracle under another name, and one that sees one class less (its pixels as the class
/// before it): two backends of one type for a cross-fitted calibration.
class NamedOracle {
 public:
  NamedOracle(int num_classes, std::string name, bool blind)
      : oracle_(num_classes), name_(std::move(name)), blind_(blind) {}
  [[nodiscard]] std::string name() const { return name_; }
  [[nodiscard]] cv::Mat segment(const Image& image) {
    ++images;
    cv::Mat labels = oracle_.segment(image);
    if (blind_) labels.setTo(1, labels == 2);
    return labels;
  }
  int images = 0;

 private:
  OracleSegmenter oracle_;
  std::string name_;
  bool blind_;
};
}  // namespace

TEST_CASE("calibration: each training field segmented by its own backend (cross-fitting)") {
  const Field a = t::blob_field(1300, 1000, 1.0, 4, 15);
  const Field b = t::blob_field(1000, 1300, 1.0, 11, 15).sub_field({0, 0, 1, 0.8});
  const std::vector<Field> fields{a, b};
  const CalibrationOptions options = small_options();
  NamedOracle plain(a.num_classes(), "oracle", false), blind(a.num_classes(), "blind oracle", true);
  const std::vector<NamedOracle*> backends{&plain, &blind};
  const CalibrationResult cal =
      calibrate(std::span<const Field>(fields), std::span<NamedOracle* const>(backends), options);
  CHECK(plain.images > 0);
  CHECK(blind.images > 0);
  CHECK(cal.field_backends == std::vector<std::string>{"oracle", "blind oracle"});
  // Field a's samples are those its own backend gives, field b's those of the blind one.
  NamedOracle plain_again(a.num_classes(), "oracle", false), blind_again(a.num_classes(), "blind oracle", true);
  const auto only_a = collect_region_samples(a, plain_again, CameraModel(kSmallCamera), 3.0, {1.0, 2.0}, a.interest(),
                                             DescentCoverage::region, 0);
  const auto only_b = collect_region_samples(b, blind_again, CameraModel(kSmallCamera), 3.0, {1.0, 2.0}, b.interest(),
                                             DescentCoverage::region, 1);
  REQUIRE(cal.samples.size() == only_a.size() + only_b.size());
  for (std::size_t k = 0; k < cal.samples.size(); ++k) {
    const RegionSample& want = k < only_a.size() ? only_a[k] : only_b[k - only_a.size()];
    CHECK(cal.samples[k].field == want.field);
    CHECK(cal.samples[k].sigma_top == want.sigma_top);
    CHECK(cal.samples[k].miou_sub == want.miou_sub);
  }
  // The blind backend changes what b's samples say: it is not the plain oracle's calibration.
  const auto plain_b = collect_region_samples(b, plain_again, CameraModel(kSmallCamera), 3.0, {1.0, 2.0}, b.interest(),
                                              DescentCoverage::region, 1);
  bool differs = false;
  for (std::size_t k = 0; k < plain_b.size(); ++k) differs = differs || plain_b[k].miou_sub != only_b[k].miou_sub;
  CHECK(differs);
  // The model records the field's backends where one differs from the missions'; the file keeps them.
  const DecisionModel model = make_decision_model(fields, "oracle", options, cal);
  CHECK(model.field_segmenters == std::vector<std::string>{"oracle", "blind oracle"});
  t::TempDir tmp;
  model.save(tmp.path() / "model.yaml");
  CHECK(DecisionModel::load(tmp.path() / "model.yaml").field_segmenters == model.field_segmenters);
  // One backend for every field: nothing recorded, no key in the file.
  const std::vector<NamedOracle*> same{&plain, &plain};
  const CalibrationResult one = calibrate(std::span<const Field>(fields), std::span<NamedOracle* const>(same), options);
  const DecisionModel one_model = make_decision_model(fields, "oracle", options, one);
  CHECK(one_model.field_segmenters.empty());
  one_model.save(tmp.path() / "one.yaml");
  std::stringstream text;
  text << std::ifstream(tmp.path() / "one.yaml").rdbuf();
  CHECK(text.str().find("field_segmenters") == std::string::npos);
  // A backend per field, no fewer, none null.
  const std::vector<NamedOracle*> short_list{&plain};
  CHECK_THROWS_WITH_AS(
      (void)calibrate(std::span<const Field>(fields), std::span<NamedOracle* const>(short_list), options),
      doctest::Contains("one backend per training field"), std::invalid_argument);
  const std::vector<NamedOracle*> with_null{&plain, nullptr};
  CHECK_THROWS_WITH_AS(
      (void)calibrate(std::span<const Field>(fields), std::span<NamedOracle* const>(with_null), options),
      doctest::Contains("null"), std::invalid_argument);
  // A file whose field_segmenters do not name one per field is refused.
  std::string bad = text.str();
  const auto at = bad.find("  segmenter:");
  REQUIRE(at != std::string::npos);
  bad.insert(at, "  field_segmenters: [oracle]\n");
  std::ofstream(tmp.path() / "bad.yaml") << bad;
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "bad.yaml"), doctest::Contains("field_segmenters"),
                       std::invalid_argument);
}

TEST_CASE("calibration: σ̂'s prior from the training fields' σ and how it varies along each flight") {
  // Field 1: σ 0.1 then 0.3 over halves (mean 0.2; after half of it the mean seen is off by
  // 0.1: v = 0.1²·0.5 / 0.5 = 0.01); field 2: 0.4 throughout (v = 0). τ² = 0.02 (mean 0.3,
  // n − 1), v = 0.005, k = 0.25.
  const std::vector<TopLevelTrace> two{{0.2, {0.1, 0.3}, {0.5, 0.5}}, {0.4, {0.4, 0.4}, {0.5, 0.5}}};
  const auto prior = estimate_sigma_prior(two);
  REQUIRE(prior.has_value());
  CHECK(prior->sd == doctest::Approx(std::sqrt(0.02)));
  CHECK(prior->weight == doctest::Approx(0.25));
  // Shares need not sum to 1 (overlapping images): they are normalised per field.
  const std::vector<TopLevelTrace> scaled{{0.2, {0.1, 0.3}, {0.6, 0.6}}, {0.4, {0.4, 0.4}, {0.7, 0.7}}};
  CHECK(estimate_sigma_prior(scaled)->weight == doctest::Approx(0.25));
  // Fields of one σ: no spread to be unsure of, the prior dominates.
  const std::vector<TopLevelTrace> same{{0.2, {0.1, 0.3}, {0.5, 0.5}}, {0.2, {0.2, 0.2}, {0.5, 0.5}}};
  CHECK(estimate_sigma_prior(same)->sd == 0.0);
  CHECK(estimate_sigma_prior(same)->weight == 100.0);
  // One field, or one without a top-level image: nothing to estimate from.
  CHECK_FALSE(estimate_sigma_prior(std::span(two).first(1)).has_value());
  const std::vector<TopLevelTrace> blind{{0.2, {0.1, 0.3}, {0.5, 0.5}}, {0.4, {}, {}}};
  CHECK_FALSE(estimate_sigma_prior(blind).has_value());
}

TEST_CASE("calibration: the model is a function of its inputs (a declared time per image)") {
  const Field f = t::blob_field(1000, 750, 1.0, 9, 15);
  OracleSegmenter oracle(f.num_classes());
  CalibrationOptions options = small_options();
  options.adaptive.mission.fixed_segmentation_time_s.reset();  // replaced by the declared time
  t::TempDir tmp;
  make_decision_model(f, oracle.name(), options, calibrate(f, oracle, options)).save(tmp.path() / "a.yaml");
  make_decision_model(f, oracle.name(), options, calibrate(f, oracle, options)).save(tmp.path() / "b.yaml");
  CHECK(t::read_file(tmp.path() / "a.yaml") == t::read_file(tmp.path() / "b.yaml"));
  CHECK(t::read_file(tmp.path() / "a.yaml").find("segmentation_time_s: 0.1\n") != std::string::npos);
}

TEST_CASE("decision model: file round trip and compatibility checks") {
  const Field f = t::blob_field(2000, 1500, 1.0, 9, 30);
  OracleSegmenter oracle(f.num_classes());
  const auto samples = collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest());
  DecisionModel m{.calibration_fields = {f.name()},
                  .segmenter = "oracle",
                  .calibration_segmentation_time_s = 0.1,
                  .classes = {"soil", "crop", "weed"},
                  .interest = {"crop", "weed"},
                  .camera = {},
                  .timing = {},
                  .top_gsd_cm = 3.0,
                  .candidate_gsd_cm = {1.0, 2.0},
                  .decision_function =
                      DecisionFunction(UtilityPolicy(GainModel::fit(samples, {.restarts = 1}), {.min_utility = 1e-3})),
                  .linear = {0.01, 0.2},
                  .samples = samples.size(),
                  .train_front_margin = 0.01};
  t::TempDir tmp;
  m.save(tmp.path() / "model.yaml");
  const DecisionModel back = DecisionModel::load(tmp.path() / "model.yaml");
  CHECK(back.classes == m.classes);
  CHECK(back.interest == m.interest);
  CHECK(back.candidate_gsd_cm == m.candidate_gsd_cm);
  CHECK(back.linear.sigma_high == m.linear.sigma_high);
  CHECK(std::get<UtilityPolicy>(back.decision_function.rule()).params().min_utility == 1e-3);
  CHECK(back.decision_function.model().o_model().size() == m.decision_function.model().o_model().size());
  CHECK(back.calibration_fields == m.calibration_fields);
  CHECK(back.coverage == DescentCoverage::region);
  back.check_compatible(f, {1, 2});
  {  // coverage is kept; a file without the key (written before it existed) is "region"
    DecisionModel focused = m;
    focused.coverage = DescentCoverage::interest;
    focused.save(tmp.path() / "focused.yaml");
    const DecisionModel focused_back = DecisionModel::load(tmp.path() / "focused.yaml");
    CHECK(focused_back.coverage == DescentCoverage::interest);
    // A mission from the model flies its camera, GSDs and coverage.
    MissionOptions mission;
    mission.interest = {1};
    mission.camera.focal_length_mm = 99.0;  // replaced by the model's
    const AdaptiveOptions ao = focused_back.adaptive_options(mission, 100.0);
    CHECK(ao.coverage == DescentCoverage::interest);
    CHECK(ao.top_gsd_cm == 3.0);
    CHECK(ao.candidate_gsd_cm == m.candidate_gsd_cm);
    CHECK(ao.mission.camera.focal_length_mm == m.camera.focal_length_mm);
    CHECK(ao.mission.interest == std::vector<int>{1});
    CHECK(ao.budget_s == 100.0);
    std::string text = t::read_file(tmp.path() / "focused.yaml");
    const auto at = text.find("descent_coverage: interest\n");
    REQUIRE(at != std::string::npos);
    t::write_file(tmp.path() / "old.yaml",
                  std::string(text).erase(at, std::string("descent_coverage: interest\n").size()));
    CHECK(DecisionModel::load(tmp.path() / "old.yaml").coverage == DescentCoverage::region);
    t::write_file(tmp.path() / "bad.yaml", std::string(text).replace(at, 26, "descent_coverage: everywhere"));
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "bad.yaml"),
                         doctest::Contains("'region', 'interest' or 'ranked'"), std::invalid_argument);
  }
  {  // the map fusion: kept when pooled and flown by the model's missions; absent (finest) when not
    CHECK(back.map_fusion == MapFusion::finest);
    CHECK(t::read_file(tmp.path() / "model.yaml").find("map_fusion") == std::string::npos);
    DecisionModel pooled = m;
    pooled.map_fusion = MapFusion::pooled;
    pooled.save(tmp.path() / "pooled.yaml");
    const std::string text = t::read_file(tmp.path() / "pooled.yaml");
    CHECK(text.find("map_fusion: pooled\n") != std::string::npos);
    const DecisionModel pooled_back = DecisionModel::load(tmp.path() / "pooled.yaml");
    CHECK(pooled_back.map_fusion == MapFusion::pooled);
    CHECK(pooled_back.adaptive_options(MissionOptions{}).mission.map_fusion == MapFusion::pooled);
    t::write_file(tmp.path() / "bad_fusion.yaml",
                  std::string(text).replace(text.find("map_fusion: pooled"), 18, "map_fusion: mean"));
    CHECK_THROWS_WITH_AS(
        (void)DecisionModel::load(tmp.path() / "bad_fusion.yaml"),
        doctest::Contains("map fusion must be 'finest', 'pooled', 'pooled-interest' or 'pooled-guarded', not 'mean'"),
        std::invalid_argument);
    DecisionModel kept = m;
    kept.map_fusion = MapFusion::pooled_interest;
    kept.save(tmp.path() / "kept.yaml");
    CHECK(t::read_file(tmp.path() / "kept.yaml").find("map_fusion: pooled-interest\n") != std::string::npos);
    CHECK(DecisionModel::load(tmp.path() / "kept.yaml").adaptive_options(MissionOptions{}).mission.map_fusion ==
          MapFusion::pooled_interest);
  }
  {  // the vertical speed limit: kept when set, absent from the file (0) when not
    CHECK(back.timing.max_vertical_speed_mps == 0.0);
    CHECK(t::read_file(tmp.path() / "model.yaml").find("vertical") == std::string::npos);
    DecisionModel slow = m;
    slow.timing.max_vertical_speed_mps = 1.5;
    slow.save(tmp.path() / "slow.yaml");
    const DecisionModel slow_back = DecisionModel::load(tmp.path() / "slow.yaml");
    CHECK(slow_back.timing.max_vertical_speed_mps == 1.5);
    CHECK(slow_back.adaptive_options(MissionOptions{}, 100.0).mission.timing.max_vertical_speed_mps == 1.5);
    std::string text = t::read_file(tmp.path() / "slow.yaml");
    const auto at = text.find("max_vertical_speed_mps: 1.5");
    REQUIRE(at != std::string::npos);
    t::write_file(tmp.path() / "bad_vz.yaml", std::string(text).replace(at, 27, "max_vertical_speed_mps: -1"));
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "bad_vz.yaml"),
                         doctest::Contains("max_vertical_speed_mps must be finite and >= 0"), std::invalid_argument);
  }
  CHECK_THROWS_WITH_AS(back.check_compatible(f, {2}), doctest::Contains("labels of interest"), std::invalid_argument);
  const Field other("o", 1.0, f.labels(), {{"a", {0, 0, 0}}, {"b", {1, 1, 1}}, {"c", {2, 2, 2}}}, {1});
  CHECK_THROWS_WITH_AS(back.check_compatible(other, {1}), doctest::Contains("classes"), std::invalid_argument);

  // Broken files: clear errors naming the file.
  std::ifstream in(tmp.path() / "model.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  t::write_file(tmp.path() / "truncated.yaml", text.substr(0, text.size() * 3 / 4));
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "truncated.yaml"), doctest::Contains("truncated.yaml"),
                       std::invalid_argument);
  t::write_file(tmp.path() / "other.yaml", "format: something/2\n");
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "other.yaml"), doctest::Contains("not an adaptseg"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "missing.yaml"), doctest::Contains("not found"),
                       std::invalid_argument);
}

TEST_CASE("decision model: a file of format 1 (adaptseg 0.1) is refused, saying to calibrate again") {
  // Its keys as adaptseg 0.1 wrote them (a decision function as an embedded text block).
  t::TempDir tmp;
  t::write_file(tmp.path() / "old.yaml",
                "format: adaptseg.decision_model/1\ncalibration_field: weedmap-000\n"
                "segmenter: oracle\ndecision_function: |\n  adaptseg.decision_function 1\n");
  CHECK_THROWS_WITH_AS(
      (void)DecisionModel::load(tmp.path() / "old.yaml"),
      doctest::Contains("old.yaml: a decision model of format 1 (adaptseg 0.1) is no longer read since "
                        "adaptseg 0.2.0; calibrate the model again (adaptseg_calibrate)"),
      std::invalid_argument);
}

TEST_CASE("decision model: a plain YAML file, every fitted number a key, written and read under any locale") {
  const Field f = t::blob_field(1000, 750, 1.0, 9, 15);
  OracleSegmenter oracle(f.num_classes());
  CalibrationOptions options = small_options();
  options.confidences = {0.5};
  const CalibrationResult cal = calibrate(f, oracle, options);
  const DecisionModel m = make_decision_model(f, oracle.name(), options, cal);
  t::TempDir tmp;
  m.save(tmp.path() / "model.yaml");
  // Any YAML reader sees the fitted state: the GPs' data and hyperparameters, the rule.
  const YAML::Node root = YAML::LoadFile((tmp.path() / "model.yaml").string());
  CHECK(root["format"].as<std::string>() == "adaptseg.decision_model/2");
  const YAML::Node o = root["gain_model"]["O"];
  REQUIRE(o.IsMap());
  CHECK(o["targets"].size() == cal.samples.size());
  CHECK(o["inputs"].size() == cal.samples.size());
  CHECK(o["inputs"][0].size() == 2);
  CHECK(o["log_parameters"].size() == 4);
  CHECK(root["gain_model"]["C"]["kernel"].as<std::string>() == "squared_exponential_ard");
  CHECK(root["gain_model"]["efficiency"]["eta"].size() == 2);
  CHECK(root["rule"]["kind"].as<std::string>() == "front-aware");
  CHECK(root["rule"]["confidence"].as<std::string>() == "0.5");
  CHECK(root["rule"]["reference"][0]["miou"].size() == 3);

  {
    std::optional<DecisionModel> back, plain;
    {
      const t::CommaLocale comma;
      m.save(tmp.path() / "comma.yaml");
      back = DecisionModel::load(tmp.path() / "comma.yaml");
      plain = DecisionModel::load(tmp.path() / "model.yaml");
    }
    CHECK(t::read_file(tmp.path() / "comma.yaml") == t::read_file(tmp.path() / "model.yaml"));
    for (const DecisionModel* b : {&*back, &*plain})
      for (double sigma : {0.01, 0.1, 0.3}) {
        const GainForecast x = m.decision_function.model().forecast(11.0, sigma);
        const GainForecast y = b->decision_function.model().forecast(11.0, sigma);
        CHECK(x.delta_sigma == y.delta_sigma);
        CHECK(x.delta_miou == y.delta_miou);
        CHECK(x.relabelled == y.relabelled);
      }
    CHECK(back->camera.image_width_px == m.camera.image_width_px);
  }
}

namespace {
/// The oracle, but below `false_below_cm` it labels bands of the soil as crop (class 1): a
/// network that writes a false class when flown lower.
struct FalseWhenLow {
  OracleSegmenter oracle{3};
  double false_below_cm = 0.0;
  [[nodiscard]] std::string name() const { return "false-when-low"; }
  [[nodiscard]] cv::Mat segment(const Image& image) { return segment_with_probabilities(image).labels; }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) {
    Segmentation s = oracle.segment_with_probabilities(image);
    if (image.gsd_cm >= false_below_cm) return s;
    for (int r = 0; r < s.labels.rows; ++r)
      for (int c = 0; c < s.labels.cols; ++c)
        if (s.labels.at<std::uint8_t>(r, c) == 0 && (r / 8) % 3 == 0) {
          s.labels.at<std::uint8_t>(r, c) = 1;
          for (std::size_t k = 0; k < s.probabilities.size(); ++k)
            s.probabilities[k].at<float>(r, c) = k == 1 ? 1.0f : 0.0f;
        }
    return s;
  }
};
}  // namespace

TEST_CASE("calibration: frozen folds fly the non-adaptive rule, and the rule kept still learns in flight") {
  // The second field's network writes a false class below 2.5 cm/px. Flown as new ground by the
  // model of the other two, its first descent relabels far more than forecast, and the
  // relabelled field factor learns to descend more where every descent loses.
  const std::vector<Field> fields{t::blob_field(1300, 1000, 1.0, 4, 15), t::blob_field(1000, 1300, 1.0, 11, 15),
                                  t::blob_field(1500, 1100, 1.0, 23, 15)};
  std::vector<FalseWhenLow> networks(3);
  networks[1].false_below_cm = 2.5;
  const std::vector<FalseWhenLow*> backends{&networks[0], &networks[1], &networks[2]};
  const std::span<FalseWhenLow* const> segmented_by(backends);
  CalibrationOptions options = ranked_options();
  options.slope_poolings = {SlopePooling::cells};
  options.front_aware.field_factor = FieldFactorSource::relabelled;
  const auto z0 = [](const CalibrationResult& c) {
    const auto t = std::find_if(c.trials.begin(), c.trials.end(),
                                [](const RuleTrial& r) { return r.description == "front-aware z=0"; });
    REQUIRE(t != c.trials.end());
    return *t;
  };
  const CalibrationResult learning = calibrate(std::span<const Field>(fields), segmented_by, options);
  options.frozen_folds = true;
  const CalibrationResult frozen = calibrate(std::span<const Field>(fields), segmented_by, options);
  // Learning in the folds' flights adds descents that lose; frozen, the folds fly one.
  CHECK(z0(learning).descents > z0(frozen).descents);
  CHECK(z0(frozen).descents >= 1);
  CHECK(z0(learning).front_margin < z0(frozen).front_margin);
  // The rule calibrated learns in flight either way.
  CHECK(learning.decision_function.online());
  CHECK(frozen.decision_function.online());
  // The folds learn nothing, so a cap on what is learnt moves none of their margins.
  options.front_aware.learn_stop_only = true;
  const CalibrationResult capped = calibrate(std::span<const Field>(fields), segmented_by, options);
  REQUIRE(capped.trials.size() == frozen.trials.size());
  for (std::size_t k = 0; k < frozen.trials.size(); ++k) {
    CHECK(capped.trials[k].description == frozen.trials[k].description);
    CHECK(capped.trials[k].margins == frozen.trials[k].margins);
  }
  // Only the front-aware rule has folds to fly frozen.
  options.front_aware.learn_stop_only = false;
  options.rule = "utility";
  CHECK_THROWS_WITH_AS((void)calibrate(std::span<const Field>(fields), segmented_by, options),
                       doctest::Contains("frozen_folds belongs to the front-aware rule"), std::invalid_argument);
}
