#pragma once
/// @file
/// What the adaptive planner (adaptive_planner.hpp) watches of the descent in progress, and
/// what it hands the policy after the descent's last image (DescentOutcome, paper §3.2.3).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/metrics.hpp>

#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// The descent in progress over its region: the region's map before it (what its outcome
/// compares), and, with ranked cells, the finer images' own mass of the ranking input over the
/// cells they re-map (the scene check: DescentOutcome::fine_input).
class DescentWatch {
 public:
  /// The descent's first image is about to be fused; `region_labels` is the region's map before it.
  void begin(const cv::Mat& region_labels) {
    before_ = region_labels.clone();
    fine_mass_.clear();
    fine_known_ = true;
  }

  /// Ranked cells: adds the mass of `input` of the descent's image at `step` (`image`,
  /// `segmentation`) over its `cell` of the map grid (non-empty), whose field is `valid_mask(cell)`.
  void add_fine_image(std::size_t step, const Image& image, const Segmentation& segmentation,
                      std::span<const int> interest, int ignore_label, const cv::Rect& cell, const cv::Mat& valid_mask,
                      DecisionInput input) {
    scene_inputs_.assign(image, segmentation, interest, ignore_label, cell, std::array{input}, GridInputs::Cells::one);
    const CellInputs c = scene_inputs_.cell(valid_mask(cell), cv::Rect(0, 0, cell.width, cell.height));
    fine_known_ = fine_known_ && (c.field_px == 0.0 || std::isfinite(c.value(input)));
    fine_mass_.emplace_back(step, c.mass(input));
  }

  /// After the descent's last image: σ of the `region` of the fused map `labels` at h' (an
  /// empty region: 0) and what the descent relabelled over its field (`valid_mask`, the map
  /// grid's), into `out`.
  void region_outcome(DescentOutcome& out, const cv::Mat& labels, const cv::Mat& valid_mask, const cv::Rect& region,
                      std::span<const int> interest, int unknown_label) const {
    if (region.area() == 0) {
      out.sigma_sub = 0.0;
      return;
    }
    out.sigma_sub = semantic_ratio(labels(region), interest, unknown_label);
    out.relabelled = relabelling(before_, labels(region), valid_mask(region), interest);
  }

  /// Ranked cells: the ranking input's mass per field pixel of the region (`region_px`) over
  /// the `flown` first cells of `chosen` as the top-level image saw them, and as the finer
  /// images saw them where every one gave it, into `out`; each cell's mass over the pixels its
  /// gain is counted over (CellInputs::gain_px, as CellGainModel::Forecast::input weighs it).
  void input_outcome(DescentOutcome& out, const Candidate& chosen, std::size_t flown, double region_px,
                     DecisionInput input) const {
    const auto to_gain_px = [&](std::size_t k) {
      const CellInputs& c = chosen.cells[k];
      return c.field_px > 0.0 ? c.gain_px() / c.field_px : 1.0;
    };
    double top_mass = 0.0;  // over the cells flown (a descent cut short flew the first ones)
    for (std::size_t k = 0; k < chosen.cells.size() && k < flown; ++k)
      top_mass += chosen.cells[k].mass(input) * to_gain_px(k);
    double fine_mass = 0.0;
    for (const auto& [step, mass] : fine_mass_)
      fine_mass += step < chosen.cells.size() ? mass * to_gain_px(step) : mass;
    if (region_px > 0.0) {
      out.top_input = top_mass / region_px;
      if (fine_known_) out.fine_input = fine_mass / region_px;
    }
  }

 private:
  cv::Mat before_;  ///< the region's map before the descent
  /// Per image so far, its step and the finer look's input mass over its cell.
  std::vector<std::pair<std::size_t, double>> fine_mass_;
  bool fine_known_ = true;   ///< ... every image of it gave the input
  GridInputs scene_inputs_;  ///< the last descent image's inputs over its cell (buffers reused)
};

}  // namespace adaptseg::detail
