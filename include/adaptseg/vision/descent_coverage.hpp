#pragma once
/// @file
/// What a descent re-maps (DescentCoverage, an AdaptiveOptions setting), one place per
/// coverage: its name, which cells it flies (cell_shows_interest for `interest`) and whether it
/// ranks them (DescentCoverageInfo). The adaptive planner and calibration ask a coverage's row,
/// never the coverage's name; a new coverage is a new row of kDescentCoverages.

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/vision/detail/label_lut.hpp>

#include <opencv2/core.hpp>

#include <array>
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

/// Whether DescentCoverage::interest flies one sub-lawnmower cell: true if some pixel of
/// `labels` (the region's top-level segmentation on a grid of `grid_gsd_cm`) inside `cell`,
/// grown by one top-level pixel (`top_gsd_cm`) on every side and clipped to the image, carries
/// a class in `interest`. One test for the planner and for calibration, so that a model's
/// samples are taken as its missions fly.
/// @throws std::invalid_argument unless `labels` is CV_8UC1 and both GSDs are finite and > 0.
[[nodiscard]] inline bool cell_shows_interest(const cv::Mat& labels, cv::Rect cell, double top_gsd_cm,
                                              double grid_gsd_cm, std::span<const int> interest) {
  detail::require(labels.type() == CV_8UC1, "cell_shows_interest: labels must be CV_8UC1", labels.type());
  detail::require(std::isfinite(top_gsd_cm) && top_gsd_cm > 0.0 && std::isfinite(grid_gsd_cm) && grid_gsd_cm > 0.0,
                  "cell_shows_interest: GSDs must be finite and > 0; top", top_gsd_cm);
  const int m = static_cast<int>(std::ceil(top_gsd_cm / grid_gsd_cm - 1e-9));  // one top-level pixel
  const cv::Rect rect = cv::Rect(cell.x - m, cell.y - m, cell.width + 2 * m, cell.height + 2 * m) &
                        cv::Rect(0, 0, labels.cols, labels.rows);
  const auto lut = detail::label_lut(interest);
  for (int r = rect.y; r < rect.y + rect.height; ++r) {
    const auto* row = labels.ptr<std::uint8_t>(r);
    for (int c = rect.x; c < rect.x + rect.width; ++c)
      if (lut[row[c]]) return true;
  }
  return false;
}

/// A coverage as the adaptive planner and calibration use it. A descent re-maps cells of its
/// region's sub-lawnmower: those with field that the coverage `flies`, and, where it
/// `ranks_cells`, the k best of those (one candidate per k, the decision chooses k).
struct DescentCoverageInfo {
  DescentCoverage coverage;
  const char* name;  ///< in model files and on the command line
  /// Whether a sub-lawnmower cell with field is flown, given the region's top-level labels
  /// (`labels`, on a grid of `grid_gsd_cm` over the region), the cell's pixels on that grid
  /// (`cell`), the top-level GSD and the labels of interest; nullptr: every cell with field. A
  /// cell it leaves out keeps its top-level labels in the map.
  bool (*flies)(const cv::Mat& labels, cv::Rect cell, double top_gsd_cm, double grid_gsd_cm,
                std::span<const int> interest);
  /// The cells are ranked by their mass of a decision input of the top-level image
  /// (AdaptiveOptions::cell_input), best first, cells without any left out, and the decision
  /// is offered one descent per number k of best cells; the backend's class probabilities are
  /// read (the inputs need them), each Candidate carries its cells and each DescentOutcome the
  /// input before and after (the scene check).
  bool ranks_cells;
};

/// Every coverage, one row each.
inline constexpr std::array<DescentCoverageInfo, 3> kDescentCoverages{{
    {DescentCoverage::region, "region", nullptr, false},
    {DescentCoverage::interest, "interest", cell_shows_interest, false},
    {DescentCoverage::ranked, "ranked", nullptr, true},
}};

/// The row of coverage `c`.
[[nodiscard]] inline const DescentCoverageInfo& descent_coverage_info(DescentCoverage c) {
  return detail::row_of(kDescentCoverages, &DescentCoverageInfo::coverage, c, "descent coverage");
}

/// The names before adaptseg 0.3 ("rule" now means a decision rule only); kept until 0.4.
using DescentCoverageRule [[deprecated("renamed adaptseg::DescentCoverageInfo in adaptseg 0.3")]] = DescentCoverageInfo;
[[deprecated("renamed adaptseg::descent_coverage_info in adaptseg 0.3")]] inline const DescentCoverageInfo&
descent_coverage_rule(DescentCoverage c) {
  return descent_coverage_info(c);
}

/// The name used in files and on the command line: "region", "interest" or "ranked".
[[nodiscard]] inline const char* to_string(DescentCoverage c) { return descent_coverage_info(c).name; }

/// Parses a coverage's name.
/// @throws std::invalid_argument for anything else.
[[nodiscard]] inline DescentCoverage parse_descent_coverage(const std::string& s) {
  return detail::row_named(kDescentCoverages, s, "descent coverage").coverage;
}

}  // namespace adaptseg
