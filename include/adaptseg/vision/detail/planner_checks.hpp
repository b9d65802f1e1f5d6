#pragma once
/// @file
/// What the adaptive planner (adaptive_planner.hpp) refuses: settings that cannot plan a
/// mission, and images reported that do not fit the camera or the protocol.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg::detail {

/// @throws std::invalid_argument for a map fused by `fusion` 'pooled' and a segmentation `s`
///         without class probabilities (`why` says so).
inline void check_pooled(MapFusion fusion, const Segmentation& s, const char* why) {
  require(!pools_probabilities(fusion) || !s.probabilities.empty(),
          std::string("AdaptivePlanner::report: map fusion '") + to_string(fusion) +
              "' needs the class probabilities behind the labels",
          why);
}

/// @throws std::invalid_argument if `budget_s` is set and does not afford the top-level coverage
///         alone: its flight `flight_s` and `images` images at `per_image_s` [s] each.
inline void check_top_level_budget(std::optional<double> budget_s, double flight_s, std::size_t images,
                                   double per_image_s) {
  if (!budget_s) return;
  const double coverage = flight_s + static_cast<double>(images) * per_image_s;
  require(coverage <= *budget_s,
          "AdaptivePlanner: budget_s [s] is too small for the top-level coverage, which needs " +
              std::to_string(coverage) + " s",
          *budget_s);
}

/// The candidate GSDs a descent may fly over `area`'s map grid (those of `options` not finer
/// than the map), after checking the settings that do not depend on the flight.
/// @throws std::invalid_argument for fixed times that are negative or not finite, no labels of
///         interest (or one that is not a class index), a top GSD finer than the map's,
///         candidates that are not finer than the top (or none to descend to), a budget that is
///         not positive.
[[nodiscard]] inline std::vector<double> planner_candidates(const AdaptiveOptions& options, const SurveyArea& area) {
  check_fixed_times(options.mission);
  const auto& interest = options.mission.interest;
  require(!interest.empty(), "AdaptivePlanner: no labels of interest (options.mission.interest)", 0);
  for (int c : interest)
    require(c >= 0 && c < area.num_classes,
            "AdaptivePlanner: a label of interest is not a class index 0.." + std::to_string(area.num_classes - 1), c);
  const double map_gsd = area.map_gsd_cm;
  require(std::isfinite(options.top_gsd_cm) && options.top_gsd_cm >= map_gsd * (1.0 - 1e-9),
          "AdaptivePlanner: top_gsd_cm must not be finer than the map's " + std::to_string(map_gsd) + " cm/px",
          options.top_gsd_cm);
  std::vector<double> candidates;
  for (double g : options.candidate_gsd_cm) {
    require(std::isfinite(g) && g > 0.0 && g < options.top_gsd_cm,
            "AdaptivePlanner: candidate GSDs must be positive and finer than top_gsd_cm", g);
    if (g >= map_gsd * (1.0 - 1e-9)) candidates.push_back(g);  // finer than the map: skip
  }
  // Without a candidate the planner could never descend: say so instead of flying a lawnmower.
  require(!candidates.empty(),
          "AdaptivePlanner: no candidate GSD to descend to (options.candidate_gsd_cm is empty or every one is finer "
          "than the map's " +
              std::to_string(map_gsd) +
              " cm/px); DecisionModel::adaptive_options sets the candidates a model was calibrated for",
          options.candidate_gsd_cm.size());
  if (options.budget_s)
    require(std::isfinite(*options.budget_s) && *options.budget_s > 0.0,
            "AdaptivePlanner: budget_s must be finite and > 0", *options.budget_s);
  return candidates;
}

/// Checks an image reported to the planner (AdaptivePlanner::report) before anything changes.
/// @throws std::invalid_argument if no waypoint is `pending` (`handed_out` so far), for an image
///         that is not of `camera`'s size or has no footprint or a yaw that is not finite, and
///         an `elapsed_s` that is negative or not finite.
inline void check_reported_image(const Image& image, const CameraModel& camera, bool pending, std::size_t handed_out,
                                 std::optional<double> elapsed_s) {
  require(pending,
          "AdaptivePlanner::report: no waypoint is waiting for an image (call next() first; each waypoint takes "
          "one image)",
          handed_out);
  require(image.width_px == camera.width_px() && image.height_px == camera.height_px(),
          "AdaptivePlanner::report: the image must have the camera's size " + std::to_string(camera.width_px()) + "x" +
              std::to_string(camera.height_px()),
          std::to_string(image.width_px) + "x" + std::to_string(image.height_px));
  require(image.bgr.empty() || image.bgr.size() == cv::Size(image.width_px, image.height_px),
          "AdaptivePlanner::report: the image's rgb must be of its size",
          std::to_string(image.bgr.cols) + "x" + std::to_string(image.bgr.rows));
  require(image.footprint_px.width > 0 && image.footprint_px.height > 0 && image.gsd_cm > 0.0,
          "AdaptivePlanner::report: the image has no footprint (make it with image_at())", image.gsd_cm);
  require(std::isfinite(image.yaw_deg), "AdaptivePlanner::report: the image's yaw_deg must be finite", image.yaw_deg);
  if (elapsed_s)
    require(std::isfinite(*elapsed_s) && *elapsed_s >= 0.0,
            "AdaptivePlanner::report: elapsed_s must be finite and >= 0", *elapsed_s);
}

/// Checks a segmentation reported with its image (AdaptivePlanner::report).
/// @throws std::invalid_argument for labels that break the segmentation contract
///         (check_segmentation()), probabilities or member votes that break theirs
///         (check_probabilities()).
[[nodiscard]] inline CheckedSegmentation check_reported_segmentation(const Segmentation& segmentation,
                                                                     const Image& image, int num_classes) {
  return CheckedSegmentation::check(
      segmentation, image, num_classes,
      {"AdaptivePlanner::report: the labels reported", "AdaptivePlanner::report: the probabilities reported",
       "AdaptivePlanner::report: the member votes reported"});
}

/// @throws std::invalid_argument for a segmentation time (AdaptivePlanner::report) that is
///         negative or not finite.
inline void check_segmentation_time(double segmentation_s) {
  require(std::isfinite(segmentation_s) && segmentation_s >= 0.0,
          "AdaptivePlanner::report: segmentation_s must be finite and >= 0", segmentation_s);
}

}  // namespace adaptseg::detail
