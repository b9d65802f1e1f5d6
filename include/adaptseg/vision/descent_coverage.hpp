#pragma once
/// @file
/// What a descent re-maps (DescentCoverage, an AdaptiveOptions setting) and the rule of its
/// `interest` coverage for one cell (cell_shows_interest), shared by the adaptive planner and
/// calibration.

#include <adaptseg/core/error.hpp>
#include <adaptseg/vision/detail/label_lut.hpp>

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

namespace adaptseg {

/// What a descent's sub-lawnmower W^{h'} covers (AdaptiveOptions::coverage).
/// - `region`: the whole top-level footprint (paper §3.2.1), cells without field skipped.
/// - `interest` (beyond the paper): only the cells where the top-level image's segmentation
///   shows a label of interest within one top-level pixel of the cell. For a spatially
///   localised class the errors of the top-level map lie on the class's edges, so a descent
///   that re-maps only those cells buys most of the gain for a fraction of the time. Cells
///   where a small instance vanished at h_max are not re-mapped.
/// - `ranked` (beyond the paper): the region's cells ranked by their own expected gain, the mass
///   of one decision input of the top-level image over the cell (AdaptiveOptions::cell_input,
///   e.g. its expected error about L from the backend's class probabilities; decision_inputs.hpp),
///   and the descent re-maps the k best, k chosen by the decision: one candidate per k. Cells
///   with none of the input are never re-mapped.
enum class DescentCoverage { region, interest, ranked };

/// The name used in files and on the command line: "region", "interest" or "ranked".
[[nodiscard]] inline const char* to_string(DescentCoverage c) noexcept {
  switch (c) {
    case DescentCoverage::interest: return "interest";
    case DescentCoverage::ranked: return "ranked";
    case DescentCoverage::region: break;
  }
  return "region";
}

/// Parses "region", "interest" or "ranked".
/// @throws std::invalid_argument for anything else.
[[nodiscard]] inline DescentCoverage parse_descent_coverage(const std::string& s) {
  if (s == "region") return DescentCoverage::region;
  if (s == "interest") return DescentCoverage::interest;
  if (s == "ranked") return DescentCoverage::ranked;
  throw std::invalid_argument("descent coverage must be 'region', 'interest' or 'ranked', not '" + s + "'");
}

/// The DescentCoverage::interest rule for one sub-lawnmower cell: true if some pixel of
/// `labels` (the region's top-level segmentation on a grid of `grid_gsd_cm`) inside `cell`,
/// grown by one top-level pixel (`top_gsd_cm`) on every side and clipped to the image, carries
/// a class in `interest`. One rule for the planner and for calibration, so that a model's
/// samples are taken as its missions fly.
/// @throws std::invalid_argument unless `labels` is CV_8UC1 and both GSDs are finite and > 0.
[[nodiscard]] inline bool cell_shows_interest(const cv::Mat& labels, cv::Rect cell, double top_gsd_cm,
                                              double grid_gsd_cm, std::span<const int> interest) {
  detail::require(labels.type() == CV_8UC1, "cell_shows_interest: labels must be CV_8UC1", labels.type());
  detail::require(std::isfinite(top_gsd_cm) && top_gsd_cm > 0.0 && std::isfinite(grid_gsd_cm) && grid_gsd_cm > 0.0,
                  "cell_shows_interest: GSDs must be finite and > 0; top", top_gsd_cm);
  const int m = static_cast<int>(std::ceil(top_gsd_cm / grid_gsd_cm - 1e-9));  // one top-level pixel
  const cv::Rect rect =
      cv::Rect(cell.x - m, cell.y - m, cell.width + 2 * m, cell.height + 2 * m) & cv::Rect(0, 0, labels.cols, labels.rows);
  const auto lut = detail::label_lut(interest);
  for (int r = rect.y; r < rect.y + rect.height; ++r) {
    const auto* row = labels.ptr<std::uint8_t>(r);
    for (int c = rect.x; c < rect.x + rect.width; ++c)
      if (lut[row[c]]) return true;
  }
  return false;
}

}  // namespace adaptseg
