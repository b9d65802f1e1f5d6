#pragma once
/// @file
/// One camera frame as a segmentation backend receives it (`Image`), and the check of what a
/// backend gives back (`check_segmentation`). OpenCV core and Eigen only: the segmentation
/// contract (segmentation_backend.hpp) needs nothing else.

#include <adaptseg/error.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <string>
#include <string_view>

namespace adaptseg {

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
