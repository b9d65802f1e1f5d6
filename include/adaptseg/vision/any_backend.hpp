#pragma once
/// @file
/// Any segmentation backend behind one type (AnyBackend): code that flies or calibrates with
/// several kinds of backend is compiled once, for this type, not once per backend.

#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>

#include <functional>
#include <string>

namespace adaptseg {

/// A backend with class probabilities behind one type: a virtual call per image, which costs
/// nothing next to a network, so that the planner, the missions and calibration are instantiated
/// once for every backend a program offers (the oracle, a network, an ensemble), and
/// calibration can segment each training field with another network (cross-fitting).
///
/// Borrows `backend`: it must outlive the AnyBackend. Thread safety is the wrapped backend's.
class AnyBackend {
 public:
  template <SegmentationBackend B>
  requires SegmentsWithProbabilities<B>
  explicit AnyBackend(B& backend)
      : name_(backend.name()),
        segment_([&backend](const Image& image) { return backend.segment(image); }),
        probabilities_([&backend](const Image& image) { return backend.segment_with_probabilities(image); }) {}
  [[nodiscard]] std::string name() const { return name_; }
  [[nodiscard]] cv::Mat segment(const Image& image) { return segment_(image); }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) { return probabilities_(image); }

 private:
  std::string name_;
  std::function<cv::Mat(const Image&)> segment_;
  std::function<Segmentation(const Image&)> probabilities_;
};

static_assert(SegmentationBackend<AnyBackend>);
static_assert(SegmentsWithProbabilities<AnyBackend>);

}  // namespace adaptseg
