#pragma once
/// @file
/// The ground-truth oracle: the segmentation a perfect classifier would give at the image's
/// resolution (docs/method.md, "Decisions where the paper is silent, and departures").

#include <adaptseg/vision/segmentation_backend.hpp>

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
    detail::require(num_classes >= 1 && num_classes <= 255, "OracleSegmenter: num_classes must be in 1..255",
                    num_classes);
  }

  [[nodiscard]] std::string name() const { return "oracle"; }
  [[nodiscard]] int num_classes() const noexcept { return num_classes_; }

  /// @throws std::invalid_argument if the image carries no ground truth, or its ground
  ///         truth does not match its footprint.
  [[nodiscard]] cv::Mat segment(const Image& image) const { return vote(image, false).labels; }

  /// segment() with the area vote behind each label as its probabilities: per camera pixel, the
  /// share of the valid orthomosaic pixels it covers that are of each class (the oracle's
  /// honest analogue of a network's softmax: 1 for the majority class of a pure pixel, split
  /// where the pixel mixes classes, as a coarse camera pixel does on a class boundary). All 0
  /// where no valid pixel votes (the ignore label). At the orthomosaic's GSD: one-hot.
  /// @throws std::invalid_argument as segment().
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) const { return vote(image, true); }

 private:
  [[nodiscard]] Segmentation vote(const Image& image, bool with_probabilities) const {
    detail::require(!image.ground_truth.empty() && image.ground_truth.type() == CV_8UC1,
                    "OracleSegmenter::segment: the image carries no CV_8UC1 ground truth "
                    "(the oracle works on simulated images only)",
                    image.ground_truth.type());
    detail::require(image.ground_truth.size() == image.footprint_px.size(),
                    "OracleSegmenter::segment: ground truth size differs from footprint", image.ground_truth.cols);
    detail::require(image.width_px > 0 && image.height_px > 0, "OracleSegmenter::segment: image size must be positive",
                    image.width_px);
    const cv::Size out_size(image.width_px, image.height_px);
    if (image.ground_truth.size() == out_size) return at_map_gsd(image, with_probabilities);
    Segmentation out;
    // The working buffers, kept by the thread from one image to the next (allocated again only
    // where the size changes): a simulated mission segments hundreds of images of a few sizes,
    // and under the sanitizers every fresh buffer is fresh pages (the oracle's allocations were
    // two fifths of the page faults of 50 simulated missions in test_adaptive_planner; kept,
    // that case ran in 16 s instead of 29). What the call returns is its own.
    thread_local Scratch scratch;
    auto& [mask, indicator, votes, better, best_votes, total] = scratch;
    best_votes.create(out_size, CV_32F);
    best_votes.setTo(0.0f);
    if (with_probabilities) {
      total.create(out_size, CV_32F);
      total.setTo(0.0f);
    }
    out.labels = cv::Mat(out_size, CV_8UC1, cv::Scalar(image.ignore_label));
    for (int c = 0; c < num_classes_; ++c) {
      cv::compare(image.ground_truth, c, mask, cv::CMP_EQ);  // 255 where class c
      if (cv::countNonZero(mask) == 0) {
        if (with_probabilities) out.probabilities.emplace_back(out_size, CV_32F, cv::Scalar(0.0f));
        continue;
      }
      mask.convertTo(indicator, CV_32F, 1.0 / 255.0);
      cv::resize(indicator, votes, out_size, 0, 0, cv::INTER_AREA);  // area fraction of c
      cv::compare(votes, best_votes, better, cv::CMP_GT);            // strict: ties keep the lower index
      votes.copyTo(best_votes, better);
      out.labels.setTo(c, better);
      if (with_probabilities) {
        total += votes;
        out.probabilities.push_back(votes.clone());
      }
    }
    if (with_probabilities) {
      // Shares of the valid pixels (ignore pixels do not vote); none where no pixel votes.
      const cv::Mat none = total <= 0.0f;
      total.setTo(1.0f, none);
      for (cv::Mat& p : out.probabilities) {
        cv::divide(p, total, p);
        p.setTo(0.0f, none);
        cv::min(p, 1.0f, p);  // rounding of INTER_AREA
      }
    }
    return out;
  }

  /// At the orthomosaic's GSD: the ground truth itself, one-hot probabilities.
  [[nodiscard]] Segmentation at_map_gsd(const Image& image, bool with_probabilities) const {
    Segmentation out;
    out.labels = image.ground_truth.clone();
    for (int c = 0; with_probabilities && c < num_classes_; ++c) {
      cv::Mat one_hot;
      cv::compare(out.labels, c, one_hot, cv::CMP_EQ);
      one_hot.convertTo(one_hot, CV_32F, 1.0 / 255.0);
      out.probabilities.push_back(one_hot);
    }
    return out;
  }

  /// The class loop's buffers (vote()).
  struct Scratch {
    cv::Mat mask, indicator, votes, better, best_votes, total;
  };

  int num_classes_;
};

static_assert(SegmentationBackend<OracleSegmenter>);
static_assert(SegmentsWithProbabilities<OracleSegmenter>);

}  // namespace adaptseg
