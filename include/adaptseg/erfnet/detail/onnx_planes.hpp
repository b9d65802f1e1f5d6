#pragma once
/// @file
/// Part of onnx_segmenter.hpp: what OnnxSegmenter does to the pixels around the network's forward
/// pass (the input blob, the softmax over the temperature, the argmax, the no-data mask). Include
/// <adaptseg/erfnet/onnx_segmenter.hpp>.

#include <adaptseg/erfnet/onnx_model_info.hpp>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace adaptseg::detail {

/// Per pixel, the index of the largest plane (ties to the lower index), CV_8UC1.
[[nodiscard]] inline cv::Mat onnx_argmax(const std::vector<cv::Mat>& planes) {
  const cv::Size size = planes.front().size();
  cv::Mat labels(size, CV_8UC1);
  const auto n = planes.size();
  std::vector<const float*> rows(n);
  for (int r = 0; r < size.height; ++r) {
    for (std::size_t c = 0; c < n; ++c) rows[c] = planes[c].ptr<float>(r);
    auto* out = labels.ptr<std::uint8_t>(r);
    for (int x = 0; x < size.width; ++x) {
      std::size_t best = 0;
      float best_v = rows[0][x];
      for (std::size_t c = 1; c < n; ++c)
        if (rows[c][x] > best_v) {  // strict: ties keep the lower index
          best_v = rows[c][x];
          best = c;
        }
      out[x] = static_cast<std::uint8_t>(best);
    }
  }
  return labels;
}

/// Logits -> softmax(logits / temperature) per pixel, in place.
inline void onnx_softmax_in_place(std::vector<cv::Mat>& planes, double temperature) {
  const cv::Size size = planes.front().size();
  const auto n = planes.size();
  const auto inv_t = static_cast<float>(1.0 / temperature);
  std::vector<float*> rows(n);
  for (int r = 0; r < size.height; ++r) {
    for (std::size_t c = 0; c < n; ++c) rows[c] = planes[c].ptr<float>(r);
    for (int x = 0; x < size.width; ++x) {
      float m = rows[0][x];
      for (std::size_t c = 1; c < n; ++c) m = std::max(m, rows[c][x]);
      float sum = 0.0f;
      for (std::size_t c = 0; c < n; ++c) {
        rows[c][x] = std::exp((rows[c][x] - m) * inv_t);
        sum += rows[c][x];
      }
      for (std::size_t c = 0; c < n; ++c) rows[c][x] /= sum;
    }
  }
}

/// NCHW float blob of an 8-bit BGR image, `(v / 255 - mean) / std` in the network's channel
/// order (`info`).
[[nodiscard]] inline cv::Mat onnx_blob(const cv::Mat& bgr, const OnnxModelInfo& info) {
  const int h = bgr.rows, w = bgr.cols;
  const int shape[] = {1, 3, h, w};
  cv::Mat blob(4, shape, CV_32F);
  std::array<float*, 3> dst{};
  for (int k = 0; k < 3; ++k) dst[static_cast<std::size_t>(k)] = blob.ptr<float>(0, k);
  // Network channel k reads BGR channel src[k].
  const std::array<int, 3> src = info.rgb_order ? std::array<int, 3>{2, 1, 0} : std::array<int, 3>{0, 1, 2};
  for (int r = 0; r < h; ++r) {
    const auto* p = bgr.ptr<std::uint8_t>(r);
    for (int x = 0; x < w; ++x)
      for (std::size_t k = 0; k < 3; ++k) {
        const float v = static_cast<float>(p[3 * x + src[k]]) / 255.0f;
        dst[k][static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
            (v - info.mean[k]) / info.std[k];
      }
  }
  return blob;
}

/// 255 where all three channels are 0 (SimulatedSensor's no-data), CV_8UC1.
[[nodiscard]] inline cv::Mat onnx_no_data_mask(const cv::Mat& bgr) {
  cv::Mat mask;
  cv::inRange(bgr, cv::Scalar(0, 0, 0), cv::Scalar(0, 0, 0), mask);
  return mask;
}

}  // namespace adaptseg::detail
