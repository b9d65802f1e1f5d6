#pragma once
/// @file
/// One camera frame as a segmentation backend receives it (`Image`), and the check of what a
/// backend gives back (`check_segmentation`), and the pixels of a raster under an area of the
/// field frame (`raster_rect`). OpenCV core and Eigen only: the segmentation contract
/// (segmentation_backend.hpp) and the live planner need nothing else.

#include <adaptseg/core/area.hpp>
#include <adaptseg/core/error.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

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
  /// The colour image, I_h x I_w, CV_8UC3 in OpenCV's channel order, **B, G, R** (`rgb` before
  /// adaptseg 0.3); empty when the field has no colour image. A backend whose network wants RGB
  /// swaps the channels itself (OnnxSegmenter does, from its model file).
  cv::Mat bgr;
  /// Simulation only: the orthomosaic's labels under the footprint at the orthomosaic's
  /// resolution, in the camera's orientation (CV_8UC1 of the footprint's size: row r, column c
  /// is the orthomosaic pixel under point (c + 0.5, r + 0.5) of FootprintFrame; the ignore
  /// label outside the orthomosaic); empty in live use.
  cv::Mat ground_truth;
  /// Orthomosaic pixels seen by the camera at yaw 0 (may extend beyond the orthomosaic):
  /// camera pixel (u, v) covers the part (u, v) of a uniform I_w x I_h grid over this
  /// rectangle, turned by `yaw_deg` about its centre (FootprintFrame).
  cv::Rect footprint_px;
  /// The camera's heading [deg]: the angle from the field's x axis to the image's x axis (its
  /// columns, u), counter-clockwise seen from above (field frame: x along the orthomosaic's
  /// columns, y up its rows). 0: image x along field x, as the planners fly every waypoint.
  double yaw_deg = 0.0;
  /// Where the image was taken: x, y [m] field frame, z altitude [m].
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double gsd_cm = 0.0;     ///< [cm/px]
  int width_px = 0;        ///< I_w
  int height_px = 0;       ///< I_h
  int ignore_label = 255;  ///< label for "no class" in ground_truth and in segmentations
};

/// Where a camera frame lies on the map grid: footprint coordinates (a, b) [map px] from the
/// top-left corner of the frame's yaw-0 footprint (a along the image's columns, b down its rows)
/// and map-pixel coordinates (x, y) [px] (x along the map's columns, y down its rows; pixel
/// (i, j) spans [i, i + 1) x [j, j + 1)), related by a turn of `yaw_deg` about the footprint's
/// centre. At yaw 0 the two frames differ by the footprint's offset only.
class FootprintFrame {
 public:
  /// @throws std::invalid_argument for an empty footprint or a yaw that is not finite.
  explicit FootprintFrame(const Image& image) : rect_(image.footprint_px) {
    detail::require(rect_.width > 0 && rect_.height > 0, "FootprintFrame: the image has no footprint",
                    rect_.width * rect_.height);
    detail::require(std::isfinite(image.yaw_deg), "FootprintFrame: yaw_deg must be finite", image.yaw_deg);
    const double r = std::remainder(image.yaw_deg, 360.0) * (3.14159265358979323846 / 180.0);
    cos_ = std::cos(r);
    sin_ = std::sin(r);
    // Quarter turns exactly: no 1e-16 residue may move a pixel centre across a pixel edge.
    if (std::abs(cos_) < 1e-12) cos_ = 0.0;
    if (std::abs(sin_) < 1e-12) sin_ = 0.0;
    cx_ = rect_.x + 0.5 * rect_.width;
    cy_ = rect_.y + 0.5 * rect_.height;
  }

  /// Footprint point (a, b) in map-pixel coordinates. The image's x axis (cos ψ, sin ψ) in the
  /// field frame is (cos ψ, -sin ψ) on the map grid, whose rows run down (field -y).
  [[nodiscard]] cv::Point2d to_map(double a, double b) const noexcept {
    const double da = a - 0.5 * rect_.width, db = b - 0.5 * rect_.height;
    return {cx_ + cos_ * da + sin_ * db, cy_ - sin_ * da + cos_ * db};
  }
  /// Map-pixel point (x, y) in footprint coordinates (the inverse of to_map()).
  [[nodiscard]] cv::Point2d to_footprint(double x, double y) const noexcept {
    const double dx = x - cx_, dy = y - cy_;
    return {0.5 * rect_.width + cos_ * dx - sin_ * dy, 0.5 * rect_.height + sin_ * dx + cos_ * dy};
  }
  /// The map pixels whose centres the turned footprint may cover (its bounding box, one pixel
  /// of margin for rounding); the footprint itself at yaw 0.
  [[nodiscard]] cv::Rect bounds() const {
    if (!turned()) return rect_;
    double x0 = cx_, x1 = cx_, y0 = cy_, y1 = cy_;
    const double w = rect_.width, h = rect_.height;
    for (const cv::Point2d& corner : {cv::Point2d(0, 0), cv::Point2d(w, 0), cv::Point2d(0, h), cv::Point2d(w, h)}) {
      const cv::Point2d p = to_map(corner.x, corner.y);
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
    const int c0 = static_cast<int>(std::floor(x0)) - 1, r0 = static_cast<int>(std::floor(y0)) - 1;
    return {c0, r0, static_cast<int>(std::ceil(x1)) + 1 - c0, static_cast<int>(std::ceil(y1)) + 1 - r0};
  }
  [[nodiscard]] bool turned() const noexcept { return cos_ != 1.0; }

 private:
  cv::Rect rect_;
  double cos_ = 1.0, sin_ = 0.0, cx_ = 0.0, cy_ = 0.0;
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

/// A segmentation as a backend may give it: per-pixel labels and, optionally, the class
/// probabilities behind them (SegmentationBackend, SegmentsWithProbabilities).
struct Segmentation {
  /// CV_8UC1 of the image's size: a class index or the image's ignore label per pixel.
  cv::Mat labels;
  /// Empty (a labels-only backend), or one CV_32FC1 plane per class of the image's size: the
  /// backend's probability of each class per pixel. On a pixel with a class label they are
  /// in [0, 1] and sum to 1; on a pixel with the ignore label they are all 0 or sum to 1.
  std::vector<cv::Mat> probabilities;
  /// Empty (one network, or a backend without members), or, from an ensemble
  /// (EnsembleSegmenter), one CV_32FC1 plane per class of the image's size: the weight share of
  /// the members whose own label is that class. Same value contract as `probabilities`; where a
  /// class's share lies strictly between 0 and 1 the members split on it (decision input `split`).
  std::vector<cv::Mat> member_votes{};
};

/// Checks `probabilities` of a segmentation of `image` with `labels` (already checked by
/// check_segmentation()) against the contract of Segmentation: none, or `num_classes` CV_32FC1
/// planes of the image's size, finite, in [0, 1], summing to 1 within `tolerance` on every
/// pixel with a class label, and to 1 or 0 on pixels with the ignore label. Always on, as
/// check_segmentation(): one pass over I_w x I_h x classes floats.
/// @throws std::invalid_argument naming `who` and the number of planes, a plane's type or size,
///         or the first bad pixel (column x, row y) with its value or sum.
inline void check_probabilities(const std::vector<cv::Mat>& probabilities, const cv::Mat& labels, const Image& image,
                                int num_classes, std::string_view who, double tolerance = 1e-3) {
  if (probabilities.empty()) return;
  const std::string source(who);
  const std::string broke = source + " broke the segmentation contract: ";
  detail::require(static_cast<int>(probabilities.size()) == num_classes,
                  broke + "probabilities must have one plane per class (" + std::to_string(num_classes) + ")",
                  probabilities.size());
  for (const cv::Mat& p : probabilities) {
    detail::require(p.type() == CV_32FC1, broke + "probability planes must be CV_32FC1",
                    "type " + cv::typeToString(p.type()));
    detail::require(p.cols == image.width_px && p.rows == image.height_px,
                    broke + "probability planes must have the image's size " + std::to_string(image.width_px) + "x" +
                        std::to_string(image.height_px),
                    std::to_string(p.cols) + "x" + std::to_string(p.rows));
  }
  const auto where = [](int x, int y) {
    return " at pixel (x " + std::to_string(x) + ", y " + std::to_string(y) + ")";
  };
  const auto text = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return std::string(buf);
  };
  std::vector<const float*> rows(probabilities.size());
  // A row at a time: every value in [0, 1] and every pixel's float sum well within the
  // tolerance of 1 (the common case, in loops the compiler vectorises); any other pixel is
  // checked, and reported, exactly as below.
  std::vector<float> row_sum(static_cast<std::size_t>(image.width_px));
  const auto clearly_one = static_cast<float>(tolerance - 1e-5);
  for (int y = 0; y < image.height_px; ++y) {
    for (std::size_t c = 0; c < rows.size(); ++c) rows[c] = probabilities[c].ptr<float>(y);
    const auto* label = labels.ptr<unsigned char>(y);
    std::fill(row_sum.begin(), row_sum.end(), 0.0f);
    int out_of_range = 0;
    for (std::size_t c = 0; c < rows.size(); ++c) {
      const float* r = rows[c];
      float* sum = row_sum.data();
      for (int x = 0; x < image.width_px; ++x) {
        sum[x] += r[x];
        out_of_range |= static_cast<int>(!(r[x] >= 0.0f) | !(r[x] <= 1.0f));  // NaN fails
      }
    }
    const bool in_range = out_of_range == 0;
    for (int x = 0; x < image.width_px; ++x) {
      if (in_range && std::abs(row_sum[static_cast<std::size_t>(x)] - 1.0f) <= clearly_one) continue;
      double sum = 0.0;
      for (std::size_t c = 0; c < rows.size(); ++c) {
        const float v = rows[c][x];
        if (!(v >= 0.0f && v <= 1.0f))  // NaN fails too
          throw std::invalid_argument(broke + "probability " + text(v) + " of class " + std::to_string(c) +
                                      where(x, y) + " is not in [0, 1]");
        sum += v;
      }
      const bool one = std::abs(sum - 1.0) <= tolerance;
      if (!one && !(label[x] == image.ignore_label && sum == 0.0))
        throw std::invalid_argument(broke + "probabilities" + where(x, y) + " sum to " + text(sum) +
                                    (label[x] == image.ignore_label ? ", neither 1 nor 0" : ", not 1") +
                                    " (tolerance " + text(tolerance) + ")");
    }
  }
}

/// Who made a segmentation, as the contract checks name it in their messages: its labels, its
/// probabilities and its member votes (e.g. "segmentation backend 'erfnet'" for the first two).
struct SegmentationSource {
  std::string labels;
  std::string probabilities;
  std::string member_votes;

  /// A backend named `name`: "segmentation backend 'NAME'" (member votes: "... (member votes)").
  [[nodiscard]] static SegmentationSource backend(std::string_view name) {
    std::string who = "segmentation backend '" + std::string(name) + "'";
    return {who, who, who + " (member votes)"};
  }
};

/// A Segmentation checked against the contract (check_segmentation(), check_probabilities())
/// for the image and class set it was made for: what crosses from the segmenter into the map and
/// the planner, checked once where it is made (check(), segment_and_check()) and trusted after.
/// Remembers the image size, ignore label and class count it was checked for (checked_for()).
class CheckedSegmentation {
 public:
  /// Checks `segmentation` of `image` for a class set of `num_classes` classes.
  /// @throws std::invalid_argument naming `source` as check_segmentation() and
  ///         check_probabilities() do.
  [[nodiscard]] static CheckedSegmentation check(Segmentation segmentation, const Image& image, int num_classes,
                                                 const SegmentationSource& source) {
    check_segmentation(segmentation.labels, image, num_classes, source.labels);
    check_probabilities(segmentation.probabilities, segmentation.labels, image, num_classes, source.probabilities);
    check_probabilities(segmentation.member_votes, segmentation.labels, image, num_classes, source.member_votes);
    return CheckedSegmentation(std::move(segmentation), num_classes, image.ignore_label);
  }

  [[nodiscard]] const Segmentation& get() const noexcept { return segmentation_; }
  [[nodiscard]] const cv::Mat& labels() const noexcept { return segmentation_.labels; }
  /// The segmentation, moved out.
  [[nodiscard]] Segmentation release() && { return std::move(segmentation_); }
  /// Whether it was checked for an image of `image`'s size and ignore label, and `num_classes`.
  [[nodiscard]] bool checked_for(const Image& image, int num_classes) const noexcept {
    return num_classes_ == num_classes && ignore_label_ == image.ignore_label &&
           segmentation_.labels.cols == image.width_px && segmentation_.labels.rows == image.height_px;
  }

 private:
  CheckedSegmentation(Segmentation s, int num_classes, int ignore_label)
      : segmentation_(std::move(s)), num_classes_(num_classes), ignore_label_(ignore_label) {}

  Segmentation segmentation_;
  int num_classes_;
  int ignore_label_;
};

}  // namespace adaptseg
