#pragma once
/// @file
/// What a decision of the adaptive planner (adaptive_planner.hpp) may choose from at one
/// top-level waypoint: per candidate GSD the descent's sub-lawnmower, or with cells ranked
/// (DescentCoverage::ranked) one option per number of its best cells.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/grid_inputs.hpp>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// What a descent at a top-level waypoint may fly at one GSD: its sub-lawnmower and, for a
/// coverage that ranks cells, the cells it re-maps.
struct DescentOption {
  double gsd_cm = 0.0;
  std::vector<Waypoint> plan;
  std::vector<CellInputs> cells;
};

/// Appends to `out` the options of a coverage that ranks cells at `gsd_cm`: the cells of the
/// sub-lawnmower `all` ranked by their mass of `input` in the region's `inputs` (each cell's
/// rectangle in the region's pixels from `cell_rect(footprint)`, its field from `field`, the
/// region's valid mask; CellInputs::footprint_px from `footprint_px(footprint)`), one option
/// per number k of the best cells (cells without any of the input left out; ties in the
/// sub-lawnmower's order), each flown in the sub-lawnmower's order.
template <class CellRect, class FootprintPx>
void append_ranked_options(std::vector<DescentOption>& out, double gsd_cm, const std::vector<Waypoint>& all,
                           const GridInputs& inputs, const cv::Mat& field, DecisionInput input, CellRect&& cell_rect,
                           FootprintPx&& footprint_px) {
  std::vector<CellInputs> cells;
  std::vector<std::size_t> ranked;
  for (std::size_t k = 0; k < all.size(); ++k) {
    cells.push_back(inputs.cell(field, cell_rect(all[k].footprint)));
    cells.back().footprint_px = footprint_px(all[k].footprint);
    if (cells.back().mass(input) > 0.0) ranked.push_back(k);
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [&](std::size_t a, std::size_t b) { return cells[a].mass(input) > cells[b].mass(input); });
  std::vector<bool> chosen(all.size(), false);
  for (std::size_t n = 0; n < ranked.size(); ++n) {
    chosen[ranked[n]] = true;
    DescentOption o{gsd_cm, {}, {}};
    for (std::size_t k = 0; k < all.size(); ++k)
      if (chosen[k]) o.plan.push_back(all[k]), o.cells.push_back(cells[k]);
    out.push_back(std::move(o));
  }
}

}  // namespace adaptseg::detail
