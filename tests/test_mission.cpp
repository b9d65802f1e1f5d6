#include "test_support.hpp"

#include <adaptseg/vision/mission.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>

#include <doctest/doctest.h>

#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;

namespace {
MissionOptions deterministic() { return t::deterministic_options(); }
}  // namespace

TEST_CASE("mission: WeedMap lawnmower at the field's GSD maps every valid pixel exactly") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  const MissionResult r = run_lawnmower_mission(f, f.gsd_cm(), oracle, deterministic());
  CHECK(r.miou_all().value() == 1.0);
  CHECK(r.miou_interest().value() == 1.0);
  const cv::Mat unobserved = (r.fused_labels == f.ignore_label()) & f.valid_mask();
  CHECK(cv::countNonZero(unobserved) == 0);
  CHECK(r.strategy == "lawnmower");
  CHECK(r.segmenter == "oracle");
}

TEST_CASE("mission: WeedMap lawnmowers from 1.0 to 3.0 cm/px trade accuracy for time") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  double prev_miou = 2.0, prev_time = 1e18;
  for (double gsd : {1.0, 1.5, 2.0, 2.5, 3.0}) {
    const MissionResult r = run_lawnmower_mission(f, gsd, oracle, deterministic());
    CAPTURE(gsd);
    const double miou = r.miou_interest().value();
    CHECK(miou < prev_miou);
    CHECK(r.total_s() < prev_time);
    const cv::Mat unobserved = (r.fused_labels == f.ignore_label()) & f.valid_mask();
    CHECK(cv::countNonZero(unobserved) == 0);  // full coverage at every GSD
    prev_miou = miou;
    prev_time = r.total_s();
  }
}

TEST_CASE("mission: time is flight by the ramp model plus fixed segmentation and planning") {
  const Field f = t::blob_field(1200, 900, 1.0);
  OracleSegmenter oracle(f.num_classes());
  MissionOptions o = deterministic();
  o.fixed_planning_time_s = 0.25;
  o.timing = {.max_speed_mps = 3.0, .max_accel_mps2 = 1.5};
  const MissionResult r = run_lawnmower_mission(f, 2.0, oracle, o);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& w : r.waypoints) pts.push_back(w.waypoint.position);
  REQUIRE(pts.size() == 4);  // 12 x 9 m field, 9.6 x 7.2 m footprints: 2 x 2
  CHECK(r.time.flight_s == doctest::Approx(TimingModel(o.timing).path_time_s(pts)));
  CHECK(r.time.segmentation_s == doctest::Approx(0.4));
  CHECK(r.time.planning_s == doctest::Approx(1.0));
  CHECK(r.total_s() == doctest::Approx(r.time.flight_s + 0.4 + 1.0));
  for (const auto& w : r.waypoints) {
    CHECK(w.level == 0);
    CHECK(w.image_miou_all.has_value());
    CHECK(w.semantic_ratio > 0.0);
    // Majority voting at 2x the field's GSD drops some of the 1-12 px blobs of L.
    REQUIRE(w.truth_ratio.has_value());
    CHECK(*w.truth_ratio > w.semantic_ratio);
  }
}

TEST_CASE("mission: at the field's own GSD the oracle's semantic ratio is the truth's") {
  const Field f = t::blob_field(1200, 900, 1.0, 7, 40);  // with an ignore border
  OracleSegmenter oracle(f.num_classes());
  const MissionResult r = run_lawnmower_mission(f, 1.0, oracle, deterministic());
  REQUIRE(r.waypoints.size() == 9);
  for (const auto& w : r.waypoints) {
    REQUIRE(w.truth_ratio.has_value());
    CHECK(*w.truth_ratio > 0.0);
    CHECK(*w.truth_ratio == doctest::Approx(w.semantic_ratio).epsilon(1e-12));
  }
}

TEST_CASE("mission: bad requests are refused before flying") {
  const Field f = t::blob_field(300, 300, 2.0);
  OracleSegmenter oracle(f.num_classes());
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 1.0, oracle, {}), doctest::Contains("finer than the field"),
                       std::invalid_argument);
  MissionOptions o;
  o.interest = {5};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 2.0, oracle, o), doctest::Contains("interest"),
                       std::invalid_argument);
  o = {};
  o.camera.focal_length_mm = -1.0;
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 2.0, oracle, o), doctest::Contains("focal_length_mm"),
                       std::invalid_argument);
  o = {};
  o.fixed_segmentation_time_s = -1.0;
  CHECK_THROWS_AS((void)run_lawnmower_mission(f, 2.0, oracle, o), std::invalid_argument);
  const Field no_interest("n", 1.0, f.labels(), t::soil_crop_weed(), {});
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(no_interest, 2.0, oracle, {}),
                       doctest::Contains("no labels of interest"), std::invalid_argument);
}

namespace {
struct BrokenBackend {
  std::string name() const { return "broken"; }
  cv::Mat segment(const Image&) { return cv::Mat(2, 2, CV_8UC1, cv::Scalar(0)); }
};
}  // namespace

TEST_CASE("mission: a backend that breaks the contract is reported by name") {
  const Field f = t::blob_field(300, 300, 1.0);
  BrokenBackend broken;
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 1.0, broken, {}), doctest::Contains("'broken'"),
                       std::invalid_argument);
}

namespace {
/// The oracle's labels without its probabilities: a labels-only backend.
struct LabelsOnlyOracle {
  OracleSegmenter oracle;
  [[nodiscard]] std::string name() const { return "labels-only"; }
  [[nodiscard]] cv::Mat segment(const Image& image) const { return oracle.segment(image); }
};
}  // namespace

TEST_CASE("mission: a pooled map maps WeedMap at the field's GSD exactly and needs the class probabilities") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  MissionOptions o = deterministic();
  o.map_fusion = MapFusion::pooled;
  const MissionResult r = run_lawnmower_mission(f, f.gsd_cm(), oracle, o);
  CHECK(r.miou_all().value() == 1.0);
  // The same images and times as the paper's fusion: only the map's rule differs.
  const MissionResult finest = run_lawnmower_mission(f, f.gsd_cm(), oracle, deterministic());
  CHECK(r.total_s() == finest.total_s());
  CHECK(cv::countNonZero(r.fused_labels != finest.fused_labels) == 0);
  LabelsOnlyOracle labels_only{OracleSegmenter(f.num_classes())};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, f.gsd_cm(), labels_only, o),
                       doctest::Contains("map fusion 'pooled' needs a backend that gives class probabilities"),
                       std::invalid_argument);
  // Keeping the labels of interest any image gave changes nothing where every look is sure, and
  // needs the probabilities as well.
  o.map_fusion = MapFusion::pooled_interest;
  const MissionResult kept = run_lawnmower_mission(f, f.gsd_cm(), oracle, o);
  CHECK(cv::countNonZero(kept.fused_labels != finest.fused_labels) == 0);
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, f.gsd_cm(), labels_only, o),
                       doctest::Contains("map fusion 'pooled-interest' needs a backend that gives class probabilities"),
                       std::invalid_argument);
}
