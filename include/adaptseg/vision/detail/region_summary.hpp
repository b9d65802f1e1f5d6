#pragma once
/// @file
/// What the adaptive planner (adaptive_planner.hpp) reads of a top-level image's region for its
/// decision: the region's decision inputs where the coverage ranks cells, and every descent the
/// decision may choose from (descent_options.hpp).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/detail/descent_options.hpp>
#include <adaptseg/vision/detail/survey_grid.hpp>
#include <adaptseg/vision/gain_extent.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>

#include <array>
#include <span>
#include <vector>

namespace adaptseg::detail {

/// Whether `policy` reads the field's mean top-level entropy (ReadsFieldEntropy), so that the
/// region's inputs hold the entropy too.
template <class Policy>
[[nodiscard]] bool reads_field_entropy(const Policy& policy) {
  if constexpr (ReadsFieldEntropy<Policy>)
    return policy.reads_field_entropy();
  else
    return false;
}

/// A top-level image's region as the decision reads it (ranked cells: DescentCoverage::ranked):
/// its decision inputs on the map grid, their buffers kept from image to image.
class RegionSummary {
 public:
  /// The input the cells are ranked by, `cell_input`, and with `entropy` (the policy reads the
  /// field's entropy, ReadsFieldEntropy) the entropy too, of the top-level image (`image`,
  /// `segmentation`) over `region` on the map grid, about the labels of `interest`; none for an
  /// empty region. Valid until the next call.
  [[nodiscard]] const GridInputs* inputs(const Image& image, const Segmentation& segmentation, const cv::Rect& region,
                                         std::span<const int> interest, int ignore_label, DecisionInput cell_input,
                                         bool entropy) {
    if (region.area() == 0) return nullptr;
    if (entropy)
      inputs_.assign(image, segmentation, interest, ignore_label, region,
                     std::array{cell_input, DecisionInput::entropy});
    else
      inputs_.assign(image, segmentation, interest, ignore_label, region, std::array{cell_input});
    return &inputs_;
  }

  /// Every descent a decision over `region` may choose from, per GSD of `candidates`: the
  /// sub-lawnmower `plan_of(gsd)` (AdaptivePlanner::descent_plan), or where cells are ranked
  /// (`inputs` given, inputs()) its cells ranked by their mass of `cell_input`
  /// (append_ranked_options; none for an empty region or without inputs), each with the field
  /// pixels of its whole footprint where `extent` counts a gain there (GainExtent::images).
  template <class PlanOf>
  [[nodiscard]] static std::vector<DescentOption> options(const SurveyGrid& grid, const cv::Rect& region,
                                                          std::span<const double> candidates, bool ranks_cells,
                                                          const GridInputs* inputs, DecisionInput cell_input,
                                                          GainExtent extent, PlanOf&& plan_of) {
    std::vector<DescentOption> out;
    if (!ranks_cells) {
      for (double g : candidates) out.push_back({g, plan_of(g), {}});
      return out;
    }
    if (region.area() == 0 || !inputs) return out;
    const cv::Mat field = grid.area().valid_mask(region);
    const auto cell_rect = [&](const Area& a) { return (grid.pixel_rect(a) & region) - region.tl(); };
    const auto footprint_px = [&](const Area& a) {
      return extent == GainExtent::images ? static_cast<double>(grid.valid_pixels(a)) : 0.0;
    };
    for (double g : candidates)
      append_ranked_options(out, g, plan_of(g), *inputs, field, cell_input, cell_rect, footprint_px);
    return out;
  }

 private:
  GridInputs inputs_;  ///< the last top-level image's inputs (buffers reused)
};

}  // namespace adaptseg::detail
