#pragma once
/// @file
/// The plug point for semantic segmentation: the `SegmentationBackend` concept.

#include <adaptseg/image.hpp>

#include <opencv2/core.hpp>

#include <concepts>
#include <string>

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

/// `backend.segment(image)`, checked against the contract (check_segmentation()) for a class
/// set of `num_classes` classes; what every planner and calibration of the library calls.
/// @throws std::invalid_argument naming the backend if its labels break the contract, and
///         whatever `segment` throws.
template <SegmentationBackend B>
[[nodiscard]] cv::Mat segment_checked(B& backend, const Image& image, int num_classes) {
  cv::Mat labels = backend.segment(image);
  check_segmentation(labels, image, num_classes, "segmentation backend '" + std::string(backend.name()) + "'");
  return labels;
}

}  // namespace adaptseg
