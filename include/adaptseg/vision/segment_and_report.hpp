#pragma once
/// @file
/// Where a backend's segmentation crosses into the adaptive planner (adaptive_planner.hpp):
/// segmented and checked once where it is made, then reported.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/detail/planner_clock.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <chrono>
#include <optional>

namespace adaptseg {

template <DecisionPolicy Policy>
class AdaptivePlanner;

/// Segments `image` with `backend` and reports it to `planner` (AdaptivePlanner::report): the
/// labels, with the backend's class probabilities where it gives them and the planner reads them
/// (AdaptivePlanner::wants_probabilities()), checked once where they are made
/// (segment_and_check()); the time the backend takes is the image's segmentation time. The
/// backend does not run for an image report() would refuse before reading its segmentation.
/// @throws std::invalid_argument as AdaptivePlanner::report (a pooled map and a labels-only
///         backend included), and whatever the backend throws.
template <SegmentationBackend Backend, DecisionPolicy Policy>
PlannerStep segment_and_report(AdaptivePlanner<Policy>& planner, Backend& backend, const Image& image,
                               std::optional<double> elapsed_s = std::nullopt) {
  planner.check_report(image, elapsed_s);
  const auto t0 = std::chrono::steady_clock::now();
  const CheckedSegmentation s =
      segment_and_check(backend, image, planner.area().num_classes, planner.wants_probabilities());
  return planner.report(image, s, detail::seconds_since(t0), elapsed_s);
}

}  // namespace adaptseg
