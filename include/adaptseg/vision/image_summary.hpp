#pragma once
/// @file
/// The per-image summary the decision reads (beyond the paper): the decision inputs of
/// decision_inputs.hpp computed once from a top-level segmentation and its class probabilities,
/// brought onto the map grid and summarised over the cells a descent may re-map.

#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/exact_sum.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace adaptseg {

/// The per-pixel quantity behind each decision input over a camera frame: one CV_32FC1 plane
/// per input (kDecisionInputs' order) of the segmentation's size; NaN on pixels with the ignore
/// label, and everywhere for inputs that need probabilities (member votes) when `segmentation`
/// has none.
/// `boundary`'s plane holds the σ indicator (its cell value is σ(1 − σ) of the mean;
/// cell_inputs()).
/// @throws std::invalid_argument for labels that are not CV_8UC1 or probabilities (member votes)
///         that are not CV_32FC1 planes of the labels' size.
[[nodiscard]] inline std::vector<cv::Mat> pixel_inputs(const Segmentation& segmentation, std::span<const int> interest,
                                                       int ignore_label) {
  const cv::Mat& labels = segmentation.labels;
  detail::require(labels.type() == CV_8UC1, "pixel_inputs: labels must be CV_8UC1", labels.type());
  const auto& probs = segmentation.probabilities;
  const auto& votes = segmentation.member_votes;
  for (const cv::Mat& p : probs)
    detail::require(p.type() == CV_32FC1 && p.size() == labels.size(),
                    "pixel_inputs: probabilities must be CV_32FC1 planes of the labels' size", p.cols);
  for (const cv::Mat& v : votes)
    detail::require(v.type() == CV_32FC1 && v.size() == labels.size(),
                    "pixel_inputs: member votes must be CV_32FC1 planes of the labels' size", v.cols);
  std::vector<cv::Mat> planes;
  for (std::size_t k = 0; k < kDecisionInputCount; ++k)
    planes.emplace_back(labels.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  std::array<bool, 256> in_l{};
  for (int c : interest)
    if (c >= 0 && c < 256) in_l[static_cast<std::size_t>(c)] = true;
  std::vector<const float*> p_row(probs.size()), v_row(votes.size());
  std::array<float*, kDecisionInputCount> out{};
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < labels.rows; ++y) {
    for (std::size_t k = 0; k < kDecisionInputCount; ++k) out[k] = planes[k].ptr<float>(y);
    for (std::size_t c = 0; c < probs.size(); ++c) p_row[c] = probs[c].ptr<float>(y);
    for (std::size_t c = 0; c < votes.size(); ++c) v_row[c] = votes[c].ptr<float>(y);
    const auto* l_row = labels.ptr<unsigned char>(y);
    pixel_input_rows(static_cast<std::size_t>(labels.cols), l_row, p_row, v_row, in_l, detail::kEveryDecisionInput,
                     out);
    for (int x = 0; x < labels.cols; ++x)
      if (l_row[x] == ignore_label)
        for (std::size_t k = 0; k < kDecisionInputCount; ++k) out[k][x] = nan;
  }
  return planes;
}

/// `planes` (camera-grid planes of `image`, e.g. pixel_inputs()) on the map grid over `rect`
/// (map pixels; typically the image's region): each map pixel whose centre the image's footprint
/// covers takes the camera pixel over that centre, as SemanticMap::fuse writes labels; NaN where
/// the footprint does not reach. Same size and type per plane: CV_32FC1 of `rect`'s size.
/// @throws std::invalid_argument for planes that are not CV_32FC1 of the image's size, or an
///         image without footprint or with a yaw that is not finite.
[[nodiscard]] inline std::vector<cv::Mat> planes_on_grid(const Image& image, const std::vector<cv::Mat>& planes,
                                                         cv::Rect rect) {
  const FootprintFrame frame(image);
  const double su = image.width_px / static_cast<double>(image.footprint_px.width);
  const double sv = image.height_px / static_cast<double>(image.footprint_px.height);
  std::vector<cv::Mat> out;
  cv::Mat up;  // each plane on the footprint: one buffer for all planes
  for (const cv::Mat& plane : planes) {
    detail::require(plane.type() == CV_32FC1 && plane.cols == image.width_px && plane.rows == image.height_px,
                    "planes_on_grid: planes must be CV_32FC1 of the image's size", plane.cols);
    cv::Mat grid(rect.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    if (!frame.turned()) {
      const cv::Rect fp = image.footprint_px;
      const cv::Rect inside = fp & rect;
      if (inside.area() > 0) {
        cv::resize(plane, up, fp.size(), 0, 0, cv::INTER_NEAREST_EXACT);
        up(inside - fp.tl()).copyTo(grid(inside - rect.tl()));
      }
    } else {
      for (int y = 0; y < rect.height; ++y) {
        auto* row = grid.ptr<float>(y);
        for (int x = 0; x < rect.width; ++x) {
          const cv::Point2d f = frame.to_footprint(rect.x + x + 0.5, rect.y + y + 0.5);
          const double u = std::floor(f.x * su), v = std::floor(f.y * sv);
          if (u < 0.0 || v < 0.0 || u >= image.width_px || v >= image.height_px) continue;
          row[x] = plane.at<float>(static_cast<int>(v), static_cast<int>(u));
        }
      }
    }
    out.push_back(std::move(grid));
  }
  return out;
}

namespace detail {
/// A cell's CellInputs from its sums and counts per input (NaN for inputs not `wanted` or
/// without a known pixel), `boundary` as σ(1 − σ) of its mean.
[[nodiscard]] inline CellInputs cell_means(const std::array<ExactSum, kDecisionInputCount>& sum,
                                           const std::array<std::int64_t, kDecisionInputCount>& count,
                                           std::int64_t field_px, const std::array<bool, kDecisionInputCount>& wanted) {
  CellInputs out;
  out.field_px = static_cast<double>(field_px);
  for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
    const double mean = wanted[k] && count[k] > 0 ? sum[k].value() / static_cast<double>(count[k])
                                                  : std::numeric_limits<double>::quiet_NaN();
    out.values[k] = cell_value(kDecisionInputs[k].input, mean);
  }
  return out;
}
}  // namespace detail

/// The decision inputs of the cell `cell` (map pixels, in the frame of `grid_planes`, e.g.
/// planes_on_grid() of a region) over the pixels where `field` (CV_8UC1 of the planes' size,
/// non-zero = field) is set and the image saw something: means of the planes, `boundary` as
/// σ(1 − σ) of its mean. NaN values for a cell without such pixels.
/// @throws std::invalid_argument unless there is one plane per input, each of `field`'s size.
[[nodiscard]] inline CellInputs cell_inputs(const std::vector<cv::Mat>& grid_planes, const cv::Mat& field,
                                            cv::Rect cell) {
  detail::require(grid_planes.size() == kDecisionInputCount, "cell_inputs: one plane per decision input needed",
                  grid_planes.size());
  for (const cv::Mat& p : grid_planes)
    detail::require(p.type() == CV_32FC1 && p.size() == field.size() && field.type() == CV_8UC1,
                    "cell_inputs: planes (CV_32FC1) and field mask (CV_8UC1) must have one size", p.cols);
  const cv::Rect r = cell & cv::Rect(0, 0, field.cols, field.rows);
  std::array<detail::ExactSum, kDecisionInputCount> sum{};
  std::array<std::int64_t, kDecisionInputCount> count{};
  std::int64_t field_px = 0;
  std::array<const float*, kDecisionInputCount> row{};
  for (int y = r.y; y < r.y + r.height; ++y) {
    const auto* f = field.ptr<unsigned char>(y);
    for (std::size_t k = 0; k < kDecisionInputCount; ++k) row[k] = grid_planes[k].ptr<float>(y);
    const float* seen = row[index_of(DecisionInput::sigma)];
    for (int x = r.x; x < r.x + r.width; ++x) {
      if (f[x] == 0 || std::isnan(seen[x])) continue;
      ++field_px;
      for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
        const float v = row[k][x];
        if (std::isnan(v)) continue;
        sum[k].add(detail::exact_units(v));
        ++count[k];
      }
    }
  }
  return detail::cell_means(sum, count, field_px, detail::kEveryDecisionInput);
}

}  // namespace adaptseg
