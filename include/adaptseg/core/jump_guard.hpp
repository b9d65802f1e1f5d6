#pragma once
/// @file
/// The jump guard (beyond the paper; docs/method.md, "The jump guard"): a network that, looking
/// closer at ground it never trained on, writes a class of interest where it is absent shows it
/// in flight, image by image, as a descent image whose σ lies far above the top-level map's σ
/// over the same cell. The bound is learned on the training fields' cells (calibration's cell
/// samples, each field segmented by a network that never saw it): the jump above which
/// re-mapping lost field accuracy there.

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg {

/// The jump guard's bound from `cells` (CellSample, one per cell re-mapped in calibration): each
/// cell's jump is its finer image's σ minus its top-level σ; sorted by jump, largest first, the
/// cells whose field gains (CellSample::field_gain) sum to the lowest negative total are those
/// the bound refuses: it lies halfway between the smallest jump among them and the next. No such
/// set (re-mapping never lost in total from the largest jump down), or fewer than two cells with
/// both σ known: infinity (no guard).
[[nodiscard]] inline double jump_bound(std::span<const CellSample> cells) {
  std::vector<std::pair<double, double>> jumps;  // (jump, field gain)
  for (const CellSample& c : cells) {
    const double jump = c.fine.value(DecisionInput::sigma) - c.top.value(DecisionInput::sigma);
    if (std::isfinite(jump) && std::isfinite(c.field_gain)) jumps.emplace_back(jump, c.field_gain);
  }
  std::sort(jumps.begin(), jumps.end(), std::greater<>());
  double sum = 0.0, lowest = 0.0;
  std::size_t refused = 0;  // the lowest total's cells: the first `refused`
  for (std::size_t k = 0; k + 1 < jumps.size(); ++k) {
    sum += jumps[k].second;
    if (sum < lowest) lowest = sum, refused = k + 1;
  }
  if (refused == 0) return std::numeric_limits<double>::infinity();
  return 0.5 * (jumps[refused - 1].first + jumps[refused].first);
}

/// The guard in flight: a descent image whose σ exceeds the top-level map's σ over its cell by
/// more than `bound` is not trusted, and once one is not, no descent is trusted for the rest of the mission
/// (the policy descends no more; AdaptivePlanner does not fuse the image and ends its descent).
class JumpGuard {
 public:
  /// @throws std::invalid_argument for a bound that is NaN (infinity: no guard).
  explicit JumpGuard(double bound = std::numeric_limits<double>::infinity()) : bound_(bound) {
    detail::require(!std::isnan(bound), "JumpGuard: the bound must not be NaN", bound);
  }
  /// Whether a descent image of σ `sigma_image` over a cell of top-level σ `sigma_top` is
  /// trusted; one that is not trips the guard.
  bool trusts(double sigma_top, double sigma_image) {
    if (sigma_image - sigma_top > bound_) tripped_ = true;
    return !tripped_;
  }
  /// Whether an image was not trusted since reset().
  [[nodiscard]] bool tripped() const noexcept { return tripped_; }
  void reset() noexcept { tripped_ = false; }
  [[nodiscard]] double bound() const noexcept { return bound_; }

 private:
  double bound_;
  bool tripped_ = false;
};

}  // namespace adaptseg
