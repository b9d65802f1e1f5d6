#include "backend_conformance.hpp"
#include "test_support.hpp"

#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;

// Concept tests: positive and negative.
namespace {
struct NoName {
  cv::Mat segment(const Image&) { return {}; }
};
struct WrongReturn {
  std::string name() const { return "x"; }
  int segment(const Image&) { return 0; }
};
}  // namespace
static_assert(SegmentationBackend<OracleSegmenter>);
static_assert(!SegmentationBackend<NoName>);
static_assert(!SegmentationBackend<WrongReturn>);
static_assert(!SegmentationBackend<int>);

TEST_CASE("oracle: passes the backend conformance suite on a synthetic field") {
  const Field f = t::blob_field(1500, 1100, 1.0, 11, 30);
  OracleSegmenter oracle(f.num_classes());
  t::check_backend_conformance(oracle, SimulatedSensor(f, CameraModel{}), f.num_classes());
}

TEST_CASE("oracle: passes the backend conformance suite on the bundled WeedMap field") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  t::check_backend_conformance(oracle, SimulatedSensor(f, CameraModel{}), f.num_classes());
}

TEST_CASE("oracle: identity at the orthomosaic's GSD, area-weighted majority above it") {
  // 960 x 720 field: a 2x2 block per camera pixel at 2 cm/px.
  cv::Mat labels(720, 960, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(0, 0, 2, 2)).setTo(1);  // whole block crop -> crop
  labels(cv::Rect(2, 0, 2, 2)).setTo(2);
  labels.at<std::uint8_t>(0, 2) = 0;  // 3 weed of 4 -> weed
  labels.at<std::uint8_t>(0, 4) = 1;  // 1 crop of 4 -> soil
  labels(cv::Rect(6, 0, 2, 2)).setTo(255);
  labels.at<std::uint8_t>(1, 7) = 2;        // 3 ignore + 1 weed -> weed (ignore does not vote)
  labels(cv::Rect(8, 0, 2, 2)).setTo(255);  // only ignore -> ignore
  labels.at<std::uint8_t>(0, 10) = 1;       // tie crop/weed 2:2 -> crop (lower index)
  labels.at<std::uint8_t>(0, 11) = 1;
  labels.at<std::uint8_t>(1, 10) = 2;
  labels.at<std::uint8_t>(1, 11) = 2;
  const Field f("blocks", 1.0, labels, t::soil_crop_weed(), {1, 2});
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(3);
  // At 1 cm/px: identity.
  const Image fine = sensor.capture(LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0).front());
  CHECK(cv::countNonZero(oracle.segment(fine) != fine.ground_truth) == 0);
  // At 2 cm/px: one image covers the whole field; top-left camera pixels as designed.
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 2.0);
  REQUIRE(plan.size() == 1);
  const cv::Mat out = oracle.segment(sensor.capture(plan.front()));
  CHECK(out.at<std::uint8_t>(0, 0) == 1);
  CHECK(out.at<std::uint8_t>(0, 1) == 2);
  CHECK(out.at<std::uint8_t>(0, 2) == 0);
  CHECK(out.at<std::uint8_t>(0, 3) == 2);
  CHECK(out.at<std::uint8_t>(0, 4) == 255);
  CHECK(out.at<std::uint8_t>(0, 5) == 1);
}

TEST_CASE("oracle: its probabilities are the shares of the area vote") {
  // 960 x 720 field, 2x2 blocks per camera pixel at 2 cm/px, as above.
  cv::Mat labels(720, 960, CV_8UC1, cv::Scalar(0));
  labels(cv::Rect(2, 0, 2, 2)).setTo(2);
  labels.at<std::uint8_t>(0, 2) = 0;  // 3 weed, 1 soil
  labels(cv::Rect(6, 0, 2, 2)).setTo(255);
  labels.at<std::uint8_t>(1, 7) = 1;        // 3 ignore, 1 crop: crop alone votes
  labels(cv::Rect(8, 0, 2, 2)).setTo(255);  // no vote at all
  const Field f("blocks", 1.0, labels, t::soil_crop_weed(), {1, 2});
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(3);
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 2.0);
  REQUIRE(plan.size() == 1);
  const Image img = sensor.capture(plan.front());
  const Segmentation s = oracle.segment_with_probabilities(img);
  CHECK(cv::countNonZero(s.labels != oracle.segment(img)) == 0);
  REQUIRE(s.probabilities.size() == 3);
  const auto p = [&](int c, int x) { return s.probabilities[static_cast<std::size_t>(c)].at<float>(0, x); };
  CHECK(p(0, 0) == doctest::Approx(1.0));  // pure soil
  CHECK(p(0, 1) == doctest::Approx(0.25));
  CHECK(p(2, 1) == doctest::Approx(0.75));
  CHECK(p(1, 1) == 0.0f);
  CHECK(p(1, 3) == doctest::Approx(1.0));              // the one valid pixel is crop
  for (int c = 0; c < 3; ++c) CHECK(p(c, 4) == 0.0f);  // nothing votes: no probability, ignore label
  CHECK(s.labels.at<std::uint8_t>(0, 4) == 255);
  CHECK_NOTHROW(check_probabilities(s.probabilities, s.labels, img, 3, "oracle"));
  // At the orthomosaic's GSD: one-hot.
  const Image fine = sensor.capture(LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0).front());
  const Segmentation one_hot = oracle.segment_with_probabilities(fine);
  cv::Mat sum = one_hot.probabilities[0] + one_hot.probabilities[1] + one_hot.probabilities[2];
  CHECK(cv::countNonZero((sum != 1.0f) & (one_hot.labels != 255)) == 0);
  CHECK(cv::countNonZero((one_hot.probabilities[2] == 1.0f) != (one_hot.labels == 2)) == 0);
}

TEST_CASE("segmentation contract: probabilities are checked like labels") {
  Image img;
  img.width_px = 4;
  img.height_px = 3;
  img.ignore_label = 255;
  const cv::Mat labels(3, 4, CV_8UC1, cv::Scalar(1));
  std::vector<cv::Mat> p{cv::Mat(3, 4, CV_32F, cv::Scalar(0.25f)), cv::Mat(3, 4, CV_32F, cv::Scalar(0.75f))};
  CHECK_NOTHROW(check_probabilities(p, labels, img, 2, "b"));
  CHECK_NOTHROW(check_probabilities({}, labels, img, 2, "b"));  // a labels-only backend
  CHECK_THROWS_WITH_AS(check_probabilities(p, labels, img, 3, "b"), doctest::Contains("one plane per class"),
                       std::invalid_argument);
  auto bad = p;
  bad[1] = cv::Mat(3, 5, CV_32F, cv::Scalar(0.75f));
  CHECK_THROWS_WITH_AS(check_probabilities(bad, labels, img, 2, "b"), doctest::Contains("image's size 4x3"),
                       std::invalid_argument);
  bad = {p[0].clone(), p[1].clone()};
  bad[0].at<float>(2, 1) = NAN;
  CHECK_THROWS_WITH_AS(check_probabilities(bad, labels, img, 2, "b"), doctest::Contains("(x 1, y 2) is not in [0, 1]"),
                       std::invalid_argument);
  bad = {p[0].clone(), p[1].clone()};
  bad[0].at<float>(1, 3) = 0.5f;
  CHECK_THROWS_WITH_AS(check_probabilities(bad, labels, img, 2, "b"), doctest::Contains("sum to 1.25"),
                       std::invalid_argument);
  // All zero: allowed on an ignore pixel only.
  bad = {p[0].clone(), p[1].clone()};
  bad[0].at<float>(0, 0) = 0.0f;
  bad[1].at<float>(0, 0) = 0.0f;
  CHECK_THROWS_AS(check_probabilities(bad, labels, img, 2, "b"), std::invalid_argument);
  cv::Mat with_ignore = labels.clone();
  with_ignore.at<std::uint8_t>(0, 0) = 255;
  CHECK_NOTHROW(check_probabilities(bad, with_ignore, img, 2, "b"));
}

TEST_CASE("oracle: small objects vanish as the GSD grows (real WeedMap data)") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(f.num_classes());
  // Per-image mIoU over {crop, weed} over the same ground area falls with GSD.
  double previous = 1.1;
  for (double gsd : {1.0, 2.0, 4.0, 8.0}) {
    const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), gsd);
    ConfusionMatrix total(f.num_classes());
    for (const auto& w : plan) {
      const Image img = sensor.capture(w);
      total += image_confusion(img, oracle.segment(img), f.num_classes());
    }
    const double miou = total.miou(f.interest()).value();
    CAPTURE(gsd);
    CHECK(miou < previous);
    previous = miou;
  }
  CHECK(previous < 0.6);
}

TEST_CASE("oracle: refuses images without ground truth and bad class counts") {
  OracleSegmenter oracle(3);
  Image img;
  img.width_px = 4;
  img.height_px = 3;
  CHECK_THROWS_WITH_AS((void)oracle.segment(img), doctest::Contains("ground truth"), std::invalid_argument);
  CHECK_THROWS_AS(OracleSegmenter(0), std::invalid_argument);
  CHECK_THROWS_AS(OracleSegmenter(256), std::invalid_argument);
}
