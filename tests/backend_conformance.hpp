#pragma once
// The conformance suite every SegmentationBackend model runs (see the concept's contract in
// include/adaptseg/vision/segmentation_backend.hpp).

#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>

#include <string>

namespace adaptseg::test {

/// Segments images of `sensor`'s field at several GSDs and checks the contract: type and
/// size, values in the class set or the ignore label, input untouched, same output for the
/// same image, and a non-empty name; for a backend that gives probabilities
/// (SegmentsWithProbabilities), the same labels and probabilities that keep their contract.
template <SegmentationBackend Backend>
void check_backend_conformance(Backend& backend, const SimulatedSensor& sensor, int num_classes) {
  CHECK_FALSE(std::string(backend.name()).empty());
  const LawnmowerPlanner planner(sensor.camera());
  const double g0 = sensor.field().gsd_cm();
  for (double factor : {1.0, 1.7, 3.0}) {
    const auto plan = planner.plan(sensor.field().area(), g0 * factor);
    REQUIRE_FALSE(plan.empty());
    for (std::size_t i = 0; i < plan.size() && i < 3; ++i) {
      const Image image = sensor.capture(plan[i]);
      const cv::Mat gt_before = image.ground_truth.clone();
      const cv::Mat rgb_before = image.bgr.clone();
      const cv::Mat labels = backend.segment(image);
      REQUIRE(labels.type() == CV_8UC1);
      REQUIRE(labels.rows == image.height_px);
      REQUIRE(labels.cols == image.width_px);
      for (int r = 0; r < labels.rows; ++r)
        for (int c = 0; c < labels.cols; ++c) {
          const int v = labels.at<std::uint8_t>(r, c);
          REQUIRE((v < num_classes || v == image.ignore_label));
        }
      CHECK(cv::countNonZero(gt_before != image.ground_truth) == 0);
      if (!rgb_before.empty()) CHECK(cv::norm(rgb_before, image.bgr, cv::NORM_INF) == 0.0);
      const cv::Mat again = backend.segment(image);
      CHECK(cv::countNonZero(again != labels) == 0);
      if constexpr (SegmentsWithProbabilities<Backend>) {
        // The same labels, with probabilities that keep the contract (check_probabilities).
        const Segmentation s = backend.segment_with_probabilities(image);
        CHECK(cv::countNonZero(s.labels != labels) == 0);
        REQUIRE(s.probabilities.size() == static_cast<std::size_t>(num_classes));
        CHECK_NOTHROW(check_probabilities(s.probabilities, s.labels, image, num_classes, "backend"));
        const Segmentation s2 = backend.segment_with_probabilities(image);
        for (std::size_t c = 0; c < s.probabilities.size(); ++c)
          CHECK(cv::norm(s.probabilities[c], s2.probabilities[c], cv::NORM_INF) == 0.0);
      }
    }
  }
}

}  // namespace adaptseg::test
