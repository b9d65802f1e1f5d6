#include <adaptseg/vision/metrics.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace adaptseg;

TEST_CASE("metrics: semantic ratio counts labels of interest over valid pixels (Eq. vr)") {
  cv::Mat m(2, 5, CV_8UC1, cv::Scalar(0));
  m.at<std::uint8_t>(0, 0) = 1;
  m.at<std::uint8_t>(0, 1) = 2;
  m.at<std::uint8_t>(1, 4) = 255;
  m.at<std::uint8_t>(1, 3) = 255;
  const std::vector<int> crop_weed{1, 2}, weed{2};
  CHECK(semantic_ratio(m, crop_weed, 255) == doctest::Approx(2.0 / 8.0));
  CHECK(semantic_ratio(m, weed, 255) == doctest::Approx(1.0 / 8.0));
  CHECK(semantic_ratio(cv::Mat(2, 2, CV_8UC1, cv::Scalar(255)), weed, 255) == 0.0);
}

TEST_CASE("metrics: IoU and mIoU on a hand-computed example") {
  // truth:     0 0 1 1 2 | pred: 0 1 1 1 255(none)
  const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 6) << 0, 0, 1, 1, 2, 255);
  const cv::Mat pred = (cv::Mat_<std::uint8_t>(1, 6) << 0, 1, 1, 1, 255, 2);
  ConfusionMatrix cm(3);
  cm.add(truth, pred, 255);
  CHECK(cm.total() == 5);      // the ignore truth pixel is skipped
  CHECK(cm.count(2, 3) == 1);  // weed predicted as none
  CHECK_THROWS_WITH_AS((void)cm.count(3, 0), doctest::Contains("truth, prediction (got 3, 0)"), std::invalid_argument);
  CHECK_THROWS_AS((void)cm.count(0, 4), std::invalid_argument);
  CHECK_THROWS_AS((void)cm.count(-1, 4), std::invalid_argument);  // not index 0 by wrapping around
  CHECK(cm.iou(0).value() == doctest::Approx(1.0 / 2.0));         // TP 1, FN 1
  CHECK(cm.iou(1).value() == doctest::Approx(2.0 / 3.0));         // TP 2, FP 1
  CHECK(cm.iou(2).value() == doctest::Approx(0.0));               // FN 1
  const std::vector<int> l{1, 2};
  CHECK(cm.miou(l).value() == doctest::Approx((2.0 / 3.0 + 0.0) / 2.0));
  CHECK(cm.miou_all().value() == doctest::Approx((0.5 + 2.0 / 3.0 + 0.0) / 3.0));
}

TEST_CASE("metrics: classes absent from truth and prediction do not count") {
  const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 3) << 0, 0, 1);
  ConfusionMatrix cm(4);
  cm.add(truth, truth, 255);
  CHECK_FALSE(cm.iou(2).has_value());
  CHECK(cm.miou_all().value() == 1.0);
  const std::vector<int> absent{2, 3};
  CHECK_FALSE(cm.miou(absent).has_value());
  CHECK_THROWS_AS((void)cm.iou(4), std::invalid_argument);
  CHECK_THROWS_AS(cm.add(truth, cv::Mat(1, 2, CV_8UC1), 255), std::invalid_argument);
}

TEST_CASE("metrics: truth share counts true labels of interest, whatever was predicted") {
  const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 5) << 0, 1, 1, 2, 255);
  const cv::Mat pred = (cv::Mat_<std::uint8_t>(1, 5) << 1, 1, 0, 1, 1);
  ConfusionMatrix cm(3);
  CHECK(cm.truth_share(std::vector<int>{1}) == 0.0);  // nothing counted yet
  cm.add(truth, pred, 255);
  CHECK(cm.truth_share(std::vector<int>{1}) == doctest::Approx(2.0 / 4.0));
  CHECK(cm.truth_share(std::vector<int>{0, 2}) == doctest::Approx(2.0 / 4.0));
  CHECK(cm.truth_share(std::vector<int>{}) == 0.0);
  CHECK_THROWS_AS((void)cm.truth_share(std::vector<int>{3}), std::invalid_argument);
}

TEST_CASE("metrics: per-image confusion compares at the orthomosaic's resolution") {
  Image img;
  img.width_px = 2;
  img.height_px = 1;
  img.footprint_px = {0, 0, 4, 2};
  img.ground_truth = (cv::Mat_<std::uint8_t>(2, 4) << 1, 1, 0, 0, 1, 0, 0, 255);
  const cv::Mat pred = (cv::Mat_<std::uint8_t>(1, 2) << 1, 0);
  const ConfusionMatrix cm = image_confusion(img, pred, 2);
  CHECK(cm.total() == 7);
  CHECK(cm.count(0, 1) == 1);  // the soil pixel under the crop camera pixel
  CHECK(cm.iou(1).value() == doctest::Approx(3.0 / 4.0));
}

TEST_CASE("metrics: relabelling splits the changes with L involved into added and removed") {
  // L = {1, 2}. before: 1 1 2 0 0 3 1 | after: 1 0 1 2 3 0 1; the last pixel outside the field.
  const cv::Mat before = (cv::Mat_<std::uint8_t>(1, 7) << 1, 1, 2, 0, 0, 3, 1);
  const cv::Mat after = (cv::Mat_<std::uint8_t>(1, 7) << 1, 0, 1, 2, 3, 0, 0);
  const cv::Mat field = (cv::Mat_<std::uint8_t>(1, 7) << 1, 1, 1, 1, 1, 1, 0);
  const std::vector<int> l{1, 2};
  const Relabelling r = relabelling(before, after, field, l);
  CHECK(r.share == doctest::Approx(5.0 / 6.0));           // all but the first field pixel changed
  CHECK(r.interest_share == doctest::Approx(3.0 / 6.0));  // 1 -> 0, 2 -> 1 (within L), 0 -> 2
  CHECK(r.added_share == doctest::Approx(1.0 / 6.0));     // 0 -> 2
  CHECK(r.removed_share == doctest::Approx(1.0 / 6.0));   // 1 -> 0 (the pixel outside the field not counted)
  const Relabelling none = relabelling(before, after, cv::Mat(1, 7, CV_8UC1, cv::Scalar(0)), l);
  CHECK(none.added_share == 0.0);
  CHECK(none.removed_share == 0.0);
}

TEST_CASE("metrics: agreeing_changes counts the changes into and out of L that every check also gives") {
  // L = {1}. before: 0 0 0 1 1 1 2 0 | after: 1 1 1 0 2 0 1 1; the last pixel outside the field.
  const cv::Mat before = (cv::Mat_<std::uint8_t>(1, 8) << 0, 0, 0, 1, 1, 1, 2, 0);
  const cv::Mat after = (cv::Mat_<std::uint8_t>(1, 8) << 1, 1, 1, 0, 2, 0, 1, 1);
  const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 8) << 1, 0, 1, 0, 3, 1, 1, 1);
  const cv::Mat coarser = (cv::Mat_<std::uint8_t>(1, 8) << 1, 1, 0, 2, 1, 0, 0, 1);
  const cv::Mat field = (cv::Mat_<std::uint8_t>(1, 8) << 1, 1, 1, 1, 1, 1, 1, 0);
  const std::vector<int> l{1};
  // Added: pixels 0, 1, 2, 6; removed: 3, 4, 5 (a change out of L to any other class).
  const Relabelling right = agreeing_changes(before, after, {truth}, field, l);
  CHECK(right.added_share == doctest::Approx(3.0 / 7.0));    // 0, 2, 6
  CHECK(right.removed_share == doctest::Approx(2.0 / 7.0));  // 3, 4 (truth 3 is outside L too)
  const Relabelling confirmed = agreeing_changes(before, after, {coarser}, field, l);
  CHECK(confirmed.added_share == doctest::Approx(2.0 / 7.0));    // 0, 1
  CHECK(confirmed.removed_share == doctest::Approx(2.0 / 7.0));  // 3, 5
  const Relabelling both = agreeing_changes(before, after, {coarser, truth}, field, l);
  CHECK(both.added_share == doctest::Approx(1.0 / 7.0));    // 0
  CHECK(both.removed_share == doctest::Approx(1.0 / 7.0));  // 3
  const Relabelling unchecked = agreeing_changes(before, after, {}, field, l);
  CHECK(unchecked.added_share == doctest::Approx(relabelling(before, after, field, l).added_share));
  CHECK_THROWS_AS((void)agreeing_changes(before, after, {cv::Mat(1, 7, CV_8UC1)}, field, l), std::invalid_argument);
}

TEST_CASE("front margin: measured against the curve's upper envelope, not a curve that falls") {
  // A lawnmower that is slower and maps worse (0.4 at 200 s) than a faster one (0.5 at 100 s).
  const std::vector<CurvePoint> curve{{300.0, 0.6}, {100.0, 0.5}, {200.0, 0.4}};
  const auto env = upper_envelope(curve);
  REQUIRE(env.size() == 3);
  CHECK(env[0].time_s == 100.0);
  CHECK(env[0].miou == 0.5);
  CHECK(env[1].time_s == doctest::Approx(250.0));  // where 200 -> 300 climbs back through 0.5
  CHECK(env[1].miou == 0.5);
  CHECK(env[2].time_s == 300.0);
  CHECK(env[2].miou == 0.6);
  // A mission of 0.45 at 200 s lies above the curve (0.4) but below the best lawnmower it could
  // have flown in that time (0.5): the front margin says so; the curve's reading does not.
  CHECK(front_margin(curve, 200.0, 0.45) == doctest::Approx(-0.05));
  CHECK(curve_front_margin(curve, 200.0, 0.45) == doctest::Approx(0.05));
  // Where the curve rises, both readings agree, and both are flat beyond the ends.
  CHECK(front_margin(curve, 275.0, 0.6) == doctest::Approx(curve_front_margin(curve, 275.0, 0.6)));
  CHECK(front_margin(curve, 50.0, 0.5) == 0.0);
  CHECK(front_margin(curve, 400.0, 0.6) == 0.0);
  // A rising curve is its own envelope.
  const std::vector<CurvePoint> rising{{10.0, 0.1}, {20.0, 0.3}, {30.0, 0.35}};
  const auto same = upper_envelope(rising);
  REQUIRE(same.size() == rising.size());
  for (std::size_t k = 0; k < same.size(); ++k)
    CHECK((same[k].time_s == rising[k].time_s && same[k].miou == rising[k].miou));
  CHECK_THROWS_AS((void)upper_envelope({}), std::invalid_argument);
  CHECK_THROWS_AS((void)front_margin({{1.0, NAN}}, 1.0, 0.5), std::invalid_argument);
}
