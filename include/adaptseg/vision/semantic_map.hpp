#pragma once
/// @file
/// The field map built from segmented images: finest GSD wins (paper §3.1, docs/method.md,
/// "Decisions where the paper is silent, and departures").

#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace adaptseg {

/// Per orthomosaic pixel, the label of the finest-GSD observation that covered it ("we
/// preserve the results obtained with the highest resolution", paper §3.1). Among equally
/// fine observations the latest wins. Pixels never observed hold `unknown_label()`.
class SemanticMap {
 public:
  /// @param size the orthomosaic's size [px].
  /// @param unknown_label value of pixels never observed (the field's ignore label).
  /// @throws std::invalid_argument for an empty size or a label outside 0..255.
  explicit SemanticMap(cv::Size size, int unknown_label = 255) : unknown_(unknown_label) {
    detail::require(size.width > 0 && size.height > 0, "SemanticMap: size must be positive", size.width * size.height);
    detail::require(unknown_label >= 0 && unknown_label <= 255, "SemanticMap: unknown_label must be in 0..255",
                    unknown_label);
    labels_ = cv::Mat(size, CV_8UC1, cv::Scalar(unknown_label));
    gsd_ = cv::Mat(size, CV_32F, cv::Scalar(std::numeric_limits<double>::infinity()));
  }

  /// Fuses the segmentation `labels` (I_h x I_w, CV_8UC1) of `image` into the map: each
  /// camera pixel is spread over the orthomosaic pixels it covers (nearest neighbour: the
  /// pixels whose centre it covers) and written where the image's GSD is at least as fine as
  /// what the map holds. Camera pixels with the image's ignore label write nothing. A camera
  /// turned by `image.yaw_deg` writes its turned footprint (FootprintFrame).
  /// @throws std::invalid_argument if `labels` does not match the image's size or type, or the
  ///         image has no footprint or a yaw that is not finite.
  void fuse(const Image& image, const cv::Mat& labels) {
    detail::require(labels.type() == CV_8UC1 && labels.cols == image.width_px && labels.rows == image.height_px,
                    "SemanticMap::fuse: labels must be CV_8UC1 of the image's size",
                    std::to_string(labels.cols) + "x" + std::to_string(labels.rows));
    const FootprintFrame frame(image);
    if (frame.turned()) return fuse_turned(image, frame, labels);
    const cv::Rect fp = image.footprint_px;
    const cv::Rect inside = fp & cv::Rect(0, 0, labels_.cols, labels_.rows);
    if (inside.area() == 0) return;
    // Which camera row / column each footprint row / column reads: INTER_NEAREST_EXACT's
    // resampling applied to the indices (as GridInputs does), kept from image to image.
    if (index_size_ != cv::Size(labels.cols, labels.rows) || index_fp_ != fp.size()) {
      cv::Mat cols(1, labels.cols, CV_32SC1), rows(labels.rows, 1, CV_32SC1);
      for (int x = 0; x < labels.cols; ++x) cols.at<int>(0, x) = x;
      for (int y = 0; y < labels.rows; ++y) rows.at<int>(y, 0) = y;
      cv::resize(cols, col_of_, cv::Size(fp.width, 1), 0, 0, cv::INTER_NEAREST_EXACT);
      cv::resize(rows, row_of_, cv::Size(1, fp.height), 0, 0, cv::INTER_NEAREST_EXACT);
      index_size_ = cv::Size(labels.cols, labels.rows);
      index_fp_ = fp.size();
    }
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

  /// Fused labels, CV_8UC1 of the orthomosaic's size.
  [[nodiscard]] const cv::Mat& labels() const noexcept { return labels_; }
  /// GSD [cm/px] of the observation each pixel holds; +inf where never observed. CV_32F.
  [[nodiscard]] const cv::Mat& gsd_cm() const noexcept { return gsd_; }
  [[nodiscard]] int unknown_label() const noexcept { return unknown_; }

 private:
  /// fuse() of a turned camera: each map pixel whose centre the footprint covers takes the
  /// camera pixel over that centre.
  void fuse_turned(const Image& image, const FootprintFrame& frame, const cv::Mat& labels) {
    const cv::Rect inside = frame.bounds() & cv::Rect(0, 0, labels_.cols, labels_.rows);
    const double su = image.width_px / static_cast<double>(image.footprint_px.width);
    const double sv = image.height_px / static_cast<double>(image.footprint_px.height);
    const auto gsd = static_cast<float>(image.gsd_cm);
    for (int y = inside.y; y < inside.y + inside.height; ++y) {
      auto* out = labels_.ptr<unsigned char>(y);
      auto* held = gsd_.ptr<float>(y);
      for (int x = inside.x; x < inside.x + inside.width; ++x) {
        const cv::Point2d f = frame.to_footprint(x + 0.5, y + 0.5);
        const double u = std::floor(f.x * su), v = std::floor(f.y * sv);
        if (u < 0.0 || v < 0.0 || u >= image.width_px || v >= image.height_px) continue;
        const unsigned char l = labels.at<unsigned char>(static_cast<int>(v), static_cast<int>(u));
        if (l == image.ignore_label || held[x] < gsd) continue;
        out[x] = l;
        held[x] = gsd;
      }
    }
  }

  cv::Mat labels_;
  cv::Mat gsd_;
  int unknown_;
  // fuse()'s scratch: the camera column / row of each footprint column / row for the last
  // (camera, footprint) sizes, and one footprint row of labels.
  cv::Mat col_of_, row_of_;
  cv::Size index_size_, index_fp_;
  std::vector<unsigned char> row_;
};

}  // namespace adaptseg
