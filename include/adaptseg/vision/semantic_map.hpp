#pragma once
/// @file
/// The field map built from segmented images: finest GSD wins (paper §3.1), or the images'
/// class probabilities pooled (MapFusion; docs/method.md, "Decisions where the paper is silent,
/// and departures").

#include <adaptseg/core/map_fusion.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// Per orthomosaic pixel, the label of the finest-GSD observation that covered it ("we
/// preserve the results obtained with the highest resolution", paper §3.1), among equally
/// fine observations the latest; or, with MapFusion::pooled, the class of the largest sum over
/// the observations of log p_c / GSD (each probability floored at kPooledFloor); with
/// MapFusion::pooled_interest the same, except that a pixel some observation labelled with a
/// label of interest keeps the label of interest of the largest sum among those it was given;
/// with MapFusion::pooled_guarded the same as pooled, except that a pixel whose coarsest images
/// give their most likely class a pooled probability above kGuardConfidence keeps that class.
/// Pixels never observed hold `unknown_label()`.
class SemanticMap {
 public:
  /// The smallest probability pooling reads: no single image vetoes a class outright.
  static constexpr float kPooledFloor = 1.0f / 256.0f;
  /// MapFusion::pooled_guarded: above this pooled probability of their most likely class, the
  /// images at a pixel's coarsest GSD keep its label whatever finer images say (chosen on the
  /// leave-one-tile-out folds' training tiles, map_fusion.hpp).
  static constexpr float kGuardConfidence = 0.75f;

  /// @param size the orthomosaic's size [px].
  /// @param unknown_label value of pixels never observed (the field's ignore label).
  /// @param fusion how observations of one pixel combine; `pooled` keeps one float plane per
  ///        class besides the labels (4 bytes per pixel and class), allocated at the first image;
  ///        `pooled_interest` one byte per pixel more (which labels of interest it was given),
  ///        `pooled_guarded` one float plane per class and one more (the coarsest images' sums
  ///        and their GSD).
  /// @param interest the labels of interest (MapFusion::pooled_interest: one to eight; the
  ///        other fusions ignore them).
  /// @throws std::invalid_argument for an empty size, a label outside 0..255, or with
  ///         MapFusion::pooled_interest no label of interest, more than eight, or one outside
  ///         0..254.
  explicit SemanticMap(cv::Size size, int unknown_label = 255, MapFusion fusion = MapFusion::finest,
                       std::vector<int> interest = {})
      : unknown_(unknown_label), fusion_(fusion), interest_(std::move(interest)) {
    detail::require(size.width > 0 && size.height > 0, "SemanticMap: size must be positive", size.width * size.height);
    detail::require(unknown_label >= 0 && unknown_label <= 255, "SemanticMap: unknown_label must be in 0..255",
                    unknown_label);
    if (fusion_ == MapFusion::pooled_interest) {
      detail::require(!interest_.empty() && interest_.size() <= 8,
                      "SemanticMap: map fusion 'pooled-interest' needs one to eight labels of interest",
                      interest_.size());
      for (int l : interest_)
        detail::require(l >= 0 && l < 255, "SemanticMap: a label of interest must be in 0..254", l);
      seen_ = cv::Mat(size, CV_8UC1, cv::Scalar(0));
    } else {
      interest_.clear();
    }
    labels_ = cv::Mat(size, CV_8UC1, cv::Scalar(unknown_label));
    gsd_ = cv::Mat(size, CV_32F, cv::Scalar(std::numeric_limits<double>::infinity()));
  }

  /// Fuses the segmentation `labels` (I_h x I_w, CV_8UC1) of `image` into the map: each
  /// camera pixel is spread over the orthomosaic pixels it covers (nearest neighbour: the
  /// pixels whose centre it covers) and written where the image's GSD is at least as fine as
  /// what the map holds. Camera pixels with the image's ignore label write nothing. A camera
  /// turned by `image.yaw_deg` writes its turned footprint (FootprintFrame).
  /// With MapFusion::pooled the labels alone cannot be fused: fuse(image, Segmentation).
  /// @throws std::invalid_argument if `labels` does not match the image's size or type, or the
  ///         image has no footprint or a yaw that is not finite; for a pooled map, always.
  void fuse(const Image& image, const cv::Mat& labels) {
    detail::require(fusion_ == MapFusion::finest,
                    "SemanticMap::fuse: a pooled map needs the class probabilities; fuse(image, segmentation)",
                    to_string(fusion_));
    check_labels(image, labels);
    const FootprintFrame frame(image);
    if (frame.turned()) return fuse_turned(image, labels);
    const cv::Rect fp = image.footprint_px;
    const cv::Rect inside = fp & cv::Rect(0, 0, labels_.cols, labels_.rows);
    if (inside.area() == 0) return;
    index_for(labels.size(), fp.size());
    const auto gsd = static_cast<float>(image.gsd_cm);
    const auto ignore = static_cast<unsigned char>(image.ignore_label);
    const int* col_of = col_of_.ptr<int>(0) + (inside.x - fp.x);
    row_.resize(static_cast<std::size_t>(inside.width));
    int last_row = -1;
    for (int y = inside.y; y < inside.y + inside.height; ++y) {
      const int camera_row = row_of_.at<int>(y - fp.y, 0);
      if (camera_row != last_row) {  // the footprint row's labels, read once per camera row
        const auto* src = labels.ptr<unsigned char>(camera_row);
        for (int x = 0; x < inside.width; ++x) row_[static_cast<std::size_t>(x)] = src[col_of[x]];
        last_row = camera_row;
      }
      // Written where the image is at least as fine as what the pixel holds and not ignored
      // (as blends, which the compiler vectorises).
      auto* out = labels_.ptr<unsigned char>(y) + inside.x;
      auto* held = gsd_.ptr<float>(y) + inside.x;
      const unsigned char* in = row_.data();
      for (int x = 0; x < inside.width; ++x) {
        const bool write = held[x] >= gsd && in[x] != ignore;
        out[x] = write ? in[x] : out[x];
        held[x] = write ? gsd : held[x];
      }
    }
  }

  /// Fuses `segmentation` of `image`: as fuse(image, labels) for MapFusion::finest; for
  /// MapFusion::pooled each orthomosaic pixel the image covers (where its label is not the
  /// ignore label) adds log(max(p_c, kPooledFloor)) / GSD to class c's sum, and takes the class
  /// of the largest sum (ties to the lower class); for MapFusion::pooled_interest the same,
  /// unless that class is not of interest and some image (this one included) labelled the
  /// pixel with a label of interest: then the one of those with the largest sum (ties to the
  /// first in the list); for MapFusion::pooled_guarded the pooled class, unless the images at the
  /// coarsest GSD that covered the pixel (GSDs within 0.01 % count as one) give their class of
  /// the largest sum of log(max(p_c, kPooledFloor)) a probability softmax(sums) above
  /// kGuardConfidence: then that class (ties to the lower class).
  /// @throws std::invalid_argument as fuse(image, labels); for a pooled map also if the
  ///         probabilities are missing, are not CV_32FC1 planes of the image's size, or their
  ///         number differs from the first image's.
  void fuse(const Image& image, const Segmentation& segmentation) {
    if (fusion_ == MapFusion::finest) return fuse(image, segmentation.labels);
    const cv::Mat& labels = segmentation.labels;
    check_labels(image, labels);
    const std::vector<cv::Mat>& p = segmentation.probabilities;
    detail::require(!p.empty(),
                    "SemanticMap::fuse: a pooled map needs the class probabilities (a backend that gives them)", 0);
    if (pooled_.empty()) pooled_.assign(p.size(), cv::Mat());
    detail::require(p.size() == pooled_.size(), "SemanticMap::fuse: the number of class planes changed", p.size());
    log_.resize(p.size());
    for (std::size_t c = 0; c < p.size(); ++c) {
      detail::require(p[c].type() == CV_32FC1 && p[c].size() == labels.size(),
                      "SemanticMap::fuse: probabilities must be CV_32FC1 planes of the image's size", c);
      if (pooled_[c].empty()) pooled_[c] = cv::Mat(labels_.size(), CV_32F, cv::Scalar(0.0f));
      if (fusion_ == MapFusion::pooled_guarded && coarse_.size() <= c)
        coarse_.emplace_back(labels_.size(), CV_32F, cv::Scalar(0.0f));
      cv::log(cv::max(p[c], kPooledFloor), log_[c]);  // once per camera pixel, not per map pixel
    }
    const float weight = 1.0f / static_cast<float>(image.gsd_cm);
    const auto gsd = static_cast<float>(image.gsd_cm);
    if (fusion_ == MapFusion::pooled_guarded && coarse_gsd_.empty())
      coarse_gsd_ = cv::Mat(labels_.size(), CV_32F, cv::Scalar(0.0f));
    each_pixel(image, labels.size(), [&](int x, int y, int u, int v) {
      const unsigned char label = labels.at<unsigned char>(v, u);
      if (label == image.ignore_label) return;
      int best = 0;
      float best_sum = -std::numeric_limits<float>::infinity();
      for (std::size_t c = 0; c < pooled_.size(); ++c) {
        float& sum = pooled_[c].at<float>(y, x);
        sum += weight * log_[c].at<float>(v, u);
        if (sum > best_sum) {
          best_sum = sum;
          best = static_cast<int>(c);
        }
      }
      if (!interest_.empty()) best = kept_interest(x, y, label, best);
      if (!coarse_.empty()) best = guarded(x, y, u, v, gsd, best);
      labels_.at<unsigned char>(y, x) = static_cast<unsigned char>(best);
      float& held = gsd_.at<float>(y, x);
      held = std::min(held, gsd);
    });
  }

  /// Fused labels, CV_8UC1 of the orthomosaic's size.
  [[nodiscard]] const cv::Mat& labels() const noexcept { return labels_; }
  /// GSD [cm/px] of the observation each pixel holds; +inf where never observed. CV_32F.
  [[nodiscard]] const cv::Mat& gsd_cm() const noexcept { return gsd_; }
  [[nodiscard]] int unknown_label() const noexcept { return unknown_; }
  [[nodiscard]] MapFusion fusion() const noexcept { return fusion_; }

 private:
  void check_labels(const Image& image, const cv::Mat& labels) const {
    detail::require(labels.type() == CV_8UC1 && labels.cols == image.width_px && labels.rows == image.height_px,
                    "SemanticMap::fuse: labels must be CV_8UC1 of the image's size",
                    std::to_string(labels.cols) + "x" + std::to_string(labels.rows));
  }

  /// MapFusion::pooled_interest at map pixel (x, y), which an image labelled `label`: marks the
  /// label as seen there if it is of interest, and returns the label the pixel takes: `best`
  /// (the pooled class) if it is of interest or no label of interest was seen there, else the
  /// seen label of interest of the largest pooled sum (ties to the first in the list).
  [[nodiscard]] int kept_interest(int x, int y, unsigned char label, int best) {
    unsigned char& seen = seen_.at<unsigned char>(y, x);
    int pooled_is_interest = 0;
    for (std::size_t j = 0; j < interest_.size(); ++j) {
      if (label == interest_[j]) seen = static_cast<unsigned char>(seen | (1U << j));
      if (best == interest_[j]) pooled_is_interest = 1;
    }
    if (pooled_is_interest != 0 || seen == 0) return best;
    int kept = best;
    float kept_sum = -std::numeric_limits<float>::infinity();
    for (std::size_t j = 0; j < interest_.size(); ++j) {
      const auto c = static_cast<std::size_t>(interest_[j]);
      if ((seen & (1U << j)) == 0 || c >= pooled_.size()) continue;
      const float sum = pooled_[c].at<float>(y, x);
      if (sum > kept_sum) {
        kept_sum = sum;
        kept = interest_[j];
      }
    }
    return kept;
  }

  /// MapFusion::pooled_guarded at map pixel (x, y), which an image of `gsd` covers with its
  /// camera pixel (u, v): adds the image's log-probabilities to the coarsest images' sums (which
  /// it replaces where it is coarser, and leaves alone where it is finer), and returns the label
  /// the pixel takes: those sums' class where its probability is above kGuardConfidence, else
  /// `best` (the pooled class).
  [[nodiscard]] int guarded(int x, int y, int u, int v, float gsd, int best) {
    float& held = coarse_gsd_.at<float>(y, x);
    const bool coarser = gsd > held * 1.0001f;
    if (coarser || gsd >= held * 0.9999f) {
      for (std::size_t c = 0; c < coarse_.size(); ++c) {
        float& sum = coarse_[c].at<float>(y, x);
        sum = (coarser ? 0.0f : sum) + log_[c].at<float>(v, u);
      }
      if (coarser) held = gsd;
    }
    int top = 0;
    float top_sum = -std::numeric_limits<float>::infinity();
    for (std::size_t c = 0; c < coarse_.size(); ++c) {
      const float sum = coarse_[c].at<float>(y, x);
      if (sum > top_sum) {
        top_sum = sum;
        top = static_cast<int>(c);
      }
    }
    if (top == best) return best;
    float z = 0.0f;  // 1 / the top class's softmax probability
    for (const cv::Mat& plane : coarse_) z += std::exp(plane.at<float>(y, x) - top_sum);
    return z * kGuardConfidence < 1.0f ? top : best;
  }

  /// Which camera row / column each footprint row / column of a `camera` image over a footprint
  /// of `footprint` pixels reads: INTER_NEAREST_EXACT's resampling applied to the indices (as
  /// GridInputs does), kept from image to image.
  void index_for(cv::Size camera, cv::Size footprint) {
    if (index_size_ == camera && index_fp_ == footprint) return;
    cv::Mat cols(1, camera.width, CV_32SC1), rows(camera.height, 1, CV_32SC1);
    for (int x = 0; x < camera.width; ++x) cols.at<int>(0, x) = x;
    for (int y = 0; y < camera.height; ++y) rows.at<int>(y, 0) = y;
    cv::resize(cols, col_of_, cv::Size(footprint.width, 1), 0, 0, cv::INTER_NEAREST_EXACT);
    cv::resize(rows, row_of_, cv::Size(1, footprint.height), 0, 0, cv::INTER_NEAREST_EXACT);
    index_size_ = camera;
    index_fp_ = footprint;
  }

  /// Calls f(x, y, u, v) for every map pixel (x, y) the image covers with the camera pixel (u, v)
  /// it reads, as fuse(image, labels) places them (fuse_turned() for a turned camera).
  template <typename F>
  void each_pixel(const Image& image, cv::Size camera, F&& f) {
    const FootprintFrame frame(image);
    if (frame.turned()) {
      const cv::Rect inside = frame.bounds() & cv::Rect(0, 0, labels_.cols, labels_.rows);
      const double su = camera.width / static_cast<double>(image.footprint_px.width);
      const double sv = camera.height / static_cast<double>(image.footprint_px.height);
      for (int y = inside.y; y < inside.y + inside.height; ++y)
        for (int x = inside.x; x < inside.x + inside.width; ++x) {
          const cv::Point2d q = frame.to_footprint(x + 0.5, y + 0.5);
          const double u = std::floor(q.x * su), v = std::floor(q.y * sv);
          if (u < 0.0 || v < 0.0 || u >= camera.width || v >= camera.height) continue;
          f(x, y, static_cast<int>(u), static_cast<int>(v));
        }
      return;
    }
    const cv::Rect fp = image.footprint_px;
    const cv::Rect inside = fp & cv::Rect(0, 0, labels_.cols, labels_.rows);
    if (inside.area() == 0) return;
    index_for(camera, fp.size());
    for (int y = inside.y; y < inside.y + inside.height; ++y) {
      const int v = row_of_.at<int>(y - fp.y, 0);
      for (int x = inside.x; x < inside.x + inside.width; ++x) f(x, y, col_of_.at<int>(0, x - fp.x), v);
    }
  }

  /// fuse() of a turned camera: each map pixel whose centre the footprint covers takes the
  /// camera pixel over that centre.
  void fuse_turned(const Image& image, const cv::Mat& labels) {
    const auto gsd = static_cast<float>(image.gsd_cm);
    each_pixel(image, labels.size(), [&](int x, int y, int u, int v) {
      const unsigned char l = labels.at<unsigned char>(v, u);
      float& held = gsd_.at<float>(y, x);
      if (l == image.ignore_label || held < gsd) return;
      labels_.at<unsigned char>(y, x) = l;
      held = gsd;
    });
  }

  cv::Mat labels_;
  cv::Mat gsd_;
  int unknown_;
  MapFusion fusion_;
  // MapFusion::pooled_interest: the labels of interest, and per pixel which of them (bit j: the
  // j-th) some image gave it; empty for the other fusions.
  std::vector<int> interest_;
  cv::Mat seen_;
  // MapFusion::pooled: per class the sum of the images' weighted log-probabilities (allocated at
  // the first image), and fuse()'s scratch: the log-probabilities of one image.
  std::vector<cv::Mat> pooled_, log_;
  // MapFusion::pooled_guarded: per class the sum of log-probabilities of the images at each
  // pixel's coarsest GSD (unweighted), and that GSD (0 where none fell yet); empty otherwise.
  std::vector<cv::Mat> coarse_;
  cv::Mat coarse_gsd_;
  // fuse()'s scratch: the camera column / row of each footprint column / row for the last
  // (camera, footprint) sizes, and one footprint row of labels.
  cv::Mat col_of_, row_of_;
  cv::Size index_size_, index_fp_;
  std::vector<unsigned char> row_;
};

}  // namespace adaptseg
