#pragma once
/// @file
/// The ground-truth oracle: the segmentation a perfect classifier would give at the image's
/// resolution (method.md §1).

#include <adaptseg/segmentation_backend.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <string>

namespace adaptseg {

/// Labels each camera pixel with the majority class, weighted by area, of the orthomosaic
/// pixels it covers, so small objects vanish at high altitude as they do for a real
/// network. Orthomosaic pixels with the ignore label do not vote; a camera pixel that covers
/// no valid pixel gets the ignore label. Ties go to the lower class index. At the
/// orthomosaic's own GSD the oracle returns the ground truth unchanged.
///
/// Needs `Image::ground_truth` (simulation only).
class OracleSegmenter {
 public:
  /// @param num_classes size of the field's class set.
  /// @throws std::invalid_argument unless 1 <= num_classes <= 255.
  explicit OracleSegmenter(int num_classes) : num_classes_(num_classes) {
    detail::require(num_classes >= 1 && num_classes <= 255,
                    "OracleSegmenter: num_classes must be in 1..255", num_classes);
  }

  [[nodiscard]] std::string name() const { return "oracle"; }
  [[nodiscard]] int num_classes() const noexcept { return num_classes_; }

  /// @throws std::invalid_argument if the image carries no ground truth, or its ground
  ///         truth does not match its footprint.
  [[nodiscard]] cv::Mat segment(const Image& image) const {
    detail::require(!image.ground_truth.empty() && image.ground_truth.type() == CV_8UC1,
                    "OracleSegmenter::segment: the image carries no CV_8UC1 ground truth "
                    "(the oracle works on simulated images only)",
                    image.ground_truth.type());
    detail::require(image.ground_truth.size() == image.footprint_px.size(),
                    "OracleSegmenter::segment: ground truth size differs from footprint",
                    image.ground_truth.cols);
    detail::require(image.width_px > 0 && image.height_px > 0,
                    "OracleSegmenter::segment: image size must be positive", image.width_px);
    const cv::Size out_size(image.width_px, image.height_px);
    if (image.ground_truth.size() == out_size) return image.ground_truth.clone();

    cv::Mat best_votes(out_size, CV_32F, cv::Scalar(0.0f));
    cv::Mat labels(out_size, CV_8UC1, cv::Scalar(image.ignore_label));
    cv::Mat indicator, votes;
    for (int c = 0; c < num_classes_; ++c) {
      cv::compare(image.ground_truth, c, indicator, cv::CMP_EQ);  // 255 where class c
      if (cv::countNonZero(indicator) == 0) continue;
      indicator.convertTo(indicator, CV_32F, 1.0 / 255.0);
      cv::resize(indicator, votes, out_size, 0, 0, cv::INTER_AREA);  // area fraction of c
      const cv::Mat better = votes > best_votes;  // strict: ties keep the lower index
      votes.copyTo(best_votes, better);
      labels.setTo(c, better);
    }
    return labels;
  }

 private:
  int num_classes_;
};

static_assert(SegmentationBackend<OracleSegmenter>);

}  // namespace adaptseg
