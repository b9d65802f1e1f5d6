#pragma once
/// @file
/// Segmentation metrics (docs/method.md, "Decisions where the paper is silent, and departures"):
/// semantic ratio (paper Eq. `eq:vr`), per-class IoU and
/// mIoU (paper Eq. `eq:iou`) over a class set, per image and over the fused field.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/vision/detail/label_lut.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// Semantic ratio σ of a label image (paper Eq. `eq:vr`): pixels labelled with a class in
/// `interest` over valid pixels (those not equal to `ignore_label`). The paper divides by all
/// pixels; pixels outside the field carry no information, so they are left out here. 0 when
/// the image has no valid pixel.
/// @throws std::invalid_argument unless `labels` is CV_8UC1.
[[nodiscard]] inline double semantic_ratio(const cv::Mat& labels, std::span<const int> interest, int ignore_label) {
  detail::require(labels.type() == CV_8UC1, "semantic_ratio: labels must be CV_8UC1", labels.type());
  std::int64_t valid = 0, hits = 0;
  const auto lut = detail::label_lut(interest);
  for (int r = 0; r < labels.rows; ++r) {
    const auto* row = labels.ptr<std::uint8_t>(r);
    for (int c = 0; c < labels.cols; ++c) {
      if (row[c] == ignore_label) continue;
      ++valid;
      hits += lut[row[c]] ? 1 : 0;
    }
  }
  return valid == 0 ? 0.0 : static_cast<double>(hits) / static_cast<double>(valid);
}

/// A class's true positives, false positives and false negatives [px] (ConfusionMatrix::counts).
struct PixelCounts {
  std::int64_t tp = 0;
  std::int64_t fp = 0;
  std::int64_t fn = 0;
};

/// Pixel counts of (true class, predicted class) over valid pixels. A prediction that is
/// no class (the ignore label, or never observed) counts in an extra "none" column, so it
/// is a false negative for the true class and a false positive for none.
class ConfusionMatrix {
 public:
  /// @throws std::invalid_argument unless 1 <= num_classes <= 255.
  explicit ConfusionMatrix(int num_classes) : n_(num_classes) {
    detail::require(num_classes >= 1 && num_classes <= 255, "ConfusionMatrix: num_classes must be in 1..255",
                    num_classes);
    counts_.assign(static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_ + 1), 0);
  }

  [[nodiscard]] int num_classes() const noexcept { return n_; }

  /// Adds every pixel where `truth` is not `ignore_label`.
  /// @throws std::invalid_argument unless both are CV_8UC1 of the same size.
  void add(const cv::Mat& truth, const cv::Mat& predicted, int ignore_label) {
    detail::require(truth.type() == CV_8UC1 && predicted.type() == CV_8UC1 && truth.size() == predicted.size(),
                    "ConfusionMatrix::add: truth and prediction must be CV_8UC1 of one size",
                    std::to_string(truth.cols) + "x" + std::to_string(truth.rows) + " vs " +
                        std::to_string(predicted.cols) + "x" + std::to_string(predicted.rows));
    for (int r = 0; r < truth.rows; ++r) {
      const auto* t = truth.ptr<std::uint8_t>(r);
      const auto* p = predicted.ptr<std::uint8_t>(r);
      for (int c = 0; c < truth.cols; ++c) {
        if (t[c] == ignore_label || t[c] >= n_) continue;
        const int pred = p[c] < n_ ? p[c] : n_;
        ++counts_[index(t[c], pred)];
      }
    }
  }

  /// Pixels of true class `truth` predicted as `predicted` (`num_classes()` = none).
  /// @throws std::invalid_argument unless 0 <= truth < num_classes() and 0 <= predicted <= num_classes().
  [[nodiscard]] std::int64_t count(int truth, int predicted) const {
    detail::require(truth >= 0 && truth < n_ && predicted >= 0 && predicted <= n_,
                    "ConfusionMatrix::count: truth must be in 0..num_classes() - 1 and prediction in "
                    "0..num_classes() (num_classes(): none); truth, prediction",
                    std::to_string(truth) + ", " + std::to_string(predicted));
    return counts_[index(truth, predicted)];
  }

  [[nodiscard]] std::int64_t total() const {
    std::int64_t s = 0;
    for (auto v : counts_) s += v;
    return s;
  }

  /// Share of the counted (valid) truth pixels whose true class is in `classes`: the semantic
  /// ratio of the ground truth (Eq. `eq:vr` on the truth instead of a segmentation); 0 if
  /// nothing was counted.
  /// @throws std::invalid_argument for a class out of range.
  [[nodiscard]] double truth_share(std::span<const int> classes) const {
    const std::int64_t all = total();
    std::int64_t in = 0;
    for (int c : classes) {
      detail::require(c >= 0 && c < n_, "ConfusionMatrix::truth_share: class out of range", c);
      for (int k = 0; k <= n_; ++k) in += count(c, k);
    }
    return all == 0 ? 0.0 : static_cast<double>(in) / static_cast<double>(all);
  }

  /// True positives, false positives and false negatives of class `c` [px] (a pixel of class
  /// `c` left without a label is a false negative).
  /// @throws std::invalid_argument for a class out of range.
  [[nodiscard]] PixelCounts counts(int c) const {
    detail::require(c >= 0 && c < n_, "ConfusionMatrix::counts: class out of range", c);
    PixelCounts out{count(c, c), 0, 0};
    for (int k = 0; k <= n_; ++k)
      if (k != c) out.fn += count(c, k);
    for (int k = 0; k < n_; ++k)
      if (k != c) out.fp += count(k, c);
    return out;
  }

  /// The same summed over `classes`.
  /// @throws std::invalid_argument for a class out of range.
  [[nodiscard]] PixelCounts counts(std::span<const int> classes) const {
    PixelCounts sum;
    for (int c : classes) {
      const PixelCounts one = counts(c);
      sum.tp += one.tp;
      sum.fp += one.fp;
      sum.fn += one.fn;
    }
    return sum;
  }

  /// IoU = TP / (TP + FP + FN) of class `c`; nullopt if `c` occurs in neither the truth nor
  /// the prediction.
  /// @throws std::invalid_argument for a class out of range.
  [[nodiscard]] std::optional<double> iou(int c) const {
    detail::require(c >= 0 && c < n_, "ConfusionMatrix::iou: class out of range", c);
    const PixelCounts k = counts(c);
    const std::int64_t uni = k.tp + k.fp + k.fn;
    if (uni == 0) return std::nullopt;
    return static_cast<double>(k.tp) / static_cast<double>(uni);
  }

  /// Mean IoU over `classes`, averaging those that occur in the truth or the prediction
  /// (paper Eq. `eq:iou`); nullopt if none does.
  [[nodiscard]] std::optional<double> miou(std::span<const int> classes) const {
    double sum = 0.0;
    int n = 0;
    for (int c : classes) {
      if (const auto v = iou(c)) {
        sum += *v;
        ++n;
      }
    }
    if (n == 0) return std::nullopt;
    return sum / n;
  }

  /// Mean IoU over all classes.
  [[nodiscard]] std::optional<double> miou_all() const {
    std::vector<int> all(static_cast<std::size_t>(n_));
    for (int c = 0; c < n_; ++c) all[static_cast<std::size_t>(c)] = c;
    return miou(all);
  }

  ConfusionMatrix& operator+=(const ConfusionMatrix& other) {
    detail::require(other.n_ == n_, "ConfusionMatrix::operator+=: class counts differ", other.n_);
    for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
    return *this;
  }

  /// Removes counts added before (e.g. one region's, to score a map without it).
  /// @throws std::invalid_argument if the class counts differ or a count would become negative.
  ConfusionMatrix& operator-=(const ConfusionMatrix& other) {
    detail::require(other.n_ == n_, "ConfusionMatrix::operator-=: class counts differ", other.n_);
    for (std::size_t i = 0; i < counts_.size(); ++i)
      detail::require(counts_[i] >= other.counts_[i], "ConfusionMatrix::operator-=: a count would become negative",
                      other.counts_[i]);
    for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] -= other.counts_[i];
    return *this;
  }

 private:
  /// The row-major index of a cell of the (num_classes() × (num_classes() + 1)) counts, in
  /// std::size_t before the product.
  [[nodiscard]] std::size_t index(int truth, int predicted) const noexcept {
    return static_cast<std::size_t>(truth) * static_cast<std::size_t>(n_ + 1) + static_cast<std::size_t>(predicted);
  }

  int n_;
  std::vector<std::int64_t> counts_;
};

/// mIoU over `classes` of two predictions of the same region, on a common class set: the
/// classes that occur in the truth or in either prediction. A class absent from the truth and
/// from one prediction scores 1 for that prediction (nothing to get wrong); a region where no
/// class of the set occurs anywhere scores 1 for both.
/// @return {mIoU of a, mIoU of b}
[[nodiscard]] inline std::pair<double, double> paired_miou(const ConfusionMatrix& a, const ConfusionMatrix& b,
                                                           std::span<const int> classes) {
  double sa = 0.0, sb = 0.0;
  int n = 0;
  for (int c : classes) {
    const auto ia = a.iou(c);
    const auto ib = b.iou(c);
    if (!ia && !ib) continue;
    sa += ia.value_or(1.0);
    sb += ib.value_or(1.0);
    ++n;
  }
  if (n == 0) return {1.0, 1.0};
  return {sa / n, sb / n};
}

namespace detail {

/// Calls `visit(row, col, before_label, after_label)` for every pixel of `before` and `after`
/// (CV_8UC1 of one size, checked by the caller) where `field_mask` is non-zero (every pixel if it
/// is empty); returns how many it visited: what relabelling() and agreeing_changes() count over.
template <class Visit>
std::int64_t for_each_field_pixel(const cv::Mat& before, const cv::Mat& after, const cv::Mat& field_mask,
                                  Visit&& visit) {
  std::int64_t n = 0;
  for (int r = 0; r < before.rows; ++r) {
    const auto* b = before.ptr<std::uint8_t>(r);
    const auto* a = after.ptr<std::uint8_t>(r);
    const auto* m = field_mask.empty() ? nullptr : field_mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < before.cols; ++c) {
      if (m != nullptr && m[c] == 0) continue;
      ++n;
      visit(r, c, b[c], a[c]);
    }
  }
  return n;
}

}  // namespace detail

/// Relabelling (decision.hpp) between two label maps of one region, over the pixels where `field_mask` is
/// non-zero (all pixels if it is empty); 0 for a region without field pixels.
/// @throws std::invalid_argument unless the maps (and a non-empty mask) are CV_8UC1 of one size.
[[nodiscard]] inline Relabelling relabelling(const cv::Mat& before, const cv::Mat& after, const cv::Mat& field_mask,
                                             std::span<const int> interest) {
  detail::require(before.type() == CV_8UC1 && after.type() == CV_8UC1 && before.size() == after.size() &&
                      (field_mask.empty() || (field_mask.type() == CV_8UC1 && field_mask.size() == before.size())),
                  "relabelling: before, after (and the mask) must be CV_8UC1 of one size",
                  std::to_string(before.cols) + "x" + std::to_string(before.rows) + " vs " +
                      std::to_string(after.cols) + "x" + std::to_string(after.rows));
  const auto lut = detail::label_lut(interest);
  std::int64_t changed = 0, changed_l = 0, added = 0, removed = 0;
  const std::int64_t n =
      detail::for_each_field_pixel(before, after, field_mask, [&](int, int, std::uint8_t b, std::uint8_t a) {
        if (a == b) return;
        ++changed;
        changed_l += lut[a] || lut[b] ? 1 : 0;
        added += lut[a] && !lut[b] ? 1 : 0;
        removed += lut[b] && !lut[a] ? 1 : 0;
      });
  if (n == 0) return {};
  const auto share = [n](std::int64_t k) { return static_cast<double>(k) / static_cast<double>(n); };
  return {share(changed), share(changed_l), share(added), share(removed)};
}

/// Of a relabelling's changes into and out of L (`before` → `after`, as relabelling() counts
/// them), the shares of the mask's pixels whose new side of L every map in `checks` also gives:
/// with the ground truth as the check, the changes that are right; with another look at the
/// region, the changes it confirms. Returned as a Relabelling's added_share and removed_share
/// (its other members 0).
/// @throws std::invalid_argument unless every map (and a non-empty mask) is CV_8UC1 of one size.
[[nodiscard]] inline Relabelling agreeing_changes(const cv::Mat& before, const cv::Mat& after,
                                                  std::initializer_list<cv::Mat> checks, const cv::Mat& field_mask,
                                                  std::span<const int> interest) {
  bool fits = before.type() == CV_8UC1 && after.type() == CV_8UC1 && before.size() == after.size() &&
              (field_mask.empty() || (field_mask.type() == CV_8UC1 && field_mask.size() == before.size()));
  for (const cv::Mat& c : checks) fits = fits && c.type() == CV_8UC1 && c.size() == before.size();
  detail::require(fits, "agreeing_changes: every map (and the mask) must be CV_8UC1 of one size",
                  std::to_string(before.cols) + "x" + std::to_string(before.rows));
  const auto lut = detail::label_lut(interest);
  std::int64_t added = 0, removed = 0;
  const std::int64_t n =
      detail::for_each_field_pixel(before, after, field_mask, [&](int r, int c, std::uint8_t b, std::uint8_t a) {
        const bool in = lut[a];
        if (in == lut[b]) return;
        if (std::all_of(checks.begin(), checks.end(),
                        [&](const cv::Mat& k) { return lut[k.at<std::uint8_t>(r, c)] == in; }))
          (in ? added : removed) += 1;
      });
  if (n == 0) return {};
  const auto share = [n](std::int64_t k) { return static_cast<double>(k) / static_cast<double>(n); };
  return {.added_share = share(added), .removed_share = share(removed)};
}

/// Confusion of one image's segmentation against its ground truth at the orthomosaic's
/// resolution (each camera pixel spread over the orthomosaic pixels it covers).
/// @throws std::invalid_argument if the image has no ground truth or `labels` is not
///         CV_8UC1 of the image's size.
[[nodiscard]] inline ConfusionMatrix image_confusion(const Image& image, const cv::Mat& labels, int num_classes) {
  detail::require(!image.ground_truth.empty(), "image_confusion: the image has no ground truth", 0);
  detail::require(labels.type() == CV_8UC1 && labels.cols == image.width_px && labels.rows == image.height_px,
                  "image_confusion: labels must be CV_8UC1 of the image's size", labels.cols);
  cv::Mat up;
  cv::resize(labels, up, image.ground_truth.size(), 0, 0, cv::INTER_NEAREST_EXACT);
  ConfusionMatrix cm(num_classes);
  cm.add(image.ground_truth, up, image.ignore_label);
  return cm;
}

}  // namespace adaptseg
