#pragma once
/// @file
/// One camera frame as a segmentation backend receives it (`Image`), and the check of what a
/// backend gives back (`check_segmentation`), and the pixels of a raster under an area of the
/// field frame (`raster_rect`). OpenCV core and Eigen only: the segmentation contract
/// (segmentation_backend.hpp) and the live planner need nothing else.

#include <adaptseg/error.hpp>
#include <adaptseg/lawnmower_planner.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

namespace adaptseg {

/// Pixels under `a` of a raster in the field frame (origin at the raster's bottom-left
/// corner, x along its columns, y up its rows; docs/data_format.md) with `rows` rows at `gsd_cm`,
/// edges rounded to the nearest pixel boundary, so that areas sharing an edge share it in
/// pixels too (no gaps, no overlaps). May extend beyond the raster. Coordinates are clamped to
/// +-2^29 px so that absurd areas cannot overflow `int` (they would wrap and miss the raster);
/// the rectangle still covers everything it should.
[[nodiscard]] inline cv::Rect raster_rect(const Area& a, double gsd_cm, int rows) {
  const double s = 100.0 / gsd_cm;
  const auto px = [](double v) {
    constexpr double kLimit = 536870912.0;
    return static_cast<int>(std::lround(std::clamp(v, -kLimit, kLimit)));
  };
  const int c0 = px(a.x_min_m * s);
  const int c1 = px(a.x_max_m * s);
  const int r0 = px(rows - a.y_max_m * s);
  const int r1 = px(rows - a.y_min_m * s);
  return {c0, r0, c1 - c0, r1 - r0};
}

/// One camera frame, as a segmentation backend receives it.
struct Image {
  /// The colour image, I_h x I_w, CV_8UC3 in OpenCV's channel order, **B, G, R** (the member
  /// keeps its historical name); empty when the field has no colour image. A backend whose
  /// network wants RGB swaps the channels itself (ErfnetSegmenter does, from its model file).
  cv::Mat rgb;
  /// Simulation only: the orthomosaic's labels under the footprint at the orthomosaic's
  /// resolution (CV_8UC1, ignore label outside the orthomosaic); empty in live use.
  cv::Mat ground_truth;
  /// Orthomosaic pixels seen by the camera (may extend beyond the orthomosaic): camera
  /// pixel (u, v) covers the part (u, v) of a uniform I_w x I_h grid over this rectangle.
  cv::Rect footprint_px;
  /// Where the image was taken: x, y [m] field frame, z altitude [m].
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double gsd_cm = 0.0;    ///< [cm/px]
  int width_px = 0;       ///< I_w
  int height_px = 0;      ///< I_h
  int ignore_label = 255; ///< label for "no class" in ground_truth and in segmentations
};

/// Checks a segmentation of `image` against the contract of segmentation_backend.hpp: a
/// CV_8UC1 matrix of the image's size whose every value is a class index (below
/// `num_classes`) or the image's ignore label. Always on, in every build: a backend that
/// breaks the contract would otherwise fly a whole mission and report a meaningless map. The
/// scan stops at the first bad pixel (one pass over I_w x I_h bytes, well under a millisecond
/// for a 480 x 360 camera).
/// @param labels the segmentation to check.
/// @param image the image it segments (its size and ignore label).
/// @param num_classes the size of the class set, 1..255.
/// @param who names the source in the message, e.g. "segmentation backend 'erfnet'".
/// @throws std::invalid_argument naming `who` and the type, the size, or the first bad value
///         with its pixel (column x, row y) and the labels allowed.
inline void check_segmentation(const cv::Mat& labels, const Image& image, int num_classes, std::string_view who) {
  const std::string source(who);
  detail::require(num_classes >= 1 && num_classes <= 255, source + ": the class set must have 1..255 classes",
                  num_classes);
  detail::require(labels.type() == CV_8UC1,
                  source + " broke the segmentation contract: labels must be CV_8UC1 (8-bit, one channel)",
                  "type " + cv::typeToString(labels.type()));
  detail::require(labels.cols == image.width_px && labels.rows == image.height_px,
                  source + " broke the segmentation contract: labels must have the image's size " +
                      std::to_string(image.width_px) + "x" + std::to_string(image.height_px),
                  std::to_string(labels.cols) + "x" + std::to_string(labels.rows));
  for (int y = 0; y < labels.rows; ++y) {
    const auto* row = labels.ptr<unsigned char>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int v = row[x];
      if (v < num_classes || v == image.ignore_label) continue;
      throw std::invalid_argument(source + " broke the segmentation contract: label " + std::to_string(v) +
                                  " at pixel (x " + std::to_string(x) + ", y " + std::to_string(y) +
                                  ") is neither a class index 0.." + std::to_string(num_classes - 1) +
                                  " nor the ignore label " + std::to_string(image.ignore_label));
    }
  }
}

}  // namespace adaptseg
