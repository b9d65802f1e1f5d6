#include "test_support.hpp"

#include <adaptseg/calibration.hpp>
#include <adaptseg/decision_model.hpp>
#include <adaptseg/oracle_segmenter.hpp>

#include <doctest/doctest.h>

#include <algorithm>

using namespace adaptseg;
namespace t = adaptseg::test;

namespace {
CalibrationOptions small_options() {
  CalibrationOptions o;
  o.adaptive.mission.fixed_segmentation_time_s = 0.1;
  o.adaptive.mission.fixed_planning_time_s = 0.0;
  o.adaptive.top_gsd_cm = 3.0;
  o.adaptive.candidate_gsd_cm = {1.0, 2.0};
  o.lawnmower_gsd_cm = {1.0, 2.0, 3.0};
  o.threshold_steps = 3;
  o.restarts = 1;
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

TEST_CASE("calibration: the chosen thresholds never fall below the training lawnmower curve") {
  const Field f = t::blob_field(2600, 2000, 1.0, 4, 30);
  OracleSegmenter oracle(f.num_classes());
  CalibrationOptions options = small_options();
  options.front_aware = false;  // the paper's rule with a calibrated threshold
  const CalibrationResult cal = calibrate(f, oracle, options);
  CHECK(cal.samples.size() == 2u * 2u * 2u);
  CHECK(cal.lawnmower_curve.size() == 3);
  REQUIRE_FALSE(cal.trials.empty());
  // "Never descend" is always tried, so the best worst-case margin is at least 0.
  CHECK(cal.trials.front().worst_margin >= 0.0);
  for (const auto& trial : cal.trials) CHECK(trial.worst_margin <= cal.trials.front().worst_margin);
  CHECK(cal.decision_function.params().min_utility == cal.trials.front().params.min_utility);
  CHECK(cal.linear.sigma_high > cal.linear.sigma_low);
  const DecisionModel model = make_decision_model(f, oracle.name(), small_options(), cal);
  CHECK(model.classes == std::vector<std::string>{"soil", "crop", "weed"});
  CHECK(model.interest == std::vector<std::string>{"crop", "weed"});
  CHECK(model.candidate_gsd_cm == std::vector<double>{1.0, 2.0});
  CHECK(model.train_front_margin == cal.trials.front().front_margin);
  model.check_compatible(f, f.interest());
}

TEST_CASE("calibration: by default the front-aware rule is chosen, with the training curve as its reference") {
  const Field f = t::blob_field(2600, 2000, 1.0, 4, 30);
  OracleSegmenter oracle(f.num_classes());
  const CalibrationOptions options = small_options();
  REQUIRE(options.front_aware);
  const CalibrationResult cal = calibrate(f, oracle, options);
  CHECK(cal.decision_function.params().front_aware);
  CHECK(cal.trials.front().params.front_aware);
  CHECK_FALSE(cal.decision_function.params().relative_utility);
  // Its reference: the training lawnmower's mIoU at each lawnmower GSD.
  const auto& reference = cal.decision_function.reference_lawnmower();
  REQUIRE(reference.size() == options.lawnmower_gsd_cm.size());
  for (std::size_t k = 0; k < reference.size(); ++k) {
    CHECK(reference[k].gsd_cm == options.lawnmower_gsd_cm[k]);
    CHECK(reference[k].miou == cal.lawnmower_curve[k].miou);
  }
  // The threshold settings are still flown and reported.
  CHECK(std::count_if(cal.trials.begin(), cal.trials.end(),
                      [](const ThresholdTrial& tr) { return !tr.params.front_aware; }) > 5);
  // The model file keeps the rule and its reference.
  t::TempDir tmp;
  make_decision_model(f, oracle.name(), options, cal).save(tmp.path() / "model.yaml");
  const DecisionModel back = DecisionModel::load(tmp.path() / "model.yaml");
  CHECK(back.decision_function.params().front_aware);
  CHECK(back.decision_function.reference_lawnmower().size() == reference.size());
}

TEST_CASE("decision model: file round trip and compatibility checks") {
  const Field f = t::blob_field(2000, 1500, 1.0, 9, 30);
  OracleSegmenter oracle(f.num_classes());
  const auto samples = collect_region_samples(f, oracle, CameraModel{}, 3.0, {1.0, 2.0}, f.interest());
  DecisionModel m{.calibration_field = f.name(),
                  .segmenter = "oracle",
                  .classes = {"soil", "crop", "weed"},
                  .interest = {"crop", "weed"},
                  .camera = {},
                  .timing = {},
                  .top_gsd_cm = 3.0,
                  .candidate_gsd_cm = {1.0, 2.0},
                  .decision_function = DecisionFunction::initialize(samples, {.min_utility = 1e-3}, 1),
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
  CHECK(back.decision_function.params().min_utility == doctest::Approx(1e-3));
  CHECK(back.decision_function.o_model().size() == m.decision_function.o_model().size());
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
    t::write_file(tmp.path() / "old.yaml", std::string(text).erase(at, std::string("descent_coverage: interest\n").size()));
    CHECK(DecisionModel::load(tmp.path() / "old.yaml").coverage == DescentCoverage::region);
    t::write_file(tmp.path() / "bad.yaml", std::string(text).replace(at, 26, "descent_coverage: everywhere"));
    CHECK_THROWS_WITH_AS((void)DecisionModel::load(tmp.path() / "bad.yaml"), doctest::Contains("'region' or 'interest'"),
                         std::invalid_argument);
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
