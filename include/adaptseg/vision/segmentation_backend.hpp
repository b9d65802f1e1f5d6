#pragma once
/// @file
/// The plug point for semantic segmentation: the `SegmentationBackend` concept.

#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>

#include <concepts>
#include <string>
#include <utility>

namespace adaptseg {

/// Has `segment(const Image&)` returning a label image.
/// Rationale: the planner needs nothing else from a network than per-pixel labels.
template <typename B>
concept SegmentsImages = requires(B& backend, const Image& image) {
  { backend.segment(image) } -> std::same_as<cv::Mat>;
};

/// Has a human-readable `name()`, written into mission results.
template <typename B>
concept NamedBackend = requires(const B& backend) {
  { backend.name() } -> std::convertible_to<std::string>;
};

/// A semantic segmentation backend (paper §3.1).
///
/// Semantic contract (checked for every model by tests/backend_conformance.hpp):
/// - `segment(image)` returns a CV_8UC1 matrix of `image.height_px` rows and
///   `image.width_px` columns; each value is a class index of the field's class set or
///   `image.ignore_label` where the backend can say nothing (e.g. outside the field).
/// - It does not modify `image` and does not keep references to it after returning.
/// - It may keep state between calls (caches, a network) but its output depends only on
///   the image: the same image gives the same labels.
/// - The library enforces the first point on every image it segments, in every build
///   (segment_checked(), check_segmentation()): a violation is a `std::invalid_argument`
///   naming the backend, the value and the pixel.
/// - `segment` may throw `std::invalid_argument` for an image it cannot handle (e.g. the
///   ERFNet backend given an image without RGB), naming what is missing.
/// - Thread safety: none is required; a planner calls one backend from one thread.
template <typename B>
concept SegmentationBackend = SegmentsImages<B> && NamedBackend<B>;

/// Optionally, a backend says how sure it is: `segment_with_probabilities(image)` returns the
/// labels `segment(image)` would give together with per-pixel class probabilities (Segmentation).
/// Rationale: where a network hesitates is where flying lower can change its map (docs/method.md,
/// "Cells that pay", its decision inputs); a labels-only backend still flies, with the decision
/// inputs that need no probabilities.
///
/// Contract, beyond SegmentationBackend's: the labels equal `segment(image)`'s; `probabilities`
/// holds one CV_32FC1 plane per class of the image's size, in [0, 1], summing to 1 on every
/// labelled pixel (0 or 1 on ignore pixels; check_probabilities()); `member_votes`, where an
/// ensemble gives them, likewise. Same image, same output.
template <typename B>
concept SegmentsWithProbabilities = requires(B& backend, const Image& image) {
  { backend.segment_with_probabilities(image) } -> std::same_as<Segmentation>;
};

/// `backend.segment(image)`, checked against the contract (check_segmentation()) for a class
/// set of `num_classes` classes: the labels alone, as a cv::Mat (segment_and_check() for a
/// CheckedSegmentation, with the class probabilities where wanted).
/// @throws std::invalid_argument naming the backend if its labels break the contract, and
///         whatever `segment` throws.
template <SegmentationBackend B>
[[nodiscard]] cv::Mat segment_checked(B& backend, const Image& image, int num_classes) {
  cv::Mat labels = backend.segment(image);
  check_segmentation(labels, image, num_classes, "segmentation backend '" + std::string(backend.name()) + "'");
  return labels;
}

/// `image` segmented by `backend` and checked (CheckedSegmentation) for a class set of
/// `num_classes` classes: with `probabilities`, the labels and the class probabilities where the
/// backend gives them (SegmentsWithProbabilities; a labels-only backend gives none); otherwise
/// the labels alone. What the library calls where it runs a backend itself (Mission, calibration,
/// segment_and_report()), so that a backend's segmentation is checked once, where it is made.
/// @throws std::invalid_argument naming the backend if its output breaks the contract, and
///         whatever the backend throws.
template <SegmentationBackend B>
[[nodiscard]] CheckedSegmentation segment_and_check(B& backend, const Image& image, int num_classes,
                                                    bool probabilities) {
  const SegmentationSource source = SegmentationSource::backend(backend.name());
  if constexpr (SegmentsWithProbabilities<B>) {
    if (probabilities)
      return CheckedSegmentation::check(backend.segment_with_probabilities(image), image, num_classes, source);
  }
  return CheckedSegmentation::check(Segmentation{backend.segment(image), {}}, image, num_classes, source);
}

/// The labels and, where the backend gives them (SegmentsWithProbabilities), the class
/// probabilities of `image`, both checked against the contract (check_segmentation(),
/// check_probabilities()) for a class set of `num_classes` classes: segment_and_check() with
/// probabilities, as a plain Segmentation. A labels-only backend gives empty probabilities.
/// @throws std::invalid_argument naming the backend if its output breaks the contract, and
///         whatever the backend throws.
template <SegmentationBackend B>
[[nodiscard]] Segmentation segment_with_probabilities_checked(B& backend, const Image& image, int num_classes) {
  return segment_and_check(backend, image, num_classes, true).release();
}

}  // namespace adaptseg
